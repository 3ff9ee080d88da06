/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* A bus whose transport's tx queue is full, with no D-Bus and no CAN: a fake
 * transport refuses writes (-EAGAIN) for a while or for good, sd-event drives
 * the bus. The refused frame goes out later, in order, once; the loop keeps
 * serving other sources meanwhile; a queue that stays full ends the running
 * operation with "transmit queue stayed full". */
#include <check.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <systemd/sd-event.h>
#include <time.h>

#include "daemon/lssd_bus.h"
#include "util/time_util.h"

#include "daemon-bus-fixture.h"

#define MAX_FRAMES 4096

typedef struct fake_tp {
        uint64_t refuse_until;  /* CLOCK_MONOTONIC µs; UINT64_MAX: for good */
        unsigned attempts;
        lss_frame written[MAX_FRAMES];
        uint64_t written_at[MAX_FRAMES];
        size_t n_written;
} fake_tp;

static fake_tp T;

static uint64_t mono(void) {
        return clock_now_us(CLOCK_MONOTONIC);
}

static int tp_send(void *impl, const lss_frame *f) {
        fake_tp *t = impl;
        t->attempts++;
        if (mono() < t->refuse_until)
                return -EAGAIN;
        ck_assert_uint_lt(t->n_written, MAX_FRAMES);
        t->written_at[t->n_written] = mono();
        t->written[t->n_written++] = *f;
        return 0;
}

static int tp_recv(void *impl, lss_frame *f, uint64_t *rx_us) {
        return 0; /* nobody answers */
}

static uint64_t tp_now(void *impl) {
        return mono();
}

static const lss_transport_ops tp_ops = {
        .send = tp_send,
        .recv = tp_recv,
        .now = tp_now,
};

static int host_open_transport(void *userdata, const char *ifname, uint32_t bitrate, const lss_transport_hooks *hooks,
                               lss_transport *ret) {
        *ret = (lss_transport) { .ops = &tp_ops, .impl = &T };
        return 0;
}

static const lssd_bus_host_ops host_ops = FAKE_HOST_OPS(host_open_transport);

static void up(fixture *f) {
        memset(&T, 0, sizeof(T));
        fixture_up(f, "can0", false, &host_ops);
}

static void run_until_idle(fixture *f) {
        for (unsigned i = 0; i < 100000 && !lssd_bus_idle(f->bus); i++)
                ck_assert_int_ge(sd_event_run(f->event, 100000), 0);
        ck_assert(lssd_bus_idle(f->bus));
}

/* another source of the same loop: what a D-Bus call would be */
typedef struct other {
        uint64_t fired_at;
        size_t written_then;
} other;

static int on_other(sd_event_source *s, uint64_t usec, void *userdata) {
        other *o = userdata;
        o->fired_at = mono();
        o->written_then = T.n_written;
        return 0;
}

/* Start (switch-global waiting) and a Scan nobody answers, the queue full
 * for the first `full_us`; `o` sees the loop 5 ms in. No bound on time:
 * under valgrind everything is many times slower. */
static void start_and_scan(uint64_t full_us, other *o) {
        fixture f;
        sd_event_source *s = NULL;
        up(&f);

        T.refuse_until = full_us ? mono() + full_us : 0;
        lssd_bus_start(f.bus, false);
        /* the send returned at once: one write, no retries inside the call
         * (the blocking send tried again and again until its deadline) */
        ck_assert_uint_eq(T.attempts, 1);
        if (full_us) {
                ck_assert_uint_eq(T.n_written, 0);
                ck_assert(!lssd_bus_idle(f.bus));
        }
        /* queued meanwhile: waits behind it */
        submit_scan(&f);
        if (full_us)
                ck_assert_uint_eq(T.n_written, 0);
        ck_assert_int_ge(sd_event_add_time_relative(f.event, &s, CLOCK_MONOTONIC, 5000, 1, on_other, o), 0);
        run_until_idle(&f);
        const lss_result *r = lss_master_result(lssd_bus_job_env(f.bus)->engine);
        ck_assert_int_ne(r->status, LSS_E_BUS_DOWN);
        sd_event_source_unref(s);
        fixture_down(&f);
}

START_TEST(refused_frame_goes_out_later_in_order) {
        static lss_frame plain[MAX_FRAMES];
        other o = {};

        start_and_scan(0, &o);
        size_t n_plain = T.n_written;
        memcpy(plain, T.written, n_plain * sizeof(plain[0]));
        ck_assert_uint_ge(n_plain, 2);
        ck_assert_uint_eq(T.attempts, n_plain);

        /* the queue full for 60 ms from the first frame on (within the
         * 1 s a frame may wait; the other source fires 5 ms in) */
        start_and_scan(60000, &o);
        /* the loop served the other source while the bus waited: nothing
         * was written yet when it fired */
        ck_assert_uint_gt(o.fired_at, 0);
        ck_assert_uint_eq(o.written_then, 0);
        /* tried again from a timer, not in a busy loop */
        ck_assert_uint_gt(T.attempts, n_plain + 3);
        ck_assert_uint_lt(T.attempts, n_plain + 1000);
        ck_assert_uint_ge(T.written_at[0], T.refuse_until);
        /* the same frames in the same order, each once: nothing lost, reordered or doubled */
        ck_assert_uint_eq(T.n_written, n_plain);
        for (size_t i = 0; i < n_plain; i++) {
                ck_assert_uint_eq(T.written[i].id, plain[i].id);
                ck_assert_mem_eq(T.written[i].data, plain[i].data, 8);
        }
}
END_TEST

/* Another writer that keeps the queue full (kvaser-enobufs: cangen beside
 * lssd) leaves lssd without a slot for longer than 100 ms now and then under
 * load: 300 ms of refusals do not end the operation. */
START_TEST(contended_queue_is_waited_for) {
        other o = {};
        start_and_scan(300000, &o);
        ck_assert_uint_ge(T.written_at[0], T.refuse_until);
        ck_assert_uint_ge(T.n_written, 2);
}
END_TEST

START_TEST(full_queue_ends_the_operation) {
        fixture f;
        up(&f);
        lssd_bus_start(f.bus, false);
        run_until_idle(&f);
        ck_assert_uint_eq(T.n_written, 1);

        T.refuse_until = UINT64_MAX;
        unsigned before = T.attempts;
        uint64_t t0 = mono();
        submit_scan(&f);
        run_until_idle(&f);
        uint64_t took = mono() - t0;
        const lss_result *r = lss_master_result(lssd_bus_job_env(f.bus)->engine);
        ck_assert_int_eq(r->status, LSS_E_BUS_DOWN);
        ck_assert_ptr_nonnull(strstr(r->message, "transmit queue stayed full"));
        ck_assert_uint_eq(T.n_written, 1);
        /* 1 s of tries (LSSD_TX_TIMEOUT_MS) from a 1 ms timer: the deadline,
         * not a hang; a few tries at least (fewer under valgrind), never a
         * busy loop */
        ck_assert_uint_ge(took, 1000000);
        ck_assert_uint_gt(T.attempts - before, 3);
        ck_assert_uint_lt(T.attempts - before, 10000);

        /* room again: the next job's frames go out */
        T.refuse_until = 0;
        submit_scan(&f);
        run_until_idle(&f);
        ck_assert_uint_gt(T.n_written, 1);
        fixture_down(&f);
}
END_TEST

static void add_tests(TCase *tc) {
        tcase_add_test(tc, refused_frame_goes_out_later_in_order);
        tcase_add_test(tc, contended_queue_is_waited_for);
        tcase_add_test(tc, full_queue_ends_the_operation);
}

int main(void) {
        return check_main("daemon-bus-tx", add_tests);
}
