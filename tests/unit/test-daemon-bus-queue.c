/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* A bus's job queue at work, with no D-Bus and no CAN: a bus on the
 * in-memory bus of --simulate (no slaves), its host a fake, sd-event
 * driving it. Jobs run in the order queued, one at a time, Cancel ends
 * the running one and the next starts, stopping drops what is queued. */
#include <check.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <systemd/sd-event.h>


#include "daemon/lssd_transport_open.h"

#include "daemon-bus-fixture.h"

/* the simulated bus of --simulate, no slaves */
static int open_simulated(void *userdata, const char *ifname, uint32_t bitrate, const lss_transport_hooks *hooks,
                          lss_transport *ret) {
        const lssd_args args = { .simulate = true };
        return lssd_transport_open(&args, ifname, bitrate, hooks, ret);
}

static const lssd_bus_host_ops host_ops = FAKE_HOST_OPS(open_simulated);

static void up(fixture *f) {
        fixture_up(f, "sim0", true, &host_ops);
}

/* Runs the loop until the bus is idle; `seen` gets the ids of the jobs in
 * the order they ran (each once), `most` the most jobs ever running or
 * queued behind the running one. */
static size_t run_until_idle(fixture *f, uint64_t *seen, size_t max) {
        size_t n = 0;
        for (unsigned i = 0; i < 100000 && !lssd_bus_idle(f->bus); i++) {
                const lssd_job *j = lssd_bus_running_job(f->bus);
                if (j && (n == 0 || seen[n - 1] != j->id) && n < max)
                        seen[n++] = j->id;
                ck_assert_int_ge(sd_event_run(f->event, 100000), 0);
        }
        ck_assert(lssd_bus_idle(f->bus));
        return n;
}

START_TEST(order_one_at_a_time) {
        fixture f;
        uint64_t seen[16], ids[3];
        up(&f);

        /* the first frame after start is switch-global waiting (a job of
         * its own, over as soon as it is sent) */
        lssd_bus_start(f.bus, false);
        run_until_idle(&f, seen, 16);
        ck_assert_uint_eq(f.host.next_id, 1);

        for (unsigned i = 0; i < 3; i++)
                ids[i] = submit_scan(&f);
        /* the first runs at once, the others wait behind it */
        ck_assert_ptr_nonnull(lssd_bus_running_job(f.bus));
        ck_assert_uint_eq(lssd_bus_running_job(f.bus)->id, ids[0]);
        ck_assert_uint_eq(lssd_bus_queue_length(f.bus), 2);
        ck_assert_str_eq(lssd_bus_state(f.bus), "busy");
        ck_assert_str_eq(lssd_bus_job_name(f.bus), "Scan");

        size_t n = run_until_idle(&f, seen, 16);
        ck_assert_uint_eq(n, 3);
        for (unsigned i = 0; i < 3; i++)
                ck_assert_uint_eq(seen[i], ids[i]);
        ck_assert_uint_eq(lssd_bus_queue_length(f.bus), 0);
        ck_assert_str_eq(lssd_bus_state(f.bus), "idle");
        ck_assert_uint_gt(f.host.idle, 0);
        fixture_down(&f);
}
END_TEST

START_TEST(queue_bound) {
        fixture f;
        sd_bus_error e = SD_BUS_ERROR_NULL;
        uint64_t seen[16];
        up(&f);
        lssd_bus_start(f.bus, false);
        run_until_idle(&f, seen, 16);

        /* one running, queue_max waiting, the next refused */
        for (unsigned i = 0; i < 1 + f.args.queue_max; i++)
                submit_scan(&f);
        ck_assert_uint_eq(lssd_bus_queue_length(f.bus), f.args.queue_max);
        lssd_job *j = NULL;
        ck_assert_int_eq(lssd_job_new(LSSD_JOB_SCAN, NULL, &j), 0);
        ck_assert_int_lt(lssd_bus_submit(f.bus, j, &e), 0);
        ck_assert_str_eq(e.name, "org.lssd.LSS1.Error.LimitsExceeded");
        sd_bus_error_free(&e);
        lssd_job_free(j);
        fixture_down(&f);
}
END_TEST

START_TEST(cancel_running_then_next) {
        fixture f;
        sd_bus_error e = SD_BUS_ERROR_NULL;
        uint64_t seen[16], a, b;
        up(&f);
        lssd_bus_start(f.bus, false);
        run_until_idle(&f, seen, 16);

        a = submit_scan(&f);
        b = submit_scan(&f);
        ck_assert_uint_eq(lssd_bus_running_job(f.bus)->id, a);
        /* Cancel ends the running job; the queued one starts */
        ck_assert_int_eq(lssd_bus_cancel(f.bus, ":1.5", &e), 0);
        ck_assert_ptr_nonnull(lssd_bus_running_job(f.bus));
        ck_assert_uint_eq(lssd_bus_running_job(f.bus)->id, b);
        ck_assert_uint_eq(lssd_bus_queue_length(f.bus), 0);
        size_t n = run_until_idle(&f, seen, 16);
        ck_assert_uint_eq(n, 1);
        ck_assert_uint_eq(seen[0], b);
        fixture_down(&f);
}
END_TEST

START_TEST(stop_drops_queue) {
        fixture f;
        uint64_t seen[16], a;
        up(&f);
        lssd_bus_start(f.bus, false);
        run_until_idle(&f, seen, 16);

        a = submit_scan(&f);
        submit_scan(&f);
        submit_scan(&f);
        ck_assert_uint_eq(lssd_bus_queue_length(f.bus), 2);
        /* stopping: the queued jobs go, the running one is cancelled, and
         * the last thing on the bus is switch-global waiting */
        lssd_bus_stop(f.bus, "test");
        ck_assert_uint_eq(lssd_bus_queue_length(f.bus), 0);
        /* the switch to waiting got the next id; a scan takes at least one
         * LSS timeout, so one that ran would be seen here */
        ck_assert_uint_eq(f.host.next_id, a + 3);
        size_t n = run_until_idle(&f, seen, 16);
        for (size_t i = 0; i < n; i++)
                ck_assert(seen[i] != a && seen[i] != a + 1 && seen[i] != a + 2);
        fixture_down(&f);
}
END_TEST

static void add_tests(TCase *tc) {
        tcase_add_test(tc, order_one_at_a_time);
        tcase_add_test(tc, queue_bound);
        tcase_add_test(tc, cancel_running_then_next);
        tcase_add_test(tc, stop_drops_queue);
}

int main(void) {
        return check_main("daemon-bus-queue", add_tests);
}
