/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* One bus with a fake host and sd-event driving it, no D-Bus: for the
 * daemon unit tests of a bus (test-daemon-bus-*.c). */
#pragma once

#include <check.h>
#include <stdio.h>
#include <string.h>
#include <systemd/sd-event.h>

#include "daemon/lssd_bus.h"

#include "check-main.h"

typedef struct fake_host {
        uint64_t next_id;
        unsigned idle;
} fake_host;

static inline uint64_t fake_host_next_job_id(void *userdata) {
        fake_host *h = userdata;
        return ++h->next_id;
}

static inline bool fake_host_no(void *userdata) {
        return false;
}

static inline bool fake_host_started(void *userdata) {
        return true; /* no boot pass */
}

static inline void fake_host_nothing(void *userdata) {
}

static inline void fake_host_removed(void *userdata, lssd_bus *b) {
}

static inline void fake_host_idle(void *userdata) {
        fake_host *h = userdata;
        h->idle++;
}

/* The fake host's ops with this transport opener. */
#define FAKE_HOST_OPS(open)                                                  \
        {                                                                    \
                .next_job_id = fake_host_next_job_id,                        \
                .stopping = fake_host_no,                                    \
                .started = fake_host_started,                                \
                .status_changed = fake_host_nothing,                         \
                .boot_pass_done = fake_host_nothing,                         \
                .removed = fake_host_removed,                                \
                .idle = fake_host_idle,                                      \
                .open_transport = (open),                                    \
        }

typedef struct fixture {
        sd_event *event;
        fake_host host;
        lssd_args args;
        lssconf_bus config;
        lssd_bus *bus;
} fixture;

/* The loop and the configuration of a bus on `ifname`: LSS timeout 20 ms,
 * fixed timing, queue of 8. Change f->config before fixture_bus_new(). */
static inline void fixture_prepare(fixture *f, const char *ifname, bool simulate) {
        memset(f, 0, sizeof(*f));
        ck_assert_int_ge(sd_event_new(&f->event), 0);
        f->args.simulate = simulate;
        f->args.queue_max = 8;
        snprintf(f->config.interface, sizeof(f->config.interface), "%s", ifname);
        f->config.bitrate = 125000;
        f->config.lss_timeout_ms = 20;
        f->config.lss_timing = LSSCONF_LSS_TIMING_FIXED;
}

static inline void fixture_bus_new(fixture *f, const lssd_bus_host_ops *ops) {
        const lssd_bus_host host = {
                .event = f->event,
                .dbus = NULL,
                .args = &f->args,
                .ops = ops,
                .userdata = &f->host,
        };
        ck_assert_int_eq(lssd_bus_new(&host, &f->config, &f->bus), 0);
}

/* fixture_prepare() and the bus. */
static inline void fixture_up(fixture *f, const char *ifname, bool simulate, const lssd_bus_host_ops *ops) {
        fixture_prepare(f, ifname, simulate);
        fixture_bus_new(f, ops);
}

static inline void fixture_down(fixture *f) {
        lssd_bus_free(f->bus);
        sd_event_unref(f->event);
}

static inline uint64_t submit_scan(fixture *f) {
        lssd_job *j = NULL;
        sd_bus_error e = SD_BUS_ERROR_NULL;
        ck_assert_int_eq(lssd_job_new(LSSD_JOB_SCAN, NULL, &j), 0);
        ck_assert_int_eq(lssd_bus_submit(f->bus, j, &e), 0);
        return j->id;
}
