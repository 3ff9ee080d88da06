/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Inside a bus: struct lssd_bus and what its files (lssd_bus*.c) share.
 * Nothing but those files includes this header. */
#pragma once

#include "can/transport.h"
#include "can/tx_echo.h"
#include "daemon/lssd_bus.h"
#include "daemon/lssd_heard.h"
#include "daemon/lssd_holder.h"

/* Frames read per wake-up before the other buses get their turn. */
#define RX_BATCH 64u
/* How long a frame the tx queue refuses is tried again before the running
 * operation fails: then nobody drains the queue (no other node
 * acknowledges). A queue that drains for other writers too (a busy bus,
 * another program) hands lssd a slot now and then, though a frame takes only
 * 0.1..1 ms on the wire: 100 ms without one was lost to such a writer under
 * load (kvaser-enobufs). */
#define LSSD_TX_TIMEOUT_MS 1000u

/* Bus PropertiesChanged bookkeeping. */
#define LSSD_BUS_CHANGED_STATE        (1u << 0)
#define LSSD_BUS_CHANGED_BITRATE      (1u << 1)
#define LSSD_BUS_CHANGED_JOB          (1u << 2)
#define LSSD_BUS_CHANGED_PROGRESS     (1u << 3)
#define LSSD_BUS_CHANGED_QUEUE_LENGTH (1u << 4)
#define LSSD_BUS_CHANGED_LAST_PASS    (1u << 5)
#define LSSD_BUS_CHANGED_FOREIGN      (1u << 6)

/* While another master's requests keep coming, ForeignMaster is published
 * at most this often (its start and end at once). */
#define LSSD_FOREIGN_PUBLISH_US 1000000u

struct lssd_bus {
        lssd_bus_host host;              /* the daemon around it */
        lssd_job_env env;                /* what the job runners see (points into this bus) */
        char *ifname;
        char *path;
        lssconf_bus *config;         /* own copy: a bus being removed outlives its configuration */

        lss_transport transport;         /* SocketCAN, the simulated bus, a test's fake: the host's choice */
        sd_event_source *io_source;
        int io_fd;
        sd_event_source *timer_source;
        lss_link_state link;
        lss_bus_state bus_state;
        uint64_t rx_dropped;
        uint32_t link_bitrate;           /* from rtnetlink for real controllers, 0 otherwise */
        bool link_virtual;               /* vcan/vxcan: frames take no time on the "wire" */
        bool link_changed;               /* the transport reported a change: handle it outside the callback */
        struct {                         /* SetBitrate's host retune (lssd_bus_retune.c) */
                sd_event_source *defer;  /* asked by the engine, begins from the loop */
                sd_event_source *io, *timer; /* what the running retune waits for */
                bool running;
                uint32_t rate;
                uint64_t begun_at, due;  /* due: end of the slaves' first delay period */
                uint64_t job_id;         /* the job that retuned: link changes are asked about while it runs */
        } retune;

        lss_master *engine;
        lss_master_stats job_stats;      /* the engine's counters when the running job began */
        bool engine_running;             /* we started an operation and did not collect it yet */
        lss_tx_echo echo;                /* which echo confirms the running step */
        lss_frame tx_frame;              /* handed out by the engine, refused by a full tx queue */
        bool tx_held;
        uint64_t tx_deadline;            /* 0 until tx_frame is first refused */
        uint64_t tx_sent_at;             /* last write of the frames handed out, for on_sent() */
        sd_event_source *tx_retry_source;

        lssd_job_queue queue;
        lssd_job *job;                   /* running */
        double progress;

        lssd_holder holder;              /* Acquire() */

        lssd_devices devices;            /* the registry */

        sd_bus_slot *slot;
        const char *state;               /* as published */
        uint32_t bitrate;                /* as published */
        uint32_t bitrate_set;            /* by SetBitrate: outlives reloads of the file's value; 0 none */
        unsigned changed;                /* LSSD_BUS_CHANGED_* not yet signalled */
        bool processing;                 /* bus_process() is on the stack */
        bool removing;                   /* dropped from the configuration: free when idle */
        sd_event_source *remove_source;  /* frees the bus outside of its own callbacks */

        char *boot_status;               /* how the boot pass ended, for STATUS= */
        lssd_heard heard;                /* node-IDs other devices speak under */

        struct {                         /* another LSS master (lssd_bus_foreign.c) */
                lssd_bus_foreign now;    /* what was heard */
                lssd_bus_foreign pub;    /* what ForeignMaster says */
                uint64_t last_at;        /* the last request (the transport's clock): quiet from then */
                uint64_t pub_at;         /* ForeignMaster last changed (the transport's clock) */
                uint64_t episode_count;  /* requests heard in this episode */
                sd_event_source *timer;  /* the end of the quiet */
        } foreign;
};

/* lssd_bus_lifecycle.c: the transport's clock, the engine's timing */
uint64_t bus_now(lssd_bus *b);
void bus_update_timing(lssd_bus *b);

/* lssd_bus_publish.c: State, Bitrate, Job, Progress, ... and the engine's
 * progress and finds */
void bus_update_published(lssd_bus *b);
void bus_flush_changes(lssd_bus *b);
void bus_set_progress(lssd_bus *b, double p);
void bus_on_engine_progress(void *userdata, double p);
void bus_on_engine_found(void *userdata, const lss_device *d);

/* lssd_bus_tx.c: frames out, held while the tx queue is full */
int bus_tx_init(lssd_bus *b);
void bus_flush_tx(lssd_bus *b);
bool bus_tx_pending(const lssd_bus *b);

/* lssd_bus_engine.c: frames in, the timer, the job at the head */
void bus_process(lssd_bus *b);
void bus_update_io(lssd_bus *b, bool force);
int bus_on_timer(sd_event_source *s, uint64_t usec, void *userdata);

/* lssd_bus_queue.c: what may be queued, the internal jobs */
void bus_queue_reset(lssd_bus *b, bool front);
void bus_queue_boot_pass(lssd_bus *b);

/* lssd_bus_holder.c */
void bus_on_holder_gone(lssd_holder *h, void *userdata);

/* lssd_bus_foreign.c: another LSS master. A request heard (not ours):
 * the bus refuses LSS jobs, those queued for callers are answered
 * ForeignMaster, the running one ends (the engine's part), until none was
 * heard for foreign_master_quiet_s. */
void bus_foreign_heard(lssd_bus *b, const lss_frame *f);
/* 0, or ForeignMaster naming the last request while the quiet is not over. */
int bus_foreign_refuse(lssd_bus *b, sd_bus_error *error);
/* The job at the head of the queue waits for the quiet (all but a Reset). */
bool bus_foreign_holds(const lssd_bus *b);
/* The engine ended the running job with LSS_E_FOREIGN_MASTER: `r` in *copy
 * with the bus's words (interface, frame, time), and the slaves it left set
 * aside queued for a GiveBack once the quiet is over. */
const lss_result *bus_foreign_result(lssd_bus *b, const lss_result *r, lss_result *copy);
/* "another LSS master is active on can0: 7E5#... at 12:03:04.512" */
void bus_foreign_text(const lssd_bus *b, char *buf, size_t size);
void bus_foreign_free(lssd_bus *b);

/* lssd_bus_queue.c: put an internal job first, behind those of the kinds
 * in `behind` (bit LSSD_JOB_x) at the head */
void bus_queue_front(lssd_bus *b, lssd_job *j, unsigned behind);
/* answers every queued job of a caller with `error` (JobFinished `result`) */
void bus_queue_abort_requests(lssd_bus *b, const char *error, const char *result, const char *why);

/* lssd_bus_link.c: the host interface */
void bus_on_link_state(void *userdata, lss_link_state old_state, lss_link_state new_state);
void bus_after_link_change(lssd_bus *b);

/* lssd_bus_retune.c: SetBitrate's host retune */
void bus_on_retune_wanted(void *userdata);
bool bus_retune_caused(lssd_bus *b, lss_link_state new_state);
void bus_retune_free(lssd_bus *b);

/* lssd_bus_views.c: what the registry and the job runners see */
extern const lssd_devices_ops bus_devices_ops;
extern const lssd_job_env_ops bus_env_ops;
