/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* When READY=1 stops waiting for the boot passes (lssd_ready_wait_tick):
 * the passes ended, boot_ready_limit_s, no engine step for the stall time;
 * EXTEND_TIMEOUT_USEC= every 10 s meanwhile. */
#include <check.h>
#include <stdlib.h>

#include "daemon/lssd_ready.h"

#define S 1000000ull
#define LIMIT (1800 * S)
#define STALL ((uint64_t) LSSD_BOOT_STALL_USEC)

/* Ticks every second from `from` to `to` (exclusive) with a pass that steps
 * every `every` seconds (0: never); the first verdict other than HOLD or
 * HOLD_EXTEND, with *at its time, or HOLD. *extends counts the extensions. */
static lssd_ready_verdict run(lssd_ready_wait *w, uint64_t from, uint64_t to, uint64_t every, uint64_t *steps,
                              uint64_t limit, unsigned *extends, uint64_t *at) {
        for (uint64_t t = from; t < to; t += S) {
                if (every && (t / S) % every == 0)
                        (*steps)++;
                lssd_ready_verdict v = lssd_ready_wait_tick(w, t, true, true, *steps, limit, STALL);
                if (v == LSSD_READY_HOLD_EXTEND)
                        (*extends)++;
                else if (v != LSSD_READY_HOLD) {
                        *at = t;
                        return v;
                }
        }
        return LSSD_READY_HOLD;
}

START_TEST(passes_end) {
        lssd_ready_wait w;
        lssd_ready_wait_start(&w, 100 * S, 0);
        ck_assert_int_eq(lssd_ready_wait_tick(&w, 101 * S, true, true, 5, LIMIT, STALL), LSSD_READY_HOLD);
        ck_assert_int_eq(lssd_ready_wait_tick(&w, 102 * S, false, false, 5, LIMIT, STALL), LSSD_READY_GO);
}
END_TEST

START_TEST(limit_while_moving) {
        lssd_ready_wait w;
        uint64_t steps = 0, at = 0;
        unsigned extends = 0;
        lssd_ready_wait_start(&w, 50 * S, 0);
        /* a pass that steps every 2 s, limit 60 s: READY at 60 s, extended every 10 s before */
        ck_assert_int_eq(run(&w, 51 * S, 1000 * S, 2, &steps, 60 * S, &extends, &at), LSSD_READY_AT_LIMIT);
        ck_assert_uint_eq(at, 110 * S);
        ck_assert_uint_eq(extends, 5); /* at 10, 20, 30, 40, 50 s */
        /* the limit holds even when no pass runs (an interface still down) */
        lssd_ready_wait_start(&w, 0, 0);
        ck_assert_int_eq(lssd_ready_wait_tick(&w, 2 * S, true, false, 0, 2 * S, STALL), LSSD_READY_AT_LIMIT);
        ck_assert_int_eq(lssd_ready_wait_tick(&w, 1 * S, false, false, 0, 1 * S, STALL), LSSD_READY_GO);
}
END_TEST

START_TEST(stall) {
        lssd_ready_wait w;
        uint64_t steps = 0, at = 0;
        unsigned extends = 0;
        lssd_ready_wait_start(&w, 0, 0);
        /* steps for 25 s, then none: READY 10 s after the last one seen */
        ck_assert_int_eq(run(&w, 1 * S, 26 * S, 1, &steps, LIMIT, &extends, &at), LSSD_READY_HOLD);
        ck_assert_int_eq(run(&w, 26 * S, 100 * S, 0, &steps, LIMIT, &extends, &at), LSSD_READY_STALLED);
        ck_assert_uint_eq(at, 35 * S);
        ck_assert_uint_eq(extends, 3);
        /* a pass that never steps at all */
        lssd_ready_wait_start(&w, 0, 7);
        steps = 7;
        ck_assert_int_eq(run(&w, 1 * S, 100 * S, 0, &steps, LIMIT, &extends, &at), LSSD_READY_STALLED);
        ck_assert_uint_eq(at, STALL);
        /* steps 9 s apart are progress: nothing but the limit ends the wait */
        lssd_ready_wait_start(&w, 0, 0);
        steps = 0;
        ck_assert_int_eq(run(&w, 1 * S, 500 * S, 9, &steps, 400 * S, &extends, &at), LSSD_READY_AT_LIMIT);
        ck_assert_uint_eq(at, 400 * S);
}
END_TEST

START_TEST(no_stall_without_a_pass) {
        lssd_ready_wait w;
        lssd_ready_wait_start(&w, 0, 3);
        /* 9 s of an interface down (no pass runs, no steps), then its pass
         * starts: the stall counts from the last look without a pass */
        for (uint64_t t = 1; t < 10; t++)
                ck_assert_int_le(lssd_ready_wait_tick(&w, t * S, true, false, 3, LIMIT, STALL), LSSD_READY_HOLD_EXTEND);
        ck_assert_int_le(lssd_ready_wait_tick(&w, 10 * S, true, true, 3, LIMIT, STALL), LSSD_READY_HOLD_EXTEND);
        ck_assert_int_le(lssd_ready_wait_tick(&w, 18 * S, true, true, 3, LIMIT, STALL), LSSD_READY_HOLD_EXTEND);
        ck_assert_int_eq(lssd_ready_wait_tick(&w, 19 * S, true, true, 3, LIMIT, STALL), LSSD_READY_STALLED);
        /* a longer stall time (buses with long LSS timeouts) waits longer */
        lssd_ready_wait_start(&w, 0, 3);
        ck_assert_int_le(lssd_ready_wait_tick(&w, 29 * S, true, true, 3, LIMIT, 30 * S), LSSD_READY_HOLD_EXTEND);
        ck_assert_int_eq(lssd_ready_wait_tick(&w, 30 * S, true, true, 3, LIMIT, 30 * S), LSSD_READY_STALLED);
}
END_TEST

static Suite *suite(void) {
        Suite *s = suite_create("daemon-ready");
        TCase *tc = tcase_create("core");
        tcase_add_test(tc, passes_end);
        tcase_add_test(tc, limit_while_moving);
        tcase_add_test(tc, stall);
        tcase_add_test(tc, no_stall_without_a_pass);
        suite_add_tcase(s, tc);
        return s;
}

int main(void) {
        SRunner *sr = srunner_create(suite());
        srunner_run_all(sr, CK_NORMAL);
        int failed = srunner_ntests_failed(sr);
        srunner_free(sr);
        return failed == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
