/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* One CAN bus the daemon is the LSS master of: its transport, its engine, its
 * job queue, its holder and its devices; published as an org.lssd.LSS1.Bus
 * object. Exactly one LSS transaction at a time runs on a bus; buses run in
 * parallel, each driven by its own fd and timer in the one event loop.
 * Implemented in lssd_bus_<concern>.c, which share lssd_bus_private.h. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <systemd/sd-bus.h>
#include <systemd/sd-event.h>

#include "can/rtnl_watch.h"
#include "can/transport.h"
#include "config/lssconf.h"
#include "daemon/lssd_args.h"
#include "daemon/lssd_auth.h"
#include "daemon/lssd_devices.h"
#include "daemon/lssd_job_queue.h"
#include "daemon/lssd_job_env.h"
#include "lss/lss_master.h"

typedef struct lssd_bus lssd_bus;

/* What a bus needs of the daemon around it (lssd_context.c in lssd). */
typedef struct lssd_bus_host_ops {
        uint64_t (*next_job_id)(void *userdata);
        bool (*stopping)(void *userdata);      /* lssd is stopping: take no jobs */
        bool (*started)(void *userdata);       /* past start-up: no boot pass for new buses */
        void (*status_changed)(void *userdata); /* the bus's trouble changed: STATUS= */
        void (*boot_pass_done)(void *userdata);
        void (*removed)(void *userdata, lssd_bus *b); /* removing and idle now: free it */
        void (*idle)(void *userdata);          /* the bus went idle (stopping waits for that) */
        /* Opens the bus's transport (lssd_transport_open(); tests: a fake):
         * `hooks` tell the bus about its link. A missing interface is no
         * error; 1: the log says already why the link is gone. */
        int (*open_transport)(void *userdata, const char *ifname, uint32_t bitrate, const lss_transport_hooks *hooks,
                              lss_transport *ret);
} lssd_bus_host_ops;

typedef struct lssd_bus_host {
        sd_event *event;
        sd_bus *dbus;                          /* the D-Bus connection; NULL: nothing published */
        lssd_auth *auth;
        const lssd_args *args;                 /* --simulate, its slaves, the queue bound */
        const lssd_bus_host_ops *ops;
        void *userdata;
} lssd_bus_host;

/* Opens the transport (a missing interface is fine), registers the object
 * and queues the first frame: switch-global waiting. */
int lssd_bus_new(const lssd_bus_host *host, const lssconf_bus *config, lssd_bus **ret);
/* Sends the queued first frame (call once lssd owns its name: a second lssd
 * must send nothing) and, with `announce`, InterfacesAdded (not for the
 * buses registered before the name was taken: nobody could see them missing). */
void lssd_bus_start(lssd_bus *b, bool announce);
lssd_bus *lssd_bus_free(lssd_bus *b);
/* A new configuration (after reload): map, timing, bit rate. */
void lssd_bus_set_config(lssd_bus *b, const lssconf_bus *config);
/* The network now runs at this rate (SetBitrate): configuration, timing,
 * Bitrate property follow; kept over reloads until lssd restarts. */
void lssd_bus_set_bitrate(lssd_bus *b, uint32_t bitrate);

/* "down", "idle", "busy", "error-passive", "bus-off" */
const char *lssd_bus_state(const lssd_bus *b);
uint32_t lssd_bus_bitrate(const lssd_bus *b);
const char *lssd_bus_job_name(const lssd_bus *b);
bool lssd_bus_idle(const lssd_bus *b);

/* May `sender` start a job now? Busy when stopping or held by somebody else,
 * BusDown when the link is not up, and for raw services AccessDenied unless
 * `sender` holds the bus. */
int lssd_bus_check_available(lssd_bus *b, const char *sender, bool raw, sd_bus_error *error);
/* Queues a job (LimitsExceeded when the queue is full) and starts it if the
 * bus is idle. Takes over the job on success. */
int lssd_bus_submit(lssd_bus *b, lssd_job *j, sd_bus_error *error);
/* lssd_bus_check_available() for the sender of `m`, then lssd_bus_submit().
 * Takes over the job in every case; 1: the job answers. */
int lssd_bus_queue_job(lssd_bus *b, sd_bus_message *m, lssd_job *j, bool raw, sd_bus_error *error);

int lssd_bus_acquire(lssd_bus *b, sd_bus_message *m, sd_bus_error *error);
int lssd_bus_release(lssd_bus *b, const char *sender, sd_bus_error *error);
/* Cancels the running job (not the queued ones). */
int lssd_bus_cancel(lssd_bus *b, const char *sender, sd_bus_error *error);

/* rtnetlink told something about a link (any interface). */
void lssd_bus_link_event(lssd_bus *b, const rtnl_link *link);
/* Stopping or removal: cancel queue and running job, end with switch-global waiting. */
void lssd_bus_stop(lssd_bus *b, const char *why);

/* AssignNodeId of Bus and Device after reading and validating: authorize,
 * refuse a node-ID another device answers to (Conflict), queue the job. */
int lssd_bus_method_assign(lssd_bus *b, sd_bus_message *m, const lss_identity *id, uint8_t node_id,
                           const lssd_assign_options *o, sd_bus_error *error);

/* ---- what other files may read ---- */
const char *lssd_bus_ifname(const lssd_bus *b);
const char *lssd_bus_object_path(const lssd_bus *b);
const lssconf_bus *lssd_bus_config_of(const lssd_bus *b);
lssd_auth *lssd_bus_auth(lssd_bus *b);
lssd_devices *lssd_bus_devices(lssd_bus *b);
/* What the job runners see of the bus. */
lssd_job_env *lssd_bus_job_env(lssd_bus *b);
const lssd_job *lssd_bus_running_job(const lssd_bus *b);
size_t lssd_bus_queue_length(const lssd_bus *b);
double lssd_bus_progress(const lssd_bus *b);
const char *lssd_bus_holder(const lssd_bus *b);
/* Dropped from the configuration: stopping, freed when idle. */
bool lssd_bus_removing(const lssd_bus *b);
void lssd_bus_set_removing(lssd_bus *b, bool removing);

/* Another LSS master on the bus (property ForeignMaster). */
typedef struct lssd_bus_foreign {
        bool active;                /* heard within foreign_master_quiet_s: LSS jobs are refused */
        uint64_t since_us;          /* CLOCK_REALTIME: the first request of this (or the last) episode; 0: never */
        uint64_t last_us;           /* CLOCK_REALTIME: the last request */
        char frame[32];             /* the last request, as candump writes it */
        uint64_t count;             /* requests heard since lssd started */
} lssd_bus_foreign;
/* What ForeignMaster says (while requests keep coming, brought up to date
 * at most once a second). */
void lssd_bus_foreign_get(const lssd_bus *b, lssd_bus_foreign *ret);

/* The boot pass of a bus, for READY=1 and STATUS= (lssd_context_ready.c). */
typedef struct lssd_bus_boot {
        bool pending;               /* the boot pass has not ended yet */
        lss_link_state link;
        const char *status;         /* how it ended, NULL before */
        uint64_t pass_started_us;   /* of the running AutoAssign, CLOCK_REALTIME */
        uint64_t engine_steps;      /* and another master's requests: waiting for its quiet is no stall */
        unsigned lss_timeout_ms;
        bool foreign;               /* another LSS master is active: the pass waits for its quiet */
        uint64_t foreign_since_us;  /* CLOCK_REALTIME: since when */
} lssd_bus_boot;
void lssd_bus_boot_get(const lssd_bus *b, lssd_bus_boot *ret);
