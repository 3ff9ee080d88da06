/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Confirming identities through LSS (lss_confirm.c) on the in-memory bus:
 * a CANopenNode-like slave (no identify services) is confirmed with its
 * node-ID, an identity nobody has is not, lost frames cost retries and not
 * devices, everybody ends in waiting. */
#include "engine-util.h"

static lss_slave_faults faults_canopennode(void) {
        lss_slave_faults f;
        lss_slave_faults_canopennode(&f);
        f.latency_us = 1000;
        f.jitter_us = 300;
        return f;
}

static const lss_result *confirm(lss_master *m, membus *b, const lss_identity *ids, size_t n) {
        ck_assert_int_eq(lss_master_confirm(m, ids, n, membus_now(b)), 0);
        const lss_result *r = run(m, b);
        ck_assert_msg(r->status == LSS_OK, "%s", r->message);
        return r;
}

static const lss_device *device_of(const lss_result *r, const lss_identity *id) {
        for (size_t i = 0; i < r->n_devices; i++)
                if (lss_identity_equal(&r->devices[i].id, id))
                        return &r->devices[i];
        return NULL;
}

/* A configured CANopenNode-like slave and a plain one are confirmed with
 * their node-IDs; an identity nobody has, asked between them, is not; the
 * non-configured slave on the bus is not reported (it was not asked for). */
START_TEST(confirm_canopennode_and_nobody) {
        membus *b = membus_new(125000);
        lss_slave_faults co = faults_canopennode(), plain = faults_latency(1000, 300);
        lss_identity a = { 0x1234, 0x10, 1, 100 }, c = { 0x9A, 3, 2, 200 }, u = { 0xEC, 0x1234, 1, 300 };
        lss_identity nobody = { 0x5555, 1, 1, 1 };
        membus_add_slave(b, &a, 12, &co);
        membus_add_slave(b, &c, 40, &plain);
        membus_add_slave(b, &u, LSS_NODE_ID_UNCONFIGURED, &co);
        lss_master *m = master_default();
        found_log fl;
        found_log_start(&fl, m, b);
        const lss_identity ids[] = { a, nobody, c };
        const lss_result *r = confirm(m, b, ids, 3);
        ck_assert_uint_eq(r->n_devices, 2);
        assert_devices_real(b, r);
        ck_assert_uint_eq(device_of(r, &a)->node_id, 12);
        ck_assert_uint_eq(device_of(r, &c)->node_id, 40);
        ck_assert_ptr_null(device_of(r, &nobody));
        found_log_check(&fl, r, membus_now(b), true);
        /* the identity nobody has was asked 1 + retries times */
        ck_assert_uint_ge(lss_master_get_stats(m)->retries, 2);
        lss_drive_idle(b, 100000);
        ck_assert(all_waiting(b));
        lss_master_free(m);
        membus_free(b);
}
END_TEST

/* Nobody has any of them: an empty result, no failure, nobody selected. */
START_TEST(confirm_nobody) {
        membus *b = membus_new(125000);
        lss_identity a = { 0x1234, 0x10, 1, 100 }, other = { 0x1234, 0x10, 1, 101 };
        membus_add_slave(b, &a, 3, NULL);
        lss_master *m = master_default();
        const lss_result *r = confirm(m, b, &other, 1);
        ck_assert_uint_eq(r->n_devices, 0);
        ck_assert(all_waiting(b));
        /* nothing to confirm: nothing sent */
        uint64_t frames = membus_get_stats(b)->lss_requests;
        r = confirm(m, b, NULL, 0);
        ck_assert_uint_eq(r->n_devices, 0);
        ck_assert_uint_eq(membus_get_stats(b)->lss_requests, frames);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

/* 3 % of the frames each slave receives are lost, plain and CANopenNode-like
 * slaves alike: every one confirmed with its node-ID over 100 seeds, all in
 * waiting at the end, and frames were made up for by retries. */
START_TEST(confirm_lossy) {
        uint64_t retries = 0;
        for (uint64_t seed = 1; seed <= 100; seed++) {
                lss_slave_faults plain = faults_latency(1000, 300), co = faults_canopennode();
                plain.rx_loss_ppm = co.rx_loss_ppm = 30000;
                membus *b = membus_new(125000);
                membus_set_seed(b, seed);
                lss_identity ids[8];
                uint64_t rng = seed;
                for (size_t i = 0; i < 8; i++) {
                        ids[i] = (lss_identity) { (uint32_t) sim_random_next(&rng), (uint32_t) sim_random_next(&rng),
                                                  (uint32_t) sim_random_next(&rng), (uint32_t) sim_random_next(&rng) };
                        membus_add_slave(b, &ids[i], (uint8_t) (10 + i), i % 2 ? &co : &plain);
                }
                lss_master *m = master_default();
                found_log fl;
                found_log_start(&fl, m, b);
                const lss_result *r = confirm(m, b, ids, 8);
                ck_assert_msg(r->n_devices == 8, "seed %u: %zu of 8 confirmed", (unsigned) seed, r->n_devices);
                assert_devices_real(b, r);
                found_log_check(&fl, r, membus_now(b), true);
                lss_drive_idle(b, 100000);
                ck_assert_msg(all_waiting(b), "seed %u: a slave left in configuration", (unsigned) seed);
                retries += lss_master_get_stats(m)->retries;
                lss_master_free(m);
                membus_free(b);
        }
        ck_assert_uint_gt(retries, 0);
}
END_TEST

/* A loaded host: every slave's answers 20-200 ms late on 5 % of them (a
 * stall holds back the slave's later answers too). A device silent to its
 * selective switch or its Inquire Node-ID was left out of the Scan's
 * result, "OK" without it (92 of these 200 seeds), and so was one whose
 * Inquire Node-ID was answered by the slave asked before too, late (1 of
 * 200 once silence was asked again). Asked again patiently first, every
 * one is confirmed (0 of 1000). */
START_TEST(confirm_through_stalls) {
        unsigned failed = 0;
        for (uint64_t seed = 0; seed < STALL_SEEDS(200u); seed++) {
                lss_slave_faults plain = faults_latency(700, 300), co = faults_canopennode();
                faults_stall(&plain, seed, 50000);
                faults_stall(&co, seed, 50000);
                membus *b = membus_new(125000);
                membus_set_seed(b, seed);
                lss_identity ids[8];
                for (size_t i = 0; i < 8; i++) {
                        ids[i] = (lss_identity) { 0x9A, 3, 1, 0x100 + (uint32_t) i };
                        membus_add_slave(b, &ids[i], (uint8_t) (10 + i), i % 2 ? &co : &plain);
                }
                lss_master *m = master_default();
                ck_assert_int_eq(lss_master_confirm(m, ids, 8, membus_now(b)), 0);
                stall_expect_found(&failed, seed, &plain, b, run(m, b), 8);
                lss_master_free(m);
                membus_free(b);
        }
        ck_assert_uint_eq(failed, 0);
}
END_TEST

/* A bad argument, and one operation at a time. */
START_TEST(confirm_arguments) {
        membus *b = membus_new(125000);
        lss_master *m = master_default();
        lss_identity a = { 1, 2, 3, 4 };
        ck_assert_int_eq(lss_master_confirm(m, NULL, 1, membus_now(b)), -EINVAL);
        ck_assert_int_eq(lss_master_confirm(m, &a, 1, membus_now(b)), 0);
        ck_assert_int_eq(lss_master_confirm(m, &a, 1, membus_now(b)), -EBUSY);
        run(m, b);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

int main(void) {
        Suite *s = suite_create("confirm");
        TCase *tc = tcase_create("confirm");
        tcase_add_test(tc, confirm_canopennode_and_nobody);
        tcase_add_test(tc, confirm_nobody);
        tcase_add_test(tc, confirm_lossy);
        tcase_add_test(tc, confirm_through_stalls);
        tcase_add_test(tc, confirm_arguments);
        suite_add_tcase(s, tc);
        return run_suite(s);
}
