/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Slaves that bend CiA 305 (CANopenNode v4 answers every Fastscan in
 * configuration state; a worst-case slave answers Fastscan in every state;
 * devices that cannot store): every pass ends, nothing unconfirmed is
 * reported, and Scan leaves the bus as it found it. */
#include <stdio.h>
#include <string.h>

#include "autoassign-util.h"
#include "lss/lss_autoassign.h"

static lss_slave_faults canopennode(void) {
        lss_slave_faults f = faults_latency(1000, 300);
        f.canopennode_lss = true;
        f.no_identify = true;
        return f;
}

static void assert_untouched(membus *b, size_t i) {
        const lss_slave_state *st = &membus_slave(b, i)->st;
        ck_assert_uint_eq(st->active_node_id, 0xFF);
        ck_assert_uint_eq(st->pending_node_id, 0xFF);
        ck_assert_uint_eq(st->stored_node_id, 0xFF);
        ck_assert(!st->configuration);
}

/* Scan: all four found, each set aside while the pass went on and given
 * 255 back, verified. Without the set-aside the pass never ends. */
START_TEST(scan_canopennode) {
        lss_slave_faults f = canopennode();
        membus *b = bus_random(4, 901, 0, 0, &f);
        lss_master *m = master_default();
        found_log fl;
        found_log_start(&fl, m, b);
        ck_assert_int_eq(lss_master_enumerate(m, NULL, membus_now(b)), 0);
        const lss_result *r = lss_drive(m, b, 120 * SECOND, NULL, NULL);
        ck_assert_msg(r->status == LSS_OK, "%s", r->message);
        ck_assert_uint_eq(r->n_devices, 4);
        assert_devices_real(b, r);
        /* announced once each although they answer every Fastscan, with 255 */
        found_log_check(&fl, r, membus_now(b), true);
        for (size_t i = 0; i < 4; i++) {
                assert_untouched(b, i);
                ck_assert_uint_ge(r->devices[i].aside_node_id, 1);
        }
        lss_master_free(m);
        membus_free(b);
}
END_TEST

/* A dry run sets nobody aside: on CANopenNode slaves it ends, naming the
 * slave that answered again and why, and nothing on the bus changed. */
START_TEST(dry_run_canopennode) {
        lss_slave_faults f = canopennode();
        membus *b = bus_random(3, 904, 0, 0, &f);
        lss_autoassign_plan p = { .unknown = LSS_UNKNOWN_POOL, .pool_lo = 20, .pool_hi = 40, .store = true,
                                  .dry_run = true };
        lss_master *m = master_default();
        ck_assert_int_eq(lss_master_autoassign(m, &p, membus_now(b)), 0);
        const lss_result *r = lss_drive(m, b, 120 * SECOND, NULL, NULL);
        ck_assert_int_eq(r->status, LSS_E_CONFLICT);
        ck_assert_msg(strstr(r->message, "a dry run sets nobody aside"), "%s", r->message);
        for (size_t i = 0; i < 3; i++)
                assert_untouched(b, i);
        /* the failed outcome names a real slave */
        size_t n, real = 0;
        const lss_outcome *o = lss_master_outcomes(m, &n);
        for (size_t i = 0; i < n; i++)
                for (size_t k = 0; k < 3; k++)
                        real += lss_identity_equal(&o[i].id, &membus_slave(b, k)->id);
        ck_assert_uint_eq(real, n);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

/* Blind AutoAssign from the pool and a mapped pass with one unmapped
 * CANopenNode slave more (left alone, reported). */
START_TEST(autoassign_canopennode) {
        lss_slave_faults f = canopennode();
        membus *b = bus_random(4, 902, 0, 0, &f);
        lss_autoassign_plan p = { .unknown = LSS_UNKNOWN_POOL, .pool_lo = 20, .pool_hi = 40, .store = true };
        lss_master *m = master_default();
        ck_assert_int_eq(lss_master_autoassign(m, &p, membus_now(b)), 0);
        const lss_result *r = lss_drive(m, b, 120 * SECOND, NULL, NULL);
        ck_assert_msg(r->status == LSS_OK, "%s", r->message);
        for (size_t i = 0; i < 4; i++) {
                const lss_slave *s = membus_slave(b, i);
                const lss_outcome *o = outcome_of(m, &s->id);
                ck_assert_ptr_nonnull(o);
                ck_assert_int_eq(o->kind, LSS_OUTCOME_POOL);
                ck_assert_uint_eq(s->st.active_node_id, o->new_node_id);
                ck_assert_uint_eq(s->st.stored_node_id, o->new_node_id);
                ck_assert(o->new_node_id >= 20 && o->new_node_id <= 40);
        }
        lss_master_free(m);
        membus_free(b);

        b = bus_random(5, 903, 0, 0, &f);
        lss_map_entry map[4];
        for (unsigned i = 0; i < 4; i++)
                map[i] = (lss_map_entry) { .id = membus_slave(b, i)->id, .revision_known = true,
                                           .node_id = (uint8_t) (10 + i) };
        lss_autoassign_plan mp = { .map = map, .n_map = 4, .store = true };
        m = master_default();
        ck_assert_int_eq(lss_master_autoassign(m, &mp, membus_now(b)), 0);
        r = lss_drive(m, b, 120 * SECOND, NULL, NULL);
        ck_assert_msg(r->status == LSS_OK, "%s", r->message);
        for (unsigned i = 0; i < 4; i++)
                ck_assert_uint_eq(membus_slave(b, i)->st.stored_node_id, 10 + i);
        ck_assert_int_eq(outcome_of(m, &membus_slave(b, 4)->id)->kind, LSS_OUTCOME_UNKNOWN);
        assert_untouched(b, 4);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

/* The worst case: one slave answers every Fastscan request. Scan and
 * AutoAssign end within their bound with an error that names it; the
 * others are left as they were. */
START_TEST(fastscan_any_is_named) {
        lss_slave_faults f = faults_latency(1000, 300);
        membus *b = bus_random(3, 904, 0, 0, &f);
        lss_slave *w = membus_slave(b, 1);
        w->faults.fastscan_any = true;
        char name[40];
        snprintf(name, sizeof(name), "%08x:%08x:%08x:%08x", w->id.vendor, w->id.product, w->id.revision,
                 w->id.serial);
        for (int pass = 0; pass < 2; pass++) {
                lss_master *m = master_default();
                found_log fl; /* what it announces is real, each once (found_log_cb) */
                found_log_start(&fl, m, b);
                lss_autoassign_plan p = { .unknown = LSS_UNKNOWN_POOL, .pool_lo = 20, .pool_hi = 40, .store = true };
                if (pass == 0)
                        ck_assert_int_eq(lss_master_enumerate(m, NULL, membus_now(b)), 0);
                else
                        ck_assert_int_eq(lss_master_autoassign(m, &p, membus_now(b)), 0);
                const lss_result *r = lss_drive(m, b, 120 * SECOND, NULL, NULL);
                ck_assert_int_eq(r->status, LSS_E_CONFLICT);
                ck_assert_msg(strstr(r->message, name), "%s", r->message);
                for (size_t i = 0; i < 3; i++)
                        if (i != 1)
                                assert_untouched(b, i);
                ck_assert(all_waiting(b));
                lss_master_free(m);
        }
        membus_free(b);
}
END_TEST

/* Raw Fastscan: no device is "no device", never 0:0:0:0; a made-up
 * identity nobody confirms is not a device either. */
START_TEST(raw_fastscan_confirmed) {
        membus *b = bus_random(0, 905, 0, 0, NULL);
        lss_master *m = master_default();
        ck_assert_int_eq(lss_master_fastscan(m, NULL, membus_now(b)), 0);
        const lss_result *r = run(m, b);
        ck_assert_int_eq(r->status, LSS_E_NOT_FOUND);
        ck_assert(!r->found);
        membus_free(b);

        /* a CANopenNode slave in configuration answers everything: 0:0:0:0
         * made up, then refused because it confirms its own identity */
        lss_slave_faults f = canopennode();
        b = bus_random(1, 906, 0, 0, &f);
        membus_slave(b, 0)->st.configuration = true;
        ck_assert_int_eq(lss_master_fastscan(m, NULL, membus_now(b)), 0);
        r = run(m, b);
        ck_assert(!r->found);
        ck_assert_int_ne(r->status, LSS_OK);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

/* A device that cannot store keeps the volatile node-ID, reported as not
 * stored (not a failure); after a power cycle a second pass assigns it again. */
START_TEST(cannot_store) {
        for (int fault = 0; fault < 2; fault++) {
                lss_slave_faults f = faults_latency(1000, 300);
                if (fault == 0)
                        f.store_unsupported = true;
                else
                        f.store_fails = true;
                membus *b = bus_random(1, 907, 0x9A, 3, &f);
                lss_map_entry map[1] = { { .id = membus_slave(b, 0)->id, .revision_known = false, .node_id = 12 } };
                lss_autoassign_plan p = { .map = map, .n_map = 1, .store = true };
                for (int boot = 0; boot < 2; boot++) {
                        lss_master *m = master_default();
                        ck_assert_int_eq(lss_master_autoassign(m, &p, membus_now(b)), 0);
                        const lss_result *r = run(m, b);
                        ck_assert_msg(r->status == LSS_OK, "%s", r->message);
                        const lss_outcome *o = outcome_of(m, &membus_slave(b, 0)->id);
                        ck_assert_int_eq(o->kind, LSS_OUTCOME_ASSIGNED);
                        ck_assert(o->not_stored);
                        ck_assert_uint_eq(o->err, fault == 0 ? 1 : 2);
                        ck_assert_uint_eq(membus_slave(b, 0)->st.active_node_id, 12);
                        ck_assert_uint_eq(membus_slave(b, 0)->st.stored_node_id, 0xFF);
                        lss_master_free(m);
                        lss_slave_power_on(membus_slave(b, 0), membus_now(b));
                        ck_assert_uint_eq(membus_slave(b, 0)->st.active_node_id, 0xFF);
                }
                membus_free(b);
        }
        ck_assert_str_eq(lss_store_error_name(1), "storing not supported");
        ck_assert_str_eq(lss_store_error_name(2), "storage media access error");
}
END_TEST

/* Cancelled while slaves are set aside: they get 255 back first. */
typedef struct cancel_at {
        bool done;
} cancel_at;

static void cancel_after_two(void *ud, membus *b, lss_master *m) {
        cancel_at *c = ud;
        size_t aside = 0;
        for (size_t i = 0; i < membus_slave_count(b); i++)
                aside += membus_slave(b, i)->st.active_node_id != 0xFF;
        if (!c->done && aside >= 2) {
                c->done = true;
                lss_master_cancel(m, membus_now(b));
        }
}

START_TEST(cancel_gives_back) {
        lss_slave_faults f = canopennode();
        membus *b = bus_random(4, 908, 0, 0, &f);
        lss_master *m = master_default();
        cancel_at c = { false };
        found_log fl;
        found_log_start(&fl, m, b);
        ck_assert_int_eq(lss_master_enumerate(m, NULL, membus_now(b)), 0);
        const lss_result *r = lss_drive(m, b, 120 * SECOND, cancel_after_two, &c);
        ck_assert(c.done);
        ck_assert_int_eq(r->status, LSS_E_CANCELLED);
        /* the two set aside before the cancel were announced then */
        ck_assert_uint_ge(fl.n, 2);
        for (size_t i = 0; i < 4; i++)
                assert_untouched(b, i);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

/* The bound and the deadline are there and finite for the default timing. */
START_TEST(bounds) {
        lss_timing_config c;
        lss_timing_config_default(&c);
        uint64_t d = lss_enumerate_deadline_us(&c);
        ck_assert(d > 60 * SECOND && d < 3600 * SECOND);
        ck_assert_uint_eq(LSS_ENUMERATE_MAX_FINDS, 127);
}
END_TEST

int main(void) {
        Suite *s = suite_create("bent-slaves");
        TCase *tc = tcase_create("bent-slaves");
        tcase_set_timeout(tc, 120);
        tcase_add_test(tc, scan_canopennode);
        tcase_add_test(tc, autoassign_canopennode);
        tcase_add_test(tc, dry_run_canopennode);
        tcase_add_test(tc, fastscan_any_is_named);
        tcase_add_test(tc, raw_fastscan_confirmed);
        tcase_add_test(tc, cannot_store);
        tcase_add_test(tc, cancel_gives_back);
        tcase_add_test(tc, bounds);
        suite_add_tcase(s, tc);
        return run_suite(s);
}
