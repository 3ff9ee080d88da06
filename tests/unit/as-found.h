/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* "The bus as the pass found it" (issue 38): what every slave held before a
 * pass, and the check afterwards that each is back in waiting with it. */
#pragma once

#include <stdio.h>

#include "engine-util.h"

#define AS_FOUND_MAX 160

typedef struct bus_before {
        size_t n;
        lss_identity id[AS_FOUND_MAX];
        uint8_t node_id[AS_FOUND_MAX], stored[AS_FOUND_MAX], bit_index[AS_FOUND_MAX];
        bool moved[AS_FOUND_MAX]; /* a change the pass made and verified: node_id is the new one */
} bus_before;

static inline void before_take(bus_before *bb, membus *b) {
        ck_assert_uint_le(membus_slave_count(b), AS_FOUND_MAX);
        memset(bb, 0, sizeof(*bb));
        bb->n = membus_slave_count(b);
        for (size_t i = 0; i < bb->n; i++) {
                const lss_slave *s = membus_slave(b, i);
                bb->id[i] = s->id;
                bb->node_id[i] = s->st.active_node_id;
                bb->stored[i] = s->st.stored_node_id;
                bb->bit_index[i] = s->st.bit_index;
        }
}

/* The pass legitimately moved this slave to node-ID `to`. */
static inline void before_moved(bus_before *bb, const lss_identity *id, uint8_t to) {
        for (size_t i = 0; i < bb->n; i++)
                if (lss_identity_equal(&bb->id[i], id)) {
                        bb->node_id[i] = to;
                        bb->moved[i] = true;
                }
}

/* After a second of the bus alone (resets, boot-ups): every slave in
 * waiting, active = pending = the node-ID it had (stored too, unless
 * moved), its bit timing untouched. `what` names the case. */
static inline void as_found(membus *b, const bus_before *bb, const char *what) {
        lss_drive_idle(b, SECOND);
        for (size_t i = 0; i < bb->n; i++) {
                /* by place, not identity: twins of one identity are told apart */
                const lss_slave *s = membus_slave(b, i);
                uint8_t want = bb->node_id[i];
                ck_assert(lss_identity_equal(&s->id, &bb->id[i]));
                ck_assert_msg(!s->st.configuration, "%s: %x left in configuration", what, bb->id[i].serial);
                ck_assert_msg(s->st.active_node_id == want && s->st.pending_node_id == want,
                              "%s: %x has node-ID %u (pending %u), had %u", what, bb->id[i].serial,
                              s->st.active_node_id, s->st.pending_node_id, want);
                ck_assert_msg(bb->moved[i] || s->st.stored_node_id == bb->stored[i],
                              "%s: %x stored node-ID %u, had %u", what, bb->id[i].serial, s->st.stored_node_id,
                              bb->stored[i]);
                ck_assert_msg(s->st.bit_index == bb->bit_index[i] && s->st.pending_bit_index == bb->bit_index[i],
                              "%s: %x bit timing %u (pending %u), had %u", what, bb->id[i].serial,
                              s->st.bit_index, s->st.pending_bit_index, bb->bit_index[i]);
        }
}
