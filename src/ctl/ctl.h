/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* lssctl: what every verb gets — the parsed command line, the bus
 * connection, how output goes out, and where a failure's exit code is kept. */
#pragma once

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <systemd/sd-bus.h>

#include "names/lssd_names.h"

typedef struct ctl_context {
        /* command line */
        const char *bus_name;       /* --bus IFACE or NULL */
        bool json;
        bool no_pager;
        bool no_legend;
        bool no_store;
        bool no_verify;
        bool skip_missing;
        bool force;                 /* assign: even a taken node-ID */
        bool quiet;                 /* no report of what was done */
        bool dry_run;               /* auto-assign: discovery only */
        bool reset;                 /* unassign: reset the device and check it runs non-configured */
        bool as_config;             /* scan: print the found devices as lssd.conf(5) buses */
        const char *as_dcf;         /* scan: write a DCF fragment per device found into this folder */
        bool global;                /* set-bitrate: SetBitrate option global */
        bool no_sdo;                /* scan: LSS only, no SDO discovery (Scan option sdo false) */
        bool no_ask_password;       /* no polkit agent, no interactive authorization */
        bool has_delay;
        uint16_t delay_ms;
        bool has_vendor, has_product;
        uint32_t vendor, product;
        char **args;                /* the verb's arguments */
        int n_args;

        /* environment */
        bool stdout_tty, stderr_tty;
        bool colors;                /* stdout gets colours */
        bool err_colors;            /* stderr gets colours */

        sd_bus *bus;
        int exit_code;              /* set by whoever reports the failure */
} ctl_context;

/* Connects to the system bus, once; verbs call it after checking their
 * arguments, so that usage errors never depend on the bus. */
int ctl_connect(ctl_context *c);

/* Reporting. Each prints one line to stderr, records the exit code and
 * returns a negative errno for the caller to pass up. */
int ctl_fail(ctl_context *c, int exit_code, int err, const char *fmt, ...) _sd_printf_(4, 5);
int ctl_usage(ctl_context *c, const char *fmt, ...) _sd_printf_(2, 3);
/* A failed D-Bus call: "<what>: <sentence> (<lssd's message>)"; the exit
 * code follows the error name (ctl_errors.h). */
int ctl_bus_fail(ctl_context *c, const sd_bus_error *error, int r, const char *what);

/* The object path of the bus to act on: --bus, or the only one served.
 * Fails (usage) when several are served and --bus is missing. */
int ctl_pick_bus(ctl_context *c, char **ret_path, char **ret_ifname);
/* Every bus lssd serves (or the --bus one), paths and interface names. */
int ctl_buses(ctl_context *c, char ***ret_paths, char ***ret_ifnames, size_t *ret_n);
/* The interface name in a bus or device object path (newly allocated). */
int ctl_path_ifname(const char *path, char **ret);
/* Both parts of a bus or device path; *ret_device is NULL for a bus. */
int ctl_path_parse(const char *path, char **ret_ifname, char **ret_device);

void ctl_strv_free(char **v, size_t n);

/* verbs */
int verb_status(ctl_context *c);
int verb_list(ctl_context *c);
int verb_scan(ctl_context *c);
int verb_auto_assign(ctl_context *c);
int verb_assign(ctl_context *c);
int verb_unassign(ctl_context *c);
int verb_set_bitrate(ctl_context *c);
int verb_reload(ctl_context *c);
int verb_monitor(ctl_context *c);
int verb_raw(ctl_context *c);
int verb_import_dcf(ctl_context *c);
