/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Another LSS master on the in-memory bus: a request (0x7E5) of another
 * sender, injected into a Scan, an AutoAssign, an assignment, a bit-rate
 * change and a raw service, ends the operation at once with
 * LSS_E_FOREIGN_MASTER: after it the master sends no Configure Node-ID,
 * Configure Bit Timing, Activate or Store, a procedure one switch to waiting
 * and nothing else; what a pass did before stands, slaves set aside are
 * given back later (lss_master_give_back). A bit-rate change past its
 * activation keeps to its window (lss_master.h). */
#include <check.h>
#include <stdlib.h>
#include <string.h>

#include "autoassign-util.h"

/* The other master's request: Inquire Vendor-ID, its reserved bytes telling
 * it from the engine's own (slaves in configuration answer it). */
static const lss_frame foreign = { .id = 0x7E5, .len = 8, .data = { 0x5A, 0xA5, 0xA5, 0xA5, 0xA5, 0xA5, 0xA5, 0xA5 } };

static bool is_foreign(const lss_frame *f) {
        return f->id == foreign.id && memcmp(f->data, foreign.data, 8) == 0;
}

/* When the injector puts the other master's request on the bus. */
typedef struct injector {
        wire_trace *tr;
        bool (*when)(struct injector *in, membus *bus, lss_master *m);
        unsigned arg;           /* for `when` */
        found_log *found;
        bool done;
        /* bit-rate changes: the test's host retunes when asked */
        unsigned retunes;
} injector;

static void hook(void *ud, membus *bus, lss_master *m) {
        injector *in = ud;
        uint32_t rate;
        if (lss_master_retune_wanted(m, &rate, NULL)) {
                in->retunes++;
                membus_set_bitrate(bus, rate);
                lss_master_retune_done(m, LSS_RETUNE_DONE, membus_now(bus));
        }
        if (!in->done && in->when(in, bus, m)) {
                membus_inject(bus, &foreign, membus_now(bus));
                in->done = true;
        }
}

/* The last frame on the wire is the master's request with this cs (and,
 * `arg` nonzero, a node-ID below it: not an enumeration's temporary one). */
static bool last_request_is(const injector *in, uint8_t cs, unsigned below) {
        if (in->tr->n == 0)
                return false;
        const lss_frame *f = &in->tr->f[in->tr->n - 1];
        return lss_is_request(f) && f->data[0] == cs && (below == 0 || f->data[1] < below);
}

/* Index of the other master's request in the trace (it must be there). */
static size_t foreign_at(const wire_trace *tr) {
        for (size_t i = 0; i < tr->n; i++)
                if (is_foreign(&tr->f[i]))
                        return i;
        ck_abort_msg("the other master's request never went on the wire");
        return 0;
}

/* After the other master's request, the master sent at most one frame, a
 * switch to waiting (none with `none`), within `within_us`; nothing else:
 * no Configure Node-ID, Configure Bit Timing, Activate or Store. */
static void expect_quiet_after(const wire_trace *tr, bool none, uint64_t within_us) {
        size_t k = foreign_at(tr);
        unsigned switches = 0;
        for (size_t i = k + 1; i < tr->n; i++) {
                const lss_frame *f = &tr->f[i];
                if (!lss_is_request(f) || is_foreign(f))
                        continue;
                char buf[32];
                ck_assert_msg(f->data[0] == LSS_CS_SWITCH_GLOBAL && f->data[1] == LSS_MODE_WAITING,
                              "the master sent %s %.1f ms after the other master's request",
                              lss_frame_format(f, buf, sizeof(buf)), (double) (tr->t[i] - tr->t[k]) / 1000.0);
                ck_assert_uint_le(tr->t[i] - tr->t[k], within_us);
                switches++;
        }
        ck_assert_uint_le(switches, none ? 0 : 1);
}

static bool after_found(injector *in, membus *bus, lss_master *m) {
        return in->found->n >= in->arg;
}

/* An enumeration of 8 slaves with `faults` (NULL: the defaults), the other
 * master's request once 3 were found: it ends ForeignMaster. */
static lss_master *enumerate_interrupted(membus **b, wire_trace *tr, found_log *fl, const lss_slave_faults *faults) {
        *b = bus_random(8, 11, 0, 0, faults);
        lss_master *m = master_default();
        injector in = { .tr = tr, .when = after_found, .arg = 3, .found = fl };

        membus_set_trace(*b, wire_trace_cb, tr);
        found_log_start(fl, m, *b);
        ck_assert_int_eq(lss_master_enumerate(m, NULL, membus_now(*b)), 0);
        const lss_result *r = lss_drive(m, *b, 600 * SECOND, hook, &in);
        ck_assert_msg(r->status == LSS_E_FOREIGN_MASTER, "%s: %s", lss_status_name(r->status), r->message);
        return m;
}

/* A Scan of CiA 305 slaves, which it keeps in configuration state, ends at
 * the request with every slave back in waiting (its switch to waiting goes
 * out behind the kept slaves' answers to the other master's inquiry) and
 * nothing left aside. */
START_TEST(enumeration_keeps_nobody_in_configuration) {
        wire_trace *tr = calloc(1, sizeof(*tr));
        found_log fl;
        membus *b;
        lss_master *m = enumerate_interrupted(&b, tr, &fl, NULL);
        expect_quiet_after(tr, false, 10000);
        lss_drive_idle(b, 20000);
        ck_assert(all_waiting(b));
        size_t n;
        lss_master_left_aside(m, &n);
        ck_assert_uint_eq(n, 0);
        for (size_t i = 0; i < 8; i++)
                ck_assert_uint_eq(membus_slave(b, i)->st.pending_node_id, LSS_NODE_ID_UNCONFIGURED);
        lss_master_set_found(m, NULL, NULL);
        lss_master_free(m);
        membus_free(b);
        free(tr);
}
END_TEST

/* A Scan (enumeration) ends at the request; the slaves it had set aside
 * (CANopenNode's, which answer Fastscan in configuration state) keep their
 * temporary node-ID until lss_master_give_back() gives them 255 back. */
START_TEST(enumeration_ends_at_once) {
        wire_trace *tr = calloc(1, sizeof(*tr));
        found_log fl;
        lss_slave_faults co;
        lss_slave_faults_canopennode(&co);
        membus *b;
        lss_master *m = enumerate_interrupted(&b, tr, &fl, &co);
        const lss_result *r = lss_master_result(m);
        ck_assert_msg(strstr(r->message, "7E5#5AA5A5A5A5A5A5A5"), "the message names the frame: %s", r->message);
        /* at once: the switch to waiting goes out behind it, nothing else */
        expect_quiet_after(tr, false, 2000);
        ck_assert(all_waiting(b));
        ck_assert_uint_eq(lss_master_get_stats(m)->foreign_requests, 1);
        lss_master_set_found(m, NULL, NULL);

        /* the three found were set aside with a temporary node-ID, which they keep */
        size_t n;
        const lss_device *left = lss_master_left_aside(m, &n);
        ck_assert_uint_eq(n, 3);
        lss_device aside[3];
        memcpy(aside, left, sizeof(aside));
        for (size_t i = 0; i < n; i++) {
                lss_slave *s = membus_find(b, &aside[i].id);
                ck_assert_ptr_nonnull(s);
                ck_assert(lss_node_id_valid(aside[i].aside_node_id));
                ck_assert_uint_eq(s->st.active_node_id, aside[i].aside_node_id);
        }

        /* once the other master is quiet: 255 back, verified */
        ck_assert_int_eq(lss_master_give_back(m, aside, n, membus_now(b)), 0);
        r = run(m, b);
        ck_assert_msg(r->status == LSS_OK, "%s: %s", lss_status_name(r->status), r->message);
        ck_assert_uint_eq(r->n_devices, 3);
        for (size_t i = 0; i < membus_slave_count(b); i++)
                ck_assert_uint_eq(membus_slave(b, i)->st.active_node_id, LSS_NODE_ID_UNCONFIGURED);
        ck_assert(all_waiting(b));
        /* a Scan now finds all eight */
        ck_assert_int_eq(lss_master_enumerate(m, NULL, membus_now(b)), 0);
        r = run(m, b);
        ck_assert_int_eq(r->status, LSS_OK);
        ck_assert_uint_eq(r->n_devices, 8);
        lss_master_free(m);
        membus_free(b);
        free(tr);
}
END_TEST

static bool after_outcomes(injector *in, membus *bus, lss_master *m) {
        size_t n;
        (void) lss_master_outcomes(m, &n);
        return n >= in->arg;
}

static bool at_pool_configure(injector *in, membus *bus, lss_master *m) {
        size_t n;
        (void) lss_master_outcomes(m, &n);
        return n >= in->arg && last_request_is(in, LSS_CS_CONFIGURE_NODE_ID, 100);
}

static const lss_autoassign_plan blind_pool = {
        .unknown = LSS_UNKNOWN_POOL, .pool_lo = 71, .pool_hi = 90, .store = true,
};

/* A blind pool pass that the other master's request, injected `when`,
 * breaks off: it ends at once, and the bus is quiet after. */
static void pass_broken_off(membus *b, lss_master *m, wire_trace *tr, bool (*when)(injector *, membus *, lss_master *),
                            unsigned arg) {
        injector in = { .tr = tr, .when = when, .arg = arg };
        membus_set_trace(b, wire_trace_cb, tr);
        ck_assert_int_eq(lss_master_autoassign(m, &blind_pool, membus_now(b)), 0);
        const lss_result *r = lss_drive(m, b, 600 * SECOND, hook, &in);
        lss_drive_idle(b, 100000);
        ck_assert_msg(r->status == LSS_E_FOREIGN_MASTER, "%s: %s", lss_status_name(r->status), r->message);
        expect_quiet_after(tr, false, 2000);
        ck_assert(all_waiting(b));
}

/* Every slave has a pool node-ID of its own, in effect and stored. */
static void expect_all_pooled(membus *b) {
        bool seen[128] = { false };
        for (size_t i = 0; i < membus_slave_count(b); i++) {
                const lss_slave *s = membus_slave(b, i);
                ck_assert_msg(s->st.active_node_id >= 71 && s->st.active_node_id <= 90, "slave %zu at node-ID %u", i,
                              s->st.active_node_id);
                ck_assert_uint_eq(s->st.stored_node_id, s->st.active_node_id);
                ck_assert(!seen[s->st.active_node_id]);
                seen[s->st.active_node_id] = true;
        }
}

/* A blind AutoAssign of eight broken off after three: those keep their
 * outcome, nothing is configured or stored after the request, and the next
 * pass on a quiet bus gives the other five theirs. */
START_TEST(autoassign_keeps_what_it_did) {
        wire_trace *tr = calloc(1, sizeof(*tr));
        membus *b = bus_random(8, 12, 0, 0, NULL);
        lss_master *m = master_default();

        pass_broken_off(b, m, tr, after_outcomes, 3);
        size_t n;
        const lss_outcome *o = lss_master_outcomes(m, &n);
        ck_assert_uint_ge(n, 3);
        unsigned pooled = 0;
        for (size_t i = 0; i < n; i++)
                if (o[i].kind == LSS_OUTCOME_POOL) {
                        const lss_slave *s = membus_find(b, &o[i].id);
                        ck_assert_uint_eq(s->st.active_node_id, o[i].new_node_id);
                        ck_assert_uint_eq(s->st.stored_node_id, o[i].new_node_id);
                        pooled++;
                }
        ck_assert_uint_ge(pooled, 3);
        ck_assert_uint_lt(pooled, 8);

        /* quiet again: the next pass assigns the rest */
        const lss_result *r = run_pass(m, b, &blind_pool);
        ck_assert_msg(r->status == LSS_OK, "%s: %s", lss_status_name(r->status), r->message);
        expect_all_pooled(b);
        ck_assert(all_waiting(b));
        pass_free(m, b);
        free(tr);
}
END_TEST

/* The request comes right after a Configure Node-ID: that device's outcome
 * says it may hold the node-ID (lssd then gives it to nobody else). */
START_TEST(autoassign_broken_off_after_configure) {
        wire_trace *tr = calloc(1, sizeof(*tr));
        /* answers after the other master's request is on the wire: it comes first */
        lss_slave_faults slow = faults_latency(1500, 0);
        membus *b = bus_random(6, 13, 0, 0, &slow);
        lss_master *m = master_default();

        pass_broken_off(b, m, tr, at_pool_configure, 2);
        size_t n;
        const lss_outcome *o = lss_master_outcomes(m, &n);
        const lss_outcome *held = NULL;
        for (size_t i = 0; i < n; i++)
                if (o[i].kind == LSS_OUTCOME_FAILED)
                        held = &o[i];
        ck_assert_ptr_nonnull(held);
        ck_assert_int_eq(held->status, LSS_E_FOREIGN_MASTER);
        ck_assert(lss_node_id_valid(held->kept_node_id));
        ck_assert_msg(strstr(held->message, "which is kept for it"), "%s", held->message);
        /* it took the node-ID when it went back to waiting (not stored) */
        const lss_slave *s = membus_find(b, &held->id);
        ck_assert_uint_eq(s->st.active_node_id, held->kept_node_id);
        ck_assert_uint_eq(s->st.stored_node_id, LSS_NODE_ID_UNCONFIGURED);
        pass_free(m, b);
        free(tr);
}
END_TEST

static bool at_request(injector *in, membus *bus, lss_master *m) {
        return last_request_is(in, (uint8_t) in->arg, 0);
}

/* An assignment broken off after its Configure Node-ID: no Store, may_hold. */
START_TEST(assign_may_hold) {
        wire_trace *tr = calloc(1, sizeof(*tr));
        lss_slave_faults slow = faults_latency(1500, 0);
        membus *b = bus_random(2, 14, 0, 0, &slow);
        lss_master *m = master_default();
        injector in = { .tr = tr, .when = at_request, .arg = LSS_CS_CONFIGURE_NODE_ID };
        lss_identity id = membus_slave(b, 1)->id;

        membus_set_trace(b, wire_trace_cb, tr);
        ck_assert_int_eq(lss_master_assign(m, &id, 42, LSS_ASSIGN_STORE | LSS_ASSIGN_VERIFY, membus_now(b)), 0);
        const lss_result *r = lss_drive(m, b, 60 * SECOND, hook, &in);
        ck_assert_msg(r->status == LSS_E_FOREIGN_MASTER, "%s: %s", lss_status_name(r->status), r->message);
        ck_assert(r->may_hold);
        ck_assert(lss_identity_equal(&r->id, &id));
        expect_quiet_after(tr, false, 2000);
        ck_assert_uint_eq(membus_slave(b, 1)->st.stored_node_id, LSS_NODE_ID_UNCONFIGURED);
        ck_assert(all_waiting(b));
        lss_master_free(m);
        membus_free(b);
        free(tr);
}
END_TEST

static membus *bitrate_bus(size_t n, lss_bitrate_device *devs) {
        membus *b = membus_new(125000);
        ck_assert_ptr_nonnull(b);
        for (size_t i = 0; i < n; i++) {
                lss_identity id = { .vendor = 0x9A, .product = 3, .revision = 1, .serial = 0x100 + (uint32_t) i };
                membus_add_slave(b, &id, (uint8_t) (10 + i), NULL);
                devs[i] = (lss_bitrate_device) { .id = id };
        }
        return b;
}

/* Past Activate Bit Timing the devices switch whatever the master does: the
 * change keeps to its window (the host follows), then ends without
 * verifying or storing, everybody in waiting at the new rate. */
START_TEST(bitrate_committed_keeps_to_its_window) {
        wire_trace *tr = calloc(1, sizeof(*tr));
        lss_bitrate_device devs[3];
        membus *b = bitrate_bus(3, devs);
        lss_master *m = master_default();
        injector in = { .tr = tr, .when = at_request, .arg = LSS_CS_ACTIVATE_BIT_TIMING };
        lss_bitrate_params p = { .bitrate = 250000, .old_bitrate = 125000, .delay_ms = 16, .store = true,
                                 .devices = devs, .n_devices = 3 };

        membus_set_trace(b, wire_trace_cb, tr);
        ck_assert_int_eq(lss_master_set_bitrate(m, &p, membus_now(b)), 0);
        const lss_result *r = lss_drive(m, b, 60 * SECOND, hook, &in);
        ck_assert_msg(r->status == LSS_E_FOREIGN_MASTER, "%s: %s", lss_status_name(r->status), r->message);
        expect_failed_at(r, LSS_SERVICE_ACTIVATE_BIT_TIMING, LSS_REASON_NONE);
        ck_assert_uint_eq(in.retunes, 1);
        ck_assert_int_eq(lss_master_retune_state(m), LSS_RETUNE_DONE);
        /* the window is 2 x 16 ms and a margin: the switch to waiting after it */
        expect_quiet_after(tr, false, 60000);
        for (size_t i = 0; i < 3; i++) {
                ck_assert_int_eq(membus_slave(b, i)->st.bit_index, lss_bit_timing_index(250000));
                ck_assert_int_eq(membus_slave(b, i)->st.stored_bit_index, lss_bit_timing_index(125000));
                ck_assert_int_eq(devs[i].outcome, LSS_BITRATE_CONFIGURED);
        }
        ck_assert(all_waiting(b));
        ck_assert(!lss_master_bitrate_committed(m));
        lss_master_free(m);
        membus_free(b);
        free(tr);
}
END_TEST

/* Before the activation it ends at once: nothing activated, the devices
 * that accepted keep the new rate pending (not configured back). */
START_TEST(bitrate_before_activation_ends_at_once) {
        wire_trace *tr = calloc(1, sizeof(*tr));
        lss_bitrate_device devs[3];
        membus *b = bitrate_bus(3, devs);
        lss_master *m = master_default();
        injector in = { .tr = tr, .when = at_request, .arg = LSS_CS_CONFIGURE_BIT_TIMING };
        lss_bitrate_params p = { .bitrate = 250000, .old_bitrate = 125000, .delay_ms = 16, .devices = devs,
                                 .n_devices = 3 };

        membus_set_trace(b, wire_trace_cb, tr);
        ck_assert_int_eq(lss_master_set_bitrate(m, &p, membus_now(b)), 0);
        const lss_result *r = lss_drive(m, b, 60 * SECOND, hook, &in);
        ck_assert_msg(r->status == LSS_E_FOREIGN_MASTER, "%s: %s", lss_status_name(r->status), r->message);
        ck_assert_uint_eq(in.retunes, 0);
        ck_assert_int_eq(lss_master_retune_state(m), LSS_RETUNE_NONE);
        expect_quiet_after(tr, false, 2000);
        for (size_t i = 0; i < 3; i++)
                ck_assert_int_eq(membus_slave(b, i)->st.bit_index, lss_bit_timing_index(125000));
        ck_assert_uint_eq(membus_bitrate(b), 125000);
        /* the first took the new rate, pending: it is named so, not configured back */
        ck_assert_int_eq(membus_slave(b, 0)->st.pending_bit_index, lss_bit_timing_index(250000));
        ck_assert_int_eq(devs[0].outcome, LSS_BITRATE_CONFIGURED);
        ck_assert_int_eq(devs[2].outcome, LSS_BITRATE_REACHED);
        ck_assert(all_waiting(b));
        lss_master_free(m);
        membus_free(b);
        free(tr);
}
END_TEST

static bool at_once(injector *in, membus *bus, lss_master *m) {
        return true;
}

/* A raw service of the holder ends too, and sends nothing more: the holder
 * decides where the slaves go. An idle engine only counts the request. */
START_TEST(raw_service_and_idle) {
        wire_trace *tr = calloc(1, sizeof(*tr));
        membus *b = bus_random(0, 15, 0, 0, NULL);
        lss_master *m = master_default();
        injector in = { .tr = tr, .when = at_once };

        membus_set_trace(b, wire_trace_cb, tr);
        lss_master_on_frame(m, &foreign, 0);
        ck_assert_uint_eq(lss_master_get_stats(m)->foreign_requests, 1);
        ck_assert(!lss_master_busy(m));

        ck_assert_int_eq(lss_master_identify_non_configured(m, membus_now(b)), 0);
        const lss_result *r = lss_drive(m, b, 60 * SECOND, hook, &in);
        ck_assert_msg(r->status == LSS_E_FOREIGN_MASTER, "%s: %s", lss_status_name(r->status), r->message);
        expect_quiet_after(tr, true, 0);
        ck_assert_uint_eq(lss_master_get_stats(m)->foreign_requests, 2);
        /* the next operation runs as before */
        ck_assert_int_eq(lss_master_identify_non_configured(m, membus_now(b)), 0);
        ck_assert_int_eq(run(m, b)->status, LSS_OK);
        lss_master_free(m);
        membus_free(b);
        free(tr);
}
END_TEST

int main(void) {
        Suite *s = suite_create("foreign");
        TCase *tc = tcase_create("core");
        tcase_set_timeout(tc, 120);
        tcase_add_test(tc, enumeration_ends_at_once);
        tcase_add_test(tc, enumeration_keeps_nobody_in_configuration);
        tcase_add_test(tc, autoassign_keeps_what_it_did);
        tcase_add_test(tc, autoassign_broken_off_after_configure);
        tcase_add_test(tc, assign_may_hold);
        tcase_add_test(tc, bitrate_committed_keeps_to_its_window);
        tcase_add_test(tc, bitrate_before_activation_ends_at_once);
        tcase_add_test(tc, raw_service_and_idle);
        suite_add_tcase(s, tc);
        return run_suite(s);
}
