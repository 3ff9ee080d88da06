/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* SetBitrate's host retune does not stop the event loop: a bus on the
 * simulated bus of --simulate (two slaves) behind a fake whose retune
 * answers in steps, each RETUNE_STEP_US after the last (a timerfd is its
 * "netlink socket"), as rtnetlink's down, bit timing, up would. Meanwhile
 * another source of the loop (what another bus or a D-Bus call would be)
 * keeps being served; the engine hears DONE and the job ends done. A
 * retune that fails ends with its errno in the job. */
#include <check.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/timerfd.h>
#include <systemd/sd-event.h>
#include <unistd.h>

#include "daemon/lssd_bus.h"
#include "simbus/simbus.h"
#include "util/time_util.h"

#include "daemon-bus-fixture.h"

#define RETUNE_STEP_US 30000u
#define RETUNE_STEPS 3u

typedef struct fake_tp {
        lss_transport sim;
        int tfd;                /* readable when the "kernel" answers */
        unsigned steps_left;
        int fail_with;          /* errno of the last answer; 0: done */
        unsigned n_started;
        uint64_t started_at, ended_at;
} fake_tp;

static fake_tp T;

static uint64_t mono(void) {
        return clock_now_us(CLOCK_MONOTONIC);
}

static int tp_send(void *impl, const lss_frame *f) {
        return lss_transport_send(&T.sim, f);
}

static int tp_recv(void *impl, lss_frame *f, uint64_t *rx_us) {
        return lss_transport_recv(&T.sim, f, rx_us);
}

static uint64_t tp_now(void *impl) {
        return lss_transport_now(&T.sim);
}

static uint64_t tp_next_event(void *impl) {
        return lss_transport_next_event(&T.sim);
}

static void arm(lss_retune_wait *w) {
        struct itimerspec its = { .it_value = us_to_timespec(RETUNE_STEP_US) };
        ck_assert_int_eq(timerfd_settime(T.tfd, 0, &its, NULL), 0);
        w->fd = T.tfd;
        w->deadline = mono() + 1000000u;
}

static int tp_retune_start(void *impl, uint32_t bitrate, lss_retune_wait *w) {
        T.n_started++;
        T.started_at = mono();
        T.steps_left = RETUNE_STEPS;
        arm(w);
        return 0;
}

static int tp_retune_step(void *impl, lss_retune_wait *w) {
        uint64_t expirations;
        if (read(T.tfd, &expirations, sizeof(expirations)) < 0) {
                /* not answered yet */
                w->fd = T.tfd;
                w->deadline = mono() + 1000000u;
                return 0;
        }
        if (--T.steps_left > 0) {
                arm(w);
                return 0;
        }
        T.ended_at = mono();
        if (T.fail_with)
                return -T.fail_with;
        return lss_transport_retune_start(&T.sim, 250000, w); /* the slaves' rate: the simulated controller follows */
}

static void tp_close(void *impl) {
        lss_transport_close(&T.sim);
        close(T.tfd);
}

static const lss_transport_ops tp_ops = {
        .kind = "retune in steps",
        .send = tp_send,
        .recv = tp_recv,
        .now = tp_now,
        .next_event = tp_next_event,
        .retune_start = tp_retune_start,
        .retune_step = tp_retune_step,
        .close = tp_close,
};

static int host_open_transport(void *userdata, const char *ifname, uint32_t bitrate, const lss_transport_hooks *hooks,
                               lss_transport *ret) {
        simbus *s;
        ck_assert_int_eq(simbus_new(bitrate, &s), 0);
        for (uint32_t i = 1; i <= 2; i++) {
                lss_identity id = { .vendor = 0x1234, .product = 7, .revision = 1, .serial = i };
                ck_assert_int_eq(simbus_add_slave(s, &id, (uint8_t) (10 + i), false), 0);
        }
        simbus_transport(s, &T.sim);
        T.tfd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
        ck_assert_int_ge(T.tfd, 0);
        *ret = (lss_transport) { .ops = &tp_ops, .impl = &T };
        return 0;
}

static const lssd_bus_host_ops host_ops = FAKE_HOST_OPS(host_open_transport);

/* another source of the same loop, every millisecond */
typedef struct other {
        sd_event_source *source;
        unsigned during_retune;
} other;

static int on_other(sd_event_source *s, uint64_t usec, void *userdata) {
        other *o = userdata;
        if (T.n_started && !T.ended_at)
                o->during_retune++;
        ck_assert_int_ge(sd_event_source_set_time_relative(s, 1000), 0);
        return 0;
}

/* SetBitrate to 250 kbit/s with a 100 ms switch delay; returns the job's result. */
static const char *set_bitrate(int fail_with, int *retune_error) {
        fixture f;
        other o = {};
        lssd_job *j = NULL;
        sd_bus_error e = SD_BUS_ERROR_NULL;
        static char result[32];

        memset(&T, 0, sizeof(T));
        T.fail_with = fail_with;
        fixture_prepare(&f, "can0", true);
        f.config.bitrate_change = true;
        fixture_bus_new(&f, &host_ops);
        lssd_bus_start(f.bus, false);

        ck_assert_int_eq(lssd_job_new(LSSD_JOB_SET_BITRATE, NULL, &j), 0);
        j->bitrate = 250000;
        j->switch_delay_ms = 100;
        ck_assert_int_ge(lssd_job_add_pair(j, 0x1234, 7), 0);
        ck_assert_int_eq(lssd_bus_submit(f.bus, j, &e), 0);
        ck_assert_int_ge(sd_event_add_time_relative(f.event, &o.source, CLOCK_MONOTONIC, 1000, 1, on_other, &o), 0);
        ck_assert_int_ge(sd_event_source_set_enabled(o.source, SD_EVENT_ON), 0);

        /* the job ends when the bus is idle; watch its result through the retune error */
        const lssd_job *running = NULL;
        for (unsigned i = 0; i < 100000 && !lssd_bus_idle(f.bus); i++) {
                const lssd_job *now = lssd_bus_running_job(f.bus);
                if (now && now->type == LSSD_JOB_SET_BITRATE) {
                        running = now;
                        *retune_error = now->retune_error;
                        snprintf(result, sizeof(result), "%s", now->result ? now->result : "");
                }
                ck_assert_int_ge(sd_event_run(f.event, 100000), 0);
        }
        ck_assert(lssd_bus_idle(f.bus));
        ck_assert_ptr_nonnull(running);
        ck_assert_uint_eq(T.n_started, 1);
        ck_assert_uint_gt(T.ended_at, T.started_at);
        /* three answers 30 ms apart: the loop went on meanwhile */
        ck_assert_uint_ge(T.ended_at - T.started_at, RETUNE_STEPS * RETUNE_STEP_US);
        ck_assert_uint_ge(o.during_retune, 20);
        const lss_master *m = lssd_bus_job_env(f.bus)->engine;
        ck_assert_int_eq(lss_master_retune_state(m), fail_with ? LSS_RETUNE_FAILED : LSS_RETUNE_DONE);
        snprintf(result, sizeof(result), "%s", lss_status_name(lss_master_result(m)->status));
        sd_event_source_disable_unref(o.source);
        fixture_down(&f);
        return result;
}

START_TEST(retune_in_steps_loop_goes_on) {
        int err = -1;
        ck_assert_str_eq(set_bitrate(0, &err), "ok");
        ck_assert_int_eq(err, 0);
}
END_TEST

START_TEST(retune_failure_has_its_errno) {
        int err = 0;
        set_bitrate(EPERM, &err);
        ck_assert_int_eq(err, EPERM);
}
END_TEST

static void add(TCase *tc) {
        tcase_add_test(tc, retune_in_steps_loop_goes_on);
        tcase_add_test(tc, retune_failure_has_its_errno);
}

int main(void) {
        return check_main("daemon-bus-retune", add);
}
