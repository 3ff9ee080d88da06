/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The node-IDs that may not be stored (lssd_unstored.c): a boot-up marks
 * its node-ID only inside the window after lssd's Reset; heartbeats and
 * other frames never do; a good AutoAssign pass forgets the marks. */
#include <check.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_unstored.h"

#include "check-main.h"

#define T0 5000000u

static lss_frame nmt_state_frame(uint8_t node, uint8_t state) {
        lss_frame f = { .id = 0x700u + node, .len = 1 };
        f.data[0] = state;
        return f;
}

static lss_frame bootup(uint8_t node) {
        return nmt_state_frame(node, 0);
}

START_TEST(window_after_reset) {
        lssd_unstored u = {};
        lss_frame f = bootup(40);

        /* never opened: nothing is marked */
        lssd_unstored_note(&u, &f, T0);
        ck_assert(!lssd_unstored_table(&u)[40]);

        lssd_unstored_open(&u, T0);
        /* before the Reset went out: not its doing */
        lssd_unstored_note(&u, &f, T0 - 1);
        ck_assert(!lssd_unstored_table(&u)[40]);
        /* inside, to its last microsecond */
        lssd_unstored_note(&u, &f, T0 + LSSD_UNSTORED_WINDOW_US / 2);
        f = bootup(41);
        lssd_unstored_note(&u, &f, T0 + LSSD_UNSTORED_WINDOW_US);
        f = bootup(42);
        lssd_unstored_note(&u, &f, T0 + LSSD_UNSTORED_WINDOW_US + 1);
        ck_assert(lssd_unstored_table(&u)[40]);
        ck_assert(lssd_unstored_table(&u)[41]);
        ck_assert(!lssd_unstored_table(&u)[42]); /* after the window */

        /* the next Reset opens a new window; marks stay until a good pass */
        lssd_unstored_open(&u, T0 + 10 * LSSD_UNSTORED_WINDOW_US);
        lssd_unstored_note(&u, &f, T0 + 10 * LSSD_UNSTORED_WINDOW_US + 1000);
        ck_assert(lssd_unstored_table(&u)[40]);
        ck_assert(lssd_unstored_table(&u)[42]);
        lssd_unstored_forget(&u);
        for (unsigned i = 0; i < 128; i++)
                ck_assert(!lssd_unstored_table(&u)[i]);
}
END_TEST

START_TEST(only_bootups) {
        lssd_unstored u = {};
        lssd_unstored_open(&u, T0);

        /* heartbeats (pre-operational, operational, stopped) */
        const uint8_t states[] = { 0x7F, 0x05, 0x04 };
        for (unsigned i = 0; i < 3; i++) {
                lss_frame f = nmt_state_frame(7, states[i]);
                lssd_unstored_note(&u, &f, T0 + 10);
        }
        /* an LSS answer, an SDO answer, a boot-up as a remote frame or of the wrong length */
        lss_frame other[] = {
                { .id = 0x7E4, .len = 8 },
                { .id = 0x587, .len = 8 },
                { .id = 0x707, .len = 1, .flags = LSS_FRAME_RTR },
                { .id = 0x707, .len = 2 },
        };
        for (unsigned i = 0; i < sizeof(other) / sizeof(other[0]); i++)
                lssd_unstored_note(&u, &other[i], T0 + 10);
        for (unsigned i = 0; i < 128; i++)
                ck_assert(!lssd_unstored_table(&u)[i]);
        /* node-IDs 1 and 127 */
        lss_frame f = bootup(1);
        lssd_unstored_note(&u, &f, T0 + 10);
        f = bootup(127);
        lssd_unstored_note(&u, &f, T0 + 10);
        ck_assert(lssd_unstored_table(&u)[1]);
        ck_assert(lssd_unstored_table(&u)[127]);
}
END_TEST

static void add(TCase *tc) {
        tcase_add_test(tc, window_after_reset);
        tcase_add_test(tc, only_bootups);
}

int main(void) {
        return check_main("daemon-unstored", add);
}
