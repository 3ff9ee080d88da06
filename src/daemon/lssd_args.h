/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* What the command line asked for (lssd_options.c reads it). */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "lss/lss_proto.h"
#include "simbus/simbus.h"

#define LSSD_QUEUE_MAX_DEFAULT 128u

/* An in-memory slave for `--simulate` (tests and demos without SocketCAN). */
typedef struct lssd_sim_slave {
        char ifname[16];
        lss_identity id;
        uint8_t node_id;
        simbus_profile profile;    /* how it behaves (a CANopenNode v4 device, ...) */
} lssd_sim_slave;

/* What the command line asked for. */
typedef struct lssd_args {
        char *config_path;         /* NULL: the default file if it exists */
        bool config_explicit;      /* --config given: the file must exist */
        char **buses;              /* --bus, in order */
        size_t n_buses;
        lssd_sim_slave *sim_slaves;
        size_t n_sim_slaves;
        simbus_foreign *sim_foreign; /* --sim-foreign-master: another LSS master on a simulated bus */
        size_t n_sim_foreign;
        bool simulate;             /* every bus is an in-memory one */
        bool check_config;
        size_t queue_max;
        unsigned lss_timeout_ms;   /* --lss-timeout for --bus buses, 0 = the default */
} lssd_args;

void lssd_args_done(lssd_args *a);
