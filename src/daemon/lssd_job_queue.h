/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Jobs and the bounded FIFO each bus runs them from. A job is one atomic
 * piece of work on one bus: one or more engine operations in a row, never
 * interleaved with another job's frames. Jobs from D-Bus keep the request
 * message and are answered when they end (deferred replies). */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <systemd/sd-bus.h>

#include "daemon/lssd_device.h"
#include "daemon/lssd_options.h"
#include "daemon/lssd_raw.h"
#include "config/lssconf.h"
#include "lss/lss_autoassign.h"
#include "lss/lss_master.h"

typedef enum lssd_job_type {
        LSSD_JOB_RESET,   /* internal: switch-global waiting (start, link up, release, stop) */
        LSSD_JOB_SCAN,    /* Scan(): fastscan enumeration + slowscan of vendor/product pairs */
        LSSD_JOB_ASSIGN,  /* AssignNodeId() of Bus or Device */
        LSSD_JOB_RAW,     /* one raw service of the bus holder */
        LSSD_JOB_EXECUTE, /* Execute(): raw services in a row, then switch-global waiting */
        LSSD_JOB_AUTO_ASSIGN, /* AutoAssign() or the boot pass: make the bus match the map */
        LSSD_JOB_SET_BITRATE, /* SetBitrate(): scan, then the whole network to a new rate (lssd_bitrate.c) */
        LSSD_JOB_UNASSIGN, /* UnassignNodeId(): back to non-configured */
        /* internal: 255 back to slaves a job broken off by another master
         * left with the temporary node-ID an enumeration set them aside with */
        LSSD_JOB_GIVE_BACK,
        _LSSD_JOB_TYPE_MAX,
} lssd_job_type;

/* The parts of a Scan, timed for the progress of the next one. */
enum { LSSD_SCAN_PART_LSS, LSSD_SCAN_PART_SDO, LSSD_SCAN_PART_CONFIRM, _LSSD_SCAN_PARTS };

typedef struct lssd_vendor_product {
        uint32_t vendor, product;
} lssd_vendor_product;

/* A device a scan found, and how (LSSD_FOUND_*). */
typedef struct lssd_scan_find {
        lss_device dev;
        unsigned by;
} lssd_scan_find;

typedef struct lssd_job lssd_job;
struct lssd_job {
        lssd_job_type type;
        uint64_t id;                 /* per daemon, for logs */
        sd_bus_message *request;     /* NULL for internal jobs */
        char *sender;                /* unique name of the caller; NULL for internal jobs */
        lssd_job *prev, *next;       /* queue links */

        const char *result;          /* how it ended: "done", "no-response", ... (JobFinished) */
        unsigned stage;              /* index of the engine operation running now */
        unsigned n_stages;           /* how many it will take (for Progress) */

        /* RAW, EXECUTE */
        lssd_raw_step *steps;
        size_t n_steps;
        sd_bus_message *reply;       /* EXECUTE: results collected so far */
        sd_bus_error error;          /* EXECUTE: the failure, answered after the final switch to waiting */

        /* ASSIGN */
        lss_identity identity;
        uint8_t node_id;
        lssd_assign_options assign;

        /* UNASSIGN (identity as ASSIGN) */
        lssd_unassign_options unassign;

        /* SCAN */
        lssd_vendor_product *pairs;
        size_t n_pairs;
        lssd_scan_find *found;       /* merged results of all stages */
        size_t n_found;
        bool scan_sdo;               /* SDO discovery and LSS confirmation after the LSS stages */
        lss_identity *sdo_cand;      /* found by SDO only: to confirm through LSS */
        size_t n_sdo_cand;
        uint64_t part_started;       /* when the running stage began (the transport's clock, µs) */
        uint64_t part_us[_LSSD_SCAN_PARTS]; /* how long each part took so far */
        unsigned expected_finds;     /* non-configured devices seen before (0: not known), for Progress */
        lss_identity *announced;     /* DeviceFound sent (when the engine confirmed them) */
        size_t n_announced;
        bool scan_incomplete;        /* a stage failed: devices not found are not "missing" */
        char **notes;                /* what the scan did not look at or could not identify (the reply's) */
        size_t n_notes;

        /* AUTO_ASSIGN: the engine keeps a pointer to the plan and its map until the pass ends */
        lss_autoassign_plan plan;
        lss_map_entry *map;
        bool boot;                   /* the pass at start (or when the interface appears) */
        char summary[192];           /* "<ifname>: N assigned, ..." once it ended, for logs and STATUS= */

        /* SET_BITRATE (also uses pairs/found for its scan) */
        uint32_t bitrate;
        uint16_t switch_delay_ms;
        bool bitrate_store, bitrate_skip_missing;
        bool bitrate_global;         /* option global: CiA 305's global procedure */
        bool br_started;             /* the discovery is over, the bit-rate procedure runs */
        lss_bitrate_device *br_devices;
        size_t n_br_devices;
        int retune_error;            /* errno of a failed host retune */

        /* GIVE_BACK: the slaves and their temporary node-IDs (aside_node_id) */
        lss_device *aside;
        size_t n_aside;
};

/* Adds a note to the Scan reply (a copy of text); -ENOMEM. */
int lssd_job_add_note(lssd_job *j, const char *text);

/* A SET_BITRATE job in its bit-rate procedure (the scan before it is over):
 * not cancelled (Cancel, stop) while its engine operation runs, as cut off
 * it could leave devices with a pending rate or the bus split; it ends
 * within seconds. */
bool lssd_job_uncancellable(const lssd_job *j);

/* "Reset", "Scan", "AssignNodeId", the raw method name, "Execute", "AutoAssign",
 * "SetBitrate", "UnassignNodeId", "GiveBack". */
const char *lssd_job_name(const lssd_job *j);

/* A new job; request (may be NULL) is referenced, its sender copied. */
int lssd_job_new(lssd_job_type type, sd_bus_message *request, lssd_job **ret);
lssd_job *lssd_job_free(lssd_job *j);

/* Fills an auto-assign job's plan from a bus configuration (the map is
 * copied: a reload during the pass does not pull it away). */
int lssd_job_set_plan(lssd_job *j, const lssconf_bus *c);

/* Adds a vendor/product pair to a scan job unless it is there. */
int lssd_job_add_pair(lssd_job *j, uint32_t vendor, uint32_t product);
/* Merges a device into a scan job's results, found by `by` (LSSD_FOUND_*):
 * a later LSS answer for the same identity replaces the node-ID (an SDO
 * answer does not replace an LSS one). 1 when new. */
int lssd_job_add_found_by(lssd_job *j, const lss_device *d, unsigned by);
/* The same, found by LSS. */
int lssd_job_add_found(lssd_job *j, const lss_device *d);

typedef struct lssd_job_queue {
        lssd_job *head, *tail;
        size_t n;
        size_t max; /* bound for jobs from D-Bus; internal jobs always fit */
} lssd_job_queue;

void lssd_job_queue_init(lssd_job_queue *q, size_t max);
/* Appends. -ENOBUFS when the queue holds `max` jobs and `force` is false. */
int lssd_job_queue_push(lssd_job_queue *q, lssd_job *j, bool force);
/* Puts a job first (internal jobs that must precede everything queued). */
void lssd_job_queue_push_front(lssd_job_queue *q, lssd_job *j);
lssd_job *lssd_job_queue_pop(lssd_job_queue *q);
void lssd_job_queue_remove(lssd_job_queue *q, lssd_job *j);
