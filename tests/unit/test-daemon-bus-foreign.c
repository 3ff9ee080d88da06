/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* A bus that hears another LSS master, no D-Bus: a bus on the simulated bus
 * of --simulate (slaves of the slave model), its host a fake, sd-event
 * driving it in real time. A request of another master ends the running
 * job, the bus refuses LSS jobs (ForeignMaster) until it heard none for
 * foreign_master_quiet_s, jobs of its own wait for that, and after it the
 * bus works as before: the job runs, slaves set aside get 255 back, the boot
 * pass ends once. */
#include <check.h>
#include <stdlib.h>
#include <string.h>
#include <systemd/sd-event.h>

#include "daemon/lssd_transport_open.h"
#include "sim/membus.h"
#include "simbus/simbus.h"

#include "daemon-bus-fixture.h"

#define N_SLAVES 6

/* The simulated bus of the test: N_SLAVES non-configured slaves, every
 * other one on CANopenNode's LSS slave (a Scan sets those aside with a
 * temporary node-ID; the others stay in configuration state), and the
 * other master `foreign` when its count is set. */
static simbus *sim;
static simbus_foreign foreign;
static unsigned boot_done;
static bool host_started = true;

static int open_sim(void *userdata, const char *ifname, uint32_t bitrate, const lss_transport_hooks *hooks,
                    lss_transport *ret) {
        ck_assert_int_eq(simbus_new(bitrate, &sim), 0);
        for (uint32_t i = 0; i < N_SLAVES; i++) {
                lss_identity id = { .vendor = 0x9A, .product = 3, .revision = 1, .serial = 0x5100 + 0x1111 * i };
                ck_assert_int_eq(simbus_add_slave(sim, &id, LSS_NODE_ID_UNCONFIGURED,
                                                  i % 2 ? SIMBUS_CANOPENNODE : SIMBUS_PLAIN), 0);
        }
        if (foreign.count) {
                snprintf(foreign.ifname, sizeof(foreign.ifname), "%s", ifname);
                simbus_add_foreign(sim, &foreign);
        }
        simbus_transport(sim, ret);
        return 0;
}

static bool host_started_now(void *userdata) {
        return host_started;
}

static void host_boot_done(void *userdata) {
        boot_done++;
}

static const lssd_bus_host_ops host_ops = {
        .next_job_id = fake_host_next_job_id,
        .stopping = fake_host_no,
        .started = host_started_now,
        .status_changed = fake_host_nothing,
        .boot_pass_done = host_boot_done,
        .removed = fake_host_removed,
        .idle = fake_host_idle,
        .open_transport = open_sim,
};

/* Quiet after 1 s; adaptive waits (the slaves answer in 0.5 ms); the pool
 * for blind passes. */
static void up(fixture *f, bool boot) {
        host_started = !boot;
        boot_done = 0;
        fixture_prepare(f, "sim0", true);
        f->config.lss_timing = LSSCONF_LSS_TIMING_ADAPTIVE;
        f->config.foreign_master_quiet_s = 1;
        f->config.unknown = LSSCONF_UNKNOWN_POOL;
        f->config.pool_lo = 71;
        f->config.pool_hi = 90;
        f->config.store = true;
        f->config.auto_assign = boot;
        fixture_bus_new(f, &host_ops);
        lssd_bus_start(f->bus, false);
}

/* Runs the loop for `us`, or (`until_idle`) until the bus is idle, which
 * it must be within `us`. */
static void run_loop(fixture *f, uint64_t us, bool until_idle) {
        uint64_t t0, t;
        ck_assert_int_ge(sd_event_now(f->event, CLOCK_MONOTONIC, &t0), 0);
        do {
                ck_assert_int_ge(sd_event_run(f->event, 10000), 0);
                ck_assert_int_ge(sd_event_now(f->event, CLOCK_MONOTONIC, &t), 0);
                ck_assert_msg(!until_idle || t - t0 < us, "the bus is not idle after %.1f s", (double) us / 1e6);
        } while (until_idle ? !lssd_bus_idle(f->bus) : t - t0 < us);
}

static void run_for(fixture *f, uint64_t us) {
        run_loop(f, us, false);
}

static void run_until_idle(fixture *f, uint64_t max_us) {
        run_loop(f, max_us, true);
}

/* up(), with the other master `spec`, once the first switch to waiting is out */
static void up_idle(fixture *f, simbus_foreign spec) {
        foreign = spec;
        up(f, false);
        run_until_idle(f, 1000000);
}

static lssd_job *auto_assign_job(fixture *f) {
        lssd_job *j = NULL;
        ck_assert_int_eq(lssd_job_new(LSSD_JOB_AUTO_ASSIGN, NULL, &j), 0);
        ck_assert_int_eq(lssd_job_set_plan(j, lssd_bus_config_of(f->bus)), 0);
        return j;
}

static bool refused(fixture *f, char *message, size_t size) {
        sd_bus_error e = SD_BUS_ERROR_NULL;
        int r = lssd_bus_check_available(f->bus, NULL, false, &e);
        if (r < 0) {
                ck_assert_str_eq(e.name, "org.lssd.LSS1.Error.ForeignMaster");
                snprintf(message, size, "%s", e.message);
        }
        sd_bus_error_free(&e);
        return r < 0;
}

static unsigned slaves_at(membus *b, uint8_t lo, uint8_t hi) {
        unsigned n = 0;
        for (size_t i = 0; i < membus_slave_count(b); i++) {
                uint8_t id = membus_slave(b, i)->st.active_node_id;
                n += id >= lo && id <= hi;
        }
        return n;
}

/* One request heard on an idle bus: LSS jobs are refused, naming it, for
 * the quiet; the property says so; then they are taken again. */
START_TEST(refused_during_quiet_then_accepted) {
        fixture f;
        char msg[512];
        lssd_bus_foreign fm;
        sd_bus_error e = SD_BUS_ERROR_NULL;
        lssd_job *reset = NULL;

        /* the other master speaks once after lssd's second request: the
         * switch to waiting of a Reset on the idle bus below */
        up_idle(&f, (simbus_foreign) { .after = 2, .count = 1, .period_ms = 100 });
        ck_assert(!refused(&f, msg, sizeof(msg)));
        lssd_bus_foreign_get(f.bus, &fm);
        ck_assert(!fm.active);
        ck_assert_uint_eq(fm.since_us, 0);

        ck_assert_int_eq(lssd_job_new(LSSD_JOB_RESET, NULL, &reset), 0);
        ck_assert_int_eq(lssd_bus_submit(f.bus, reset, &e), 0);
        for (unsigned i = 0; i < 200 && !refused(&f, msg, sizeof(msg)); i++)
                run_for(&f, 10000);
        ck_assert(refused(&f, msg, sizeof(msg)));
        ck_assert_msg(strstr(msg, "another LSS master is active on sim0: " SIMBUS_FOREIGN_FRAME " at "), "%s", msg);
        ck_assert_msg(strstr(msg, "once it heard no LSS request of another master for 1 s"), "%s", msg);
        lssd_bus_foreign_get(f.bus, &fm);
        ck_assert(fm.active);
        ck_assert_uint_gt(fm.since_us, 0);
        ck_assert_str_eq(fm.frame, SIMBUS_FOREIGN_FRAME);
        ck_assert_uint_eq(fm.count, 1);

        /* a job of its own waits */
        ck_assert_int_eq(lssd_bus_submit(f.bus, auto_assign_job(&f), &e), 0);
        ck_assert_ptr_null(lssd_bus_running_job(f.bus));
        ck_assert_uint_eq(lssd_bus_queue_length(f.bus), 1);
        run_for(&f, 500000);
        ck_assert(refused(&f, msg, sizeof(msg)));
        ck_assert_ptr_null(lssd_bus_running_job(f.bus));

        /* quiet for 1 s: taken again, the job runs */
        run_for(&f, 700000);
        ck_assert(!refused(&f, msg, sizeof(msg)));
        lssd_bus_foreign_get(f.bus, &fm);
        ck_assert(!fm.active);
        ck_assert_str_eq(fm.frame, SIMBUS_FOREIGN_FRAME);
        run_until_idle(&f, 30000000);
        ck_assert_str_eq(lssd_bus_job_env(f.bus)->last_pass.result, "done");
        ck_assert_uint_eq(slaves_at(simbus_bus(sim), 71, 90), N_SLAVES);
        fixture_down(&f);
}
END_TEST

/* A running AutoAssign ends at the request: LastPass says so, what it did
 * stands; the next pass, after the quiet, gives the rest their node-IDs. */
START_TEST(running_job_ends) {
        fixture f;
        char msg[512];

        /* the other master speaks once lssd wrote 300 LSS requests: mid-pass */
        up_idle(&f, (simbus_foreign) { .after = 300, .count = 1, .period_ms = 100 });
        sd_bus_error e = SD_BUS_ERROR_NULL;
        ck_assert_int_eq(lssd_bus_submit(f.bus, auto_assign_job(&f), &e), 0);
        run_until_idle(&f, 30000000);
        const lssd_pass_record *p = &lssd_bus_job_env(f.bus)->last_pass;
        ck_assert_str_eq(p->result, "foreign-master");
        /* A device whose Configure Node-ID had gone out when the request
         * came fails and keeps that node-ID (its outcome says so): it may
         * take it at the switch to waiting lssd sends last, a boot-up later.
         * Before, this test read the slaves at once and wanted the pool's
         * count alone: under load the request fell between Configure and
         * the outcome in about 1 run of 5. */
        run_for(&f, 100000);
        unsigned before = slaves_at(simbus_bus(sim), 71, 90);
        ck_assert_uint_le(p->counts[LSS_OUTCOME_POOL], before);
        ck_assert_uint_le(before, p->counts[LSS_OUTCOME_POOL] + p->counts[LSS_OUTCOME_FAILED]);
        ck_assert_uint_lt(before, N_SLAVES);
        ck_assert(refused(&f, msg, sizeof(msg)));

        run_for(&f, 1100000);
        ck_assert(!refused(&f, msg, sizeof(msg)));
        ck_assert_int_eq(lssd_bus_submit(f.bus, auto_assign_job(&f), &e), 0);
        run_until_idle(&f, 30000000);
        ck_assert_str_eq(p->result, "done");
        ck_assert_uint_eq(p->counts[LSS_OUTCOME_POOL], N_SLAVES - before);
        ck_assert_uint_eq(slaves_at(simbus_bus(sim), 71, 90), N_SLAVES);
        fixture_down(&f);
}
END_TEST

/* A Scan broken off with slaves set aside: a GiveBack after the quiet gives
 * them 255 back. */
START_TEST(set_aside_given_back) {
        fixture f;
        char msg[512];

        up_idle(&f, (simbus_foreign) { .after = 200, .count = 1, .period_ms = 100 });
        submit_scan(&f);
        /* the Scan ends at the request; some slaves are at their temporary node-ID */
        for (unsigned i = 0; i < 100000 && !refused(&f, msg, sizeof(msg)); i++)
                ck_assert_int_ge(sd_event_run(f.event, 10000), 0);
        run_for(&f, 300000);
        ck_assert_ptr_null(lssd_bus_running_job(f.bus));
        unsigned aside = slaves_at(simbus_bus(sim), 100, 127);
        ck_assert_uint_gt(aside, 0);
        ck_assert_uint_eq(lssd_bus_queue_length(f.bus), 1); /* the GiveBack, waiting */

        run_until_idle(&f, 30000000);
        ck_assert_uint_eq(slaves_at(simbus_bus(sim), 1, 127), 0);
        ck_assert(!refused(&f, msg, sizeof(msg)));
        fixture_down(&f);
}
END_TEST

/* The boot pass, broken off by a master that keeps talking for a while,
 * waits for its quiet instead of failing and then ends, once. */
START_TEST(boot_pass_waits) {
        fixture f;
        uint64_t t0, t;

        foreign = (simbus_foreign) { .after = 0, .count = 5, .period_ms = 200 };
        up(&f, true);
        ck_assert_int_ge(sd_event_now(f.event, CLOCK_MONOTONIC, &t0), 0);
        run_until_idle(&f, 60000000);
        ck_assert_int_ge(sd_event_now(f.event, CLOCK_MONOTONIC, &t), 0);
        ck_assert_uint_eq(boot_done, 1);
        ck_assert_str_eq(lssd_bus_job_env(f.bus)->last_pass.result, "done");
        ck_assert(lssd_bus_job_env(f.bus)->last_pass.boot);
        ck_assert_uint_eq(slaves_at(simbus_bus(sim), 71, 90), N_SLAVES);
        /* not before the last request (0.8 s) and the quiet after it */
        ck_assert_uint_ge(t - t0, 1800000);
        lssd_bus_foreign f2;
        lssd_bus_foreign_get(f.bus, &f2);
        ck_assert(!f2.active);
        ck_assert_uint_eq(f2.count, 5);
        fixture_down(&f);
}
END_TEST

static void add_tests(TCase *tc) {
        tcase_add_test(tc, refused_during_quiet_then_accepted);
        tcase_add_test(tc, running_job_ends);
        tcase_add_test(tc, set_aside_given_back);
        tcase_add_test(tc, boot_pass_waits);
}

int main(void) {
        return check_main("daemon-bus-foreign", add_tests);
}
