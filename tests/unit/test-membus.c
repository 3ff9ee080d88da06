/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The in-memory bus: bit times, arbitration, delivery, isolation, stats. */
#include <check.h>
#include <stdlib.h>
#include <string.h>

#include "lss/lss_proto.h"
#include "sim/membus.h"

static lss_identity ident(uint32_t serial) {
        return (lss_identity) { 0x319, 0xA10002, 0x20005, serial };
}

static void run_idle(membus *b) {
        uint64_t t;
        while ((t = membus_next_event(b)) != UINT64_MAX)
                membus_advance(b, t);
}

typedef struct id_log {
        uint32_t *ids;
        unsigned *n;
} id_log;

static void record_ids(void *ud, const lss_frame *f, uint64_t t_us) {
        const id_log *l = ud;
        (void) t_us;
        ck_assert_uint_lt(*l->n, 5);
        l->ids[(*l->n)++] = f->id;
}

static unsigned drain(membus *b, lss_frame *out, uint64_t *t, unsigned max) {
        unsigned n = 0;
        lss_frame f;
        uint64_t rx;
        while (membus_master_recv(b, &f, &rx)) {
                if (n < max) {
                        if (out)
                                out[n] = f;
                        if (t)
                                t[n] = rx;
                }
                n++;
        }
        return n;
}

static void frame_with_id(lss_frame *f, uint32_t id, uint8_t tag) {
        memset(f, 0, sizeof(*f));
        f->id = id;
        f->len = 2;
        f->data[0] = tag;
}

START_TEST(bit_time_125k) {
        membus *b = membus_new(125000);
        ck_assert_ptr_nonnull(b);
        ck_assert_uint_eq(membus_now(b), 0);
        ck_assert_uint_eq(membus_next_event(b), UINT64_MAX);
        size_t i = membus_add_slave(b, &(lss_identity) { 1, 2, 3, 4 }, 0xFF, NULL);
        ck_assert_uint_eq(i, 0);

        lss_frame f;
        lss_encode_switch_global(&f, LSS_MODE_CONFIGURATION);
        uint64_t bits = can_frame_bits(&f);
        membus_advance(b, 100);
        membus_master_send(b, &f);
        ck_assert_uint_eq(membus_next_event(b), 100);
        membus_advance(b, 100);
        ck_assert_uint_eq(membus_next_event(b), 100 + bits * 8);
        membus_advance(b, 100 + bits * 8 - 1);
        ck_assert(!membus_slave(b, 0)->st.configuration);
        membus_advance(b, 100 + bits * 8);
        ck_assert(membus_slave(b, 0)->st.configuration);
        ck_assert_uint_eq(membus_next_event(b), UINT64_MAX);
        /* the master does not hear itself */
        ck_assert(!membus_master_recv(b, NULL, NULL));

        const membus_stats *st = membus_get_stats(b);
        ck_assert_uint_eq(st->frames, 1);
        ck_assert_uint_eq(st->master_frames, 1);
        ck_assert_uint_eq(st->slave_frames, 0);
        ck_assert_uint_eq(st->lss_requests, 1);
        ck_assert_uint_eq(st->busy_us, bits * 8);
        membus_free(b);
}
END_TEST

START_TEST(bit_time_fractional) {
        /* 1.25 µs a bit: no rounding drift over many frames */
        membus *b = membus_new(800000);
        lss_frame f;
        uint64_t bits = 0;
        for (unsigned i = 0; i < 7; i++) {
                frame_with_id(&f, 0x100 + i, (uint8_t) i);
                membus_inject(b, &f, 0);
                bits += can_frame_bits(&f);
        }
        run_idle(b);
        uint64_t t[8];
        ck_assert_uint_eq(drain(b, NULL, t, 8), 7);
        uint64_t ns = bits * 1250;
        ck_assert_uint_eq(t[6], (ns + 999) / 1000);
        ck_assert_uint_eq(membus_get_stats(b)->busy_us, ns / 1000);
        ck_assert_uint_eq(membus_get_stats(b)->injected_frames, 7);
        membus_free(b);
}
END_TEST

START_TEST(round_trip_with_latency) {
        membus *b = membus_new(250000);
        lss_slave_faults fl;
        lss_slave_faults_default(&fl);
        fl.latency_us = 700;
        lss_identity id = ident(77);
        membus_add_slave(b, &id, 0x21, &fl);

        lss_frame f;
        lss_encode_switch_global(&f, LSS_MODE_CONFIGURATION);
        membus_master_send(b, &f);
        run_idle(b);
        uint64_t t0 = membus_now(b);
        lss_encode_inquire(&f, LSS_FIELD_COUNT);
        uint64_t req_bits = can_frame_bits(&f);
        membus_master_send(b, &f);
        run_idle(b);

        lss_frame a;
        uint64_t rx;
        ck_assert(membus_master_recv(b, &a, &rx));
        ck_assert(lss_is_response(&a));
        ck_assert_uint_eq(a.data[0], 0x5E);
        ck_assert_uint_eq(a.data[1], 0x21);
        /* request on the wire, latency counted from its end, answer on the wire */
        ck_assert_uint_eq(rx, t0 + req_bits * 4 + 700 + can_frame_bits(&a) * 4);
        ck_assert(!membus_master_recv(b, NULL, NULL));
        ck_assert_uint_eq(membus_get_stats(b)->lss_responses, 1);
        ck_assert_uint_eq(membus_get_stats(b)->slave_frames, 1);
        membus_free(b);
}
END_TEST

START_TEST(arbitration) {
        membus *b = membus_new(1000000);
        lss_frame f, got[8];
        /* ready together: lowest identifier first, FIFO among equal ones */
        frame_with_id(&f, 0x7E5, 1);
        membus_inject(b, &f, 10);
        frame_with_id(&f, 0x100, 2);
        membus_inject(b, &f, 10);
        frame_with_id(&f, 0x100, 3);
        membus_inject(b, &f, 10);
        /* an extended frame with the same base ID loses to the standard one */
        frame_with_id(&f, 0x080u << 18, 4);
        f.flags = LSS_FRAME_EFF;
        membus_inject(b, &f, 10);
        frame_with_id(&f, 0x080, 5);
        f.flags = LSS_FRAME_RTR;
        membus_inject(b, &f, 10);
        frame_with_id(&f, 0x080, 6);
        membus_inject(b, &f, 10);
        run_idle(b);
        ck_assert_uint_eq(drain(b, got, NULL, 8), 6);
        static const uint8_t order[] = { 6, 5, 4, 2, 3, 1 };
        for (unsigned i = 0; i < 6; i++)
                ck_assert_uint_eq(got[i].data[0], order[i]);
        membus_free(b);
}
END_TEST

START_TEST(readiness_then_arbitration) {
        membus *b = membus_new(1000000);
        lss_frame f, got[4];
        uint64_t t[4];
        /* the bus is idle at 0: the 0x700 goes at once, however high its ID */
        frame_with_id(&f, 0x700, 1);
        membus_inject(b, &f, 0);
        frame_with_id(&f, 0x7FF, 2);
        membus_inject(b, &f, 1);
        frame_with_id(&f, 0x200, 3);
        membus_inject(b, &f, 20);
        /* ready after the others are done */
        frame_with_id(&f, 0x001, 4);
        membus_inject(b, &f, 1000);
        run_idle(b);
        ck_assert_uint_eq(drain(b, got, t, 4), 4);
        /* both waiting when the wire frees up: the lower ID wins */
        ck_assert_uint_eq(got[0].data[0], 1);
        ck_assert_uint_eq(got[1].data[0], 3);
        ck_assert_uint_eq(got[2].data[0], 2);
        ck_assert_uint_eq(got[3].data[0], 4);
        frame_with_id(&f, 0x700, 1);
        ck_assert_uint_eq(t[0], can_frame_bits(&f));
        frame_with_id(&f, 0x001, 4);
        ck_assert_uint_eq(t[3], 1000 + can_frame_bits(&f));
        membus_free(b);
}
END_TEST

START_TEST(master_queue_back_to_back) {
        membus *b = membus_new(500000);
        membus_add_slave(b, &(lss_identity) { 1, 2, 3, 4 }, 0x10, NULL);
        lss_frame f[3];
        lss_encode_switch_global(&f[0], LSS_MODE_CONFIGURATION);
        lss_encode_configure_node_id(&f[1], 0x11);
        lss_encode_store(&f[2]);
        uint64_t end = 0;
        for (unsigned i = 0; i < 3; i++) {
                membus_master_send(b, &f[i]);
                end += can_frame_bits(&f[i]) * 2;
        }
        /* the answer to configure node-ID (0x7E4) is ready when the store
         * (0x7E5) waits for the wire, and wins arbitration */
        lss_frame ans;
        lss_frame_response(&ans, LSS_CS_CONFIGURE_NODE_ID);
        end += can_frame_bits(&ans) * 2;
        membus_advance(b, end - 1);
        ck_assert_uint_eq(membus_slave(b, 0)->st.stored_node_id, 0x10);
        membus_advance(b, end);
        ck_assert_uint_eq(membus_slave(b, 0)->st.stored_node_id, 0x11);
        run_idle(b);
        lss_frame got[4];
        uint64_t t[4];
        ck_assert_uint_eq(drain(b, got, t, 4), 2);
        ck_assert_uint_eq(got[0].data[0], 0x11);
        ck_assert_uint_eq(t[0], (can_frame_bits(&f[0]) + can_frame_bits(&f[1]) + can_frame_bits(&ans)) * 2);
        ck_assert_uint_eq(got[1].data[0], 0x17);
        membus_free(b);
}
END_TEST

static void count_trace(void *ud, const lss_frame *f, uint64_t t_us) {
        uint64_t *c = ud;
        c[0]++;
        c[1] = t_us;
}

START_TEST(injection_and_trace) {
        membus *b = membus_new(125000);
        membus_add_slave(b, &(lss_identity) { 1, 2, 3, 4 }, 0xFF, NULL);
        uint64_t tr[2] = { 0, 0 };
        membus_set_trace(b, count_trace, tr);
        /* a stranger switches the slaves; the master hears it too */
        lss_frame f;
        lss_encode_switch_global(&f, LSS_MODE_CONFIGURATION);
        membus_inject(b, &f, 5000);
        ck_assert_uint_eq(membus_next_event(b), 5000);
        run_idle(b);
        ck_assert(membus_slave(b, 0)->st.configuration);
        uint64_t rx;
        lss_frame got;
        ck_assert(membus_master_recv(b, &got, &rx));
        ck_assert_mem_eq(&got, &f, sizeof(f));
        ck_assert_uint_eq(rx, 5000 + can_frame_bits(&f) * 8);
        ck_assert_uint_eq(tr[0], 1);
        ck_assert_uint_eq(tr[1], rx);

        /* injected in the past: goes now */
        membus_advance(b, 20000);
        lss_encode_inquire(&f, LSS_FIELD_SERIAL);
        membus_inject(b, &f, 100);
        ck_assert_uint_eq(membus_next_event(b), 20000);
        run_idle(b);
        lss_frame a[2];
        ck_assert_uint_eq(drain(b, a, NULL, 2), 2);
        ck_assert_uint_eq(a[0].data[0], 0x5D);
        ck_assert_uint_eq(a[1].data[0], 0x5D);
        ck_assert(lss_is_request(&a[0]));
        ck_assert(lss_is_response(&a[1]));
        ck_assert_uint_eq(lss_get_u32(a[1].data + 1), 4);
        ck_assert_uint_eq(tr[0], 3);

        const membus_stats *st = membus_get_stats(b);
        ck_assert_uint_eq(st->injected_frames, 2);
        ck_assert_uint_eq(st->slave_frames, 1);
        ck_assert_uint_eq(st->frames, 3);
        ck_assert_uint_eq(st->lss_requests, 2);
        ck_assert_uint_eq(st->lss_responses, 1);
        membus_reset_stats(b);
        ck_assert_uint_eq(st->frames, 0);
        ck_assert_uint_eq(st->busy_us, 0);
        membus_set_trace(b, NULL, NULL);
        membus_free(b);
}
END_TEST

START_TEST(rate_mismatch_isolation) {
        membus *b = membus_new(125000);
        membus_add_slave(b, &(lss_identity) { 1, 2, 3, 1 }, 0x05, NULL);
        membus_add_slave(b, &(lss_identity) { 1, 2, 3, 2 }, 0x06, NULL);
        ck_assert_uint_eq(membus_slave_count(b), 2);
        ck_assert_ptr_null(membus_slave(b, 2));
        lss_slave *other = membus_slave(b, 1);
        other->st.bit_index = other->st.pending_bit_index = other->st.stored_bit_index = 2; /* 500 kbit/s */

        /* it neither hears nor is heard */
        lss_frame f;
        lss_encode_switch_global(&f, LSS_MODE_CONFIGURATION);
        membus_master_send(b, &f);
        run_idle(b);
        ck_assert(membus_slave(b, 0)->st.configuration);
        ck_assert(!other->st.configuration);
        lss_slave_power_on(other, membus_now(b));
        lss_slave_power_on(membus_slave(b, 0), membus_now(b));
        run_idle(b);
        lss_frame got[4];
        ck_assert_uint_eq(drain(b, got, NULL, 4), 1);
        ck_assert_uint_eq(got[0].id, 0x705);
        ck_assert_uint_eq(membus_get_stats(b)->dropped_frames, 1);

        /* the bus goes to its rate: now the other one is isolated */
        membus_set_bitrate(b, 500000);
        ck_assert_uint_eq(membus_bitrate(b), 500000);
        membus_master_send(b, &f);
        run_idle(b);
        ck_assert(other->st.configuration);
        ck_assert(!membus_slave(b, 0)->st.configuration);
        /* a rate outside table 0: nobody */
        membus_set_bitrate(b, 0);
        ck_assert_uint_eq(membus_bitrate(b), 500000);
        membus_set_bitrate(b, 33333);
        lss_encode_switch_global(&f, LSS_MODE_WAITING);
        membus_master_send(b, &f);
        run_idle(b);
        ck_assert(other->st.configuration);
        ck_assert_ptr_null(membus_new(0));
        membus_free(b);
}
END_TEST

START_TEST(bit_rate_change_end_to_end) {
        membus *b = membus_new(125000);
        lss_slave_faults miss;
        lss_slave_faults_default(&miss);
        miss.miss_activation = true;
        for (uint32_t i = 1; i <= 3; i++)
                membus_add_slave(b, &(lss_identity) { 1, 2, 3, i }, (uint8_t) (0x10 + i), i == 3 ? &miss : NULL);

        lss_frame f;
        lss_encode_switch_global(&f, LSS_MODE_CONFIGURATION);
        membus_master_send(b, &f);
        lss_encode_configure_bit_timing(&f, 0, 2);
        membus_master_send(b, &f);
        run_idle(b);
        lss_frame got[8];
        ck_assert_uint_eq(drain(b, got, NULL, 8), 3);
        for (unsigned i = 0; i < 3; i++)
                ck_assert_uint_eq(got[i].data[0], 0x13);

        lss_encode_activate_bit_timing(&f, 10);
        membus_master_send(b, &f);
        uint64_t t_act = membus_now(b) + can_frame_bits(&f) * 8;
        membus_advance(b, t_act);
        /* the switch is a timed event on an otherwise idle bus */
        ck_assert_uint_eq(membus_next_event(b), t_act + 10000);
        /* inside the window: nobody listens (the missing one is at the old rate) */
        lss_encode_inquire(&f, LSS_FIELD_SERIAL);
        membus_master_send(b, &f);
        membus_advance(b, t_act + 5000);
        ck_assert_uint_eq(drain(b, got, NULL, 8), 1);
        ck_assert_uint_eq(lss_get_u32(got[0].data + 1), 3);
        membus_advance(b, t_act + 10000);
        ck_assert_uint_eq(membus_slave(b, 0)->st.bit_index, 2);
        ck_assert_uint_eq(membus_slave(b, 1)->st.bit_index, 2);
        ck_assert_uint_eq(membus_slave(b, 2)->st.bit_index, 4);
        ck_assert_uint_eq(membus_next_event(b), UINT64_MAX);

        membus_set_bitrate(b, 500000);
        /* second period: switched but still silent */
        membus_advance(b, t_act + 15000);
        membus_master_send(b, &f);
        run_idle(b);
        ck_assert_uint_eq(drain(b, got, NULL, 8), 0);
        membus_advance(b, t_act + 20000);
        membus_master_send(b, &f);
        run_idle(b);
        ck_assert_uint_eq(drain(b, got, NULL, 8), 2);
        membus_free(b);
}
END_TEST

/* Two slaves with their own switch times: each switches at its own. */
START_TEST(independent_deadlines) {
        membus *b = membus_new(125000);
        lss_slave_faults late;
        lss_slave_faults_default(&late);
        late.ignore_cs = LSS_CS_ACTIVATE_BIT_TIMING;
        membus_add_slave(b, &(lss_identity) { 1, 2, 3, 1 }, 0x10, NULL);
        membus_add_slave(b, &(lss_identity) { 1, 2, 3, 2 }, 0x11, &late);
        lss_frame f;
        lss_encode_switch_global(&f, LSS_MODE_CONFIGURATION);
        membus_master_send(b, &f);
        lss_encode_configure_bit_timing(&f, 0, 3);
        membus_master_send(b, &f);
        lss_encode_activate_bit_timing(&f, 10);
        membus_master_send(b, &f);
        run_idle(b);
        ck_assert_uint_eq(drain(b, NULL, NULL, 0), 2);
        ck_assert_uint_eq(membus_slave(b, 0)->st.bit_index, 3);
        ck_assert_uint_eq(membus_slave(b, 1)->st.bit_index, 4);

        /* the second one hears a later activation; the first is off the bus
         * (its window lasts 20 ms) */
        membus_slave(b, 1)->faults.ignore_cs = -1;
        lss_encode_activate_bit_timing(&f, 30);
        membus_master_send(b, &f);
        uint64_t t1 = membus_now(b) + can_frame_bits(&f) * 8;
        membus_advance(b, t1);
        ck_assert_uint_eq(membus_next_event(b), t1 + 30000);
        /* the pointer handed out may be used to change things behind the bus's back */
        lss_slave *s0 = membus_slave(b, 0);
        lss_encode_activate_bit_timing(&f, 3);
        lss_slave_on_frame(s0, &f, t1 + 15000);
        ck_assert_uint_eq(membus_next_event(b), t1 + 18000);
        membus_advance(b, t1 + 18000);
        ck_assert_uint_eq(membus_next_event(b), t1 + 30000);
        ck_assert_uint_eq(s0->st.bit_index, 3);
        ck_assert_uint_eq(membus_slave(b, 1)->st.bit_index, 4);
        run_idle(b);
        ck_assert_uint_eq(membus_now(b), t1 + 30000);
        ck_assert_uint_eq(membus_slave(b, 1)->st.bit_index, 3);
        membus_free(b);
}
END_TEST

START_TEST(answer_inside_window_dropped) {
        /* a slow slave's answer that falls into its own window never goes out */
        membus *b = membus_new(125000);
        lss_slave_faults fl;
        lss_slave_faults_default(&fl);
        fl.latency_us = 3000;
        membus_add_slave(b, &(lss_identity) { 1, 2, 3, 4 }, 0x10, &fl);
        lss_frame f;
        lss_encode_switch_global(&f, LSS_MODE_CONFIGURATION);
        membus_master_send(b, &f);
        lss_encode_store(&f);
        membus_master_send(b, &f);
        lss_encode_activate_bit_timing(&f, 10);
        membus_master_send(b, &f);
        run_idle(b);
        ck_assert_uint_eq(drain(b, NULL, NULL, 0), 0);
        ck_assert_uint_eq(membus_get_stats(b)->dropped_frames, 1);
        membus_free(b);
}
END_TEST

START_TEST(find_and_seed) {
        membus *b = membus_new(1000000);
        membus_set_seed(b, 99);
        lss_identity a = ident(1), c = ident(2), none = ident(3);
        membus_add_slave(b, &a, 1, NULL);
        membus_add_slave(b, &c, 2, NULL);
        ck_assert_ptr_eq(membus_find(b, &c), membus_slave(b, 1));
        ck_assert_ptr_null(membus_find(b, &none));
        ck_assert_uint_ne(membus_slave(b, 0)->rng, membus_slave(b, 1)->rng);
        uint64_t r0 = membus_slave(b, 0)->rng;
        membus_free(b);

        b = membus_new(1000000);
        membus_set_seed(b, 99);
        membus_add_slave(b, &a, 1, NULL);
        ck_assert_uint_eq(membus_slave(b, 0)->rng, r0);
        membus_free(b);
        b = membus_new(1000000);
        membus_set_seed(b, 100);
        membus_add_slave(b, &a, 1, NULL);
        ck_assert_uint_ne(membus_slave(b, 0)->rng, r0);
        membus_free(b);
        membus_free(NULL);
}
END_TEST

/* Same answer times for the same seed, with jitter. */
static void jitter_run(uint64_t seed, uint64_t *t, unsigned n) {
        membus *b = membus_new(1000000);
        membus_set_seed(b, seed);
        lss_slave_faults fl;
        lss_slave_faults_default(&fl);
        fl.latency_us = 100;
        fl.jitter_us = 2000;
        for (unsigned i = 0; i < n; i++)
                membus_add_slave(b, &(lss_identity) { 1, 2, 3, i }, 0xFF, &fl);
        lss_frame f;
        lss_encode_fastscan(&f, 0, LSS_FASTSCAN_PING, 0, 0);
        membus_master_send(b, &f);
        run_idle(b);
        ck_assert_uint_eq(drain(b, NULL, t, n), n);
        membus_free(b);
}

START_TEST(jitter_determinism) {
        uint64_t a[10], c[10], d[10];
        jitter_run(5, a, 10);
        jitter_run(5, c, 10);
        jitter_run(6, d, 10);
        ck_assert_mem_eq(a, c, sizeof(a));
        ck_assert(memcmp(a, d, sizeof(a)) != 0);
}
END_TEST

START_TEST(merge_identical) {
        for (int merge = 0; merge <= 1; merge++) {
                membus *b = membus_new(125000);
                membus_set_merge_identical(b, merge);
                lss_slave_faults dup;
                lss_slave_faults_default(&dup);
                dup.duplicate_answers = true;
                for (uint32_t i = 0; i < 20; i++)
                        membus_add_slave(b, &(lss_identity) { 1, 2, 3, i }, 0xFF, i == 7 ? &dup : NULL);
                lss_frame f;
                lss_encode_fastscan(&f, 0, LSS_FASTSCAN_PING, 0, 0);
                membus_master_send(b, &f);
                run_idle(b);
                unsigned n = drain(b, NULL, NULL, 0);
                const membus_stats *st = membus_get_stats(b);
                if (merge) {
                        /* all 20 first answers are one frame; slave 7's copy follows */
                        ck_assert_uint_eq(n, 2);
                        ck_assert_uint_eq(st->merged_frames, 19);
                } else {
                        ck_assert_uint_eq(n, 21);
                        ck_assert_uint_eq(st->merged_frames, 0);
                }
                ck_assert_uint_eq(st->frames, n + 1);

                /* different answers do not merge */
                lss_encode_switch_global(&f, LSS_MODE_CONFIGURATION);
                membus_master_send(b, &f);
                lss_encode_inquire(&f, LSS_FIELD_SERIAL);
                membus_master_send(b, &f);
                run_idle(b);
                ck_assert_uint_eq(drain(b, NULL, NULL, 0), 21);
                membus_free(b);
        }
}
END_TEST

static void merge_with_stranger_and_master_fifo(bool fifo) {
        membus *b = membus_new(125000);
        membus_set_merge_identical(b, true);
        membus_set_master_fifo(b, fifo);
        membus_add_slave(b, &(lss_identity) { 1, 2, 3, 4 }, 0xFF, NULL);
        lss_frame f;
        lss_encode_switch_global(&f, LSS_MODE_CONFIGURATION);
        /* master and two strangers send the same frame on the same bit */
        membus_inject(b, &f, 0);
        membus_inject(b, &f, 0);
        membus_master_send(b, &f);
        run_idle(b);
        /* the master sent it too, so it does not receive it */
        ck_assert_uint_eq(drain(b, NULL, NULL, 0), 0);
        ck_assert_uint_eq(membus_get_stats(b)->frames, 1);
        ck_assert_uint_eq(membus_get_stats(b)->merged_frames, 2);
        ck_assert(membus_slave(b, 0)->st.configuration);
        membus_free(b);
}

START_TEST(merge_with_stranger_and_master) {
        merge_with_stranger_and_master_fifo(false);
        merge_with_stranger_and_master_fifo(true);
}
END_TEST

/* master_fifo: the master's frames leave in the order sent, whatever their
 * identifiers; by default the lowest identifier ready goes first. */
static void master_order(bool fifo, const uint32_t *expect) {
        membus *b = membus_new(125000);
        membus_set_master_fifo(b, fifo);
        const uint32_t ids[] = { 0x7E5, 0x605, 0x000, 0x601 };
        uint32_t seen[5];
        unsigned n = 0;
        membus_set_trace(b, record_ids, &(id_log) { seen, &n });
        for (size_t i = 0; i < 4; i++)
                membus_master_send(b, &(lss_frame) { .id = ids[i], .len = 2 });
        /* a stranger's frame ready later still wins against the queue */
        membus_inject(b, &(lss_frame) { .id = 0x100, .len = 1 }, 100);
        run_idle(b);
        ck_assert_uint_eq(n, 5);
        for (unsigned i = 0; i < 5; i++)
                ck_assert_uint_eq(seen[i], expect[i]);
        membus_free(b);
}

START_TEST(master_fifo_order) {
        master_order(false, (const uint32_t[]) { 0x000, 0x100, 0x601, 0x605, 0x7E5 });
        master_order(true, (const uint32_t[]) { 0x7E5, 0x100, 0x605, 0x000, 0x601 });
}
END_TEST

START_TEST(merge_skips_off_bus_sender) {
        membus *b = membus_new(125000);
        membus_set_merge_identical(b, true);
        lss_slave_faults fl;
        lss_slave_faults_default(&fl);
        fl.latency_us = 100;
        membus_add_slave(b, &(lss_identity) { 1, 2, 3, 1 }, 0xFF, &fl);
        membus_add_slave(b, &(lss_identity) { 1, 2, 3, 2 }, 0xFF, &fl);
        lss_frame f;
        lss_encode_fastscan(&f, 0, LSS_FASTSCAN_PING, 0, 0);
        membus_master_send(b, &f);
        /* both answer 100 µs after the ping; slave 1 leaves the bus before that */
        membus_advance(b, can_frame_bits(&f) * 8 + 50);
        membus_slave(b, 1)->st.bit_index = 0;
        run_idle(b);
        ck_assert_uint_eq(drain(b, NULL, NULL, 0), 1);
        ck_assert_uint_eq(membus_get_stats(b)->dropped_frames, 1);
        ck_assert_uint_eq(membus_get_stats(b)->merged_frames, 0);
        membus_free(b);
}
END_TEST

/* ---- a whole fastscan of 127 slaves, the master side written out here ---- */

typedef struct scan_rig {
        membus *b;
        uint64_t timeout_us;
        unsigned requests;
} scan_rig;

/* Sends a request and waits the timeout; true when any 0x4F came back. */
static bool fs(scan_rig *r, uint32_t idn, uint8_t bitcheck, uint8_t sub, uint8_t next) {
        lss_frame f;
        lss_encode_fastscan(&f, idn, bitcheck, sub, next);
        membus_master_send(r->b, &f);
        r->requests++;
        membus_advance(r->b, membus_now(r->b) + r->timeout_us);
        bool any = false;
        lss_frame a;
        while (membus_master_recv(r->b, &a, NULL))
                any |= lss_is_response(&a) && a.data[0] == LSS_CS_IDENTIFY_SLAVE;
        return any;
}

static bool scan_one(scan_rig *r, lss_identity *found) {
        if (!fs(r, 0, LSS_FASTSCAN_PING, 0, 0))
                return false;
        for (unsigned sub = 0; sub < LSS_FIELD_COUNT; sub++) {
                uint32_t v = 0;
                for (int bit = 31; bit >= 0; bit--)
                        if (!fs(r, v, (uint8_t) bit, (uint8_t) sub, (uint8_t) sub))
                                v |= UINT32_C(1) << bit;
                ck_assert(fs(r, v, 0, (uint8_t) sub, (uint8_t) ((sub + 1) % LSS_FIELD_COUNT)));
                lss_identity_set_field(found, sub, v);
        }
        return true;
}

/* Fastscan 127 slaves of one vendor, giving each found one an ID; stop
 * after `limit` found. */
static void fastscan_many(bool merge, unsigned limit) {
        enum { N = 127 };
        membus *b = membus_new(1000000);
        membus_set_merge_identical(b, merge);
        uint64_t x = 12345;
        for (unsigned i = 0; i < N; i++) {
                x = x * 6364136223846793005ull + 1442695040888963407ull;
                lss_identity id = { 0x319, 0xA10000u + (unsigned) (x >> 62), 0x20000u + (unsigned) ((x >> 40) & 3),
                                    (uint32_t) (x >> 8) };
                membus_add_slave(b, &id, 0xFF, NULL);
        }
        /* enough for 127 answers in a row at 1 Mbit/s */
        scan_rig r = { .b = b, .timeout_us = merge ? 1000 : 20000 };
        lss_identity found;
        unsigned n = 0;
        while (n < limit && scan_one(&r, &found)) {
                lss_slave *s = membus_find(b, &found);
                ck_assert_ptr_nonnull(s);
                ck_assert(s->st.configuration);
                /* assign an ID and let it go: it boots and leaves the scan */
                lss_frame f, a[2];
                lss_encode_configure_node_id(&f, (uint8_t) (n + 1));
                membus_master_send(b, &f);
                lss_encode_switch_global(&f, LSS_MODE_WAITING);
                membus_master_send(b, &f);
                membus_advance(b, membus_now(b) + r.timeout_us);
                ck_assert_uint_eq(drain(b, a, NULL, 2), 2);
                ck_assert_uint_eq(a[0].data[0], LSS_CS_CONFIGURE_NODE_ID);
                ck_assert_uint_eq(a[1].id, 0x700 + n + 1);
                n++;
                ck_assert_uint_le(n, N);
        }
        ck_assert_uint_eq(n, limit);
        ck_assert_uint_eq(drain(b, NULL, NULL, 0), 0);
        bool seen[N + 1] = { false };
        unsigned configured = 0;
        for (unsigned i = 0; i < N; i++) {
                uint8_t nid = membus_slave(b, i)->st.active_node_id;
                if (nid == LSS_NODE_ID_UNCONFIGURED)
                        continue;
                ck_assert(lss_node_id_valid(nid));
                ck_assert(!seen[nid]);
                seen[nid] = true;
                configured++;
        }
        ck_assert_uint_eq(configured, limit);
        /* all found: a ping goes unanswered */
        if (limit == N) {
                ck_assert_uint_eq(r.requests, N * (1 + 4 * 33));
                ck_assert(!fs(&r, 0, LSS_FASTSCAN_PING, 0, 0));
        }
        const membus_stats *st = membus_get_stats(b);
        ck_assert_uint_eq(st->master_frames, r.requests + 2 * limit);
        if (!merge)
                ck_assert_uint_gt(st->frames, 20000);
        else
                ck_assert_uint_gt(st->merged_frames, 1000);
        membus_free(b);
}

START_TEST(fastscan_127_fifo) {
        /* every copy of every answer on the wire: tens of thousands of frames */
        fastscan_many(false, 24);
}
END_TEST

START_TEST(fastscan_127_merged) {
        fastscan_many(true, 127);
}
END_TEST

int main(void) {
        Suite *s = suite_create("membus");
        TCase *tc = tcase_create("core");
        tcase_add_test(tc, bit_time_125k);
        tcase_add_test(tc, bit_time_fractional);
        tcase_add_test(tc, round_trip_with_latency);
        tcase_add_test(tc, arbitration);
        tcase_add_test(tc, readiness_then_arbitration);
        tcase_add_test(tc, master_queue_back_to_back);
        tcase_add_test(tc, injection_and_trace);
        tcase_add_test(tc, rate_mismatch_isolation);
        tcase_add_test(tc, bit_rate_change_end_to_end);
        tcase_add_test(tc, independent_deadlines);
        tcase_add_test(tc, answer_inside_window_dropped);
        tcase_add_test(tc, find_and_seed);
        tcase_add_test(tc, jitter_determinism);
        tcase_add_test(tc, merge_identical);
        tcase_add_test(tc, merge_with_stranger_and_master);
        tcase_add_test(tc, master_fifo_order);
        tcase_add_test(tc, merge_skips_off_bus_sender);
        suite_add_tcase(s, tc);
        TCase *big = tcase_create("many");
        tcase_set_timeout(big, 120);
        tcase_add_test(big, fastscan_127_fifo);
        tcase_add_test(big, fastscan_127_merged);
        suite_add_tcase(s, big);
        SRunner *sr = srunner_create(s);
        srunner_run_all(sr, CK_NORMAL);
        int failed = srunner_ntests_failed(sr);
        srunner_free(sr);
        return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
