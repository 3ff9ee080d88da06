/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* A Scan leaves a running plant as it was: a CiA 305 slave found by Fastscan
 * stays in configuration state, where it takes no part, and is given
 * nothing; only a slave that answers Fastscan there (CANopenNode's) is set
 * aside with a temporary node-ID (lss_enumerate.c). */
#include "autoassign-util.h"
#include "check-main.h"

typedef struct wire_count {
        unsigned nmt, configure, configure_not_255, bootups;
} wire_count;

static void count_wire(void *ud, const lss_frame *f, uint64_t t) {
        wire_count *c = ud;
        (void) t;
        c->nmt += f->id == 0;
        if (lss_is_request(f) && f->data[0] == LSS_CS_CONFIGURE_NODE_ID) {
                c->configure++;
                c->configure_not_255 += f->data[1] != LSS_NODE_ID_UNCONFIGURED;
        }
        c->bootups += bootup_decode(f, NULL, NULL);
}

/* One enumeration of bus b, its wire counted into *c: ok, n devices, all real. */
static lss_master *enumerate_counted(membus *b, wire_count *c, size_t n, uint64_t seed) {
        membus_set_trace(b, count_wire, c);
        lss_master *m = master_default();
        ck_assert_int_eq(lss_master_enumerate(m, NULL, membus_now(b)), 0);
        const lss_result *r = run(m, b);
        ck_assert_msg(r->status == LSS_OK, "seed %u: %s", (unsigned) seed, r->message);
        ck_assert_uint_eq(r->n_devices, n);
        assert_devices_real(b, r);
        return m;
}

static void add_configured(membus *b, size_t n, uint64_t seed, const lss_slave_faults *f) {
        for (size_t i = 0; i < n; i++) {
                lss_identity id = { 0x9A, 3, (uint32_t) sim_random_next(&seed), (uint32_t) sim_random_next(&seed) };
                membus_add_slave(b, &id, (uint8_t) (20 + i), f);
        }
}

/* The Scan: 8 non-configured and 2 configured compliant slaves.
 * Nothing on the bus that changes a slave: no NMT command, no Configure
 * Node-ID, no boot-up; every slave as it was. Before: 21 Configure Node-ID,
 * 8 NMT commands and 8 boot-ups. */
START_TEST(scan_sends_nothing_that_changes) {
        for (uint64_t seed = 1; seed <= 20; seed++) {
                lss_slave_faults f = faults_latency(1000, 300);
                membus *b = bus_random(8, seed, 0, 0, &f);
                add_configured(b, 2, seed + 100, &f);
                lss_slave_state before[10];
                for (size_t i = 0; i < 10; i++)
                        before[i] = membus_slave(b, i)->st;
                wire_count c = { 0 };
                lss_master *m = enumerate_counted(b, &c, 8, seed);
                lss_drive_idle(b, 100000);
                ck_assert_msg(c.nmt == 0 && c.configure == 0 && c.bootups == 0,
                              "seed %u: %u NMT, %u Configure Node-ID, %u boot-ups", (unsigned) seed, c.nmt,
                              c.configure, c.bootups);
                for (size_t i = 0; i < 10; i++) {
                        const lss_slave_state *st = &membus_slave(b, i)->st;
                        ck_assert(st->active_node_id == before[i].active_node_id &&
                                  st->pending_node_id == before[i].pending_node_id &&
                                  st->stored_node_id == before[i].stored_node_id && !st->configuration);
                }
                pass_free(m, b);
        }
}
END_TEST

/* 4 compliant and 2 CANopenNode slaves, non-configured: all 6 found; the
 * two CANopenNode ones, which answer Fastscan in configuration state, are
 * set aside: at most 2 Configure Node-ID other than 255. */
START_TEST(only_canopennode_set_aside) {
        for (uint64_t seed = 1; seed <= 20; seed++) {
                lss_slave_faults f = faults_latency(1000, 300), co;
                lss_slave_faults_canopennode(&co);
                co.latency_us = 1000;
                co.jitter_us = 300;
                membus *b = bus_random(4, seed, 0, 0, &f);
                for (size_t i = 0; i < 2; i++) {
                        lss_identity id = { 0x5005, 0x11, 1, (uint32_t) (0x55 + i + seed * 16) };
                        membus_add_slave(b, &id, LSS_NODE_ID_UNCONFIGURED, &co);
                }
                wire_count c = { 0 };
                lss_master *m = enumerate_counted(b, &c, 6, seed);
                const lss_result *r = lss_master_result(m);
                ck_assert_msg(c.configure_not_255 <= 2, "seed %u: %u Configure Node-ID other than 255",
                              (unsigned) seed, c.configure_not_255);
                for (size_t i = 0; i < r->n_devices; i++)
                        ck_assert((r->devices[i].aside_node_id != 0) == (r->devices[i].id.vendor == 0x5005));
                lss_drive_idle(b, 100000);
                for (size_t i = 0; i < 6; i++) {
                        const lss_slave_state *st = &membus_slave(b, i)->st;
                        ck_assert(st->active_node_id == 0xFF && st->pending_node_id == 0xFF && st->stored_node_id == 0xFF);
                }
                pass_free(m, b);
        }
}
END_TEST

/* AutoAssign by the same rule: with unknown = "ignore" a compliant device
 * the map does not know is found, reported and left untouched. */
START_TEST(ignored_unknown_untouched) {
        lss_slave_faults f = faults_latency(1000, 300);
        membus *b = bus_random(3, 77, 0x9A, 3, &f);
        lss_map_entry map[] = { { .id = membus_slave(b, 0)->id, .revision_known = true, .node_id = 5 } };
        lss_autoassign_plan p = { .map = map, .n_map = 1, .store = true };
        /* the map names one by vendor and product only: the enumeration finds all three */
        map[0].revision_known = false;
        wire_count c = { 0 };
        membus_set_trace(b, count_wire, &c);
        lss_master *m = master_default();
        const lss_result *r = run_pass(m, b, &p);
        ck_assert_msg(r->status == LSS_OK, "%s", r->message);
        expect_outcome(m, &membus_slave(b, 0)->id, LSS_OUTCOME_ASSIGNED);
        for (size_t i = 1; i < 3; i++) {
                expect_outcome(m, &membus_slave(b, i)->id, LSS_OUTCOME_UNKNOWN);
                const lss_slave_state *st = &membus_slave(b, i)->st;
                ck_assert(st->active_node_id == 0xFF && st->pending_node_id == 0xFF && st->stored_node_id == 0xFF);
        }
        ck_assert_uint_eq(c.configure, 1); /* the mapped one's */
        pass_free(m, b);
}
END_TEST

static void add(TCase *tc) {
        tcase_set_timeout(tc, 300);
        tcase_add_test(tc, scan_sends_nothing_that_changes);
        tcase_add_test(tc, only_canopennode_set_aside);
        tcase_add_test(tc, ignored_unknown_untouched);
}

int main(void) {
        return check_main("scan-untouched", add);
}
