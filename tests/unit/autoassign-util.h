/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Helpers shared by the AutoAssign tests: a device's outcome. */
#pragma once

#include "engine-util.h"
#include "lss/lss_autoassign.h"

/* The outcome of the last pass for this identity, NULL: none. */
static inline const lss_outcome *outcome_of(lss_master *m, const lss_identity *id) {
        size_t n;
        const lss_outcome *o = lss_master_outcomes(m, &n);
        for (size_t i = 0; i < n; i++)
                if (lss_identity_equal(&o[i].id, id))
                        return &o[i];
        return NULL;
}

/* The outcome, which must be of this kind. */
static inline const lss_outcome *expect_outcome(lss_master *m, const lss_identity *id, enum lss_outcome_kind kind) {
        const lss_outcome *o = outcome_of(m, id);
        ck_assert_msg(o && o->kind == kind, "device %x: %s (%s), want %s", id->serial,
                      o ? lss_outcome_name(o->kind) : "no outcome", o ? o->message : "", lss_outcome_name(kind));
        return o;
}

/* An AutoAssign pass to its end, then 100 ms of the bus (boot-ups, resets). */
static inline const lss_result *run_pass(lss_master *m, membus *b, const lss_autoassign_plan *p) {
        ck_assert_int_eq(lss_master_autoassign(m, p, membus_now(b)), 0);
        const lss_result *r = run(m, b);
        lss_drive_idle(b, 100000);
        return r;
}

/* The end of a test's pass: the master and its bus freed. */
static inline void pass_free(lss_master *m, membus *b) {
        lss_master_free(m);
        membus_free(b);
}

/* Counts the master's Configure Node-ID to a node-ID below 100 (the
 * enumeration sets slaves aside from 127 down and gives them 255 back)
 * and Store Configuration, for a bus trace. */
static inline void count_configure_store(const lss_frame *f, unsigned *configure, unsigned *store) {
        if (!lss_is_request(f))
                return;
        *configure += f->data[0] == LSS_CS_CONFIGURE_NODE_ID && f->data[1] < 100;
        *store += f->data[0] == LSS_CS_STORE;
}

/* The device replaced the map's identity `old`, its node-ID went from
 * `from` to `to` (equal: it had it already). */
static inline const lss_outcome *expect_replaced(lss_master *m, const lss_identity *id, const lss_identity *old,
                                                 uint8_t from, uint8_t to) {
        const lss_outcome *o = expect_outcome(m, id, LSS_OUTCOME_REPLACED);
        ck_assert_uint_eq(o->old_node_id, from);
        ck_assert_uint_eq(o->new_node_id, to);
        ck_assert(o->replacing);
        ck_assert(lss_identity_equal(&o->replaced, old));
        return o;
}
