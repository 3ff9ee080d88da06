/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* What a job runner (lssd_jobs.c, lssd_bitrate.c) may see and touch of the
 * bus it runs on: the engine, the map, the device registry, the frames
 * heard, the state of AutoAssign passes, and a few callbacks into the bus.
 * The bus owns it and hands it to the runners; they never see the bus. */
#pragma once

#include <stdbool.h>
#include <stdint.h>
#include <systemd/sd-bus.h>

#include "can/transport.h"
#include "config/lssconf.h"
#include "daemon/lssd_devices.h"
#include "daemon/lssd_heard.h"
#include "daemon/lssd_job_queue.h"
#include "daemon/lssd_unstored.h"
#include "lss/lss_autoassign.h"
#include "lss/lss_master.h"

/* How the last AutoAssign pass of a bus went (property LastPass). */
typedef struct lssd_pass_record {
        uint64_t started_us;             /* CLOCK_REALTIME; 0: no pass yet */
        uint64_t duration_us;
        bool boot;                       /* the pass at start, not a call */
        char result[24];                 /* "done", "partial", or what broke it off */
        uint32_t counts[LSS_OUTCOME_FAILED + 1]; /* by lss_outcome_kind */
} lssd_pass_record;

/* The host interface as far as a bit-rate change cares. */
typedef struct lssd_host_link {
        const char *ifname;
        lss_link_state link;
        lss_bus_state bus_state;
        bool simulated;                  /* the in-memory bus of --simulate */
        bool virtual_link;               /* vcan/vxcan: no bit timing */
        uint32_t bitrate;                /* the bus's rate now */
} lssd_host_link;

typedef struct lssd_job_env_ops {
        uint64_t (*now)(void *userdata);                /* the transport's clock (CLOCK_MONOTONIC µs) */
        uint32_t (*bitrate)(void *userdata);            /* the rate the bus runs at */
        const char *(*holder)(void *userdata);          /* unique name of the holder (Acquire), NULL none */
        void (*host_link)(void *userdata, lssd_host_link *ret);
        /* the network runs at this rate now (SetBitrate) */
        void (*set_bitrate)(void *userdata, uint32_t bitrate);
        /* last_pass changed: publish LastPass */
        void (*last_pass_changed)(void *userdata);
} lssd_job_env_ops;

typedef struct lssd_job_env {
        const char *ifname;
        const char *path;                /* the bus's object path, for signals */
        sd_bus *dbus;                    /* NULL: no signals */
        lss_master *engine;
        const lssconf_bus *config;   /* the map in force */
        lssd_devices *devices;
        lssd_heard *heard;
        bool taken_with_devices;         /* lssd_taken_check() */

        /* AutoAssign passes */
        bool boot_pending;               /* auto_assign: the boot pass has not ended yet */
        lssd_unstored unstored;          /* node-IDs that may not be stored */
        lssd_pass_record last_pass;
        uint64_t pass_started_us;        /* of the running AutoAssign, CLOCK_REALTIME */

        /* how long each part of the last whole Scan with SDO took (µs;
         * zeros: none yet): the next one's progress is weighted by them */
        uint64_t scan_part_us[_LSSD_SCAN_PARTS];

        const lssd_job_env_ops *ops;
        void *userdata;
} lssd_job_env;

static inline uint64_t lssd_job_env_now(const lssd_job_env *e) {
        return e->ops->now(e->userdata);
}

static inline uint32_t lssd_job_env_bitrate(const lssd_job_env *e) {
        return e->ops->bitrate(e->userdata);
}
