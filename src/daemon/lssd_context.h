/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The daemon's one context: event loop, D-Bus connection, configuration,
 * link watcher and the buses. lssd_context_free() frees it all. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <systemd/sd-bus.h>
#include <systemd/sd-event.h>

#include "can/rtnl_watch.h"
#include "config/lssconf.h"
#include "daemon/lssd_args.h"
#include "daemon/lssd_auth.h"
#include "daemon/lssd_bus.h"
#include "daemon/lssd_ready.h"

#define LSSD_DEFAULT_CONFIG   "/etc/lssd/lssd.conf"
#define LSSD_STOP_TIMEOUT_USEC (5u * 1000000u)


typedef struct lssd_context {
        sd_event *event;
        sd_bus *dbus;              /* the D-Bus connection (a CAN bus is a lssd_bus) */
        sd_bus_slot *manager_slot, *object_manager_slot;
        rtnl_watch *rtnl;
        sd_event_source *rtnl_source;
        sd_event_source *stop_timeout;

        lssd_auth auth;
        lssd_args args;            /* owned copy */
        char *config_path;         /* the file in use, NULL when none */
        lssconf *config;       /* file + --bus buses; the buses point into it */

        lssd_bus **buses;
        size_t n_buses;
        uint64_t next_job_id;
        bool stopping;
        bool started;              /* past start-up: buses added now get no boot pass */
        bool name_owned;           /* buses may send (lssd_context_start_buses) */
        bool ready_deferred;       /* READY=1 waits for boot auto-assign passes */
        bool ready_sent;           /* READY=1 went (it goes once) */
        sd_event_source *ready_timer; /* meanwhile: EXTEND_TIMEOUT_USEC=, the limits (lssd_ready.h) */
        lssd_ready_wait ready_wait;
} lssd_context;

/* Takes over `args` (it is zeroed). */
int lssd_context_new(lssd_args *args, lssd_context **ret);
lssd_context *lssd_context_free(lssd_context *ctx);

/* Reads the configuration file (if any) and adds the --bus buses. Messages go
 * to `diag`. Does not touch the buses. */
int lssd_context_read_config(lssd_context *ctx, lssconf **ret, lssconf_diag *diag);
/* Makes `config` the one in force: new buses are created, gone ones removed,
 * the others get their new map. Takes over `config`. */
int lssd_context_apply_config(lssd_context *ctx, lssconf *config);
/* SIGHUP and ReloadConfig(): the last good configuration stays when the new
 * one is bad (error says why). */
int lssd_context_reload(lssd_context *ctx, sd_bus_error *error);

int lssd_context_open_rtnl(lssd_context *ctx);
/* lssd owns its name now: every bus sends its first frame, and buses added
 * from now on do at once. */
void lssd_context_start_buses(lssd_context *ctx);
/* Feeds the current state of every link to the buses. */
int lssd_context_dump_links(lssd_context *ctx);
int lssd_context_connect_bus(lssd_context *ctx);
/* Owns org.lssd.LSS1; call before any CAN bus is opened. -EEXIST (logged
 * as "lssd is already running") when another process owns it. */
int lssd_context_request_name(lssd_context *ctx);

lssd_bus *lssd_context_find_bus(lssd_context *ctx, const char *ifname);
/* Called by a bus that was being removed and is idle now. */
void lssd_context_bus_removed(lssd_context *ctx, lssd_bus *b);

/* SIGTERM/SIGINT: stop taking jobs, cancel what is queued, finish or cancel
 * the running step, switch every slave back to waiting, release the name,
 * exit. */
void lssd_context_stop(lssd_context *ctx);
/* A bus went idle: finish stopping when all are. */
void lssd_context_check_stopped(lssd_context *ctx);

/* ---- READY=1 and STATUS= (lssd_context_ready.c; the wait itself is lssd_ready.h) ---- */

/* The status line (and READY=1 with `ready`, only the first time). */
void lssd_ready_status(lssd_context *ctx, bool ready);
/* Start-up is done: READY=1 now, or once every boot auto-assign pass on a
 * bus that is up finished or gave up (a bus that is not there does not hold
 * it back: STATUS= says it is waited for; one that is there but down holds it
 * for LSSD_LINK_GRACE_USEC, then no more), at the latest at the limits of lssd_ready.h. */
void lssd_ready_startup_done(lssd_context *ctx);
/* A bus's boot pass ended. */
void lssd_ready_boot_pass_done(lssd_context *ctx);
