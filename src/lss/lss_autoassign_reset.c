/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* reset_after_pass: devices that took their node-ID only for their next
 * reset (lss_outcome.pending_reset; a slave such as Lely's applies a
 * configured node-ID at NMT Reset only) are reset all at once by one
 * broadcast NMT Reset Communication and verified by their boot-ups. One
 * that does not boot up with its node-ID gets its old one back (configured,
 * stored, read back), so that no node-ID is left pending unverified. */
#include <stdio.h>
#include <string.h>

#include "lss/lss_autoassign_state.h"

#define SEND(m, pc, frame_expr) STEP_REQUEST(m, pc, frame_expr, -1)

static bool pending(const lss_outcome *o) {
        return o->pending_reset && !o->dry;
}

static size_t count_pending(const lss_aa_state *s) {
        size_t n = 0;
        for (size_t i = 0; i < s->n_out; i++)
                n += pending(&s->out[i]);
        return n;
}

/* A boot-up: the pending device of that node-ID is verified. */
static void booted(lss_aa_state *s, const lss_frame *f) {
        uint8_t node, state;
        if (!bootup_decode(f, &node, &state) || state != 0)
                return;
        for (size_t i = 0; i < s->n_out; i++)
                if (pending(&s->out[i]) && s->out[i].new_node_id == node)
                        s->out[i].pending_reset = false;
}

/* The outcome of a device the reset did not verify: given back, or kept. */
static void not_booted(lss_master *m, lss_outcome *o) {
        uint8_t node = o->new_node_id;
        o->kind = LSS_OUTCOME_FAILED;
        o->status = LSS_E_VERIFY;
        o->pending_reset = false;
        if (m->result.given_back) {
                o->new_node_id = o->old_node_id;
                snprintf(o->message, sizeof(o->message), "no boot-up from node %u after the NMT Reset Communication "
                         "of the bus: given back node-ID %u", node, o->old_node_id);
        } else {
                o->new_node_id = o->old_node_id;
                o->kept_node_id = node;
                snprintf(o->message, sizeof(o->message), "no boot-up from node %u after the NMT Reset Communication "
                         "of the bus, and node-ID %u could not be given back: the device may hold node-ID %u, "
                         "which is kept for it", node, o->old_node_id, node);
        }
}

int aa_proc_reset_pending(lss_master *m, lss_aa_state *s) {
        PT_BEGIN(&s->r_pc);
        if (count_pending(s) == 0)
                goto out;
        s->until = m->now + m->timing.cfg.bootup_timeout_us;
        m->step = (lss_step) { .kind = STEP_EVENT, .wait_us = m->timing.cfg.bootup_timeout_us };
        lss_frame reset;
        nmt_encode(&reset, NMT_CS_RESET_COMMUNICATION, 0);
        step_add_tx(m, &reset);
        step_start(m);
        for (;;) {
                PT_YIELD(&s->r_pc);
                if (m->step.n_answers > 0)
                        booted(s, &m->step.answer);
                if (count_pending(s) == 0 || m->now >= s->until)
                        break;
                step_event(m, s->until);
        }
        for (s->k = 0; s->k < s->n_out; s->k++) {
                if (!pending(&s->out[s->k]))
                        continue;
                memset(&m->as, 0, sizeof(m->as));
                m->as.id = s->out[s->k].id;
                m->as.old = s->out[s->k].old_node_id;
                m->as.flags = s->plan->store ? LSS_ASSIGN_STORE : 0;
                m->result.given_back = false;
                /* silent, it keeps what it was given (may_hold): asked patiently */
                SELECT_RETRIED(m, &s->r_pc, m->as.attempt, &m->as.id);
                AGAIN_PATIENTLY_IF_SILENT(m, SELECT_RETRIED(m, &s->r_pc, m->as.attempt, &m->as.id));
                if (step_answered(m)) {
                        m->as.gpc = 0;
                        PT_CALL(&s->r_pc, proc_give_back(m, &m->as));
                        SEND(m, &s->r_pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                }
                not_booted(m, &s->out[s->k]);
        }
        m->result.given_back = m->result.may_hold = false;
        if (s->plan->nmt_stop) {
                /* the reset took them out of Stopped */
                SEND(m, &s->r_pc, nmt_encode(&f__, NMT_CS_STOP, 0));
        }
out:;
        PT_END(&s->r_pc);
}
