/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Internal to src/config: rules across entries (duplicates, pool overlap),
 * run on the plain structs once every value has been read and checked. */
#pragma once

#include <stdbool.h>

#include "config/lssd_config.h"

/* Where things were in the file, kept beside the structs while loading. */
typedef struct lssd_device_src {
        unsigned node_id_line;
        bool ok; /* identity and node-ID are complete and valid */
} lssd_device_src;

typedef struct lssd_bus_src {
        unsigned interface_line;
        unsigned pool_line;
        bool interface_ok;
        bool pool_ok;               /* a valid pool is given */
        lssd_device_src *devices;   /* n_devices of them */
} lssd_bus_src;

/* Duplicate identities, duplicate node-IDs, pool over mapped node-IDs.
 * Errors go to diag; returns 0 or -ENOMEM. */
int lssd_config_check_bus(const char *name, size_t bus_index, const lssd_bus_config *b,
                          const lssd_bus_src *src, lssd_diag *diag);

/* The same interface in two buses. Returns 0 or -ENOMEM. */
int lssd_config_check_interfaces(const char *name, const lssd_config *c,
                                 const lssd_bus_src *src, lssd_diag *diag);
