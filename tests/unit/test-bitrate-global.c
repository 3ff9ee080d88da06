/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* CiA 305's global bit-rate procedure (lss_bitrate_params.global) on the
 * in-memory bus: all answer -> activated and verified; one refuses ->
 * nothing activated, all back at the old timing; a lost Configure Bit
 * Timing is asked again; silence is a refusal too; a device that never hears
 * it is found only at the new rate (what the procedure cannot detect);
 * devices without selective switch are verified by SDO. */
#include <check.h>
#include <stdlib.h>
#include <string.h>

#include "engine-util.h"

typedef struct run_ctx {
        size_t n_activations, n_configures;
        /* slaves that ignore Configure Bit Timing until the engine retried once */
        bool heal_on_retry;
        int heal_cs;
} run_ctx;

static void on_trace(void *ud, const lss_frame *f, uint64_t t_us) {
        run_ctx *c = ud;
        (void) t_us;
        if (f->id == 0x7E5 && f->data[0] == LSS_CS_ACTIVATE_BIT_TIMING)
                c->n_activations++;
        if (f->id == 0x7E5 && f->data[0] == LSS_CS_CONFIGURE_BIT_TIMING)
                c->n_configures++;
}

/* The host retunes as soon as asked; lost frames come back after a retry. */
static void on_event(void *ud, membus *bus, lss_master *m) {
        run_ctx *c = ud;
        uint32_t rate;
        if (c->heal_on_retry && lss_master_get_stats(m)->retries > 0) {
                for (size_t i = 0; i < membus_slave_count(bus); i++)
                        if (membus_slave(bus, i)->faults.ignore_cs == c->heal_cs)
                                membus_slave(bus, i)->faults.ignore_cs = -1;
                c->heal_on_retry = false;
        }
        if (!lss_master_retune_wanted(m, &rate, NULL))
                return;
        membus_set_bitrate(bus, rate);
        lss_master_retune_done(m, LSS_RETUNE_DONE, membus_now(bus));
}

/* One test's bus of n slaves at 125k (node-IDs 10..), its engine, its devices. */
typedef struct fx {
        run_ctx c;
        membus *b;
        lss_master *m;
        lss_bitrate_device devs[4];
        size_t n;
} fx;

static void fx_start(fx *x, size_t n) {
        memset(x, 0, sizeof(*x));
        x->n = n;
        x->b = membus_new(125000);
        ck_assert_ptr_nonnull(x->b);
        for (size_t i = 0; i < n; i++) {
                lss_identity id = { .vendor = 0x100 + (uint32_t) i, .product = 7, .revision = 1,
                                    .serial = 0x2000 + (uint32_t) i };
                ck_assert_uint_eq(membus_add_slave(x->b, &id, (uint8_t) (10 + i), NULL), i);
                x->devs[i] = (lss_bitrate_device) { .id = id, .node_id = (uint8_t) (10 + i) };
        }
        membus_set_trace(x->b, on_trace, &x->c);
        x->m = master_default();
}

static void fx_end(fx *x) {
        lss_master_free(x->m);
        membus_free(x->b);
}

/* 125k -> 250k by the global procedure. */
static const lss_result *change(fx *x) {
        lss_bitrate_params p = { .bitrate = 250000, .old_bitrate = 125000, .delay_ms = 16, .devices = x->devs,
                                 .n_devices = x->n, .global = true };
        ck_assert_int_eq(lss_master_set_bitrate(x->m, &p, membus_now(x->b)), 0);
        return lss_drive(x->m, x->b, 60 * SECOND, on_event, &x->c);
}

static void expect_ok(const lss_result *r) {
        ck_assert_msg(r->status == LSS_OK, "%s: %s", lss_status_name(r->status), r->message);
}

/* Every slave runs at index `index` with `pending` pending, all in waiting. */
static void assert_all_at(membus *b, int index, int pending) {
        for (size_t i = 0; i < membus_slave_count(b); i++) {
                ck_assert_int_eq(membus_slave(b, i)->st.bit_index, index);
                ck_assert_int_eq(membus_slave(b, i)->st.pending_bit_index, pending);
        }
        ck_assert(all_waiting(b));
}

/* Outcome of device i is want[i]; one activation went out. */
static void expect_outcomes(const fx *x, const enum lss_bitrate_outcome *want) {
        ck_assert_uint_eq(x->c.n_activations, 1);
        for (size_t i = 0; i < x->n; i++)
                ck_assert_int_eq(x->devs[i].outcome, want[i]);
}

static const enum lss_bitrate_outcome ALL_SWITCHED[4] = { LSS_BITRATE_SWITCHED, LSS_BITRATE_SWITCHED,
                                                          LSS_BITRATE_SWITCHED, LSS_BITRATE_SWITCHED };

static void set_ignore(fx *x, size_t from, size_t to, int cs) {
        for (size_t i = from; i < to; i++)
                membus_slave(x->b, i)->faults.ignore_cs = cs;
}

START_TEST(all_answer_activated) {
        fx x;
        fx_start(&x, 4);
        expect_ok(change(&x));
        ck_assert_uint_eq(lss_master_bitrate_answers(x.m), 4);
        ck_assert_uint_eq(x.c.n_configures, 1); /* one request for everybody */
        expect_outcomes(&x, ALL_SWITCHED);
        assert_all_at(x.b, 3, 3);
        ck_assert_uint_eq(membus_bitrate(x.b), 250000);
        fx_end(&x);
}
END_TEST

/* Identical answers in one frame, as on a real bus: fewer counted, asked
 * again, no refusal; the check at the new rate finds everybody. */
START_TEST(merged_answers_no_refusal) {
        fx x;
        fx_start(&x, 4);
        membus_set_merge_identical(x.b, true);
        expect_ok(change(&x));
        ck_assert_uint_ge(lss_master_bitrate_answers(x.m), 1);
        ck_assert_uint_eq(x.c.n_activations, 1);
        assert_all_at(x.b, 3, 3);
        fx_end(&x);
}
END_TEST

/* Refused (why): nothing activated, the slaves that took the new timing
 * pending were configured back, the host untouched. */
static void expect_refused(fx *x, enum lss_reason why) {
        const lss_result *r = change(x);
        ck_assert_int_eq(r->status, LSS_E_REJECTED);
        expect_failed_at(r, LSS_SERVICE_CONFIGURE_BIT_TIMING, why);
        ck_assert_uint_eq(x->c.n_activations, 0);
        assert_all_at(x->b, 4, 4);
        ck_assert_uint_eq(membus_bitrate(x->b), 125000);
        ck_assert_int_eq(lss_master_retune_state(x->m), LSS_RETUNE_NONE);
}

START_TEST(refused_nothing_activated) {
        fx x;
        fx_start(&x, 3);
        membus_slave(x.b, 1)->faults.bit_index_unsupported = 1u << 3; /* 250k */
        expect_refused(&x, LSS_REASON_REFUSED);
        ck_assert_uint_eq(lss_master_result(x.m)->err, 1);
        fx_end(&x);

        /* nobody ever answers (CANopenNode without a bit-rate callback) */
        fx_start(&x, 2);
        membus_slave(x.b, 0)->faults.bit_timing_silent = membus_slave(x.b, 1)->faults.bit_timing_silent = true;
        expect_refused(&x, LSS_REASON_NO_ANSWER);
        fx_end(&x);
}
END_TEST

/* The first Configure Bit Timing reaches nobody (all), or one device of
 * three: asked again, then done. */
START_TEST(lost_configure_retried) {
        for (size_t from = 0; from < 3; from += 2) {
                fx x;
                fx_start(&x, 3);
                x.c = (run_ctx) { .heal_on_retry = true, .heal_cs = LSS_CS_CONFIGURE_BIT_TIMING };
                set_ignore(&x, from, 3, LSS_CS_CONFIGURE_BIT_TIMING);
                expect_ok(change(&x));
                ck_assert_uint_eq(x.c.n_configures, 2);
                ck_assert_uint_eq(lss_master_bitrate_answers(x.m), 3);
                assert_all_at(x.b, 3, 3);
                fx_end(&x);
        }
}
END_TEST

/* Verified at the new rate: a device without selective switch (found by
 * SDO alone) by its SDO server (one by one it cannot be done: refused up
 * front). */
START_TEST(verified_after) {
        fx x;
        /* what it cannot detect: a device that never hears Configure Bit
         * Timing while others answer is activated with them, found silent after */
        fx_start(&x, 3);
        set_ignore(&x, 0, 1, LSS_CS_CONFIGURE_BIT_TIMING);
        ck_assert_int_eq(change(&x)->status, LSS_E_INCOMPLETE);
        expect_outcomes(&x, (const enum lss_bitrate_outcome[]) { LSS_BITRATE_LOST, LSS_BITRATE_SWITCHED,
                                                                  LSS_BITRATE_SWITCHED });
        fx_end(&x);

        fx_start(&x, 3);
        set_ignore(&x, 1, 2, LSS_CS_SWITCH_SEL_VENDOR);
        x.devs[1].no_select = true;
        expect_ok(change(&x));
        expect_outcomes(&x, ALL_SWITCHED);
        assert_all_at(x.b, 3, 3);
        lss_bitrate_params p = { .bitrate = 500000, .old_bitrate = 250000, .delay_ms = 16, .devices = x.devs,
                                 .n_devices = 3 };
        ck_assert_int_eq(lss_master_set_bitrate(x.m, &p, membus_now(x.b)), -EINVAL);
        fx_end(&x);
}
END_TEST

int main(void) {
        Suite *s = suite_create("bitrate-global");
        TCase *tc = tcase_create("global");
        tcase_add_test(tc, all_answer_activated);
        tcase_add_test(tc, merged_answers_no_refusal);
        tcase_add_test(tc, refused_nothing_activated);
        tcase_add_test(tc, lost_configure_retried);
        tcase_add_test(tc, verified_after);
        suite_add_tcase(s, tc);
        return run_suite(s);
}
