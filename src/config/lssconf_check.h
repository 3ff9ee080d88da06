/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Internal to src/config: rules across entries (duplicates, pool overlap),
 * run on the plain structs once every value has been read and checked. */
#pragma once

#include <stdbool.h>

#include "config/lssconf.h"

/* Where things were in the file, kept beside the structs while loading. */
typedef struct lssconf_device_src {
        unsigned node_id_line;
        bool ok; /* identity and node-ID are complete and valid */
} lssconf_device_src;

/* One pattern of a bus's `dcf`, as written (in the libconfig tree). */
typedef struct lssconf_dcf_pattern {
        const char *pattern;
        unsigned line;
} lssconf_dcf_pattern;

typedef struct lssconf_bus_src {
        unsigned interface_line;
        unsigned pool_line;
        bool interface_ok;
        bool pool_ok;               /* a valid pool is given */
        lssconf_device_src *devices;   /* n_devices of them */
        lssconf_dcf_pattern *dcf;   /* the `dcf` patterns, n_dcf of them */
        size_t n_dcf;
        unsigned dcf_line;
} lssconf_bus_src;

/* Duplicate identities, duplicate node-IDs, pool over mapped node-IDs.
 * Errors go to diag; returns 0 or -ENOMEM. */
int lssconf_check_bus(const char *name, size_t bus_index, const lssconf_bus *b,
                          const lssconf_bus_src *src, lssconf_diag *diag);

/* Pool over mapped node-IDs, for the entries from index `from` on; c (or
 * NULL) names the DCFs entries came from. */
void lssconf_check_pool(const char *name, size_t bus_index, const lssconf_bus *b, const lssconf_bus_src *src,
                        size_t from, const lssconf *c, lssconf_diag *diag);

/* The same interface in two buses. Returns 0 or -ENOMEM. */
int lssconf_check_interfaces(const char *name, const lssconf *c,
                                 const lssconf_bus_src *src, lssconf_diag *diag);
