/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* What lssd heard from each node-ID: what marks one taken, what frees it. */
#include <check.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_heard.h"

static lss_frame frame(uint32_t id, uint8_t len, uint8_t b0) {
        return (lss_frame) { .id = id, .len = len, .data = { b0 } };
}

START_TEST(what_marks_taken) {
        lssd_heard h = { 0 };
        char buf[80];
        lss_frame f = frame(0x706, 1, 0x04);   /* heartbeat, stopped */
        lssd_heard_rx(&h, &f, 1000000);
        ck_assert(h.taken[6]);
        ck_assert_str_eq(lssd_heard_describe(&h, 6, 13000000, buf, sizeof(buf)),
                         "sent a heartbeat (stopped) 12 s ago");
        f = frame(0x70A, 1, 0x00);              /* boot-up */
        lssd_heard_rx(&h, &f, 1000000);
        ck_assert_str_eq(lssd_heard_describe(&h, 10, 1000000, buf, sizeof(buf)), "booted up just now");
        f = frame(0x58B, 8, 0x43);              /* SDO answer */
        lssd_heard_rx(&h, &f, 1000000);
        ck_assert(h.taken[11]);
        f = frame(0x08C, 8, 0x00);              /* emergency */
        lssd_heard_rx(&h, &f, 1000000);
        ck_assert(h.taken[12]);

        /* not a device speaking under a node-ID: SYNC, LSS, SDO requests, RTR, our own echo */
        lss_frame others[] = { frame(0x080, 0, 0), frame(0x7E4, 8, 0x5E), frame(0x60D, 8, 0x40),
                               { .id = 0x70E, .len = 1, .flags = LSS_FRAME_RTR },
                               { .id = 0x70F, .len = 1, .flags = LSS_FRAME_ECHO } };
        for (size_t i = 0; i < sizeof(others) / sizeof(others[0]); i++)
                lssd_heard_rx(&h, &others[i], 1000000);
        for (unsigned n = 13; n < 128; n++)
                ck_assert_msg(!h.taken[n], "node %u", n);
        ck_assert(!h.taken[0]);
        ck_assert_str_eq(lssd_heard_describe(&h, 13, 1000000, buf, sizeof(buf)), "");
}
END_TEST

/* lssd's own NMT reset of a node-ID forgets it (whoever stays boots up
 * again); a broadcast reset forgets all; other NMT commands forget nothing. */
START_TEST(what_frees) {
        lssd_heard h = { 0 };
        for (uint32_t n = 1; n <= 3; n++) {
                lss_frame f = frame(0x700 + n, 1, 0x7F);
                lssd_heard_rx(&h, &f, 1);
        }
        lss_frame stop = { .id = 0, .len = 2, .data = { 0x02, 1 } };
        lssd_heard_tx(&h, &stop);
        ck_assert(h.taken[1]);
        lss_frame reset = { .id = 0, .len = 2, .data = { 0x82, 1 } };
        lssd_heard_tx(&h, &reset);
        ck_assert(!h.taken[1]);
        ck_assert(h.taken[2]);
        lss_frame reset_all = { .id = 0, .len = 2, .data = { 0x81, 0 } };
        lssd_heard_tx(&h, &reset_all);
        ck_assert(!h.taken[2] && !h.taken[3]);
}
END_TEST

/* What was heard at a node-ID does not count against the device lssd knows
 * spoke there, and is forgotten once that device is found elsewhere (a
 * device that cannot store, power-cycled back to 255: the bent-cannot-store
 * VM test found its own old boot-up held against it). */
START_TEST(whose_it_was) {
        static const lss_identity x = { 0x9A, 3, 1, 0x5707 }, y = { 0x9A, 3, 1, 0x5708 };
        lssd_heard h = { 0 };
        lss_frame bootup = frame(0x70C, 1, 0x00);
        lssd_heard_rx(&h, &bootup, 1);
        ck_assert(lssd_heard_taken(&h, 12, &x) && lssd_heard_taken(&h, 12, NULL));
        lssd_heard_owner(&h, 12, &x);
        ck_assert(!lssd_heard_taken(&h, 12, &x));
        ck_assert(lssd_heard_taken(&h, 12, &y));
        ck_assert(lssd_heard_taken(&h, 12, NULL));
        lssd_heard_owner(&h, 0xFF, &x);           /* x found non-configured */
        ck_assert(!lssd_heard_taken(&h, 12, &y));
        ck_assert(!h.taken[12]);
}
END_TEST

static Suite *suite(void) {
        Suite *s = suite_create("daemon-heard");
        TCase *tc = tcase_create("core");
        tcase_add_test(tc, what_marks_taken);
        tcase_add_test(tc, what_frees);
        tcase_add_test(tc, whose_it_was);
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
