/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* An assignment whose boot-up did not come. Configure Node-ID N (and Store)
 * were answered: from then on the device may hold N, for its next reset or
 * power cycle, whether it boots up now or not (a slave such as Lely's takes
 * a configured node-ID only at NMT Reset; another may boot late, or lose
 * its boot-up). So a missing boot-up never frees N: the device is asked
 * what it holds and the result says it (docs/engine.md, "A node-ID
 * configured is the device's"):
 *   - it answers SDO at N: N is in effect, its boot-up was lost (LSS_OK);
 *   - it answers Inquire Node-ID with N and had none before: N takes effect
 *     at its next reset (LSS_OK, result.pending_reset);
 *   - anything else it answers (or a configured slave that did not take N
 *     at the NMT Reset Communication it was sent): it gets its old node-ID
 *     back, read back by Inquire Node-ID (LSS_E_VERIFY, result.given_back);
 *   - silence, or a give-back that did not take: LSS_E_VERIFY with
 *     result.may_hold — N is kept for it.
 * Its LSS asks wait patiently: silence here is a verdict. */
#include "lss/lss_internal.h"

#define SEND(m, pc, frame_expr) STEP_REQUEST(m, pc, frame_expr, -1)

/* The answer of the step just done, from one slave, with this cs. */
static bool one_answer(const lss_master *m) {
        return step_answered(m) && !step_conflict(m);
}

int proc_give_back(lss_master *m, lss_assign_state *s) {
        PT_BEGIN(&s->gpc);
        m->result.may_hold = true;
        /* (patient already from proc_assign_unverified; after a reset pass not) */
        REQUEST_RETRIED(m, &s->gpc, s->attempt, lss_encode_configure_node_id(&f__, s->old),
                        LSS_CS_CONFIGURE_NODE_ID);
        AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->gpc, s->attempt,
                                                     lss_encode_configure_node_id(&f__, s->old),
                                                     LSS_CS_CONFIGURE_NODE_ID));
        if (!one_answer(m) || m->step.answer.data[1] != LSS_ERR_OK)
                goto out;
        if (s->flags & LSS_ASSIGN_STORE) {
                REQUEST_RETRIED(m, &s->gpc, s->attempt, lss_encode_store(&f__), LSS_CS_STORE);
                AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->gpc, s->attempt, lss_encode_store(&f__),
                                                             LSS_CS_STORE));
                /* a device that cannot store kept nothing of N either */
                if (!one_answer(m) || (m->step.answer.data[1] != LSS_ERR_OK &&
                                       m->step.answer.data[1] != LSS_ERR_STORE_NOT_SUPPORTED))
                        goto out;
        }
        REQUEST_RETRIED(m, &s->gpc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_COUNT), LSS_CS_INQUIRE_NODE_ID);
        AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->gpc, s->attempt,
                                                     lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                                                     LSS_CS_INQUIRE_NODE_ID));
        if (!one_answer(m))
                goto out;
        s->held = m->step.answer.data[1];
        if (s->held == s->old) {
                m->result.may_hold = false;
                m->result.given_back = true;
        }
out:;
        PT_END(&s->gpc);
}

int proc_assign_unverified(lss_master *m, lss_assign_state *s) {
        PT_BEGIN(&s->vpc);
        s->patient = false;
        /* The switch to waiting that makes N take effect has no answer: a
         * device that lost it is still in configuration, where it answers
         * no selective switch. Once more; then, in effect (its boot-up
         * lost, or it just took N), it answers SDO at N. */
        SEND(m, &s->vpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        step_node_in_use(m, s->node_id);
        PT_YIELD(&s->vpc);
        if (m->step.n_answers > 0)
                goto out;

        s->patient = !m->patient;
        if (s->patient)
                master_patient_begin(m, lss_timing_patient_wait(&m->timing, LSS_VERDICT_WAIT_FLOOR_US));
        SELECT_RETRIED(m, &s->vpc, s->attempt, &s->id);
        if (!step_answered(m)) {
                m->result.may_hold = true;
                master_fail_at(m, LSS_E_VERIFY, LSS_SERVICE_VERIFY, LSS_REASON_NO_ANSWER,
                               "no boot-up from node %u after the assignment, and no answer to a selective switch "
                               "since: the device may hold node-ID %u, which is kept for it", s->node_id, s->node_id);
                goto out;
        }
        REQUEST_RETRIED(m, &s->vpc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_COUNT), LSS_CS_INQUIRE_NODE_ID);
        if (!one_answer(m)) {
                m->result.may_hold = true;
                master_fail_at(m, LSS_E_VERIFY, LSS_SERVICE_VERIFY, LSS_REASON_NO_ANSWER,
                               "no boot-up from node %u after the assignment, and no clear answer to Inquire "
                               "Node-ID since: the device may hold node-ID %u, which is kept for it", s->node_id,
                               s->node_id);
                goto waiting;
        }
        s->held = m->step.answer.data[1];
        if (s->held == s->node_id && s->old == LSS_NODE_ID_UNCONFIGURED) {
                m->result.pending_reset = true;
                goto waiting;
        }
        /* it holds something else, or a configured slave did not take N at
         * the NMT Reset Communication it was sent: its old node-ID back */
        s->gpc = 0;
        PT_CALL(&s->vpc, proc_give_back(m, s));
        if (m->result.given_back)
                master_fail_at(m, LSS_E_VERIFY, LSS_SERVICE_VERIFY, LSS_REASON_NO_ANSWER,
                               "no boot-up from node %u after the assignment (the device answered Inquire Node-ID "
                               "with %u): given back node-ID %u%s", s->node_id, s->held, s->old,
                               s->flags & LSS_ASSIGN_STORE ? ", stored" : "");
        else
                master_fail_at(m, LSS_E_VERIFY, LSS_SERVICE_VERIFY, LSS_REASON_NO_ANSWER,
                               "no boot-up from node %u after the assignment, and node-ID %u could not be given back: "
                               "the device may hold node-ID %u, which is kept for it", s->node_id, s->old,
                               s->node_id);
waiting:
        SEND(m, &s->vpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
out:
        if (s->patient)
                master_patient_end(m);
        s->patient = false;
        PT_END(&s->vpc);
}
