/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* SDO identity discovery (lss_sdo_discover.c) on the in-memory bus: every
 * device at a node-ID found with its 1018h identity, many node-IDs asked at
 * once; lost, late and aborted answers; two devices at one node-ID; devices
 * in NMT Stopped; nothing written, no NMT. */
#include <stdio.h>

#include "engine-util.h"

/* What went on the wire: every master frame must be an upload request of
 * 1018h:1..4 (nothing written, no NMT, no LSS); the requests' bus time. */
typedef struct wire {
        membus *bus;
        unsigned requests, other_master;
        uint64_t request_bits;
        /* fake SDO servers: node-ID -> answers to 1018h:1..4 (0: none) */
        const lss_frame *fake[LSS_NODE_ID_MAX + 1];
        uint32_t fake_latency_us;
} wire;

static void on_wire(void *ud, const lss_frame *f, uint64_t t_us) {
        wire *w = ud;
        if (f->id >= 0x601 && f->id <= 0x67F) {
                ck_assert_uint_eq(f->len, 8);
                ck_assert_uint_eq(f->data[0], 0x40);
                ck_assert_uint_eq(lss_get_u16(f->data + 1), 0x1018);
                ck_assert(f->data[3] >= 1 && f->data[3] <= 4);
                w->requests++;
                w->request_bits += can_frame_bits(f);
                const lss_frame *fake = w->fake[f->id - 0x600];
                if (fake)
                        membus_inject(w->bus, &fake[f->data[3] - 1], t_us + w->fake_latency_us);
        } else if (f->id == 0x000 || f->id == LSS_COB_MASTER)
                w->other_master++;
}

/* The master's frames leave in order, as from a SocketCAN socket. */
static void wire_start(wire *w, membus *b) {
        memset(w, 0, sizeof(*w));
        w->bus = b;
        membus_set_trace(b, on_wire, w);
        membus_set_master_fifo(b, true);
}

/* A bus with one device at node_id, watched by w. */
static membus *bus_one(wire *w, const lss_identity *id, uint8_t node_id) {
        membus *b = membus_new(125000);
        ck_assert_ptr_nonnull(b);
        membus_add_slave(b, id, node_id, NULL);
        wire_start(w, b);
        return b;
}

static const lss_result *discover(lss_master *m, membus *b, uint8_t first, uint8_t last, unsigned window) {
        lss_sdo_discover_params p = { .first = first, .last = last, .window = window };
        ck_assert_int_eq(lss_master_sdo_discover(m, &p, membus_now(b)), 0);
        const lss_result *r = run(m, b);
        ck_assert_msg(r->status == LSS_OK, "%s", r->message);
        return r;
}

static const lss_sdo_node *node_of(const lss_result *r, uint8_t node_id) {
        for (size_t i = 0; i < r->n_sdo_nodes; i++)
                if (r->sdo_nodes[i].node_id == node_id)
                        return &r->sdo_nodes[i];
        return NULL;
}

/* node_id answered 1018h with exactly this identity, from one device */
static void expect_identity(const lss_result *r, uint8_t node_id, const lss_identity *id) {
        const lss_sdo_node *d = node_of(r, node_id);
        ck_assert_msg(d != NULL, "node-ID %u not found", node_id);
        ck_assert_msg(d->known == 0xF, "node-ID %u: fields known 0x%x", node_id, d->known);
        ck_assert(d->source & LSS_SDO_FROM_SDO);
        ck_assert(!d->conflict);
        ck_assert_uint_eq(d->aborted, 0);
        ck_assert(lss_identity_equal(&d->id, id));
}

/* n configured devices at node-IDs 1..n, random identities */
static membus *bus_configured(size_t n, uint64_t seed, const lss_slave_faults *f) {
        membus *b = bus_random(n, seed, 0, 0, f);
        for (size_t i = 0; i < n; i++) {
                lss_slave_state *st = &membus_slave(b, i)->st;
                st->active_node_id = st->pending_node_id = st->stored_node_id = (uint8_t) (i + 1);
        }
        return b;
}

static void expect_all(membus *b, const lss_result *r, size_t n) {
        ck_assert_uint_eq(r->n_sdo_nodes, n);
        for (size_t i = 0; i < n; i++) {
                lss_slave *s = membus_slave(b, i);
                expect_identity(r, s->st.active_node_id, &s->id);
        }
}

/* Nobody there: two requests per node-ID, nothing found, nothing else sent. */
START_TEST(sdo_discover_empty) {
        /* a non-configured device has no SDO server */
        lss_identity id = { 1, 2, 3, 4 };
        wire w;
        membus *b = bus_one(&w, &id, LSS_NODE_ID_UNCONFIGURED);
        lss_master *m = master_default();
        uint64_t t0 = membus_now(b);
        const lss_result *r = discover(m, b, 1, 127, 0);
        ck_assert_uint_eq(r->n_sdo_nodes, 0);
        ck_assert_uint_eq(r->n_devices, 0);
        ck_assert_uint_eq(w.requests, 2 * 127);
        ck_assert_uint_eq(w.other_master, 0);
        /* 8 rounds of 16 node-IDs, each waiting a quarter of the 20 ms limit
         * twice, and the full limit once at the end (0.71 s when first
         * contact waited the full limit) */
        uint64_t took = membus_now(b) - t0;
        ck_assert_uint_lt(took, 600000);
        ck_assert_uint_eq(lss_master_get_stats(m)->retries, 127);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

/* One device: its identity, from SDO; the range is respected. */
START_TEST(sdo_discover_one) {
        lss_identity id = { 0x9A, 3, 0x10002, 0xCAFE };
        wire w;
        membus *b = bus_one(&w, &id, 42);
        lss_master *m = master_default();
        const lss_result *r = discover(m, b, 1, 127, 0);
        ck_assert_uint_eq(r->n_sdo_nodes, 1);
        expect_identity(r, 42, &id);
        ck_assert_uint_eq(r->sdo_nodes[0].source, LSS_SDO_FROM_SDO);
        ck_assert_uint_eq(r->sdo_nodes[0].nmt_state, 0xFF);
        ck_assert_uint_eq(w.requests, 2 * 126 + 4);
        ck_assert_uint_eq(w.other_master, 0);
        /* a range without it */
        w.requests = 0;
        r = discover(m, b, 1, 41, 4);
        ck_assert_uint_eq(r->n_sdo_nodes, 0);
        ck_assert_uint_eq(w.requests, 2 * 41);
        r = discover(m, b, 42, 42, 1);
        ck_assert_uint_eq(r->n_sdo_nodes, 1);
        expect_identity(r, 42, &id);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

/* 127 devices: all found, and the pass takes little more than the bus time
 * of its frames (printed: the numbers of the report). */
static void full_bus(unsigned window, uint32_t bitrate, uint32_t latency_us, bool fifo, double max_ratio) {
        lss_slave_faults f = faults_latency(latency_us, latency_us / 2);
        membus *b = bus_configured(127, 1127, &f);
        membus_set_bitrate(b, bitrate);
        for (size_t i = 0; i < 127; i++)
                membus_slave(b, i)->st.bit_index = membus_slave(b, i)->st.pending_bit_index =
                        (uint8_t) lss_bit_timing_index(bitrate);
        wire w;
        wire_start(&w, b);
        membus_set_master_fifo(b, fifo);
        lss_timing_config c;
        lss_timing_config_default(&c);
        c.bitrate = bitrate;
        lss_master *m = lss_master_new(&c);
        membus_reset_stats(b);
        uint64_t t0 = membus_now(b);
        lss_sdo_discover_params p = { .first = 1, .last = 127, .window = window };
        ck_assert_int_eq(lss_master_sdo_discover(m, &p, t0), 0);
        const lss_result *r = run(m, b);
        /* the end of the pass, without lss_drive's 2 ms tail */
        uint64_t took = membus_now(b) - t0 - 2000;
        ck_assert_int_eq(r->status, LSS_OK);
        expect_all(b, r, 127);
        /* a retry where a jittery answer came later than the adaptive wait */
        if (fifo)
                ck_assert_uint_le(w.requests, 127 * 4 + (latency_us ? 8 : 0));
        ck_assert_uint_eq(w.other_master, 0);
        double req_floor = (double) w.request_bits * 1e6 / bitrate;
        double all_floor = (double) membus_get_stats(b)->busy_us;
        fprintf(stderr,
                "sdo-discover 127 nodes, %u kbit/s, window %u, answer latency %.1f-%.1f ms, master %s: %.1f ms; "
                "bus floor of its %u requests %.1f ms, of all %llu frames (requests and answers) %.1f ms (x%.2f)\n",
                bitrate / 1000, window ? window : LSS_SDO_WINDOW_DEFAULT, latency_us / 1000.0,
                (latency_us + latency_us / 2) / 1000.0, fifo ? "FIFO" : "by identifier", took / 1000.0, w.requests,
                req_floor / 1000.0, (unsigned long long) membus_get_stats(b)->frames, all_floor / 1000.0,
                took / all_floor);
        ck_assert_msg(took < max_ratio * all_floor, "%.1f ms for a bus floor of %.1f ms", took / 1000.0,
                      all_floor / 1000.0);
        lss_master_free(m);
        membus_free(b);
}

START_TEST(sdo_discover_127) {
        full_bus(0, 125000, 0, true, 1.05);
        full_bus(0, 125000, 0, false, 1.3);
        full_bus(0, 125000, 1000, true, 1.1);
        full_bus(16, 125000, 1000, true, 1.1);
        full_bus(1, 125000, 1000, true, 3.0);
        full_bus(8, 1000000, 0, true, 1.3);
        full_bus(8, 1000000, 1000, true, 2.0);
}
END_TEST

/* Answers lost on the way to and from the devices: one retry keeps them. */
START_TEST(sdo_discover_lost_answers) {
        lss_slave_faults f = faults_latency(0, 0);
        f.rx_loss_ppm = f.tx_loss_ppm = 30000;
        membus *b = bus_configured(64, 77, &f);
        wire w;
        wire_start(&w, b);
        lss_master *m = master_default();
        const lss_result *r = discover(m, b, 1, 127, 0);
        expect_all(b, r, 64);
        ck_assert_uint_gt(lss_master_get_stats(m)->retries, 63 + 10);
        ck_assert_uint_eq(w.other_master, 0);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

/* Answers later than the timeout (30 ms and 25..45 ms against 20 ms), and
 * one later than both requests (70 ms): all found, each answer counted once,
 * and the waits grow to the latency seen. */
START_TEST(sdo_discover_late_answers) {
        lss_slave_faults f = faults_latency(30000, 0);
        membus *b = bus_configured(6, 5, &f);
        membus_slave(b, 1)->faults.latency_us = 25000;
        membus_slave(b, 1)->faults.jitter_us = 20000;
        membus_slave(b, 2)->faults.latency_us = 70000;
        membus_slave(b, 3)->faults.latency_us = 1000;
        wire w;
        wire_start(&w, b);
        lss_master *m = master_default();
        const lss_result *r = discover(m, b, 1, 127, 0);
        expect_all(b, r, 6);
        ck_assert_uint_gt(lss_master_get_stats(m)->late_answers, 0);
        ck_assert_uint_gt(lss_master_get_stats(m)->patience_us, 20000);
        ck_assert_uint_eq(lss_master_get_stats(m)->conflicts, 0);
        ck_assert_uint_eq(w.other_master, 0);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

#define SDO_VALUE(node, sub, v) { .id = 0x580 + (node), .len = 8, .data = { 0x43, 0x18, 0x10, (sub), \
        (uint8_t) (v), (uint8_t) ((v) >> 8), (uint8_t) ((v) >> 16), (uint8_t) ((v) >> 24) } }
#define SDO_ABORT(node, sub, code) { .id = 0x580 + (node), .len = 8, .data = { 0x80, 0x18, 0x10, (sub), \
        (uint8_t) (code), (uint8_t) ((code) >> 8), (uint8_t) ((code) >> 16), (uint8_t) ((code) >> 24) } }

/* Devices whose 1018h lacks sub-indexes, or that have none: present,
 * identity incomplete; a 1-byte answer is a value too. */
START_TEST(sdo_discover_aborts) {
        lss_identity id = { 0x9A, 3, 1, 2 };
        wire w;
        membus *b = bus_one(&w, &id, 7);
        const lss_frame partial[] = {
                SDO_VALUE(40, 1, 0x1234), SDO_VALUE(40, 2, 0x55),
                SDO_ABORT(40, 3, 0x06090011), SDO_ABORT(40, 4, 0x06090011),
        };
        const lss_frame none[] = {
                SDO_ABORT(41, 1, 0x06020000), SDO_ABORT(41, 2, 0x06020000),
                SDO_ABORT(41, 3, 0x06020000), SDO_ABORT(41, 4, 0x06020000),
        };
        lss_frame small[] = {
                SDO_VALUE(42, 1, 0x77), SDO_VALUE(42, 2, 0x1), SDO_VALUE(42, 3, 0x2), SDO_VALUE(42, 4, 0x3),
        };
        small[0].data[0] = 0x4F;  /* 1 byte */
        small[0].data[5] = 0xEE;  /* junk beyond the size */
        w.fake[40] = partial;
        w.fake[41] = none;
        w.fake[42] = small;
        w.fake_latency_us = 500;
        lss_master *m = master_default();
        const lss_result *r = discover(m, b, 1, 127, 0);
        ck_assert_uint_eq(r->n_sdo_nodes, 4);
        expect_identity(r, 7, &id);
        const lss_sdo_node *d = node_of(r, 40);
        ck_assert_ptr_nonnull(d);
        ck_assert_uint_eq(d->known, 0x3);
        ck_assert_uint_eq(d->aborted, 0xC);
        ck_assert_uint_eq(d->abort_code, 0x06090011);
        ck_assert_uint_eq(d->id.vendor, 0x1234);
        ck_assert_uint_eq(d->id.product, 0x55);
        ck_assert(!d->conflict);
        d = node_of(r, 41);
        ck_assert_ptr_nonnull(d);
        ck_assert_uint_eq(d->known, 0);
        ck_assert_uint_eq(d->aborted, 0x1);
        ck_assert_uint_eq(d->abort_code, 0x06020000);
        ck_assert_uint_eq(d->source, LSS_SDO_FROM_SDO);
        d = node_of(r, 42);
        ck_assert_ptr_nonnull(d);
        ck_assert_uint_eq(d->known, 0xF);
        ck_assert_uint_eq(d->id.vendor, 0x77);
        /* 41 had no 1018h: asked once */
        ck_assert_uint_eq(w.requests, 2 * 123 + 4 + 4 + 1 + 4);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

/* Two devices at one node-ID: a conflict, never one device; the fields
 * they agree on are kept. Also when identical frames merge on the wire. */
static void two_at_one(bool merge, uint32_t latency_b, uint8_t node_id) {
        membus *b = membus_new(125000);
        wire w;
        wire_start(&w, b);
        membus_set_merge_identical(b, merge);
        lss_identity a = { 0x9A, 3, 1, 100 }, c = { 0x9A, 3, 1, 200 }, other = { 0xEC, 0x1234, 5, 6 };
        lss_slave_faults fb = faults_latency(latency_b, 0);
        membus_add_slave(b, &a, node_id, NULL);
        membus_add_slave(b, &c, node_id, &fb);
        membus_add_slave(b, &other, node_id - 1, NULL);
        lss_master *m = master_default();
        const lss_result *r = discover(m, b, 1, 127, 0);
        ck_assert_uint_eq(r->n_sdo_nodes, 2);
        const lss_sdo_node *d = node_of(r, node_id);
        ck_assert_ptr_nonnull(d);
        ck_assert(d->conflict);
        ck_assert_uint_eq(d->known, 0x7); /* vendor, product, revision agree; the serial does not */
        ck_assert_uint_eq(d->id.vendor, 0x9A);
        expect_identity(r, node_id - 1, &other);
        ck_assert_uint_eq(lss_master_get_stats(m)->conflicts, 1);
        lss_master_free(m);
        membus_free(b);
}

START_TEST(sdo_discover_two_at_one_node_id) {
        two_at_one(false, 0, 9);
        two_at_one(true, 0, 9);
        /* the second one answers after the first's answer moved the pass on */
        two_at_one(false, 3000, 9);
        two_at_one(true, 15000, 9);
        /* ... and after the last request of the pass */
        two_at_one(true, 15000, 127);
}
END_TEST

/* A device in NMT Stopped does not answer SDO: not found, and nothing is
 * sent to wake it. With a heartbeat it is heard, in state Stopped. Other
 * devices' heartbeats and boot-ups are recorded, in the range or not. */
START_TEST(sdo_discover_stopped_and_heard) {
        membus *b = bus_configured(4, 31, NULL);
        membus_slave(b, 1)->st.nmt = SLAVE_NMT_STOPPED;
        membus_slave(b, 2)->st.nmt = SLAVE_NMT_STOPPED;
        lss_slave_set_heartbeat(membus_slave(b, 2), 50);
        lss_identity far = { 7, 7, 7, 7 };
        size_t i_far = membus_add_slave(b, &far, 100, NULL);
        lss_slave_set_heartbeat(membus_slave(b, i_far), 50);
        lss_slave_set_heartbeat(membus_slave(b, 3), 100);
        wire w;
        wire_start(&w, b);
        lss_master *m = master_default();
        const lss_result *r = discover(m, b, 1, 64, 0);
        ck_assert_uint_eq(w.other_master, 0);
        expect_identity(r, 1, &membus_slave(b, 0)->id);
        ck_assert_ptr_null(node_of(r, 2));
        const lss_sdo_node *d = node_of(r, 3);
        ck_assert_ptr_nonnull(d);
        ck_assert_uint_eq(d->source, LSS_SDO_FROM_HEARD);
        ck_assert_uint_eq(d->known, 0);
        ck_assert_uint_eq(d->nmt_state, 0x04);
        d = node_of(r, 4);
        ck_assert_ptr_nonnull(d);
        ck_assert_uint_eq(d->source, LSS_SDO_FROM_SDO | LSS_SDO_FROM_HEARD);
        ck_assert_uint_eq(d->nmt_state, 0x7F);
        d = node_of(r, 100);
        ck_assert_ptr_nonnull(d);
        ck_assert_uint_eq(d->source, LSS_SDO_FROM_HEARD);
        ck_assert_uint_eq(r->n_sdo_nodes, 4);
        /* the stopped devices are still stopped */
        ck_assert_int_eq(membus_slave(b, 1)->st.nmt, SLAVE_NMT_STOPPED);
        ck_assert_int_eq(membus_slave(b, 2)->st.nmt, SLAVE_NMT_STOPPED);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

START_TEST(sdo_discover_arguments) {
        lss_master *m = master_default();
        const lss_sdo_discover_params bad[] = {
                { 0, 127, 0 }, { 1, 128, 0 }, { 10, 9, 0 }, { 1, 127, LSS_SDO_WINDOW_MAX + 1 }, { 1, 255, 0 },
        };
        for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++)
                ck_assert_int_eq(lss_master_sdo_discover(m, &bad[i], 0), -EINVAL);
        lss_sdo_discover_params ok = { 1, 127, LSS_SDO_WINDOW_MAX };
        ck_assert_int_eq(lss_master_sdo_discover(m, &ok, 0), 0);
        ck_assert_int_eq(lss_master_sdo_discover(m, &ok, 0), -EBUSY);
        /* a cancel ends it; nothing is reported */
        lss_master_cancel(m, 1000);
        ck_assert(lss_master_done(m) || lss_master_busy(m) == false);
        ck_assert_int_eq(lss_master_result(m)->status, LSS_E_CANCELLED);
        ck_assert_uint_eq(lss_master_result(m)->n_sdo_nodes, 0);
        lss_master_free(m);
}
END_TEST

int main(void) {
        Suite *s = suite_create("sdo-discover");
        TCase *tc = tcase_create("core");
        tcase_set_timeout(tc, 120);
        tcase_add_test(tc, sdo_discover_empty);
        tcase_add_test(tc, sdo_discover_one);
        tcase_add_test(tc, sdo_discover_127);
        tcase_add_test(tc, sdo_discover_lost_answers);
        tcase_add_test(tc, sdo_discover_late_answers);
        tcase_add_test(tc, sdo_discover_aborts);
        tcase_add_test(tc, sdo_discover_two_at_one_node_id);
        tcase_add_test(tc, sdo_discover_stopped_and_heard);
        tcase_add_test(tc, sdo_discover_arguments);
        suite_add_tcase(s, tc);
        return run_suite(s);
}
