/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The echo rule shared by lssd and lss-vcan-master (can/tx_echo.c): only
 * the echo of the last LSS request written confirms, once; an identical
 * older request's echo is told apart by its time, up to the clock slack. */
#include <check.h>
#include <string.h>

#include "can/tx_echo.h"

#include "check-main.h"

#define T0 7000000u

static lss_frame request(uint8_t cs) {
        lss_frame f = { .id = LSS_COB_MASTER, .len = 8 };
        f.data[0] = cs;
        return f;
}

START_TEST(last_request_confirms_once) {
        lss_tx_echo e = {};
        lss_frame a = request(0x5E), b = request(0x5A);

        ck_assert(!lss_tx_echo_confirms(&e, &a, T0)); /* nothing written */
        lss_tx_echo_written(&e, &a, T0);
        lss_tx_echo_written(&e, &b, T0 + 100);
        ck_assert(!lss_tx_echo_confirms(&e, &a, T0 + 200)); /* not the last one */
        ck_assert(lss_tx_echo_confirms(&e, &b, T0 + 200));
        ck_assert(!lss_tx_echo_confirms(&e, &b, T0 + 300)); /* once */

        /* frames that are no LSS request never become the one to confirm */
        lss_frame nmt = { .id = 0, .len = 2 };
        lss_tx_echo_written(&e, &nmt, T0 + 400);
        ck_assert(!lss_tx_echo_confirms(&e, &nmt, T0 + 500));

        /* a new socket: the old one's echo never comes */
        lss_tx_echo_written(&e, &a, T0 + 600);
        lss_tx_echo_forget(&e);
        ck_assert(!lss_tx_echo_confirms(&e, &a, T0 + 700));
}
END_TEST

/* A retry repeats its request: the first try's echo reads before the retry
 * was written and does not confirm it, unless within the clock slack. */
START_TEST(older_identical_request) {
        lss_tx_echo e = {};
        lss_frame a = request(0x5E);
        uint64_t retry_at = T0 + 50000;

        lss_tx_echo_written(&e, &a, retry_at);
        ck_assert(!lss_tx_echo_confirms(&e, &a, retry_at - LSS_TX_ECHO_CLOCK_SLACK_US - 1));
        ck_assert(lss_tx_echo_confirms(&e, &a, retry_at - LSS_TX_ECHO_CLOCK_SLACK_US));
}
END_TEST

static void add(TCase *tc) {
        tcase_add_test(tc, last_request_confirms_once);
        tcase_add_test(tc, older_identical_request);
}

int main(void) {
        return check_main("tx-echo", add);
}
