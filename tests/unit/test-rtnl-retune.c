/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* SetBitrate's rtnetlink retune as a state machine (rtnl_retune.c) on the
 * fake kernel of rtnl-fake.h: one request per step, never a wait inside
 * (the fake's poll() is never called), an error answer ends it with its
 * errno, no answer ends it after the request timeout, and it claims the
 * link changes it made and no others. */
#include <poll.h>

#include "can/rtnl_retune.h"

#include "check-main.h"
#include "rtnl-fake.h"

/* Steps until the end as an event loop would: the fake (sys) answers at
 * once, the real kernel (sys NULL) when its socket is readable. */
static int run_on(const can_sys *sys, const char *ifname, uint32_t bitrate) {
        rtnl_retune *r;
        int k = rtnl_retune_start(sys, ifname, bitrate, &r);
        if (k < 0)
                return k;
        for (unsigned i = 0; i < 16 && (k = rtnl_retune_step(r)) == 0; i++) {
                struct pollfd p = { .fd = rtnl_retune_fd(r), .events = POLLIN };
                if (!sys)
                        ck_assert_int_ge(poll(&p, 1, 1000), 0);
        }
        ck_assert_int_ne(k, 0);
        ck_assert_int_eq(rtnl_retune_fd(r), -1);
        ck_assert_uint_eq(rtnl_retune_deadline(r), UINT64_MAX);
        rtnl_retune_free(r);
        return k;
}

static int run(const char *ifname, uint32_t bitrate) {
        return run_on(&nf_sys, ifname, bitrate);
}

/* A retune of can0 to 250 kbit/s on a fresh fake kernel answering `later` or never (`mute`). */
static rtnl_retune *start_can0(bool later, bool mute) {
        rtnl_retune *r;
        nf_reset();
        nf_standard_links();
        NF.later = later;
        NF.mute = mute;
        ck_assert_int_eq(rtnl_retune_start(&nf_sys, "can0", 250000, &r), 0);
        return r;
}

/* The kernel answers only when the test says so: the retune waits in
 * steps, one request each, and never blocks. */
START_TEST(steps_across_loop_turns) {
        rtnl_retune *r = start_can0(true, false);

        ck_assert_int_ge(rtnl_retune_fd(r), 0);
        ck_assert_uint_eq(rtnl_retune_deadline(r), NF.mono_us + 1000000u);
        ck_assert_uint_eq(NF.n_requests, 1); /* the lookup */

        const char *after[] = { "down ", "down rate=250000 ", "down rate=250000 up " };
        for (unsigned i = 0; i < 3; i++) {
                /* no answer yet: nothing moves */
                ck_assert_int_eq(rtnl_retune_step(r), 0);
                ck_assert_uint_eq(NF.n_requests, 1 + i);
                nf_release();
                /* the answer: the next request, and back to the loop */
                ck_assert_int_eq(rtnl_retune_step(r), 0);
                ck_assert_uint_eq(NF.n_requests, 2 + i);
                ck_assert_str_eq(NF.ops, after[i]);
        }
        ck_assert_int_eq(rtnl_retune_step(r), 0);
        nf_release();
        ck_assert_int_eq(rtnl_retune_step(r), 1);
        ck_assert_int_eq(rtnl_retune_step(r), 1); /* over: stays so */
        ck_assert_uint_eq(NF.n_polls, 0);
        ck_assert_uint_eq(nf_find(4, NULL)->bitrate, 250000);
        ck_assert(nf_find(4, NULL)->flags & IFF_UP);
        ck_assert_uint_eq(NF.n_sockets, NF.n_closes); /* its socket closed at the end */

        /* it took the link down and up: those two changes are its own, once */
        ck_assert(rtnl_retune_claim(r, false));
        ck_assert(!rtnl_retune_claim(r, false));
        ck_assert(rtnl_retune_claim(r, true));
        ck_assert(!rtnl_retune_claim(r, true));
        rtnl_retune_free(r);
}
END_TEST

/* Events come in order: seeing the link up again claims the way down too
 * (a lost or merged "down" never makes a later real one look like ours). */
START_TEST(claims_up_takes_down) {
        rtnl_retune *r = start_can0(false, false);

        ck_assert(!rtnl_retune_claim(r, false)); /* nothing done yet */
        ck_assert_int_eq(rtnl_retune_step(r), 0);
        ck_assert_str_eq(NF.ops, "down ");
        ck_assert(!rtnl_retune_claim(r, true)); /* not set up (yet) */
        while (rtnl_retune_step(r) == 0)
                ;
        ck_assert(rtnl_retune_claim(r, true));
        ck_assert(!rtnl_retune_claim(r, false));
        rtnl_retune_free(r);
}
END_TEST

START_TEST(error_answers) {
        nf_reset();
        nf_standard_links();

        /* a rate the controller refuses: its error, and the link up again with its old rate */
        ck_assert_int_eq(run("can0", 12345), -EINVAL);
        ck_assert_str_eq(NF.ops, "down refused up ");
        ck_assert_uint_eq(nf_find(4, NULL)->bitrate, 125000);
        ck_assert(nf_find(4, NULL)->flags & IFF_UP);

        /* no CAP_NET_ADMIN: the first change fails, nothing else is tried, nothing is its own */
        rtnl_retune *r;
        NF.ops[0] = 0;
        NF.fail_newlink_with = -EPERM;
        ck_assert_int_eq(rtnl_retune_start(&nf_sys, "can0", 1000000, &r), 0);
        ck_assert_int_eq(rtnl_retune_step(r), 0);
        ck_assert_int_eq(rtnl_retune_step(r), -EPERM);
        ck_assert_str_eq(NF.ops, "");
        ck_assert(!rtnl_retune_claim(r, false));
        ck_assert(!rtnl_retune_claim(r, true));
        rtnl_retune_free(r);
        NF.fail_newlink_with = 0;

        /* already there and up: only the lookup, no controller restart */
        unsigned req = NF.n_requests;
        ck_assert_int_eq(run("can0", 125000), 1);
        ck_assert_uint_eq(NF.n_requests, req + 1);

        /* a link that was down ends up */
        ck_assert_int_eq(run("can1", 500000), 1);
        ck_assert_str_eq(NF.ops, "down rate=500000 up ");
        ck_assert(nf_find(6, NULL)->flags & IFF_UP);

        /* no bit rate on vcan or anything else; no such link; no rate */
        NF.ops[0] = 0;
        ck_assert_int_eq(run("vcan0", 250000), -EOPNOTSUPP);
        ck_assert_int_eq(run("lo", 250000), -EOPNOTSUPP);
        ck_assert_int_eq(run("eth0", 250000), -EOPNOTSUPP);
        ck_assert_str_eq(NF.ops, "");
        ck_assert_int_eq(run("can7", 250000), -ENODEV);
        req = NF.n_requests;
        ck_assert_int_eq(run("can0", 0), -EINVAL);
        ck_assert_int_eq(run("0123456789abcdef", 250000), -EINVAL);
        ck_assert_uint_eq(NF.n_requests, req);

        /* socket trouble */
        NF.socket_err = -EMFILE;
        ck_assert_int_eq(run("can0", 500000), -EMFILE);
        NF.socket_err = 0;
        NF.write_err = -ENOBUFS;
        ck_assert_int_eq(run("can0", 500000), -ENOBUFS);
        NF.write_err = 0;
        ck_assert_uint_eq(NF.n_sockets, NF.n_closes);
        ck_assert_uint_eq(NF.n_polls, 0);
}
END_TEST

/* The kernel never answers: each request gives up after its timeout. */
START_TEST(no_answer_times_out) {
        rtnl_retune *r = start_can0(false, true);

        uint64_t deadline = rtnl_retune_deadline(r);
        NF.mono_us = deadline - 1;
        ck_assert_int_eq(rtnl_retune_step(r), 0);
        NF.mono_us = deadline;
        ck_assert_int_eq(rtnl_retune_step(r), -ETIMEDOUT);
        ck_assert_int_eq(rtnl_retune_fd(r), -1);
        rtnl_retune_free(r);
        ck_assert_uint_eq(NF.n_polls, 0);

        /* the way down never answered: the state of the link is unknown, stop there */
        r = start_can0(true, false);
        nf_release();
        ck_assert_int_eq(rtnl_retune_step(r), 0); /* down sent */
        NF.mono_us = rtnl_retune_deadline(r);
        ck_assert_int_eq(rtnl_retune_step(r), -ETIMEDOUT);
        rtnl_retune_free(r);

        ck_assert_uint_eq(NF.n_polls, 0);
        ck_assert_uint_eq(NF.n_sockets, NF.n_closes);
}
END_TEST

/* The real kernel: links without bit timing, and none at all. */
START_TEST(real_kernel) {
        ck_assert_int_eq(run_on(NULL, "lo", 250000), -EOPNOTSUPP);
        ck_assert_int_eq(run_on(NULL, "lssnosuch0", 250000), -ENODEV);
}
END_TEST

static void add(TCase *tc) {
        tcase_add_test(tc, steps_across_loop_turns);
        tcase_add_test(tc, claims_up_takes_down);
        tcase_add_test(tc, error_answers);
        tcase_add_test(tc, no_answer_times_out);
        tcase_add_test(tc, real_kernel);
}

int main(void) {
        return check_main("rtnl-retune", add);
}
