/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The slave model driven directly: frames in, captured frames out. */
#include <check.h>
#include <stdlib.h>
#include <string.h>

#include "lss/lss_proto.h"
#include "sim/lss_slave.h"

#define CAP_MAX 1024

typedef struct rig {
        lss_slave s;
        lss_frame out[CAP_MAX];
        uint64_t delay[CAP_MAX];
        unsigned n;
        uint64_t now;
} rig;

static const lss_identity ID = { 0x00000319, 0x00A10002, 0x00020005, 0x12345678 };

static void capture(void *ud, const lss_frame *f, uint64_t delay_us) {
        rig *r = ud;
        ck_assert_uint_lt(r->n, CAP_MAX);
        r->out[r->n] = *f;
        r->delay[r->n++] = delay_us;
}

static void rig_init(rig *r, uint8_t node_id, const lss_slave_faults *faults) {
        memset(r, 0, sizeof(*r));
        r->now = 1000;
        lss_slave_init(&r->s, &ID, node_id, 4, faults, 42, capture, r);
}

static void feed(rig *r, const lss_frame *f) {
        lss_slave_on_frame(&r->s, f, r->now);
}

/* Sends a request and returns how many frames came out. */
static unsigned ask(rig *r, const lss_frame *f) {
        unsigned before = r->n;
        feed(r, f);
        return r->n - before;
}

static const lss_frame *last(const rig *r) {
        ck_assert_uint_gt(r->n, 0);
        return &r->out[r->n - 1];
}

static void expect_answer(const rig *r, uint8_t cs, uint8_t b1, uint8_t b2) {
        const lss_frame *f = last(r);
        ck_assert(lss_is_response(f));
        ck_assert_uint_eq(f->data[0], cs);
        ck_assert_uint_eq(f->data[1], b1);
        ck_assert_uint_eq(f->data[2], b2);
        for (unsigned i = 3; i < 8; i++)
                ck_assert_uint_eq(f->data[i], 0);
}

static void expect_bootup(const rig *r, uint8_t nid) {
        uint8_t got = 0, st = 0xAA;
        ck_assert(bootup_decode(last(r), &got, &st));
        ck_assert_uint_eq(got, nid);
        ck_assert_uint_eq(st, 0);
}

/* Switch state global; only a boot-up can come out of it. */
static void global(rig *r, enum lss_mode mode) {
        lss_frame f;
        lss_encode_switch_global(&f, mode);
        unsigned n = ask(r, &f);
        ck_assert_uint_le(n, 1);
        if (n == 1)
                ck_assert(bootup_decode(last(r), NULL, NULL));
        ck_assert(r->s.st.configuration == (mode == LSS_MODE_CONFIGURATION));
}

static unsigned configure_node_id(rig *r, uint8_t nid) {
        lss_frame f;
        lss_encode_configure_node_id(&f, nid);
        return ask(r, &f);
}

/* Configuration state, Configure Node-ID (accepted), waiting again. */
static void give_pending(rig *r, uint8_t nid) {
        global(r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(configure_node_id(r, nid), 1);
        expect_answer(r, 0x11, LSS_ERR_OK, 0);
        global(r, LSS_MODE_WAITING);
}

static unsigned nmt(rig *r, enum nmt_cs cs, uint8_t node) {
        lss_frame f;
        nmt_encode(&f, cs, node);
        return ask(r, &f);
}

/* An NMT command that sends nothing; the NMT state it leaves. */
static enum lss_slave_nmt nmt_quiet(rig *r, enum nmt_cs cs, uint8_t node) {
        ck_assert_uint_eq(nmt(r, cs, node), 0);
        return r->s.st.nmt;
}

static unsigned inquire(rig *r, unsigned field) {
        lss_frame f;
        lss_encode_inquire(&f, field);
        return ask(r, &f);
}

/* Inquire Node-ID, which must be answered: the node-ID answered. */
static uint8_t inquire_node_id(rig *r) {
        ck_assert_uint_eq(inquire(r, LSS_FIELD_COUNT), 1);
        expect_answer(r, 0x5E, last(r)->data[1], 0);
        return last(r)->data[1];
}

static unsigned store(rig *r) {
        lss_frame f;
        lss_encode_store(&f);
        return ask(r, &f);
}

static unsigned bit_timing(rig *r, uint8_t table, uint8_t index) {
        lss_frame f;
        lss_encode_configure_bit_timing(&f, table, index);
        return ask(r, &f);
}

static unsigned activate(rig *r, uint16_t ms) {
        lss_frame f;
        lss_encode_activate_bit_timing(&f, ms);
        return ask(r, &f);
}

static unsigned fastscan(rig *r, uint32_t idn, uint8_t bitcheck, uint8_t sub, uint8_t next) {
        lss_frame f;
        lss_encode_fastscan(&f, idn, bitcheck, sub, next);
        return ask(r, &f);
}

static unsigned selective(rig *r, enum lss_field field, uint32_t v) {
        lss_frame f;
        lss_encode_switch_selective(&f, field, v);
        return ask(r, &f);
}

static unsigned select_all(rig *r, const lss_identity *id) {
        unsigned n = 0;
        for (unsigned i = 0; i < LSS_FIELD_COUNT; i++)
                n += selective(r, i, lss_identity_field(id, i));
        return n;
}

static unsigned identify(rig *r, uint32_t vendor, uint32_t product, uint32_t rev_lo, uint32_t rev_hi,
                         uint32_t ser_lo, uint32_t ser_hi) {
        uint32_t v[6] = { vendor, product, rev_lo, rev_hi, ser_lo, ser_hi };
        unsigned n = 0;
        for (unsigned i = 0; i < 6; i++) {
                lss_frame f;
                lss_encode_identify_remote(&f, i, v[i]);
                unsigned got = ask(r, &f);
                if (i < 5)
                        ck_assert_uint_eq(got, 0);
                n += got;
        }
        return n;
}

START_TEST(init_and_defaults) {
        lss_slave_faults f;
        memset(&f, 0x5A, sizeof(f));
        lss_slave_faults_default(&f);
        ck_assert_int_eq(f.ignore_cs, -1);
        ck_assert(!f.silent && !f.wrong_dlc && !f.duplicate_answers);
        ck_assert_uint_eq(f.latency_us, 0);
        ck_assert_int_eq(f.early_config, SLAVE_EARLY_NONE);

        rig r;
        rig_init(&r, 0x22, NULL);
        ck_assert_uint_eq(r.s.st.active_node_id, 0x22);
        ck_assert_uint_eq(r.s.st.pending_node_id, 0x22);
        ck_assert_uint_eq(r.s.st.stored_node_id, 0x22);
        ck_assert_uint_eq(r.s.st.bit_index, 4);
        ck_assert_uint_eq(r.s.st.stored_bit_index, 4);
        ck_assert(!r.s.st.configuration);
        ck_assert_int_eq(r.s.st.nmt, SLAVE_NMT_PRE_OPERATIONAL);
        ck_assert_int_eq(r.s.fs_sub, -1);
        ck_assert_int_eq(r.s.faults.ignore_cs, -1);
        ck_assert_uint_eq(lss_slave_deadline(&r.s), UINT64_MAX);
        ck_assert_uint_eq(r.s.changes, 0);
        ck_assert_uint_eq(r.n, 0);
        ck_assert(lss_slave_on_bus(&r.s, 4, 0));
        ck_assert(!lss_slave_on_bus(&r.s, 3, 0));
}
END_TEST

START_TEST(switch_global_modes) {
        rig r;
        rig_init(&r, 0x22, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        global(&r, LSS_MODE_CONFIGURATION);
        lss_frame f;
        lss_frame_request(&f, LSS_CS_SWITCH_GLOBAL);
        f.data[1] = 2; /* reserved mode: ignored */
        ck_assert_uint_eq(ask(&r, &f), 0);
        ck_assert(r.s.st.configuration);
        global(&r, LSS_MODE_WAITING);
        global(&r, LSS_MODE_WAITING);
        ck_assert_uint_eq(r.n, 0);
}
END_TEST

START_TEST(configure_node_id_errors) {
        rig r;
        rig_init(&r, 0x22, NULL);
        /* not in configuration: nobody answers */
        ck_assert_uint_eq(configure_node_id(&r, 5), 0);
        ck_assert_uint_eq(r.s.st.pending_node_id, 0x22);
        global(&r, LSS_MODE_CONFIGURATION);

        ck_assert_uint_eq(configure_node_id(&r, 0), 1);
        expect_answer(&r, 0x11, LSS_ERR_NODE_ID_OUT_OF_RANGE, 0);
        ck_assert_uint_eq(configure_node_id(&r, 128), 1);
        expect_answer(&r, 0x11, LSS_ERR_NODE_ID_OUT_OF_RANGE, 0);
        ck_assert_uint_eq(configure_node_id(&r, 0xFE), 1);
        expect_answer(&r, 0x11, LSS_ERR_NODE_ID_OUT_OF_RANGE, 0);
        ck_assert_uint_eq(r.s.st.pending_node_id, 0x22);

        ck_assert_uint_eq(configure_node_id(&r, 127), 1);
        expect_answer(&r, 0x11, LSS_ERR_OK, 0);
        ck_assert_uint_eq(r.s.st.pending_node_id, 127);
        ck_assert_uint_eq(configure_node_id(&r, 1), 1);
        expect_answer(&r, 0x11, LSS_ERR_OK, 0);
        ck_assert_uint_eq(r.s.st.pending_node_id, 1);
        ck_assert_uint_eq(configure_node_id(&r, 0xFF), 1);
        expect_answer(&r, 0x11, LSS_ERR_OK, 0);
        ck_assert_uint_eq(r.s.st.pending_node_id, 0xFF);
        /* inquire returns the active ID until a reset */
        ck_assert_uint_eq(inquire(&r, LSS_FIELD_COUNT), 1);
        expect_answer(&r, 0x5E, 0x22, 0);
        ck_assert_uint_eq(r.s.st.active_node_id, 0x22);
}
END_TEST

START_TEST(non_configured_applies_id_on_waiting) {
        rig r;
        rig_init(&r, 0xFF, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(inquire(&r, LSS_FIELD_COUNT), 1);
        expect_answer(&r, 0x5E, 0xFF, 0);
        ck_assert_uint_eq(configure_node_id(&r, 0x44), 1);
        ck_assert_uint_eq(r.s.st.active_node_id, 0xFF);
        r.n = 0;
        global(&r, LSS_MODE_WAITING);
        ck_assert_uint_eq(r.n, 1);
        expect_bootup(&r, 0x44);
        ck_assert_uint_eq(r.s.st.active_node_id, 0x44);
        ck_assert_int_eq(r.s.st.nmt, SLAVE_NMT_PRE_OPERATIONAL);
        /* only once: it is configured now */
        global(&r, LSS_MODE_WAITING);
        ck_assert_uint_eq(r.n, 1);
}
END_TEST

START_TEST(non_configured_without_id_stays_silent) {
        rig r;
        rig_init(&r, 0xFF, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(configure_node_id(&r, 0xFF), 1);
        r.n = 0;
        global(&r, LSS_MODE_WAITING);
        ck_assert_uint_eq(r.n, 0);
        ck_assert_uint_eq(r.s.st.active_node_id, 0xFF);
        /* an NMT reset of a non-configured node: no ID, no boot-up */
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_COMMUNICATION, 0), 0);
}
END_TEST

START_TEST(configured_applies_id_on_reset_comm) {
        rig r;
        rig_init(&r, 0x22, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(configure_node_id(&r, 0x30), 1);
        r.n = 0;
        global(&r, LSS_MODE_WAITING);
        ck_assert_uint_eq(r.n, 0);
        ck_assert_uint_eq(r.s.st.active_node_id, 0x22);

        /* addressed to another node, to an invalid one: not for us */
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_COMMUNICATION, 0x23), 0);
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_COMMUNICATION, 0x30), 0);
        ck_assert_uint_eq(r.s.st.active_node_id, 0x22);

        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_COMMUNICATION, 0x22), 1);
        expect_bootup(&r, 0x30);
        ck_assert_uint_eq(r.s.st.active_node_id, 0x30);

        /* broadcast (node 0) resets everyone, unconfigure goes through too */
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(configure_node_id(&r, 0xFF), 1);
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_COMMUNICATION, 0), 0);
        ck_assert_uint_eq(r.s.st.active_node_id, 0xFF);
        ck_assert(!r.s.st.configuration);
}
END_TEST

START_TEST(reset_comm_leaves_configuration) {
        rig r;
        rig_init(&r, 0x22, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_COMMUNICATION, 0), 1);
        expect_bootup(&r, 0x22);
        ck_assert(!r.s.st.configuration);
}
END_TEST

START_TEST(nmt_states) {
        rig r;
        rig_init(&r, 0x22, NULL);
        ck_assert_int_eq(nmt_quiet(&r, NMT_CS_START, 0x22), SLAVE_NMT_OPERATIONAL);
        ck_assert_int_eq(nmt_quiet(&r, NMT_CS_STOP, 0), SLAVE_NMT_STOPPED);
        ck_assert_int_eq(nmt_quiet(&r, NMT_CS_PRE_OPERATIONAL, 0x22), SLAVE_NMT_PRE_OPERATIONAL);
        ck_assert_int_eq(nmt_quiet(&r, NMT_CS_START, 0x21), SLAVE_NMT_PRE_OPERATIONAL);
        /* unknown command */
        ck_assert_int_eq(nmt_quiet(&r, (enum nmt_cs) 0x33, 0), SLAVE_NMT_PRE_OPERATIONAL);
        /* NMT frame with a bad DLC is not NMT */
        lss_frame f;
        nmt_encode(&f, NMT_CS_STOP, 0);
        f.len = 3;
        ck_assert_uint_eq(ask(&r, &f), 0);
        ck_assert_int_eq(r.s.st.nmt, SLAVE_NMT_PRE_OPERATIONAL);
        /* the boot-up puts the node back to pre-operational */
        ck_assert_uint_eq(nmt(&r, NMT_CS_START, 0), 0);
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_COMMUNICATION, 0), 1);
        ck_assert_int_eq(r.s.st.nmt, SLAVE_NMT_PRE_OPERATIONAL);
}
END_TEST

START_TEST(store_and_power_on) {
        rig r;
        rig_init(&r, 0x22, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(configure_node_id(&r, 0x40), 1);
        ck_assert_uint_eq(bit_timing(&r, 0, 2), 1);
        ck_assert_uint_eq(store(&r), 1);
        expect_answer(&r, 0x17, LSS_ERR_OK, 0);
        ck_assert_uint_eq(r.s.st.stored_node_id, 0x40);
        ck_assert_uint_eq(r.s.st.stored_bit_index, 2);
        ck_assert_uint_eq(r.s.st.active_node_id, 0x22);
        ck_assert_uint_eq(r.s.st.bit_index, 4);

        /* changed again but not stored: lost on power cycle */
        ck_assert_uint_eq(configure_node_id(&r, 0x41), 1);
        r.n = 0;
        lss_slave_power_on(&r.s, 5000);
        ck_assert_uint_eq(r.n, 1);
        expect_bootup(&r, 0x40);
        ck_assert_uint_eq(r.s.st.active_node_id, 0x40);
        ck_assert_uint_eq(r.s.st.pending_node_id, 0x40);
        ck_assert_uint_eq(r.s.st.bit_index, 2);
        ck_assert_uint_eq(r.s.st.pending_bit_index, 2);
        ck_assert(!r.s.st.configuration);
        ck_assert(lss_slave_on_bus(&r.s, 2, 5000));
        ck_assert(!lss_slave_on_bus(&r.s, 4, 5000));
}
END_TEST

START_TEST(power_on_non_configured) {
        rig r;
        rig_init(&r, 0xFF, NULL);
        lss_slave_power_on(&r.s, 0);
        ck_assert_uint_eq(r.n, 0);
        ck_assert_uint_eq(r.s.changes, 0);
        /* stored 0xFF ("none") after a store of 0xFF: comes up non-configured */
        rig_init(&r, 0x10, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(configure_node_id(&r, 0xFF), 1);
        ck_assert_uint_eq(store(&r), 1);
        r.n = 0;
        lss_slave_power_on(&r.s, 0);
        ck_assert_uint_eq(r.n, 0);
        ck_assert_uint_eq(r.s.st.active_node_id, 0xFF);
}
END_TEST

START_TEST(reset_node_restores_stored) {
        rig r;
        rig_init(&r, 0x22, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(configure_node_id(&r, 0x40), 1);
        ck_assert_uint_eq(store(&r), 1);
        ck_assert_uint_eq(configure_node_id(&r, 0x41), 1);
        ck_assert_uint_eq(bit_timing(&r, 0, 3), 1);
        global(&r, LSS_MODE_WAITING);
        r.n = 0;
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_NODE, 0x22), 1);
        expect_bootup(&r, 0x40);
        ck_assert_uint_eq(r.s.st.active_node_id, 0x40);
        ck_assert_uint_eq(r.s.st.pending_node_id, 0x40);
        ck_assert_uint_eq(r.s.st.pending_bit_index, 4);
}
END_TEST

START_TEST(store_errors) {
        lss_slave_faults f;
        rig r;

        lss_slave_faults_default(&f);
        f.store_unsupported = true;
        rig_init(&r, 0x22, &f);
        ck_assert_uint_eq(store(&r), 0); /* waiting: not for us */
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(configure_node_id(&r, 0x40), 1);
        ck_assert_uint_eq(store(&r), 1);
        expect_answer(&r, 0x17, LSS_ERR_STORE_NOT_SUPPORTED, 0);
        ck_assert_uint_eq(r.s.st.stored_node_id, 0x22);

        lss_slave_faults_default(&f);
        f.store_fails = true;
        rig_init(&r, 0x22, &f);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(configure_node_id(&r, 0x40), 1);
        ck_assert_uint_eq(store(&r), 1);
        expect_answer(&r, 0x17, LSS_ERR_STORE_MEDIA, 0);
        ck_assert_uint_eq(r.s.st.stored_node_id, 0x22);
}
END_TEST

START_TEST(bit_timing_errors) {
        rig r;
        rig_init(&r, 0x22, NULL);
        ck_assert_uint_eq(bit_timing(&r, 0, 2), 0);
        global(&r, LSS_MODE_CONFIGURATION);
        for (uint8_t i = 0; i <= 8; i++) {
                ck_assert_uint_eq(bit_timing(&r, 0, i), 1);
                expect_answer(&r, 0x13, LSS_ERR_OK, 0);
                ck_assert_uint_eq(r.s.st.pending_bit_index, i);
        }
        ck_assert_uint_eq(bit_timing(&r, 0, 9), 1); /* automatic detection */
        expect_answer(&r, 0x13, LSS_ERR_BIT_RATE_NOT_SUPPORTED, 0);
        ck_assert_uint_eq(bit_timing(&r, 0, 200), 1);
        expect_answer(&r, 0x13, LSS_ERR_BIT_RATE_NOT_SUPPORTED, 0);
        ck_assert_uint_eq(bit_timing(&r, 1, 2), 1);
        expect_answer(&r, 0x13, LSS_ERR_BIT_RATE_NOT_SUPPORTED, 0);
        ck_assert_uint_eq(bit_timing(&r, 128, 2), 1);
        expect_answer(&r, 0x13, LSS_ERR_BIT_RATE_NOT_SUPPORTED, 0);
        ck_assert_uint_eq(r.s.st.pending_bit_index, 8);
        ck_assert_uint_eq(r.s.st.bit_index, 4);

        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.bit_index_unsupported = (1u << 5) | (1u << 1);
        rig_init(&r, 0x22, &f);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(bit_timing(&r, 0, 5), 1);
        expect_answer(&r, 0x13, LSS_ERR_BIT_RATE_NOT_SUPPORTED, 0);
        ck_assert_uint_eq(bit_timing(&r, 0, 1), 1);
        expect_answer(&r, 0x13, LSS_ERR_BIT_RATE_NOT_SUPPORTED, 0);
        ck_assert_uint_eq(r.s.st.pending_bit_index, 4);
        ck_assert_uint_eq(bit_timing(&r, 0, 6), 1);
        expect_answer(&r, 0x13, LSS_ERR_OK, 0);

        lss_slave_faults_default(&f);
        f.bit_timing_silent = true;
        rig_init(&r, 0x22, &f);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(bit_timing(&r, 0, 2), 0);
        ck_assert_uint_eq(r.s.st.pending_bit_index, 4);
        ck_assert_uint_eq(r.s.changes, 1); /* entering configuration only */
}
END_TEST

START_TEST(activation_window) {
        rig r;
        rig_init(&r, 0x22, NULL);
        /* waiting slaves do not take part */
        ck_assert_uint_eq(activate(&r, 10), 0);
        ck_assert_uint_eq(lss_slave_deadline(&r.s), UINT64_MAX);

        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(bit_timing(&r, 0, 2), 1);
        r.now = 1000;
        ck_assert(lss_slave_on_bus(&r.s, 4, 999));
        ck_assert_uint_eq(activate(&r, 10), 0);
        ck_assert_uint_eq(lss_slave_deadline(&r.s), 11000);
        /* first period: still the old rate, but off the bus */
        ck_assert(!lss_slave_on_bus(&r.s, 4, 1000));
        ck_assert(!lss_slave_on_bus(&r.s, 2, 1000));
        ck_assert(!lss_slave_on_bus(&r.s, 4, 10999));
        ck_assert_uint_eq(r.s.st.bit_index, 4);
        /* deaf inside the window */
        r.now = 5000;
        ck_assert_uint_eq(inquire(&r, LSS_FIELD_COUNT), 0);
        lss_slave_on_time(&r.s, 11000);
        ck_assert_uint_eq(r.s.st.bit_index, 2);
        ck_assert_uint_eq(lss_slave_deadline(&r.s), UINT64_MAX);
        /* second period: switched, still silent */
        ck_assert(!lss_slave_on_bus(&r.s, 2, 11000));
        ck_assert(!lss_slave_on_bus(&r.s, 2, 20999));
        r.now = 20999;
        ck_assert_uint_eq(inquire(&r, LSS_FIELD_COUNT), 0);
        ck_assert(lss_slave_on_bus(&r.s, 2, 21000));
        ck_assert(!lss_slave_on_bus(&r.s, 4, 21000));
        r.now = 21000;
        ck_assert_uint_eq(inquire(&r, LSS_FIELD_COUNT), 1);
        expect_answer(&r, 0x5E, 0x22, 0);
        /* still in configuration: the master ends it at the new rate */
        ck_assert(r.s.st.configuration);
        /* the new rate is volatile until stored */
        ck_assert_uint_eq(r.s.st.stored_bit_index, 4);
}
END_TEST

START_TEST(activation_switch_without_on_time) {
        rig r;
        rig_init(&r, 0x22, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(bit_timing(&r, 0, 7), 1);
        ck_assert_uint_eq(activate(&r, 2), 0);
        /* on_bus works out the switch even when on_time() was not called */
        ck_assert(lss_slave_on_bus(&r.s, 7, 5000));
        ck_assert(!lss_slave_on_bus(&r.s, 4, 5000));
        /* and a frame after the window applies it */
        r.now = 5000;
        ck_assert_uint_eq(inquire(&r, LSS_FIELD_VENDOR), 1);
        ck_assert_uint_eq(r.s.st.bit_index, 7);
}
END_TEST

START_TEST(activation_zero_delay_and_missed) {
        rig r;
        rig_init(&r, 0x22, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(bit_timing(&r, 0, 0), 1);
        ck_assert_uint_eq(activate(&r, 0), 0);
        ck_assert_uint_eq(r.s.st.bit_index, 0);
        ck_assert(lss_slave_on_bus(&r.s, 0, r.now));
        ck_assert_uint_eq(lss_slave_deadline(&r.s), UINT64_MAX);

        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.miss_activation = true;
        rig_init(&r, 0x22, &f);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(bit_timing(&r, 0, 0), 1);
        ck_assert_uint_eq(activate(&r, 10), 0);
        ck_assert_uint_eq(lss_slave_deadline(&r.s), UINT64_MAX);
        ck_assert(lss_slave_on_bus(&r.s, 4, r.now + 5000));
        ck_assert(lss_slave_on_bus(&r.s, 4, r.now + 50000));
        ck_assert_uint_eq(r.s.st.bit_index, 4);
}
END_TEST

START_TEST(power_on_cancels_activation) {
        rig r;
        rig_init(&r, 0x22, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(bit_timing(&r, 0, 2), 1);
        ck_assert_uint_eq(activate(&r, 100), 0);
        lss_slave_power_on(&r.s, 2000);
        ck_assert_uint_eq(lss_slave_deadline(&r.s), UINT64_MAX);
        ck_assert(lss_slave_on_bus(&r.s, 4, 2000));
        ck_assert_uint_eq(r.s.st.bit_index, 4);
}
END_TEST

START_TEST(inquire_services) {
        rig r;
        rig_init(&r, 0x22, NULL);
        for (unsigned i = 0; i <= LSS_FIELD_COUNT; i++)
                ck_assert_uint_eq(inquire(&r, i), 0);
        global(&r, LSS_MODE_CONFIGURATION);
        for (unsigned i = 0; i < LSS_FIELD_COUNT; i++) {
                ck_assert_uint_eq(inquire(&r, i), 1);
                const lss_frame *f = last(&r);
                ck_assert(lss_is_response(f));
                ck_assert_uint_eq(f->data[0], 0x5A + i);
                ck_assert_uint_eq(lss_get_u32(f->data + 1), lss_identity_field(&ID, i));
                ck_assert_uint_eq(f->data[5] | f->data[6] | f->data[7], 0);
        }
        ck_assert_uint_eq(inquire(&r, LSS_FIELD_COUNT), 1);
        expect_answer(&r, 0x5E, 0x22, 0);
        /* unknown configuration cs: ignored */
        lss_frame f;
        lss_frame_request(&f, 0x5F);
        ck_assert_uint_eq(ask(&r, &f), 0);
        lss_frame_request(&f, 0x19);
        ck_assert_uint_eq(ask(&r, &f), 0);
}
END_TEST

START_TEST(selective_switch) {
        rig r;
        rig_init(&r, 0x22, NULL);
        ck_assert_uint_eq(select_all(&r, &ID), 1);
        expect_answer(&r, 0x44, 0, 0);
        ck_assert(r.s.st.configuration);
        /* already in configuration: selection is not processed */
        ck_assert_uint_eq(select_all(&r, &ID), 0);
        global(&r, LSS_MODE_WAITING);

        /* one wrong field anywhere */
        for (unsigned wrong = 0; wrong < LSS_FIELD_COUNT; wrong++) {
                lss_identity other = ID;
                lss_identity_set_field(&other, wrong, lss_identity_field(&ID, wrong) + 1);
                ck_assert_uint_eq(select_all(&r, &other), 0);
                ck_assert(!r.s.st.configuration);
        }
        /* out of order */
        ck_assert_uint_eq(selective(&r, LSS_FIELD_VENDOR, ID.vendor), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_REVISION, ID.revision), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_SERIAL, ID.serial), 0);
        ck_assert(!r.s.st.configuration);
        /* a mismatch resets: the rest of an earlier good sequence is not enough */
        ck_assert_uint_eq(selective(&r, LSS_FIELD_VENDOR, ID.vendor), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_PRODUCT, ID.product), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_REVISION, ID.revision + 1), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_SERIAL, ID.serial), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_REVISION, ID.revision), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_SERIAL, ID.serial), 0);
        ck_assert(!r.s.st.configuration);
        /* vendor restarts a sequence */
        ck_assert_uint_eq(selective(&r, LSS_FIELD_VENDOR, ID.vendor), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_VENDOR, ID.vendor + 1), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_PRODUCT, ID.product), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_REVISION, ID.revision), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_SERIAL, ID.serial), 0);
        ck_assert(!r.s.st.configuration);
        ck_assert_uint_eq(select_all(&r, &ID), 1);
        ck_assert(r.s.st.configuration);
}
END_TEST

START_TEST(identify_remote_ranges) {
        rig r;
        rig_init(&r, 0x22, NULL);
        const uint32_t rev = ID.revision, ser = ID.serial;
        /* inclusive boundaries */
        ck_assert_uint_eq(identify(&r, ID.vendor, ID.product, rev, rev, ser, ser), 1);
        expect_answer(&r, 0x4F, 0, 0);
        ck_assert_uint_eq(identify(&r, ID.vendor, ID.product, 0, UINT32_MAX, 0, UINT32_MAX), 1);
        ck_assert_uint_eq(identify(&r, ID.vendor, ID.product, rev - 1, rev + 1, ser - 1, ser + 1), 1);
        /* just outside each boundary */
        ck_assert_uint_eq(identify(&r, ID.vendor, ID.product, rev + 1, UINT32_MAX, 0, UINT32_MAX), 0);
        ck_assert_uint_eq(identify(&r, ID.vendor, ID.product, 0, rev - 1, 0, UINT32_MAX), 0);
        ck_assert_uint_eq(identify(&r, ID.vendor, ID.product, 0, UINT32_MAX, ser + 1, UINT32_MAX), 0);
        ck_assert_uint_eq(identify(&r, ID.vendor, ID.product, 0, UINT32_MAX, 0, ser - 1), 0);
        /* vendor and product must be equal */
        ck_assert_uint_eq(identify(&r, ID.vendor + 1, ID.product, 0, UINT32_MAX, 0, UINT32_MAX), 0);
        ck_assert_uint_eq(identify(&r, ID.vendor, ID.product - 1, 0, UINT32_MAX, 0, UINT32_MAX), 0);
        /* a match is not carried over into the next sequence */
        ck_assert_uint_eq(identify(&r, ID.vendor, ID.product, 0, UINT32_MAX, 0, UINT32_MAX), 1);

        /* out of order or incomplete: no answer */
        lss_frame f;
        lss_encode_identify_remote(&f, 5, UINT32_MAX);
        ck_assert_uint_eq(ask(&r, &f), 0);
        lss_encode_identify_remote(&f, 0, ID.vendor);
        ck_assert_uint_eq(ask(&r, &f), 0);
        lss_encode_identify_remote(&f, 1, ID.product);
        ck_assert_uint_eq(ask(&r, &f), 0);
        lss_encode_identify_remote(&f, 3, UINT32_MAX); /* rev_low skipped */
        ck_assert_uint_eq(ask(&r, &f), 0);
        lss_encode_identify_remote(&f, 4, 0);
        ck_assert_uint_eq(ask(&r, &f), 0);
        lss_encode_identify_remote(&f, 5, UINT32_MAX);
        ck_assert_uint_eq(ask(&r, &f), 0);

        /* answered in configuration state and by non-configured slaves too */
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(identify(&r, ID.vendor, ID.product, rev, rev, ser, ser), 1);
        rig_init(&r, 0xFF, NULL);
        ck_assert_uint_eq(identify(&r, ID.vendor, ID.product, rev, rev, ser, ser), 1);
        ck_assert_uint_eq(r.s.changes, 0);
}
END_TEST

START_TEST(identify_non_configured) {
        lss_frame f;
        lss_encode_identify_non_configured(&f);
        rig r;
        rig_init(&r, 0xFF, NULL);
        ck_assert_uint_eq(ask(&r, &f), 1);
        expect_answer(&r, 0x50, 0, 0);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(ask(&r, &f), 1);
        /* a pending ID does not make it configured yet */
        ck_assert_uint_eq(configure_node_id(&r, 0x10), 1);
        ck_assert_uint_eq(ask(&r, &f), 1);
        global(&r, LSS_MODE_WAITING);
        ck_assert_uint_eq(ask(&r, &f), 0);

        rig_init(&r, 0x22, NULL);
        ck_assert_uint_eq(ask(&r, &f), 0);
}
END_TEST

START_TEST(no_identify) {
        lss_slave_faults fl;
        lss_slave_faults_default(&fl);
        fl.no_identify = true;
        rig r;
        rig_init(&r, 0xFF, &fl);
        lss_frame f;
        lss_encode_identify_non_configured(&f);
        ck_assert_uint_eq(ask(&r, &f), 0);
        ck_assert_uint_eq(identify(&r, ID.vendor, ID.product, 0, UINT32_MAX, 0, UINT32_MAX), 0);
        /* the rest still works */
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 1);
        ck_assert_uint_eq(select_all(&r, &ID), 1);
}
END_TEST

/* CANopenNode v4: Fastscan in waiting only while pending and active are
 * both 255; in configuration every Fastscan request and every selective
 * serial number is answered, matching or not. */
START_TEST(canopennode_lss) {
        lss_slave_faults fl;
        lss_slave_faults_default(&fl);
        fl.canopennode_lss = true;
        fl.no_identify = true;
        rig r;
        rig_init(&r, 0xFF, &fl);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 1);
        ck_assert_uint_eq(fastscan(&r, ~ID.vendor, 0, 0, 1), 1); /* no match, answered anyway */
        lss_frame f;
        lss_encode_switch_selective(&f, LSS_FIELD_SERIAL, ID.serial + 1);
        ck_assert_uint_eq(ask(&r, &f), 1);
        expect_answer(&r, LSS_CS_SWITCH_SEL_RESPONSE, 0, 0);
        /* a pending node-ID: out of Fastscan in waiting, still answering in configuration */
        ck_assert_uint_eq(configure_node_id(&r, 0x30), 1);
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 1);
        global(&r, LSS_MODE_WAITING); /* takes the pending node-ID: boot-up */
        ck_assert_uint_eq(r.s.st.active_node_id, 0x30);
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 0);
        /* Configure Node-ID 255 is accepted; pending 255, active 0x30: still out */
        ck_assert_uint_eq(select_all(&r, &ID), 1);
        ck_assert_uint_eq(configure_node_id(&r, 0xFF), 1);
        expect_answer(&r, LSS_CS_CONFIGURE_NODE_ID, 0, 0);
        global(&r, LSS_MODE_WAITING);
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 0);
}
END_TEST

/* The worst case: every Fastscan request answered, in every state. */
START_TEST(fastscan_any) {
        lss_slave_faults fl;
        lss_slave_faults_default(&fl);
        fl.fastscan_any = true;
        rig r;
        rig_init(&r, 0x05, &fl);
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 1);
        ck_assert_uint_eq(fastscan(&r, ~ID.vendor, 0, 0, 1), 1);
        ck_assert(!r.s.st.configuration);
        ck_assert_uint_eq(fastscan(&r, 0, 0, 3, 0), 1); /* back to the vendor: "found" */
        ck_assert(r.s.st.configuration);
        ck_assert_uint_eq(fastscan(&r, 0, 7, 1, 1), 1);
}
END_TEST

/* The master side of fastscan, against the rig's one slave. */
static void scan(rig *r, lss_identity *found) {
        ck_assert_uint_eq(fastscan(r, 0, LSS_FASTSCAN_PING, 0, 0), 1);
        for (unsigned sub = 0; sub < LSS_FIELD_COUNT; sub++) {
                uint32_t v = 0;
                for (int bit = 31; bit >= 0; bit--)
                        if (fastscan(r, v, (uint8_t) bit, (uint8_t) sub, (uint8_t) sub) == 0)
                                v |= UINT32_C(1) << bit;
                ck_assert(!r->s.st.configuration);
                ck_assert_uint_eq(fastscan(r, v, 0, (uint8_t) sub, (uint8_t) ((sub + 1) % LSS_FIELD_COUNT)), 1);
                lss_identity_set_field(found, sub, v);
        }
}

START_TEST(fastscan_full) {
        rig r;
        rig_init(&r, 0xFF, NULL);
        lss_identity found = { 0 };
        scan(&r, &found);
        ck_assert(lss_identity_equal(&found, &ID));
        ck_assert(r.s.st.configuration);
        ck_assert_int_eq(r.s.fs_sub, -1);
        /* in configuration: no more fastscan */
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 0);
        ck_assert_uint_eq(inquire(&r, LSS_FIELD_SERIAL), 1);
}
END_TEST

START_TEST(fastscan_bitcheck) {
        rig r;
        rig_init(&r, 0xFF, NULL);
        /* no ping yet: not scanning */
        ck_assert_uint_eq(fastscan(&r, ID.vendor, 0, 0, 1), 0);
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 1);
        expect_answer(&r, 0x4F, 0, 0);
        ck_assert_int_eq(r.s.fs_sub, 0);
        /* bits bitcheck..31 compared, lower ones ignored */
        ck_assert_uint_eq(fastscan(&r, ID.vendor ^ 0x7F, 7, 0, 0), 1);
        ck_assert_uint_eq(fastscan(&r, ID.vendor ^ 0x80, 7, 0, 0), 0);
        ck_assert_uint_eq(fastscan(&r, ID.vendor ^ 0x80000000u, 31, 0, 0), 0);
        ck_assert_uint_eq(fastscan(&r, ID.vendor & 0x80000000u, 31, 0, 0), 1);
        ck_assert_uint_eq(fastscan(&r, ID.vendor ^ 1, 0, 0, 1), 0);
        ck_assert_int_eq(r.s.fs_sub, 0);
        /* wrong sub: silence */
        ck_assert_uint_eq(fastscan(&r, ID.product, 0, 1, 2), 0);
        /* invalid: bitcheck 32..0x7F, 0x81.., sub or next > 3 */
        ck_assert_uint_eq(fastscan(&r, ID.vendor, 32, 0, 1), 0);
        ck_assert_uint_eq(fastscan(&r, ID.vendor, 0x7F, 0, 1), 0);
        ck_assert_uint_eq(fastscan(&r, 0, 0x81, 0, 0), 0);
        ck_assert_uint_eq(fastscan(&r, ID.vendor, 0, 4, 1), 0);
        ck_assert_uint_eq(fastscan(&r, ID.vendor, 0, 0, 4), 0); /* the lssnext = 4 bug */
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 4), 0);
        ck_assert_int_eq(r.s.fs_sub, 0);
        /* confirm vendor, jump straight to serial (known fields may be skipped) */
        ck_assert_uint_eq(fastscan(&r, ID.vendor, 0, 0, 3), 1);
        ck_assert_int_eq(r.s.fs_sub, 3);
        ck_assert_uint_eq(fastscan(&r, ID.product, 0, 1, 2), 0);
        ck_assert(!r.s.st.configuration);
        /* lssnext == lsssub on the serial: stays, not yet found */
        ck_assert_uint_eq(fastscan(&r, ID.serial, 0, 3, 3), 1);
        ck_assert(!r.s.st.configuration);
        /* lssnext back to 0 after the serial: found */
        ck_assert_uint_eq(fastscan(&r, ID.serial, 0, 3, 0), 1);
        ck_assert(r.s.st.configuration);
}
END_TEST

START_TEST(fastscan_ping_resets) {
        rig r;
        rig_init(&r, 0xFF, NULL);
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 1);
        ck_assert_uint_eq(fastscan(&r, ID.vendor, 0, 0, 1), 1);
        ck_assert_uint_eq(fastscan(&r, ID.product, 0, 1, 2), 1);
        ck_assert_int_eq(r.s.fs_sub, 2);
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 1);
        ck_assert_int_eq(r.s.fs_sub, 0);
        ck_assert_uint_eq(fastscan(&r, ID.revision, 0, 2, 3), 0);
        /* an NMT reset forgets the scan */
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_COMMUNICATION, 0), 0);
        ck_assert_int_eq(r.s.fs_sub, -1);
        ck_assert_uint_eq(fastscan(&r, ID.vendor, 0, 0, 1), 0);
}
END_TEST

START_TEST(fastscan_participation) {
        rig r;
        /* configured: not taking part */
        rig_init(&r, 0x22, NULL);
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 0);

        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.fastscan_when_configured = true;
        rig_init(&r, 0x22, &f);
        lss_identity found = { 0 };
        scan(&r, &found);
        ck_assert(lss_identity_equal(&found, &ID));
        ck_assert(r.s.st.configuration);

        /* non-configured, but in configuration state: silent */
        rig_init(&r, 0xFF, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 0);
}
END_TEST

START_TEST(fastscan_early_config) {
        static const enum lss_slave_early_config modes[] = {
                SLAVE_EARLY_AFTER_VENDOR, SLAVE_EARLY_AFTER_PRODUCT, SLAVE_EARLY_AFTER_REVISION,
        };
        for (unsigned m = 0; m < 3; m++) {
                lss_slave_faults f;
                lss_slave_faults_default(&f);
                f.early_config = modes[m];
                rig r;
                rig_init(&r, 0xFF, &f);
                ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 1);
                for (unsigned sub = 0; sub <= m; sub++) {
                        ck_assert(!r.s.st.configuration);
                        ck_assert_uint_eq(fastscan(&r, lss_identity_field(&ID, sub), 0, (uint8_t) sub,
                                                   (uint8_t) (sub + 1)), 1);
                }
                ck_assert(r.s.st.configuration);
                /* the rest of the scan goes unanswered */
                ck_assert_uint_eq(fastscan(&r, lss_identity_field(&ID, m + 1), 0, (uint8_t) (m + 1),
                                           (uint8_t) ((m + 2) % 4)), 0);
        }
}
END_TEST

START_TEST(needs_nmt_stopped) {
        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.needs_nmt_stopped = true;
        rig r;
        rig_init(&r, 0x22, &f);
        lss_frame g;
        lss_encode_switch_global(&g, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(ask(&r, &g), 0);
        ck_assert(!r.s.st.configuration);
        ck_assert_uint_eq(select_all(&r, &ID), 0);
        ck_assert_uint_eq(identify(&r, ID.vendor, ID.product, 0, UINT32_MAX, 0, UINT32_MAX), 0);
        ck_assert_uint_eq(nmt(&r, NMT_CS_START, 0), 0);
        ck_assert_uint_eq(select_all(&r, &ID), 0);
        ck_assert_uint_eq(nmt(&r, NMT_CS_STOP, 0x22), 0);
        ck_assert_uint_eq(select_all(&r, &ID), 1);
        ck_assert(r.s.st.configuration);
        ck_assert_uint_eq(inquire(&r, LSS_FIELD_COUNT), 1);
        expect_answer(&r, 0x5E, 0x22, 0);
}
END_TEST

START_TEST(strict_request_validation) {
        rig r;
        rig_init(&r, 0xFF, NULL);
        lss_frame good, f;
        lss_encode_switch_global(&good, LSS_MODE_CONFIGURATION);

        f = good;
        f.len = 7;
        ck_assert_uint_eq(ask(&r, &f), 0);
        f = good;
        f.len = 0;
        ck_assert_uint_eq(ask(&r, &f), 0);
        static const uint8_t flags[] = { LSS_FRAME_EFF, LSS_FRAME_RTR, LSS_FRAME_FD, LSS_FRAME_ERR };
        for (unsigned i = 0; i < 4; i++) {
                f = good;
                f.flags = flags[i];
                ck_assert_uint_eq(ask(&r, &f), 0);
        }
        f = good;
        f.id = LSS_COB_SLAVE;
        ck_assert_uint_eq(ask(&r, &f), 0);
        f = good;
        f.id = 0x7E6;
        ck_assert_uint_eq(ask(&r, &f), 0);
        ck_assert(!r.s.st.configuration);
        ck_assert_uint_eq(r.s.changes, 0);

        /* and the ping, for an answering service */
        lss_encode_fastscan(&f, 0, LSS_FASTSCAN_PING, 0, 0);
        f.flags = LSS_FRAME_RTR;
        ck_assert_uint_eq(ask(&r, &f), 0);
        f.flags = 0;
        ck_assert_uint_eq(ask(&r, &f), 1);
        ck_assert_uint_eq(ask(&r, &good), 0);
        ck_assert(r.s.st.configuration);
}
END_TEST

START_TEST(fault_silent) {
        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.silent = true;
        rig r;
        rig_init(&r, 0xFF, &f);
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 0);
        ck_assert_uint_eq(select_all(&r, &ID), 0);
        ck_assert(r.s.st.configuration); /* obeys */
        ck_assert_uint_eq(configure_node_id(&r, 0x33), 0);
        ck_assert_uint_eq(r.s.st.pending_node_id, 0x33);
        ck_assert_uint_eq(inquire(&r, LSS_FIELD_COUNT), 0);
        /* boot-ups still go out */
        global(&r, LSS_MODE_WAITING);
        ck_assert_uint_eq(r.n, 1);
        expect_bootup(&r, 0x33);
}
END_TEST

START_TEST(fault_ignore_cs) {
        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.ignore_cs = LSS_CS_STORE;
        rig r;
        rig_init(&r, 0x22, &f);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(configure_node_id(&r, 0x40), 1);
        ck_assert_uint_eq(store(&r), 0);
        ck_assert_uint_eq(r.s.st.stored_node_id, 0x22);

        f.ignore_cs = LSS_CS_SWITCH_GLOBAL;
        rig_init(&r, 0x22, &f);
        lss_frame g;
        lss_encode_switch_global(&g, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(ask(&r, &g), 0);
        ck_assert(!r.s.st.configuration);
        ck_assert_uint_eq(select_all(&r, &ID), 1);
}
END_TEST

START_TEST(fault_wrong_dlc_and_duplicates) {
        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.wrong_dlc = true;
        rig r;
        rig_init(&r, 0x22, &f);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(inquire(&r, LSS_FIELD_COUNT), 1);
        ck_assert_uint_eq(last(&r)->len, 7);
        ck_assert(!lss_is_response(last(&r)));
        ck_assert_uint_eq(last(&r)->data[0], 0x5E);
        /* boot-ups are not LSS answers */
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_COMMUNICATION, 0), 1);
        ck_assert_uint_eq(last(&r)->len, 1);

        lss_slave_faults_default(&f);
        f.duplicate_answers = true;
        f.latency_us = 300;
        rig_init(&r, 0x22, &f);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(inquire(&r, LSS_FIELD_SERIAL), 2);
        ck_assert_mem_eq(&r.out[0], &r.out[1], sizeof(lss_frame));
        ck_assert_uint_eq(r.delay[0], 300);
        ck_assert_uint_eq(r.delay[1], 300);
        ck_assert_uint_eq(lss_get_u32(r.out[1].data + 1), ID.serial);
}
END_TEST

START_TEST(fault_configure_error_specific) {
        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.configure_error_specific = true;
        rig r;
        rig_init(&r, 0xFF, &f);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(configure_node_id(&r, 0x10), 1);
        expect_answer(&r, 0x11, LSS_ERR_SPECIFIC, 0x42);
        ck_assert_uint_eq(r.s.st.pending_node_id, 0xFF);
        global(&r, LSS_MODE_WAITING);
        ck_assert_uint_eq(r.n, 1);
}
END_TEST

static void collect_delays(uint64_t seed, uint32_t lat, uint32_t jit, uint64_t *d, unsigned n) {
        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.latency_us = lat;
        f.jitter_us = jit;
        rig r;
        rig_init(&r, 0xFF, &f);
        r.s.rng = seed;
        for (unsigned i = 0; i < n; i++) {
                /* spaced out so that the transmit queue does not hold them back */
                r.now += 10000;
                ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 1);
                d[i] = r.delay[i];
        }
}

START_TEST(latency_and_jitter) {
        enum { N = 40 };
        uint64_t a[N], b[N], c[N];
        collect_delays(7, 500, 0, a, N);
        for (unsigned i = 0; i < N; i++)
                ck_assert_uint_eq(a[i], 500);

        collect_delays(7, 500, 1000, a, N);
        collect_delays(7, 500, 1000, b, N);
        collect_delays(8, 500, 1000, c, N);
        ck_assert_mem_eq(a, b, sizeof(a));
        bool differs = false, spread = false;
        for (unsigned i = 0; i < N; i++) {
                ck_assert_uint_ge(a[i], 500);
                ck_assert_uint_le(a[i], 1500);
                differs |= a[i] != c[i];
                spread |= a[i] != a[0];
        }
        ck_assert(differs);
        ck_assert(spread);
}
END_TEST

START_TEST(answers_keep_order) {
        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.latency_us = 100;
        f.jitter_us = 5000;
        rig r;
        rig_init(&r, 0x22, &f);
        global(&r, LSS_MODE_CONFIGURATION);
        /* back-to-back requests: ready times never go backwards */
        uint64_t prev = 0;
        for (unsigned i = 0; i < 30; i++) {
                r.now += 10;
                ck_assert_uint_eq(inquire(&r, i % 5), 1);
                uint64_t ready = r.now + r.delay[r.n - 1];
                ck_assert_uint_ge(ready, prev);
                ck_assert_uint_ge(r.delay[r.n - 1], 100);
                prev = ready;
        }
}
END_TEST

START_TEST(changes_counter) {
        rig r;
        rig_init(&r, 0xFF, NULL);
        unsigned c = r.s.changes;
        /* no state change, no count */
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 1);
        lss_frame f;
        lss_encode_identify_non_configured(&f);
        ck_assert_uint_eq(ask(&r, &f), 1);
        ck_assert_uint_eq(r.s.changes, c);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(r.s.changes, ++c);
        ck_assert_uint_eq(inquire(&r, LSS_FIELD_VENDOR), 1);
        ck_assert_uint_eq(r.s.changes, c);
        ck_assert_uint_eq(configure_node_id(&r, 0x12), 1);
        ck_assert_uint_eq(r.s.changes, ++c);
        ck_assert_uint_eq(configure_node_id(&r, 0x12), 1); /* same value again */
        ck_assert_uint_eq(r.s.changes, c);
        ck_assert_uint_eq(store(&r), 1);
        ck_assert_uint_eq(r.s.changes, ++c);
        ck_assert_uint_eq(bit_timing(&r, 0, 3), 1);
        ck_assert_uint_eq(r.s.changes, ++c);
        ck_assert_uint_eq(activate(&r, 1), 0);
        ck_assert_uint_eq(r.s.changes, c);
        lss_slave_on_time(&r.s, r.now + 1000);
        ck_assert_uint_eq(r.s.changes, ++c); /* the switch */
        lss_slave_on_time(&r.s, r.now + 5000);
        ck_assert_uint_eq(r.s.changes, c);
        r.now += 5000;
        global(&r, LSS_MODE_WAITING);
        ck_assert_uint_eq(r.s.changes, ++c);
        lss_slave_power_on(&r.s, r.now);
        ck_assert_uint_eq(r.s.changes, ++c); /* stored bit index 4 back */
}
END_TEST

/* An SDO request to node 0x22 (index, sub-index, command byte). */
static unsigned sdo(rig *r, uint8_t cs, uint16_t index, uint8_t sub) {
        lss_frame f = { .id = 0x622, .len = 8, .data = { cs, (uint8_t) index, (uint8_t) (index >> 8), sub } };
        return ask(r, &f);
}

/* The last frame is the SDO answer of node 0x22 to index:sub with this
 * command byte and 32-bit payload. */
static void expect_sdo(const rig *r, uint8_t cs, uint16_t index, uint8_t sub, uint32_t v) {
        const lss_frame *f = last(r);
        ck_assert_uint_eq(f->id, 0x5A2);
        ck_assert_uint_eq(f->len, 8);
        ck_assert_uint_eq(f->flags, 0);
        ck_assert_uint_eq(f->data[0], cs);
        ck_assert_uint_eq(lss_get_u16(f->data + 1), index);
        ck_assert_uint_eq(f->data[3], sub);
        ck_assert_uint_eq(lss_get_u32(f->data + 4), v);
}

/* Default faults but for the heartbeat and the transmit loss. */
static lss_slave_faults faults_with(uint16_t heartbeat_ms, uint32_t tx_loss_ppm) {
        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.heartbeat_ms = heartbeat_ms;
        f.tx_loss_ppm = tx_loss_ppm;
        return f;
}

/* 1018h from the LSS address, 1000h, 1017h: expedited uploads with the size
 * indicated; everything else aborted with the CiA 301 code. */
START_TEST(sdo_identity_object) {
        rig r;
        lss_slave_faults f = faults_with(250, 0);
        rig_init(&r, 0x22, &f);
        static const struct {
                uint8_t cs;
                uint16_t index;
                uint8_t sub, answer;
                uint32_t value;
        } cases[] = {
                { 0x40, 0x1018, 0, 0x4F, 4 },
                { 0x40, 0x1018, 1, 0x43, 0x00000319 },
                { 0x40, 0x1018, 2, 0x43, 0x00A10002 },
                { 0x40, 0x1018, 3, 0x43, 0x00020005 },
                { 0x40, 0x1018, 4, 0x43, 0x12345678 },
                { 0x40, 0x1000, 0, 0x43, 0x00000192 },
                { 0x40, 0x1017, 0, 0x4B, 250 },
                /* aborts */
                { 0x40, 0x1018, 5, 0x80, 0x06090011 },
                { 0x40, 0x1000, 1, 0x80, 0x06090011 },
                { 0x40, 0x2000, 0, 0x80, 0x06020000 },
                /* downloads: never written */
                { 0x23, 0x1017, 0, 0x80, 0x06010002 },
                { 0x2F, 0x1018, 1, 0x80, 0x06010002 },
                { 0x23, 0x6000, 0, 0x80, 0x06020000 },
                /* other commands: segment requests, block transfers */
                { 0x60, 0x1018, 1, 0x80, 0x05040001 },
                { 0xA4, 0x1018, 1, 0x80, 0x05040001 },
        };
        for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
                ck_assert_uint_eq(sdo(&r, cases[i].cs, cases[i].index, cases[i].sub), 1);
                expect_sdo(&r, cases[i].answer, cases[i].index, cases[i].sub, cases[i].value);
        }
        ck_assert_uint_eq(r.s.faults.heartbeat_ms, 250);
        /* the client's abort is not answered */
        ck_assert_uint_eq(sdo(&r, 0x80, 0x1018, 1), 0);
        /* another node's request, a short frame: nothing */
        lss_frame o = { .id = 0x623, .len = 8, .data = { 0x40, 0x18, 0x10, 0x01 } };
        ck_assert_uint_eq(ask(&r, &o), 0);
        o.id = 0x622;
        o.len = 4;
        ck_assert_uint_eq(ask(&r, &o), 0);
        /* a non-configured slave has no SDO server */
        rig_init(&r, 0xFF, NULL);
        ck_assert_uint_eq(sdo(&r, 0x40, 0x1018, 1), 0);
}
END_TEST

/* No SDO in Stopped; pre-operational and operational answer. */
START_TEST(sdo_silent_when_stopped) {
        rig r;
        rig_init(&r, 0x22, NULL);
        ck_assert_uint_eq(nmt(&r, NMT_CS_STOP, 0x22), 0);
        ck_assert_uint_eq(sdo(&r, 0x40, 0x1018, 1), 0);
        ck_assert_uint_eq(sdo(&r, 0x40, 0x1000, 0), 0);
        ck_assert_uint_eq(sdo(&r, 0x23, 0x1017, 0), 0);
        ck_assert_uint_eq(nmt(&r, NMT_CS_START, 0), 0);
        ck_assert_uint_eq(sdo(&r, 0x40, 0x1018, 4), 1);
        expect_sdo(&r, 0x43, 0x1018, 4, ID.serial);
        ck_assert_uint_eq(nmt(&r, NMT_CS_STOP, 0), 0);
        ck_assert_uint_eq(sdo(&r, 0x40, 0x1018, 4), 0);
        ck_assert_uint_eq(nmt(&r, NMT_CS_PRE_OPERATIONAL, 0x22), 0);
        ck_assert_uint_eq(sdo(&r, 0x40, 0x1018, 4), 1);
        /* a reset from Stopped: boot-up, pre-operational, answers again */
        ck_assert_uint_eq(nmt(&r, NMT_CS_STOP, 0), 0);
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_NODE, 0x22), 1);
        expect_bootup(&r, 0x22);
        ck_assert_int_eq(r.s.st.nmt, SLAVE_NMT_PRE_OPERATIONAL);
        ck_assert_uint_eq(sdo(&r, 0x40, 0x1018, 1), 1);
}
END_TEST

/* Heartbeat: every period from the boot-up, with the NMT state, also in
 * Stopped; none without a node-ID; 0 = off. */
START_TEST(heartbeat_producer) {
        rig r;
        lss_slave_faults f = faults_with(100, 0);
        memset(&r, 0, sizeof(r));
        lss_slave_init(&r.s, &ID, 0x22, 4, &f, 42, capture, &r);
        lss_slave_power_on(&r.s, 5000);
        ck_assert_uint_eq(r.n, 1);
        expect_bootup(&r, 0x22);
        ck_assert_uint_eq(lss_slave_deadline(&r.s), 105000);
        lss_slave_on_time(&r.s, 104999);
        ck_assert_uint_eq(r.n, 1);
        lss_slave_on_time(&r.s, 105000);
        ck_assert_uint_eq(r.n, 2);
        ck_assert_uint_eq(last(&r)->id, 0x722);
        ck_assert_uint_eq(last(&r)->len, 1);
        ck_assert_uint_eq(last(&r)->data[0], 0x7F);
        ck_assert_uint_eq(lss_slave_deadline(&r.s), 205000);
        r.now = 150000;
        ck_assert_uint_eq(nmt(&r, NMT_CS_START, 0), 0);
        lss_slave_on_time(&r.s, 205000);
        ck_assert_uint_eq(last(&r)->data[0], 0x05);
        r.now = 250000;
        ck_assert_uint_eq(nmt(&r, NMT_CS_STOP, 0), 0);
        lss_slave_on_time(&r.s, 305000);
        ck_assert_uint_eq(r.n, 4);
        ck_assert_uint_eq(last(&r)->data[0], 0x04);
        /* overdue by several periods: one heartbeat, the next a period later */
        lss_slave_on_time(&r.s, 1000000);
        ck_assert_uint_eq(r.n, 5);
        ck_assert_uint_eq(lss_slave_deadline(&r.s), 1100000);
        /* a reset: boot-up, the period starts over */
        r.now = 1050000;
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_COMMUNICATION, 0), 1);
        expect_bootup(&r, 0x22);
        ck_assert_uint_eq(lss_slave_deadline(&r.s), 1150000);
        /* off */
        lss_slave_set_heartbeat(&r.s, 0);
        ck_assert_uint_eq(lss_slave_deadline(&r.s), UINT64_MAX);
        /* non-configured: the timer runs, nothing is sent */
        lss_slave_init(&r.s, &ID, 0xFF, 4, &f, 42, capture, &r);
        unsigned n = r.n;
        lss_slave_on_time(&r.s, 100000);
        lss_slave_on_time(&r.s, 200000);
        ck_assert_uint_eq(r.n, n);
}
END_TEST

/* tx_loss_ppm: frames the slave sends are lost, about as often as asked. */
START_TEST(fault_tx_loss) {
        rig r;
        lss_slave_faults f = faults_with(0, 250000);
        rig_init(&r, 0x22, &f);
        unsigned got = 0;
        for (unsigned i = 0; i < 400; i++) {
                got += sdo(&r, 0x40, 0x1018, 1);
                if (r.n > CAP_MAX - 8)
                        r.n = 0;
        }
        ck_assert_uint_gt(got, 250);
        ck_assert_uint_lt(got, 350);
}
END_TEST

START_TEST(no_emit_callback) {
        lss_slave s;
        lss_slave_init(&s, &ID, 0xFF, 4, NULL, 1, NULL, NULL);
        lss_frame f;
        lss_encode_switch_global(&f, LSS_MODE_CONFIGURATION);
        lss_slave_on_frame(&s, &f, 0);
        lss_encode_configure_node_id(&f, 9);
        lss_slave_on_frame(&s, &f, 0);
        lss_encode_switch_global(&f, LSS_MODE_WAITING);
        lss_slave_on_frame(&s, &f, 0);
        ck_assert_uint_eq(s.st.active_node_id, 9);
}
END_TEST

/* ---- lely-core's LSS slave (lss_slave_faults_lely) ---- */

static void rig_init_lely(rig *r, uint8_t node_id, void (*tweak)(lss_slave_faults *)) {
        lss_slave_faults f;
        lss_slave_faults_lely(&f);
        if (tweak)
                tweak(&f);
        rig_init(r, node_id, &f);
}

/* A configured node-ID waits for an NMT reset, also on a device that had
 * none: the switch to waiting brings no boot-up. */
START_TEST(lely_no_bootup_at_waiting) {
        rig r;
        rig_init_lely(&r, 0xFF, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(configure_node_id(&r, 0x44), 1);
        expect_answer(&r, 0x11, LSS_ERR_OK, 0);
        r.n = 0;
        global(&r, LSS_MODE_WAITING);
        ck_assert_uint_eq(r.n, 0);
        ck_assert_uint_eq(r.s.st.active_node_id, 0xFF);
        ck_assert_uint_eq(r.s.st.pending_node_id, 0x44);
        /* the pending node-ID is no address yet */
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_COMMUNICATION, 0x44), 0);
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_COMMUNICATION, 0), 1);
        expect_bootup(&r, 0x44);
        ck_assert_uint_eq(r.s.st.active_node_id, 0x44);
}
END_TEST

/* Reset Node reloads the object dictionary, not the pending node-ID kept
 * beside it; power-on takes the stored one. */
START_TEST(lely_reset_node_keeps_pending) {
        rig r;
        rig_init_lely(&r, 0x22, NULL);
        give_pending(&r, 0x30);
        r.n = 0;
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_NODE, 0x22), 1);
        expect_bootup(&r, 0x30);
        ck_assert_uint_eq(r.s.st.active_node_id, 0x30);
        ck_assert_uint_eq(r.s.st.pending_node_id, 0x30);
        ck_assert_uint_eq(r.s.st.stored_node_id, 0x22);
        lss_slave_power_on(&r.s, r.now);
        expect_bootup(&r, 0x22);
        ck_assert_uint_eq(r.s.st.pending_node_id, 0x22);

        /* one without a node-ID hears the broadcast */
        rig_init_lely(&r, 0xFF, NULL);
        give_pending(&r, 0x45);
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_NODE, 0), 1);
        expect_bootup(&r, 0x45);
}
END_TEST

/* Inquire Node-ID: the pending node-ID while NMT initialises (the device
 * has no active one), else the active one. */
START_TEST(lely_inquire_pending_while_initialising) {
        rig r;
        rig_init_lely(&r, 0xFF, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(inquire_node_id(&r), 0xFF);
        ck_assert_uint_eq(configure_node_id(&r, 0x44), 1);
        ck_assert_uint_eq(inquire_node_id(&r), 0x44);

        rig_init_lely(&r, 0x22, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(configure_node_id(&r, 0x30), 1);
        ck_assert_uint_eq(inquire_node_id(&r), 0x22);
        /* unconfigured by a reset: initialising again, the pending one counts */
        ck_assert_uint_eq(configure_node_id(&r, 0xFF), 1);
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_COMMUNICATION, 0), 0);
        ck_assert_uint_eq(r.s.st.active_node_id, 0xFF);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(configure_node_id(&r, 0x12), 1);
        ck_assert_uint_eq(inquire_node_id(&r), 0x12);
}
END_TEST

/* lely's NMT obeys a command for node 0 or its own node-ID, 255 on a device
 * without one; such a device stays in its boot-up state, which obeys only
 * the resets. */
START_TEST(lely_nmt_without_node_id) {
        rig r;
        rig_init_lely(&r, 0xFF, NULL);
        ck_assert_int_eq(nmt_quiet(&r, NMT_CS_STOP, 0), SLAVE_NMT_PRE_OPERATIONAL);
        ck_assert_int_eq(nmt_quiet(&r, NMT_CS_START, 0), SLAVE_NMT_PRE_OPERATIONAL);
        give_pending(&r, 0x44);
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_COMMUNICATION, 0xFF), 1);
        expect_bootup(&r, 0x44);
        ck_assert_int_eq(nmt_quiet(&r, NMT_CS_STOP, 0x44), SLAVE_NMT_STOPPED);
        /* with a node-ID, 255 is someone else */
        ck_assert_int_eq(nmt_quiet(&r, NMT_CS_RESET_COMMUNICATION, 0xFF), SLAVE_NMT_STOPPED);
}
END_TEST

/* No bit-rate hook: Configure Bit Timing "not supported" for every table
 * and index, Activate Bit Timing not acted on. */
START_TEST(lely_bit_timing_unsupported) {
        rig r;
        rig_init_lely(&r, 0x22, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        for (uint8_t i = 0; i <= 9; i++) {
                ck_assert_uint_eq(bit_timing(&r, 0, i), 1);
                expect_answer(&r, 0x13, LSS_ERR_BIT_RATE_NOT_SUPPORTED, 0);
        }
        ck_assert_uint_eq(bit_timing(&r, 1, 2), 1);
        expect_answer(&r, 0x13, LSS_ERR_BIT_RATE_NOT_SUPPORTED, 0);
        ck_assert_uint_eq(r.s.st.pending_bit_index, 4);
        ck_assert_uint_eq(activate(&r, 10), 0);
        ck_assert_uint_eq(lss_slave_deadline(&r.s), UINT64_MAX);
        ck_assert(lss_slave_on_bus(&r.s, 4, r.now + 5000));
}
END_TEST

static void store_unsupported(lss_slave_faults *f) {
        f->store_unsupported = true;
}

static void store_fails(lss_slave_faults *f) {
        f->store_fails = true;
}

/* Configure Node-ID takes 1..127 and 255 into the pending node-ID; the
 * store hook stores it (17 00), the store knobs still apply. */
START_TEST(lely_configure_and_store) {
        rig r;
        rig_init_lely(&r, 0x22, NULL);
        global(&r, LSS_MODE_CONFIGURATION);
        static const uint8_t bad[] = { 0, 128, 0xFE };
        for (unsigned i = 0; i < 3; i++) {
                ck_assert_uint_eq(configure_node_id(&r, bad[i]), 1);
                expect_answer(&r, 0x11, LSS_ERR_NODE_ID_OUT_OF_RANGE, 0);
        }
        static const uint8_t good[] = { 1, 127, 0xFF, 0x40 };
        for (unsigned i = 0; i < 4; i++) {
                ck_assert_uint_eq(configure_node_id(&r, good[i]), 1);
                expect_answer(&r, 0x11, LSS_ERR_OK, 0);
                ck_assert_uint_eq(r.s.st.pending_node_id, good[i]);
        }
        ck_assert_uint_eq(r.s.st.active_node_id, 0x22);
        ck_assert_uint_eq(store(&r), 1);
        expect_answer(&r, 0x17, LSS_ERR_OK, 0);
        ck_assert_uint_eq(r.s.st.stored_node_id, 0x40);
        ck_assert_uint_eq(r.s.st.stored_bit_index, 4);

        rig_init_lely(&r, 0x22, store_unsupported);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(store(&r), 1);
        expect_answer(&r, 0x17, LSS_ERR_STORE_NOT_SUPPORTED, 0);
        rig_init_lely(&r, 0x22, store_fails);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(configure_node_id(&r, 0x40), 1);
        ck_assert_uint_eq(store(&r), 1);
        expect_answer(&r, 0x17, LSS_ERR_STORE_MEDIA, 0);
        ck_assert_uint_eq(r.s.st.stored_node_id, 0x22);
}
END_TEST

/* Fastscan in waiting whatever the node-IDs: a configured device is found
 * like one without a node-ID; in configuration Fastscan is ignored. */
START_TEST(lely_fastscan_whatever_node_id) {
        rig r;
        rig_init_lely(&r, 0x22, NULL);
        lss_identity found = { 0 };
        scan(&r, &found);
        ck_assert(lss_identity_equal(&found, &ID));
        ck_assert(r.s.st.configuration);
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 0);
        ck_assert_uint_eq(configure_node_id(&r, 0x30), 1);
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 0);
        global(&r, LSS_MODE_WAITING);
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 1);
}
END_TEST

/* LSSPos is the vendor on entering waiting; a request is answered when it
 * asks about LSSPos and the unmasked bits match, and moves LSSPos to
 * lssnext whatever its bitcheck; the ping always answers and goes back to
 * the vendor; bitcheck 0 with lssnext < lsssub enters configuration. */
START_TEST(lely_fastscan_position) {
        rig r;
        rig_init_lely(&r, 0xFF, NULL);
        /* no ping needed */
        ck_assert_uint_eq(fastscan(&r, ID.vendor & 0x80000000u, 31, 0, 0), 1);
        /* a bit step that names another lssnext moves on */
        ck_assert_uint_eq(fastscan(&r, ID.vendor ^ 0x0F, 4, 0, 1), 1);
        ck_assert_uint_eq(fastscan(&r, ID.vendor, 0, 0, 1), 0);
        ck_assert_uint_eq(fastscan(&r, ID.product ^ 0x10, 4, 1, 1), 0);
        ck_assert_uint_eq(fastscan(&r, ID.product, 0, 1, 2), 1);
        /* lssnext past the serial: answered, then nothing matches */
        ck_assert_uint_eq(fastscan(&r, ID.revision, 0, 2, 4), 1);
        ck_assert_uint_eq(fastscan(&r, ID.revision, 0, 2, 3), 0);
        ck_assert_uint_eq(fastscan(&r, 0, 0, 4, 0), 0);
        /* until a ping, whatever its lsssub and lssnext */
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 7, 9), 1);
        ck_assert_uint_eq(fastscan(&r, ID.vendor, 0, 0, 1), 1);
        /* reserved bitchecks are ignored */
        ck_assert_uint_eq(fastscan(&r, ID.product, 32, 1, 1), 0);
        ck_assert_uint_eq(fastscan(&r, ID.product, 0x81, 1, 1), 0);
        ck_assert(!r.s.st.configuration);
        ck_assert_uint_eq(fastscan(&r, ID.product, 0, 1, 0), 1);
        ck_assert(r.s.st.configuration);
}
END_TEST

/* Entering waiting, also by 04 00 while waiting, starts Fastscan, the
 * selective switch and identify remote slave over. */
START_TEST(lely_waiting_resets_progress) {
        rig r;
        rig_init_lely(&r, 0xFF, NULL);
        ck_assert_uint_eq(fastscan(&r, 0, LSS_FASTSCAN_PING, 0, 0), 1);
        ck_assert_uint_eq(fastscan(&r, ID.vendor, 0, 0, 1), 1);
        global(&r, LSS_MODE_WAITING);
        ck_assert_uint_eq(fastscan(&r, ID.product, 0, 1, 2), 0);
        ck_assert_uint_eq(fastscan(&r, ID.vendor, 0, 0, 1), 1);

        ck_assert_uint_eq(selective(&r, LSS_FIELD_VENDOR, ID.vendor), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_PRODUCT, ID.product), 0);
        global(&r, LSS_MODE_WAITING);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_REVISION, ID.revision), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_SERIAL, ID.serial), 0);
        ck_assert(!r.s.st.configuration);

        lss_frame f;
        for (unsigned i = 0; i < 3; i++) {
                lss_encode_identify_remote(&f, i, i == 0 ? ID.vendor : i == 1 ? ID.product : 0);
                ck_assert_uint_eq(ask(&r, &f), 0);
        }
        global(&r, LSS_MODE_WAITING);
        for (unsigned i = 3; i < 6; i++) {
                lss_encode_identify_remote(&f, i, i == 4 ? 0 : UINT32_MAX);
                ck_assert_uint_eq(ask(&r, &f), 0);
        }

        /* leaving configuration: the vendor again */
        ck_assert_uint_eq(select_all(&r, &ID), 1);
        global(&r, LSS_MODE_WAITING);
        ck_assert_uint_eq(fastscan(&r, ID.vendor, 0, 0, 1), 1);
}
END_TEST

/* Identify non-configured remote slave, in waiting and in configuration,
 * only while the active and the pending node-ID are both 255 (NMT is
 * initialising then: lely keeps a device without node-ID there). */
START_TEST(lely_identify_non_configured) {
        lss_frame f;
        lss_encode_identify_non_configured(&f);
        rig r;
        rig_init_lely(&r, 0xFF, NULL);
        ck_assert_uint_eq(ask(&r, &f), 1);
        expect_answer(&r, 0x50, 0, 0);
        global(&r, LSS_MODE_CONFIGURATION);
        ck_assert_uint_eq(ask(&r, &f), 1);
        ck_assert_uint_eq(configure_node_id(&r, 0x10), 1);
        ck_assert_uint_eq(ask(&r, &f), 0);
        ck_assert_uint_eq(configure_node_id(&r, 0xFF), 1);
        ck_assert_uint_eq(ask(&r, &f), 1);

        rig_init_lely(&r, 0x22, NULL);
        give_pending(&r, 0xFF);
        ck_assert_uint_eq(ask(&r, &f), 0);
        ck_assert_uint_eq(nmt(&r, NMT_CS_RESET_COMMUNICATION, 0), 0);
        ck_assert_uint_eq(ask(&r, &f), 1);
}
END_TEST

static unsigned identify_step(rig *r, unsigned step, uint32_t v) {
        lss_frame f;
        lss_encode_identify_remote(&f, step, v);
        return ask(r, &f);
}

/* One expected command specifier serves the selective switch and identify
 * remote slave: a frame of one breaks a sequence of the other. */
START_TEST(lely_selective_and_identify_share_progress) {
        rig r;
        rig_init_lely(&r, 0x22, NULL);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_VENDOR, ID.vendor), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_PRODUCT, ID.product), 0);
        ck_assert_uint_eq(identify_step(&r, 0, ID.vendor), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_REVISION, ID.revision), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_SERIAL, ID.serial), 0);
        ck_assert(!r.s.st.configuration);

        const uint32_t v[6] = { ID.vendor, ID.product, 0, UINT32_MAX, 0, UINT32_MAX };
        for (unsigned i = 0; i < 3; i++)
                ck_assert_uint_eq(identify_step(&r, i, v[i]), 0);
        ck_assert_uint_eq(selective(&r, LSS_FIELD_VENDOR, ID.vendor), 0);
        for (unsigned i = 3; i < 6; i++)
                ck_assert_uint_eq(identify_step(&r, i, v[i]), 0);

        /* each on its own, identify in configuration too */
        ck_assert_uint_eq(identify(&r, v[0], v[1], v[2], v[3], v[4], v[5]), 1);
        ck_assert_uint_eq(select_all(&r, &ID), 1);
        ck_assert_uint_eq(identify(&r, v[0], v[1], v[2], v[3], v[4], v[5]), 1);
}
END_TEST

int main(void) {
        Suite *s = suite_create("slave");
        TCase *tc = tcase_create("core");
        tcase_add_test(tc, init_and_defaults);
        tcase_add_test(tc, switch_global_modes);
        tcase_add_test(tc, configure_node_id_errors);
        tcase_add_test(tc, non_configured_applies_id_on_waiting);
        tcase_add_test(tc, non_configured_without_id_stays_silent);
        tcase_add_test(tc, configured_applies_id_on_reset_comm);
        tcase_add_test(tc, reset_comm_leaves_configuration);
        tcase_add_test(tc, nmt_states);
        tcase_add_test(tc, store_and_power_on);
        tcase_add_test(tc, power_on_non_configured);
        tcase_add_test(tc, reset_node_restores_stored);
        tcase_add_test(tc, store_errors);
        tcase_add_test(tc, bit_timing_errors);
        tcase_add_test(tc, activation_window);
        tcase_add_test(tc, activation_switch_without_on_time);
        tcase_add_test(tc, activation_zero_delay_and_missed);
        tcase_add_test(tc, power_on_cancels_activation);
        tcase_add_test(tc, inquire_services);
        tcase_add_test(tc, selective_switch);
        tcase_add_test(tc, identify_remote_ranges);
        tcase_add_test(tc, identify_non_configured);
        tcase_add_test(tc, no_identify);
        tcase_add_test(tc, canopennode_lss);
        tcase_add_test(tc, fastscan_any);
        tcase_add_test(tc, fastscan_full);
        tcase_add_test(tc, fastscan_bitcheck);
        tcase_add_test(tc, fastscan_ping_resets);
        tcase_add_test(tc, fastscan_participation);
        tcase_add_test(tc, fastscan_early_config);
        tcase_add_test(tc, needs_nmt_stopped);
        tcase_add_test(tc, strict_request_validation);
        tcase_add_test(tc, fault_silent);
        tcase_add_test(tc, fault_ignore_cs);
        tcase_add_test(tc, fault_wrong_dlc_and_duplicates);
        tcase_add_test(tc, fault_configure_error_specific);
        tcase_add_test(tc, latency_and_jitter);
        tcase_add_test(tc, answers_keep_order);
        tcase_add_test(tc, changes_counter);
        tcase_add_test(tc, no_emit_callback);
        tcase_add_test(tc, sdo_identity_object);
        tcase_add_test(tc, sdo_silent_when_stopped);
        tcase_add_test(tc, heartbeat_producer);
        tcase_add_test(tc, fault_tx_loss);
        suite_add_tcase(s, tc);
        tc = tcase_create("lely");
        tcase_add_test(tc, lely_no_bootup_at_waiting);
        tcase_add_test(tc, lely_reset_node_keeps_pending);
        tcase_add_test(tc, lely_inquire_pending_while_initialising);
        tcase_add_test(tc, lely_nmt_without_node_id);
        tcase_add_test(tc, lely_bit_timing_unsupported);
        tcase_add_test(tc, lely_configure_and_store);
        tcase_add_test(tc, lely_fastscan_whatever_node_id);
        tcase_add_test(tc, lely_fastscan_position);
        tcase_add_test(tc, lely_waiting_resets_progress);
        tcase_add_test(tc, lely_identify_non_configured);
        tcase_add_test(tc, lely_selective_and_identify_share_progress);
        suite_add_tcase(s, tc);
        SRunner *sr = srunner_create(s);
        srunner_run_all(sr, CK_NORMAL);
        int failed = srunner_ntests_failed(sr);
        srunner_free(sr);
        return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
