/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* One CAN bus the daemon is the LSS master of: its transport, its engine, its
 * job queue, its holder and its devices; published as an org.lssd.LSS1.Bus
 * object. Exactly one LSS transaction at a time runs on a bus; buses run in
 * parallel, each driven by its own fd and timer in the one event loop. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <systemd/sd-bus.h>
#include <systemd/sd-event.h>

#include "can/rtnl_watch.h"
#include "can/socketcan.h"
#include "can/transport.h"
#include "config/lssd_config.h"
#include "daemon/lssd_context.h"
#include "daemon/lssd_device.h"
#include "daemon/lssd_heard.h"
#include "daemon/lssd_job.h"
#include "daemon/lssd_simbus.h"
#include "lss/lss_autoassign.h"
#include "lss/lss_master.h"

/* Bus PropertiesChanged bookkeeping. */
#define LSSD_BUS_CHANGED_STATE        (1u << 0)
#define LSSD_BUS_CHANGED_BITRATE      (1u << 1)
#define LSSD_BUS_CHANGED_JOB          (1u << 2)
#define LSSD_BUS_CHANGED_PROGRESS     (1u << 3)
#define LSSD_BUS_CHANGED_QUEUE_LENGTH (1u << 4)
#define LSSD_BUS_CHANGED_LAST_PASS    (1u << 5)

/* How the last AutoAssign pass of a bus went (property LastPass). */
typedef struct lssd_pass_record {
        uint64_t started_us;             /* CLOCK_REALTIME; 0: no pass yet */
        uint64_t duration_us;
        bool boot;                       /* the pass at start, not a call */
        char result[24];                 /* "done", "partial", or what broke it off */
        uint32_t counts[LSS_OUTCOME_FAILED + 1]; /* by lss_outcome_kind */
} lssd_pass_record;

struct lssd_bus {
        lssd_context *ctx;
        char *ifname;
        char *path;
        lssd_bus_config *config;         /* own copy: a bus being removed outlives its configuration */

        lss_transport transport;
        socketcan_port *port;            /* behind transport, NULL when simulated */
        lssd_simbus *sim;                /* behind transport when simulated */
        sd_event_source *io_source;
        int io_fd;
        sd_event_source *timer_source;
        lss_link_state link;
        lss_bus_state bus_state;
        uint64_t rx_dropped;
        uint32_t link_bitrate;           /* from rtnetlink for real controllers, 0 otherwise */
        bool link_virtual;               /* vcan/vxcan: frames take no time on the "wire" */
        bool link_changed;               /* socketcan reported a change: handle it outside the callback */

        lss_master *engine;
        bool engine_running;             /* we started an operation and did not collect it yet */
        lss_frame echo_want;             /* last LSS request written: its echo confirms it is on the wire */
        uint64_t echo_want_at;           /* when it was written */
        bool echo_pending;

        lssd_job_queue queue;
        lssd_job *job;                   /* running */
        double progress;

        sd_bus_track *holder;            /* Acquire() */
        char *holder_name;

        lssd_device *devices;
        size_t n_devices;

        sd_bus_slot *slot;
        const char *state;               /* as published */
        uint32_t bitrate;                /* as published */
        uint32_t bitrate_set;            /* by SetBitrate: outlives reloads of the file's value; 0 none */
        unsigned changed;                /* LSSD_BUS_CHANGED_* not yet signalled */
        bool processing;                 /* bus_process() is on the stack */
        bool removing;                   /* dropped from the configuration: free when idle */
        sd_event_source *remove_source;  /* frees the bus outside of its own callbacks */

        bool boot_pending;               /* auto_assign: the boot pass has not ended yet */
        /* node-IDs that booted up right after a Reset: a slave that an
         * interrupted pass configured but may not have stored took its pending
         * ID then; the next AutoAssign stores it (lss_autoassign_plan) */
        bool unstored[128];
        uint64_t unstored_until;         /* end of that window after the last Reset (the
                                          * engine's wait for a boot-up after an assignment) */
        char *boot_status;               /* how the boot pass ended, for STATUS= */
        lssd_heard heard;                /* node-IDs other devices speak under */
        bool taken_with_devices;         /* lssd_taken_check() */
        lssd_pass_record last_pass;
        uint64_t pass_started_us;        /* of the running AutoAssign, CLOCK_REALTIME */
};

/* Opens the transport (a missing interface is fine), registers the object
 * and queues the first frame: switch-global waiting. */
int lssd_bus_new(lssd_context *ctx, const lssd_bus_config *config, lssd_bus **ret);
/* Sends the queued first frame (call once lssd owns its name: a second lssd
 * must send nothing) and, with `announce`, InterfacesAdded (not for the
 * buses registered before the name was taken: nobody could see them missing). */
void lssd_bus_start(lssd_bus *b, bool announce);
lssd_bus *lssd_bus_free(lssd_bus *b);
/* A new configuration (after reload): map, timing, bit rate. */
void lssd_bus_set_config(lssd_bus *b, const lssd_bus_config *config);
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

/* ---- devices ---- */
lssd_device *lssd_bus_find_device(lssd_bus *b, const lss_identity *id);
/* The device with this identity, created (with node_id) and announced if new. */
int lssd_bus_get_device(lssd_bus *b, const lss_identity *id, uint8_t node_id, lssd_device **ret);
/* The same; a new one made with !revision_known (from a map entry without
 * revision, never seen) publishes RevisionKnown false. */
int lssd_bus_get_device_full(lssd_bus *b, const lss_identity *id, bool revision_known, uint8_t node_id,
                             lssd_device **ret);
/* Recomputes mapped node-IDs and states of every device and emits
 * PropertiesChanged for what changed. */
void lssd_bus_refresh_devices(lssd_bus *b);
/* A present device other than `except` answering to node_id, NULL if none. */
lssd_device *lssd_bus_device_with_node_id(lssd_bus *b, uint8_t node_id, const lss_identity *except);


/* ---- for the job code ---- */
uint64_t lssd_bus_now(lssd_bus *b);      /* the transport's clock (CLOCK_MONOTONIC µs) */
uint64_t lssd_realtime_us(void);         /* CLOCK_REALTIME µs, for LastSeen */
