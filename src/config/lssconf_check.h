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

typedef struct lssconf_bus_src {
        unsigned interface_line;
        unsigned pool_line;
        bool interface_ok;
        bool pool_ok;               /* a valid pool is given */
        lssconf_device_src *devices;   /* n_devices of them */
} lssconf_bus_src;

/* Duplicate identities, duplicate node-IDs, pool over mapped node-IDs.
 * Errors go to diag; returns 0 or -ENOMEM. */
int lssconf_check_bus(const char *name, size_t bus_index, const lssconf_bus *b,
                          const lssconf_bus_src *src, lssconf_diag *diag);

/* The same interface in two buses. Returns 0 or -ENOMEM. */
int lssconf_check_interfaces(const char *name, const lssconf *c,
                                 const lssconf_bus_src *src, lssconf_diag *diag);
