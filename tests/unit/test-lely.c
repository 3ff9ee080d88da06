/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Devices on Lely's LSS slave (lss_slave_faults_lely: Fastscan answered in
 * waiting whatever the node-ID, a node-ID taken only at NMT reset, Inquire
 * Node-ID giving the pending one while it has none, 13 01 without a rate
 * hook), alone and beside CANopenNode and plain slaves, configured and not,
 * at the default timing: every slave found once with its identity, nobody
 * named misbehaving, every assignment right, SetBitrate refused before
 * anything changes. */
#include "autoassign-util.h"
#include "check-main.h"

#define SEEDS 40

enum kind { PLAIN, LELY, CANOPENNODE };

static lss_slave_faults faults_of(enum kind k, uint64_t *seed) {
        lss_slave_faults f;
        if (k == LELY)
                lss_slave_faults_lely(&f);
        else if (k == CANOPENNODE)
                lss_slave_faults_canopennode(&f);
        else
                lss_slave_faults_default(&f);
        /* 0.5..2.5 ms, jitter up to 1 ms: devices of several makes */
        f.latency_us = 500 + (uint32_t) (sim_random_next(seed) % 2000);
        f.jitter_us = (uint32_t) (sim_random_next(seed) % 1000);
        return f;
}

typedef struct slave_spec {
        enum kind kind;
        uint8_t node_id;
} slave_spec;

/* The slaves of `spec`, random identities of a few vendors. */
static membus *bus_of(const slave_spec *spec, size_t n, uint64_t seed) {
        membus *b = membus_new(125000);
        membus_set_seed(b, seed);
        for (size_t i = 0; i < n; i++) {
                lss_identity id = { .vendor = 0x1A2 + (uint32_t) spec[i].kind, .product = 0xB0B,
                                    .revision = (uint32_t) sim_random_next(&seed),
                                    .serial = (uint32_t) sim_random_next(&seed) };
                lss_slave_faults f = faults_of(spec[i].kind, &seed);
                membus_add_slave(b, &id, spec[i].node_id, &f);
        }
        return b;
}

/* What fastscan can find: a non-configured slave, or a Lely one whatever its node-ID. */
static bool answers_fastscan(const slave_spec *s) {
        return s->node_id == LSS_NODE_ID_UNCONFIGURED || s->kind == LELY;
}

/* A Scan's enumeration: each slave that answers Fastscan found once, with
 * its node-ID, and every slave left as it was. */
static void expect_scan(const slave_spec *spec, size_t n, uint64_t seed) {
        membus *b = bus_of(spec, n, seed);
        lss_slave_state before[16];
        for (size_t i = 0; i < n; i++)
                before[i] = membus_slave(b, i)->st;
        lss_master *m = master_default();
        ck_assert_int_eq(lss_master_enumerate(m, NULL, membus_now(b)), 0);
        const lss_result *r = run(m, b);
        ck_assert_msg(r->status == LSS_OK, "seed %llu: %s", (unsigned long long) seed, r->message);
        size_t want = 0;
        for (size_t i = 0; i < n; i++)
                want += answers_fastscan(&spec[i]);
        ck_assert_msg(r->n_devices == want, "seed %llu: %zu found, want %zu", (unsigned long long) seed, r->n_devices,
                      want);
        assert_devices_real(b, r);
        lss_drive_idle(b, 100000);
        for (size_t i = 0; i < n; i++) {
                const lss_slave_state *st = &membus_slave(b, i)->st;
                ck_assert_msg(st->active_node_id == before[i].active_node_id &&
                              st->pending_node_id == before[i].pending_node_id &&
                              st->stored_node_id == before[i].stored_node_id,
                              "seed %llu: slave %zu %u/%u/%u, was %u/%u/%u", (unsigned long long) seed, i,
                              st->active_node_id, st->pending_node_id, st->stored_node_id,
                              before[i].active_node_id, before[i].pending_node_id, before[i].stored_node_id);
        }
        ck_assert(all_waiting(b));
        pass_free(m, b);
}

/* The blind Scan (before: "Fastscan found ... 2 times but no slave
 * confirmed it"), and the four configured at 10..13. */
START_TEST(scan_lely) {
        static const slave_spec spec[] = {
                { LELY, 0xFF }, { LELY, 0xFF }, { LELY, 0xFF }, { LELY, 0xFF },
                { LELY, 10 },   { LELY, 11 },   { LELY, 12 },   { LELY, 13 },
        };
        for (uint64_t seed = 1; seed <= SEEDS; seed++)
                expect_scan(spec, 8, seed);
}
END_TEST

static const slave_spec MIXED[] = {
        { LELY, 0xFF },  { LELY, 20 },  { CANOPENNODE, 0xFF }, { CANOPENNODE, 0xFF },
        { PLAIN, 0xFF }, { PLAIN, 21 }, { PLAIN, 0xFF },       { LELY, 0xFF },
};
#define N_MIXED (sizeof(MIXED) / sizeof(MIXED[0]))

START_TEST(scan_mixed) {
        for (uint64_t seed = 1; seed <= SEEDS; seed++)
                expect_scan(MIXED, N_MIXED, seed);
}
END_TEST

/* A blind pass from a pool on the mixed bus: every non-configured slave a
 * pool node-ID of its own (Lely's pending its reset), the configured ones
 * left alone, never a node-ID held twice. */
START_TEST(pool_pass_mixed) {
        lss_autoassign_plan p = { .unknown = LSS_UNKNOWN_POOL, .pool_lo = 71, .pool_hi = 90, .store = true };
        for (uint64_t seed = 1; seed <= SEEDS; seed++) {
                membus *b = bus_of(MIXED, N_MIXED, seed);
                lss_master *m = master_default();
                const lss_result *r = run_pass(m, b, &p);
                ck_assert_msg(r->status == LSS_OK, "seed %llu: %s", (unsigned long long) seed, r->message);
                bool held[128] = { false };
                for (size_t i = 0; i < N_MIXED; i++) {
                        const lss_slave *s = membus_slave(b, i);
                        if (MIXED[i].node_id != LSS_NODE_ID_UNCONFIGURED) {
                                ck_assert_uint_eq(s->st.active_node_id, MIXED[i].node_id);
                                ck_assert_uint_eq(s->st.pending_node_id, MIXED[i].node_id);
                                continue;
                        }
                        const lss_outcome *o = expect_outcome(m, &s->id, LSS_OUTCOME_POOL);
                        ck_assert(o->pending_reset == (MIXED[i].kind == LELY));
                        ck_assert_uint_eq(s->st.pending_node_id, o->new_node_id);
                        ck_assert_uint_eq(s->st.stored_node_id, o->new_node_id);
                        ck_assert_uint_eq(s->st.active_node_id,
                                          MIXED[i].kind == LELY ? LSS_NODE_ID_UNCONFIGURED : o->new_node_id);
                        ck_assert_msg(!held[o->new_node_id], "seed %llu: node-ID %u twice",
                                      (unsigned long long) seed, o->new_node_id);
                        held[o->new_node_id] = true;
                }
                ck_assert(all_waiting(b));
                pass_free(m, b);
        }
}
END_TEST

/* A pass that does not know a Lely device holds a pool node-ID for its next
 * reset (lssd restarted since the pass that gave it): found first (the
 * lowest identity: Fastscan reads bits 0 first), it answers Inquire Node-ID
 * with it, and no device found after it is given that node-ID (before: 71
 * to the next device found, two devices holding 71). One found before it
 * may be: lssd(8) says so. */
START_TEST(pending_pool_id_not_given_again) {
        lss_autoassign_plan p = { .unknown = LSS_UNKNOWN_POOL, .pool_lo = 71, .pool_hi = 90, .store = true };
        for (uint64_t seed = 1; seed <= SEEDS; seed++) {
                membus *b = membus_new(125000);
                membus_set_seed(b, seed);
                uint64_t r = seed;
                for (uint32_t i = 0; i < 4; i++) {
                        lss_identity id = { i == 0 ? 0x100 : 0x200, 0xB0B, 1, (uint32_t) sim_random_next(&r) };
                        lss_slave_faults f = faults_of(i == 0 ? LELY : PLAIN, &r);
                        membus_add_slave(b, &id, LSS_NODE_ID_UNCONFIGURED, &f);
                }
                lss_slave_state *held = &membus_slave(b, 0)->st;
                held->pending_node_id = held->stored_node_id = 71;
                lss_master *m = master_default();
                const lss_result *res = run_pass(m, b, &p);
                ck_assert_msg(res->status == LSS_OK, "seed %llu: %s", (unsigned long long) seed, res->message);
                for (size_t i = 1; i < 4; i++) {
                        const lss_slave_state *st = &membus_slave(b, i)->st;
                        ck_assert_msg(st->pending_node_id != 71 && st->stored_node_id != 71,
                                      "seed %llu: slave %zu given 71, which slave 0 holds", (unsigned long long) seed, i);
                }
                ck_assert_uint_eq(held->pending_node_id, 71);
                pass_free(m, b);
        }
}
END_TEST

/* SetBitrate with a Lely device (13 01 without a rate hook): refused, the
 * device named by its outcome, nothing activated, every rate as it was. */
START_TEST(bitrate_refused_by_lely) {
        static const slave_spec spec[] = { { PLAIN, 21 }, { LELY, 20 }, { PLAIN, 22 } };
        membus *b = bus_of(spec, 3, 7);
        lss_bitrate_device devs[3];
        for (size_t i = 0; i < 3; i++)
                devs[i] = (lss_bitrate_device) { .id = membus_slave(b, i)->id };
        lss_master *m = master_default();
        lss_bitrate_params p = { .bitrate = 250000, .old_bitrate = 125000, .delay_ms = 16, .devices = devs,
                                 .n_devices = 3 };
        ck_assert_int_eq(lss_master_set_bitrate(m, &p, membus_now(b)), 0);
        const lss_result *r = run(m, b);
        ck_assert_int_eq(r->status, LSS_E_REJECTED);
        ck_assert_int_eq(devs[1].outcome, LSS_BITRATE_REFUSED);
        ck_assert_uint_eq(devs[1].err, 1);
        for (size_t i = 0; i < 3; i++) {
                ck_assert_uint_eq(membus_slave(b, i)->st.bit_index, 4);
                ck_assert_uint_eq(membus_slave(b, i)->st.pending_bit_index, 4);
        }
        ck_assert(all_waiting(b));
        pass_free(m, b);
}
END_TEST

static void add(TCase *tc) {
        tcase_set_timeout(tc, 300);
        tcase_add_test(tc, scan_lely);
        tcase_add_test(tc, scan_mixed);
        tcase_add_test(tc, pool_pass_mixed);
        tcase_add_test(tc, pending_pool_id_not_given_again);
        tcase_add_test(tc, bitrate_refused_by_lely);
}

int main(void) {
        return check_main("lely", add);
}
