/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The replacement of a broken device by AutoAssign (plan.replace,
 * lss_replace.h) on the in-memory bus. */
#include "autoassign-util.h"
#include "lss/lss_autoassign.h"

/* What the master asked of the bus: Configure Node-ID to a node-ID below
 * 100 (the enumeration sets slaves aside from 127 down and gives them 255
 * back), Store, NMT; and the boot-ups of node-ID 12. */
typedef struct tally {
        unsigned configure, store, nmt, bootup_12;
} tally;

static void count(void *ud, const lss_frame *f, uint64_t t) {
        tally *c = ud;
        (void) t;
        count_configure_store(f, &c->configure, &c->store);
        c->nmt += f->id == 0;
        c->bootup_12 += f->id == 0x700 + 12 && f->len == 1 && f->data[0] == 0;
}

static const lss_identity OLD = { 0x9A, 3, 1, 0xDEF };   /* mapped to 12, broken: not on the bus */
static const lss_identity OLD2 = { 0x9A, 3, 1, 0xDEE };  /* mapped to 13, not on the bus either */
static const lss_identity C = { 0x9A, 3, 1, 19 };        /* mapped to 6 and at 6 */
static const lss_identity NEW = { 0x9A, 3, 1, 0xABC };   /* the spare, out of its box */
static const lss_identity NEW2 = { 0x9A, 3, 2, 0xABD };  /* a second spare */
static const lss_identity U = { 0x77, 5, 1, 99 };        /* another product, not in the map */

static membus *bus_with(const lss_identity *const *ids, size_t n) {
        membus *b = membus_new(125000);
        lss_slave_faults f = faults_latency(800, 400);
        membus_add_slave(b, &C, 6, &f);
        membus_add_slave(b, &U, 0xFF, &f);
        for (size_t i = 0; i < n; i++)
                membus_add_slave(b, ids[i], 0xFF, &f);
        return b;
}

/* run_pass() that must end well, every slave in waiting */
static const lss_result *run_pass_ok(lss_master *m, membus *b, const lss_autoassign_plan *p) {
        const lss_result *r = run_pass(m, b, p);
        ck_assert_int_eq(r->status, LSS_OK);
        ck_assert(all_waiting(b));
        return r;
}

/* A pass with a new master, counting what it sends. */
static lss_master *traced_pass(membus *b, tally *c, const lss_autoassign_plan *p) {
        lss_master *m = master_default();
        *c = (tally) { 0 };
        membus_set_trace(b, count, c);
        run_pass_ok(m, b, p);
        return m;
}

/* One mapped device gone, one new non-configured device of its vendor and
 * product: it gets the node-ID, stored and verified by its boot-up, and its
 * outcome names the identity it replaced (the map's: without a revision
 * there, revision 0 and not known). Another product's unknown device is
 * left alone, or pooled: the rule comes before the pool. A second pass
 * configures nothing: the replacement is at 12 now, still the replacement
 * (the map names OLD until it is updated), with nothing sent to it. */
START_TEST(replaced_by_new_device) {
        for (int variant = 0; variant < 3; variant++) {
                bool no_revision = variant == 1, pool = variant == 2;
                const lss_identity *on_bus[] = { &NEW };
                membus *b = bus_with(on_bus, 1);
                lss_map_entry map[] = {
                        { .id = C, .revision_known = true, .node_id = 6 },
                        { .id = OLD, .revision_known = !no_revision, .node_id = 12 },
                };
                if (no_revision)
                        map[1].id.revision = 0;
                lss_autoassign_plan p = { .map = map, .n_map = 2, .store = true, .replace = true,
                                          .unknown = pool ? LSS_UNKNOWN_POOL : LSS_UNKNOWN_IGNORE,
                                          .pool_lo = 10, .pool_hi = 20 };
                tally c;
                lss_master *m = traced_pass(b, &c, &p);
                const lss_outcome *o = expect_replaced(m, &NEW, &map[1].id, 0xFF, 12);
                ck_assert(o->replaced_revision_known == !no_revision);
                ck_assert(!o->dry);
                ck_assert_uint_eq(membus_find(b, &NEW)->st.active_node_id, 12);
                ck_assert_uint_eq(membus_find(b, &NEW)->st.stored_node_id, 12);
                ck_assert_uint_eq(c.bootup_12, 1);
                o = expect_outcome(m, &map[1].id, LSS_OUTCOME_MISSING);
                ck_assert_msg(strstr(o->message, "replaced by 0000009a:00000003:00000001:00000abc at node-ID 12"),
                              "%s", o->message);
                expect_outcome(m, &C, LSS_OUTCOME_UNCHANGED);
                /* 10 and 11 are free: the pool takes the lowest, not the missing entry's 12 */
                expect_outcome(m, &U, pool ? LSS_OUTCOME_POOL : LSS_OUTCOME_UNKNOWN);
                ck_assert_uint_eq(membus_find(b, &U)->st.active_node_id, pool ? 10 : 0xFF);

                /* NEW is configured at 12 now: 1018h there names it, the
                 * replacement in place, nothing sent to it */
                c = (tally) { 0 };
                run_pass_ok(m, b, &p);
                expect_replaced(m, &NEW, &map[1].id, 12, 12);
                expect_outcome(m, &map[1].id, LSS_OUTCOME_MISSING);
                ck_assert_uint_eq(c.configure, 0);
                ck_assert_uint_eq(c.store, 0);
                lss_master_free(m);
                membus_free(b);
        }
}
END_TEST

/* Each outcome's detail is its own: the missing entry's "no slave answered"
 * stays with it, not with the mapped device dealt with next (seen with the
 * missing entry first in the map: lssctl and the journal gave the present
 * device the missing one's failure). */
START_TEST(details_stay_with_their_device) {
        const lss_identity *on_bus[] = { &NEW };
        membus *b = bus_with(on_bus, 1);
        lss_map_entry map[] = {
                { .id = OLD, .revision_known = true, .node_id = 12 },
                { .id = C, .revision_known = true, .node_id = 6 },
        };
        lss_autoassign_plan p = { .map = map, .n_map = 2, .store = true, .replace = true };
        tally c;
        lss_master *m = traced_pass(b, &c, &p);
        const lss_outcome *o = expect_outcome(m, &C, LSS_OUTCOME_UNCHANGED);
        ck_assert_msg(o->message[0] == 0, "C: %s", o->message);
        expect_replaced(m, &NEW, &OLD, 0xFF, 12);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

/* Two candidates for one missing device, or one for two: nobody is
 * replaced (a guess would give a node-ID, and the configuration behind it,
 * to the wrong device), with or without a pool, and the outcomes say why. */
static void expect_nothing_replaced(const lss_identity *const *on_bus, size_t n_bus, const char *why) {
        for (int pool = 0; pool < 2; pool++) {
                membus *b = bus_with(on_bus, n_bus);
                const lss_map_entry map[] = {
                        { .id = C, .revision_known = true, .node_id = 6 },
                        { .id = OLD, .revision_known = true, .node_id = 12 },
                        { .id = OLD2, .revision_known = true, .node_id = 13 },
                };
                size_t n_map = n_bus == 1 ? 3 : 2;
                lss_autoassign_plan p = { .map = map, .n_map = n_map, .store = true, .replace = true,
                                          .unknown = pool ? LSS_UNKNOWN_POOL : LSS_UNKNOWN_IGNORE,
                                          .pool_lo = 20, .pool_hi = 30 };
                tally c;
                lss_master *m = traced_pass(b, &c, &p);
                for (size_t i = 0; i < n_bus; i++) {
                        const lss_outcome *o = expect_outcome(m, on_bus[i], LSS_OUTCOME_UNKNOWN);
                        ck_assert_msg(strcmp(o->message, why) == 0, "%s", o->message);
                        ck_assert_uint_eq(membus_find(b, on_bus[i])->st.active_node_id, 0xFF);
                }
                for (size_t i = 1; i < n_map; i++) {
                        const lss_outcome *o = expect_outcome(m, &map[i].id, LSS_OUTCOME_MISSING);
                        ck_assert_msg(strstr(o->message, why), "%s", o->message);
                }
                /* only the other product's device from the pool */
                ck_assert_uint_eq(c.configure, pool ? 1 : 0);
                expect_outcome(m, &U, pool ? LSS_OUTCOME_POOL : LSS_OUTCOME_UNKNOWN);
                lss_master_free(m);
                membus_free(b);
        }
}

START_TEST(two_candidates_are_ambiguous) {
        const lss_identity *on_bus[] = { &NEW, &NEW2 };
        expect_nothing_replaced(on_bus, 2, "2 unknown devices of 0x9A:0x3 and 1 missing: not replaced, ambiguous");
}
END_TEST

START_TEST(two_missing_are_ambiguous) {
        const lss_identity *on_bus[] = { &NEW };
        expect_nothing_replaced(on_bus, 1, "1 unknown device of 0x9A:0x3 and 2 missing: not replaced, ambiguous");
}
END_TEST

/* The bus of one broken device (OLD, mapped to 12) and its spare (NEW),
 * and `at_12` configured at 12 if not NULL, after a pass with the plan's
 * flags as given (map filled in here). */
static lss_master *one_missing_pass(membus **b, tally *c, lss_autoassign_plan p, const lss_identity *at_12) {
        /* the pass is done when traced_pass() returns: plan and map may end here */
        const lss_map_entry map[] = {
                { .id = C, .revision_known = true, .node_id = 6 },
                { .id = OLD, .revision_known = true, .node_id = 12 },
        };
        const lss_identity *on_bus[] = { &NEW };
        *b = bus_with(on_bus, 1);
        if (at_12) {
                lss_slave_faults f = faults_latency(800, 400);
                membus_add_slave(*b, at_12, 12, &f);
        }
        p.map = map;
        p.n_map = 2;
        p.store = true;
        return traced_pass(*b, c, &p);
}

/* Without the option nothing changes: the new device is unknown, the old
 * one missing, nothing is configured. */
START_TEST(replace_off_changes_nothing) {
        membus *b;
        tally c;
        lss_master *m = one_missing_pass(&b, &c, (lss_autoassign_plan) { .replace = false }, NULL);
        const lss_outcome *o = expect_outcome(m, &NEW, LSS_OUTCOME_UNKNOWN);
        ck_assert(!o->replacing);
        ck_assert_str_eq(o->message, "");
        o = expect_outcome(m, &OLD, LSS_OUTCOME_MISSING);
        ck_assert_ptr_null(strstr(o->message, "replaced"));
        ck_assert_uint_eq(c.configure, 0);
        ck_assert_uint_eq(membus_find(b, &NEW)->st.active_node_id, 0xFF);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

/* A dry run says what would be replaced and sends no Configure, Store or NMT. */
START_TEST(dry_run_says_what_would_be_replaced) {
        membus *b;
        tally c;
        lss_autoassign_plan p = { .nmt_stop = true, .replace = true, .dry_run = true };
        lss_master *m = one_missing_pass(&b, &c, p, NULL);
        const lss_outcome *o = expect_outcome(m, &NEW, LSS_OUTCOME_REPLACED);
        ck_assert(o->dry);
        ck_assert_uint_eq(o->new_node_id, 12);
        o = expect_outcome(m, &OLD, LSS_OUTCOME_MISSING);
        ck_assert_msg(strstr(o->message, "would be replaced by"), "%s", o->message);
        ck_assert_uint_eq(c.configure, 0);
        ck_assert_uint_eq(c.store, 0);
        ck_assert_uint_eq(c.nmt, 0);
        ck_assert_uint_eq(membus_find(b, &NEW)->st.active_node_id, 0xFF);
        ck_assert_uint_eq(membus_find(b, &NEW)->st.pending_node_id, 0xFF);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

/* The missing device's node-ID answers on the bus (another device took it):
 * the replacement is a conflict, like any assignment to a taken node-ID. */
START_TEST(taken_node_id_is_a_conflict) {
        const lss_identity X = { 0x55, 1, 1, 1 };
        membus *b;
        tally c;
        lss_master *m = one_missing_pass(&b, &c, (lss_autoassign_plan) { .replace = true }, &X);
        const lss_outcome *o = expect_outcome(m, &NEW, LSS_OUTCOME_CONFLICT);
        ck_assert_msg(strncmp(o->message, "not replaced: ", 14) == 0, "%s", o->message);
        ck_assert(o->replacing);
        ck_assert_uint_eq(membus_find(b, &NEW)->st.active_node_id, 0xFF);
        ck_assert_uint_eq(membus_find(b, &X)->st.active_node_id, 12);
        ck_assert_uint_eq(c.configure, 0);
        lss_master_free(m);
        membus_free(b);
}
END_TEST

int main(void) {
        Suite *s = suite_create("replace");
        TCase *tc = tcase_create("replace");
        tcase_set_timeout(tc, 120);
        tcase_add_test(tc, replaced_by_new_device);
        tcase_add_test(tc, details_stay_with_their_device);
        tcase_add_test(tc, two_candidates_are_ambiguous);
        tcase_add_test(tc, two_missing_are_ambiguous);
        tcase_add_test(tc, replace_off_changes_nothing);
        tcase_add_test(tc, dry_run_says_what_would_be_replaced);
        tcase_add_test(tc, taken_node_id_is_a_conflict);
        suite_add_tcase(s, tc);
        return run_suite(s);
}
