/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Frame loss is never a silent miss (docs/engine.md, "Frame loss"): every
 * slave loses each frame it receives and each it sends with one
 * probability, and no pass reports success while a slave is missing. A
 * seeded sample of bench/loss-bench's 1000 seeds per case (src/sim/loss_trial). */
#include "engine-util.h"
#include "sim/loss_trial.h"

#define SLAVES 16

static void expect_no_silent_miss(enum loss_trial_kind kind, uint32_t drop_ppm, uint64_t seed) {
        loss_trial t;
        ck_assert_int_eq(loss_trial_run(kind, SLAVES, drop_ppm, seed, &t), 0);
        ck_assert_msg(!loss_trial_silent_miss(&t), "kind %d, %u ppm, seed %u: success with %zu of %zu found (%s)",
                      (int) kind, (unsigned) drop_ppm, (unsigned) seed, t.found, t.n, t.message);
}

/* Blind Scan and blind AutoAssign from a pool of 16, 1 % and 3 % loss: the
 * enumeration ends after its last pings were silent, as often as the loss
 * it saw calls for. */
START_TEST(enumeration_and_pool) {
        for (uint64_t seed = 1; seed <= 30; seed++)
                for (int kind = LOSS_TRIAL_SCAN; kind <= LOSS_TRIAL_POOL; kind++) {
                        expect_no_silent_miss((enum loss_trial_kind) kind, 10000, seed);
                        expect_no_silent_miss((enum loss_trial_kind) kind, 30000, seed);
                }
}
END_TEST

/* A Scan of one vendor and product (slowscan), 3 % loss. Before, these
 * seeds reported OK with 15 of 16 found (11 of seeds 1..200): a slave
 * that answered a gap between the slaves found and was lost again on the
 * way down was left out, as the gaps were asked again only while they
 * found somebody. */
START_TEST(slowscan) {
        static const uint64_t seeds[] = { 4, 11, 56 };
        for (size_t i = 0; i < sizeof(seeds) / sizeof(seeds[0]); i++)
                expect_no_silent_miss(LOSS_TRIAL_SLOWSCAN, 30000, seeds[i]);
}
END_TEST

/* The SDO discovery of 1..127, devices at 1..16, 3 % loss. Before, these
 * seeds reported OK with 15 of 16 (15 of seeds 1..200): a device whose two
 * first requests or their answers were lost was taken for nobody. */
START_TEST(sdo_discovery) {
        static const uint64_t seeds[] = { 12, 19, 34, 45, 68, 76 };
        for (size_t i = 0; i < sizeof(seeds) / sizeof(seeds[0]); i++)
                expect_no_silent_miss(LOSS_TRIAL_SDO, 30000, seeds[i]);
}
END_TEST

/* A blind AutoAssign from a pool, 3 % loss: the device that lost the
 * switch to waiting after its Configure Node-ID and Store stays in
 * configuration, with no boot-up, and answers no selective switch there.
 * Before, these seeds ended "partial", that device failed with "no boot-up
 * ... no answer to a selective switch since" (42 % of 1000 seeds were not
 * "done" at 3 %, 8 % now); the switch is sent once more before it is asked. */
START_TEST(pool_lost_switch_to_waiting) {
        static const uint64_t seeds[] = { 2, 9, 14 };
        for (size_t i = 0; i < sizeof(seeds) / sizeof(seeds[0]); i++) {
                loss_trial t;
                ck_assert_int_eq(loss_trial_run(LOSS_TRIAL_POOL, SLAVES, 30000, seeds[i], &t), 0);
                ck_assert_msg(t.success && t.found == SLAVES, "seed %u: %zu of %zu given a node-ID (%s)",
                              (unsigned) seeds[i], t.found, t.n, t.message);
        }
}
END_TEST

/* A blind Scan, 3 % loss: a kept slave whose reselection (selective
 * switch back to configuration after a switch to waiting) lost its frames
 * every time stayed in waiting and was found again. Before, that named the
 * compliant slave: "answered Fastscan again in configuration state, where
 * it was silent to it before: it does not follow CiA 305": every Scan of
 * seeds 1..3000 that failed, 21 of them (33 at 812a40a, which changed the
 * steps; seed 43 failed there, 312 before); now it is kept again. */
START_TEST(scan_reselect_lost_is_no_verdict) {
        for (uint64_t seed = 1; seed <= STALL_SEEDS(400u); seed++) {
                loss_trial t;
                ck_assert_int_eq(loss_trial_run(LOSS_TRIAL_SCAN, SLAVES, 30000, seed, &t), 0);
                ck_assert_msg(t.success && t.found == SLAVES, "seed %u: %zu of %zu found (%s)", (unsigned) seed,
                              t.found, t.n, t.message);
        }
}
END_TEST

int main(void) {
        Suite *s = suite_create("loss");
        TCase *tc = tcase_create("loss");
        tcase_add_test(tc, enumeration_and_pool);
        tcase_add_test(tc, slowscan);
        tcase_add_test(tc, sdo_discovery);
        tcase_add_test(tc, pool_lost_switch_to_waiting);
        tcase_add_test(tc, scan_reselect_lost_is_no_verdict);
        suite_add_tcase(s, tc);
        return run_suite(s);
}
