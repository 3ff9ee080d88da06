/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Who holds a bus (lssd_holder.c) with no D-Bus: one client at a time,
 * Release by the holder only, and the holder dropped when its client leaves
 * the bus (the watch is a fake that the test fires). */
#include <check.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_holder.h"

#include "daemon-util.h"

typedef struct fake {
        unsigned watches, unwatches, gone;
        int fail;                        /* watch() returns this when negative */
        char gone_name[32];              /* the holder's name as on_gone saw it */
} fake;

static fake F;

static int fake_watch(lssd_holder *h, sd_bus_message *m) {
        if (F.fail < 0)
                return F.fail;
        F.watches++;
        h->watch = &F;
        return 0;
}

static void fake_unwatch(lssd_holder *h) {
        ck_assert_ptr_eq(h->watch, &F);
        F.unwatches++;
        h->watch = NULL;
}

static const lssd_holder_ops fake_ops = { .watch = fake_watch, .unwatch = fake_unwatch };

static void on_gone(lssd_holder *h, void *userdata) {
        F.gone++;
        snprintf(F.gone_name, sizeof(F.gone_name), "%s", h->name ? h->name : "(none)");
        ck_assert_ptr_eq(userdata, &F);
}

static void setup(lssd_holder *h) {
        memset(&F, 0, sizeof(F));
        lssd_holder_init(h, &fake_ops, on_gone, &F);
}

START_TEST(one_holder_at_a_time) {
        lssd_holder h;
        setup(&h);

        ck_assert(!lssd_holder_is(&h, ":1.1"));
        ck_assert(!lssd_holder_is(&h, NULL));
        ck_assert_int_eq(lssd_holder_take(&h, ":1.1", NULL), 1);
        ck_assert(lssd_holder_is(&h, ":1.1"));
        ck_assert(!lssd_holder_is(&h, ":1.2"));
        ck_assert(!lssd_holder_is(&h, NULL));
        ck_assert_uint_eq(F.watches, 1);

        /* again by the holder: nothing new */
        ck_assert_int_eq(lssd_holder_take(&h, ":1.1", NULL), 0);
        ck_assert_uint_eq(F.watches, 1);
        /* somebody else: busy, the holder stays */
        ck_assert_int_eq(lssd_holder_take(&h, ":1.2", NULL), -EBUSY);
        ck_assert(lssd_holder_is(&h, ":1.1"));

        /* Release: nobody holds it, the watch is gone, on_gone is not called */
        lssd_holder_drop(&h);
        ck_assert_ptr_null(h.name);
        ck_assert_uint_eq(F.unwatches, 1);
        ck_assert_uint_eq(F.gone, 0);
        lssd_holder_drop(&h); /* no-op */
        ck_assert_uint_eq(F.unwatches, 1);

        /* now the other one may */
        ck_assert_int_eq(lssd_holder_take(&h, ":1.2", NULL), 1);
        ck_assert(lssd_holder_is(&h, ":1.2"));
        lssd_holder_drop(&h);
}
END_TEST

START_TEST(released_on_disconnect) {
        lssd_holder h;
        setup(&h);

        ck_assert_int_eq(lssd_holder_take(&h, ":1.7", NULL), 1);
        /* the client leaves the bus: the owner hears who it was, then nobody holds it */
        lssd_holder_gone(&h);
        ck_assert_uint_eq(F.gone, 1);
        ck_assert_str_eq(F.gone_name, ":1.7");
        ck_assert_ptr_null(h.name);
        ck_assert_ptr_null(h.watch);
        ck_assert_uint_eq(F.unwatches, 1);
        ck_assert(!lssd_holder_is(&h, ":1.7"));

        /* a late second report changes nothing */
        lssd_holder_gone(&h);
        ck_assert_uint_eq(F.gone, 1);
        ck_assert_uint_eq(F.unwatches, 1);

        /* the bus is free for the next client */
        ck_assert_int_eq(lssd_holder_take(&h, ":1.8", NULL), 1);
        lssd_holder_drop(&h);
}
END_TEST

START_TEST(watch_fails) {
        lssd_holder h;
        setup(&h);

        /* a client that cannot be watched does not hold the bus */
        F.fail = -ENOMEM;
        ck_assert_int_eq(lssd_holder_take(&h, ":1.3", NULL), -ENOMEM);
        ck_assert_ptr_null(h.name);
        ck_assert(!lssd_holder_is(&h, ":1.3"));
        F.fail = 0;
        ck_assert_int_eq(lssd_holder_take(&h, ":1.3", NULL), 1);
        lssd_holder_drop(&h);
}
END_TEST

static Suite *suite(void) {
        Suite *s = suite_create("daemon-holder");
        TCase *tc = tcase_create("holder");
        tcase_add_test(tc, one_holder_at_a_time);
        tcase_add_test(tc, released_on_disconnect);
        tcase_add_test(tc, watch_fails);
        suite_add_tcase(s, tc);
        return s;
}

int main(void) {
        return test_run_suite(suite());
}
