/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Taking a slave back to non-configured (lss_master_unassign). CiA 305:
 * Configure Node-ID 255 sets the pending node-ID only; a configured slave
 * keeps answering to its old node-ID until NMT Reset Communication (or a
 * reset or power cycle) makes the pending one active. So the procedure says
 * what it saw: the old node-ID, whether 255 was stored, and whether the
 * slave runs non-configured now — which only a reset (LSS_UNASSIGN_RESET)
 * followed by Inquire Node-ID = 255 shows. */
#include "lss/lss_internal.h"

/* Send an unconfirmed frame (no wait). */
#define SEND(m, pc, frame_expr) STEP_REQUEST(m, pc, frame_expr, -1)

int proc_unassign(lss_master *m, lss_assign_state *s) {
        PT_BEGIN(&s->pc);
        m->result.id = s->id;
        m->result.node_id = LSS_NODE_ID_UNCONFIGURED;
        /* every silence below would end in a verdict on a slave that may
         * only be stalled: asked again patiently first */
        SELECT_RETRIED(m, &s->pc, s->attempt, &s->id);
        AGAIN_PATIENTLY_IF_SILENT(m, SELECT_RETRIED(m, &s->pc, s->attempt, &s->id));
        if (!step_answered(m)) {
                master_fail_at(m, LSS_E_NOT_FOUND, LSS_SERVICE_SWITCH_SELECTIVE, LSS_REASON_NO_ANSWER,
                               "no slave %08x:%08x:%08x:%08x answered the selective switch", s->id.vendor,
                               s->id.product, s->id.revision, s->id.serial);
                goto out;
        }
        REQUEST_RETRIED(m, &s->pc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_COUNT), LSS_CS_INQUIRE_NODE_ID);
        AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->pc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                                                     LSS_CS_INQUIRE_NODE_ID));
        if (!inquired_node_id_ok(m))
                goto out;
        s->old = m->result.node_id;

        /* also when it runs at 255 already: its pending or stored node-ID may not be */
        REQUEST_RETRIED(m, &s->pc, s->attempt, lss_encode_configure_node_id(&f__, LSS_NODE_ID_UNCONFIGURED),
                        LSS_CS_CONFIGURE_NODE_ID);
        AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->pc, s->attempt,
                                                     lss_encode_configure_node_id(&f__, LSS_NODE_ID_UNCONFIGURED),
                                                     LSS_CS_CONFIGURE_NODE_ID));
        if (!configure_answer_ok(m, LSS_NODE_ID_UNCONFIGURED))
                goto out;
        m->result.changed = s->old != LSS_NODE_ID_UNCONFIGURED;

        if (s->flags & LSS_UNASSIGN_STORE) {
                REQUEST_RETRIED(m, &s->pc, s->attempt, lss_encode_store(&f__), LSS_CS_STORE);
                AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->pc, s->attempt, lss_encode_store(&f__),
                                                             LSS_CS_STORE));
                if (!store_answer_ok(m))
                        goto out;
                m->result.stored = !m->result.not_stored;
        }

        SEND(m, &s->pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        if (s->old == LSS_NODE_ID_UNCONFIGURED) {
                /* it answered 255 just now: nothing to reset */
                m->result.in_effect = true;
                goto out;
        }
        if (!(s->flags & LSS_UNASSIGN_RESET))
                goto out;

        /* the pending 255 becomes active at Reset Communication; then ask
         * the slave itself, until it answers 255 or the boot-up timeout ran out */
        SEND(m, &s->pc, nmt_encode(&f__, NMT_CS_RESET_COMMUNICATION, s->old));
        s->until = m->now + m->timing.cfg.bootup_timeout_us;
        s->patient = false;
        for (;;) {
                m->step = (lss_step) { .kind = STEP_DELAY, .wait_us = m->timing.cfg.timeout_us };
                step_start(m);
                PT_YIELD(&s->pc);
                /* the last round ends in a verdict: its asks wait patiently */
                if (m->now >= s->until && !m->patient) {
                        s->patient = true;
                        master_patient_begin(m, lss_timing_patient_wait(&m->timing, LSS_VERDICT_WAIT_FLOOR_US));
                }
                SELECT_RETRIED(m, &s->pc, s->attempt, &s->id);
                if (step_answered(m)) {
                        REQUEST_RETRIED(m, &s->pc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                                        LSS_CS_INQUIRE_NODE_ID);
                        if (step_answered(m) && !step_conflict(m))
                                s->seen = m->step.answer.data[1];
                }
                /* also after a silent select: one answered after its wait put
                 * the slave in configuration, where no selective switch reaches it */
                SEND(m, &s->pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                if (s->seen == LSS_NODE_ID_UNCONFIGURED) {
                        m->result.in_effect = true;
                        goto out;
                }
                if (s->patient)
                        break;
                m->stats.retries++;
        }
        if (s->seen)
                master_fail_at(m, LSS_E_VERIFY, LSS_SERVICE_VERIFY, LSS_REASON_NOT_CONFIRMED,
                               "node-ID 255 was configured%s, but after NMT Reset Communication the device still "
                               "answers as node %u", m->result.stored ? " and stored" : "", s->seen);
        else
                master_fail_at(m, LSS_E_VERIFY, LSS_SERVICE_VERIFY, LSS_REASON_NO_ANSWER,
                               "node-ID 255 was configured%s, but the device did not answer after NMT Reset "
                               "Communication", m->result.stored ? " and stored" : "");
out:
        if (s->patient)
                master_patient_end(m);
        PT_END(&s->pc);
}
