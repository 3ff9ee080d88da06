/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Giving one slave its node-ID. The slave is put in configuration state by
 * selective switch (its full identity is known) or by fastscan (then its
 * identity is read back by inquiry and must equal what fastscan found, or
 * everything goes back to waiting and the scan is retried). Nothing is
 * configured or stored when it already has the node-ID. */
#include "lss/lss_internal.h"

/* Send an unconfirmed frame (no wait). */
#define SEND(m, pc, frame_expr) STEP_REQUEST(m, pc, frame_expr, -1)

bool inquired_node_id_ok(lss_master *m) {
        if (!step_answered(m)) {
                master_fail_at(m, LSS_E_NO_RESPONSE, LSS_SERVICE_INQUIRE, LSS_REASON_NO_ANSWER,
                               "the selected slave did not answer Inquire Node-ID");
                return false;
        }
        if (step_conflict(m)) {
                master_fail_at(m, LSS_E_CONFLICT, LSS_SERVICE_INQUIRE, LSS_REASON_SEVERAL_ANSWERS,
                               "more than one slave in configuration state answered Inquire Node-ID");
                return false;
        }
        m->result.node_id = m->step.answer.data[1];
        return true;
}

/* The answer to Inquire Serial Number asked of the selected slave `id`:
 * nobody else answered. */
static bool alone_in_configuration(lss_master *m, const lss_identity *id) {
        if (!step_answered(m)) {
                master_fail_at(m, LSS_E_NO_RESPONSE, LSS_SERVICE_INQUIRE, LSS_REASON_NO_ANSWER,
                               "the selected slave did not answer Inquire Serial Number: nothing configured");
                return false;
        }
        uint32_t serial = lss_get_u32(m->step.answer.data + 1);
        if (step_conflict(m)) {
                master_fail_at(m, LSS_E_CONFLICT, LSS_SERVICE_INQUIRE, LSS_REASON_SEVERAL_ANSWERS,
                               "another slave is in configuration state beside the selected one (%u different "
                               "answers to Inquire Serial Number): nothing configured", m->step.n_answers);
                return false;
        }
        if (serial != id->serial) {
                master_fail_at(m, LSS_E_CONFLICT, LSS_SERVICE_INQUIRE, LSS_REASON_SEVERAL_ANSWERS,
                               "another slave is in configuration state instead of the selected one (serial "
                               "%08x answered, not %08x): nothing configured", serial, id->serial);
                return false;
        }
        return true;
}

bool configure_answer_ok(lss_master *m, uint8_t node_id) {
        if (!step_answered(m)) {
                master_fail_at(m, LSS_E_NO_RESPONSE, LSS_SERVICE_CONFIGURE_NODE_ID, LSS_REASON_NO_ANSWER,
                               "no answer to Configure Node-ID %u", node_id);
                return false;
        }
        if (step_conflict(m)) {
                master_fail_at(m, LSS_E_CONFLICT, LSS_SERVICE_CONFIGURE_NODE_ID, LSS_REASON_SEVERAL_ANSWERS,
                               "more than one slave answered Configure Node-ID");
                return false;
        }
        m->result.err = m->step.answer.data[1];
        m->result.spec = m->step.answer.data[2];
        if (m->result.err != 0) {
                master_fail_at(m, LSS_E_REJECTED, LSS_SERVICE_CONFIGURE_NODE_ID, LSS_REASON_REFUSED,
                               "Configure Node-ID %u rejected by the slave: error %u, spec %u", node_id, m->result.err,
                               m->result.spec);
                return false;
        }
        return true;
}

bool store_answer_ok(lss_master *m) {
        if (!step_answered(m)) {
                master_fail_at(m, LSS_E_NO_RESPONSE, LSS_SERVICE_STORE, LSS_REASON_NO_ANSWER,
                               "no answer to Store Configuration");
                return false;
        }
        m->result.err = m->step.answer.data[1];
        m->result.spec = m->step.answer.data[2];
        if (m->result.err == LSS_ERR_STORE_NOT_SUPPORTED || m->result.err == LSS_ERR_STORE_MEDIA) {
                /* a device that cannot store still takes the node-ID
                 * until its next power cycle: go on, say so */
                m->result.not_stored = true;
        } else if (m->result.err != 0) {
                master_fail_at(m, LSS_E_REJECTED, LSS_SERVICE_STORE, LSS_REASON_REFUSED,
                               "Store Configuration rejected by the slave: %s (error %u, spec %u)",
                               lss_store_error_name(m->result.err), m->result.err, m->result.spec);
                return false;
        }
        return true;
}

/* The part shared by both ways in: the slave is the only one in configuration. */
static int assign_tail(lss_master *m, lss_assign_state *s) {
        PT_BEGIN(&s->tail_pc);
        if (s->old_known) {
                m->result.node_id = s->old;
        } else {
                REQUEST_RETRIED(m, &s->tail_pc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                                LSS_CS_INQUIRE_NODE_ID);
                AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->tail_pc, s->attempt,
                                                             lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                                                             LSS_CS_INQUIRE_NODE_ID));
                if (!inquired_node_id_ok(m))
                        goto out;
                s->old = m->result.node_id;
                s->lone = m->step.n_frames == 1 && !m->step.void_;
        }
        if (s->old == s->node_id) {
                /* Already right: nothing to configure, nothing to store —
                 * unless the node-ID came from an interrupted pass: configured,
                 * maybe not stored, taken when the slave went back to waiting. */
                if ((s->flags & LSS_ASSIGN_STORE) && s->unstored && s->unstored[s->node_id]) {
                        m->result.changed = true;
                        if (s->flags & LSS_ASSIGN_DRY_RUN)
                                goto dry;
                        goto store;
                }
                SEND(m, &s->tail_pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                goto out;
        }

        if (!s->lone) {
                /* Inquire Node-ID had two answers (or a void step): another
                 * slave may be in configuration beside this one (it lost the
                 * switches to waiting), and it would take the node-ID too
                 * (loss-bench, 3 % loss: node-ID 6 stored in two slaves).
                 * Their node-IDs look alike, their serials do not: only this
                 * slave's may answer (a slave that answers twice gives it twice). */
                REQUEST_RETRIED(m, &s->tail_pc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_SERIAL),
                                LSS_CS_INQUIRE_VENDOR + LSS_FIELD_SERIAL);
                AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->tail_pc, s->attempt,
                                                             lss_encode_inquire(&f__, LSS_FIELD_SERIAL),
                                                             LSS_CS_INQUIRE_VENDOR + LSS_FIELD_SERIAL));
                if (!alone_in_configuration(m, &s->id))
                        goto out;
        }
        if ((s->taken && s->taken[s->node_id]) ||
            ((s->flags & LSS_ASSIGN_CHECK_FREE) && m->taken_fn && m->taken_fn(m->taken_ud, s->node_id, &s->id))) {
                m->result.in_use = true;
                master_fail_at(m, LSS_E_CONFLICT, LSS_SERVICE_CONFIGURE_NODE_ID, LSS_REASON_IN_USE,
                               "node-ID %u already answered on the bus", s->node_id);
                goto out;
        }
        if ((s->flags & LSS_ASSIGN_CHECK_FREE) && !(s->free && s->free[s->node_id])) {
                step_node_in_use(m, s->node_id);
                PT_YIELD(&s->tail_pc);
                if (m->step.n_answers > 0) {
                        m->result.in_use = true;
                        master_fail_at(m, LSS_E_CONFLICT, LSS_SERVICE_CONFIGURE_NODE_ID, LSS_REASON_IN_USE,
                                       "node-ID %u already answers on the bus", s->node_id);
                        goto out;
                }
        }

        if (s->flags & LSS_ASSIGN_DRY_RUN) {
                m->result.changed = true;
                goto dry;
        }
        s->configuring = true;
        REQUEST_RETRIED_ENDS(m, &s->tail_pc, s->attempt, lss_encode_configure_node_id(&f__, s->node_id),
                             LSS_CS_CONFIGURE_NODE_ID, s->lone);
        AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->tail_pc, s->attempt,
                                                     lss_encode_configure_node_id(&f__, s->node_id),
                                                     LSS_CS_CONFIGURE_NODE_ID));
        if (!configure_answer_ok(m, s->node_id))
                goto out;
        m->result.changed = true;

store:
        if (s->flags & LSS_ASSIGN_STORE) {
                REQUEST_RETRIED_ENDS(m, &s->tail_pc, s->attempt, lss_encode_store(&f__), LSS_CS_STORE, s->lone);
                AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->tail_pc, s->attempt, lss_encode_store(&f__),
                                                             LSS_CS_STORE));
                if (!store_answer_ok(m))
                        goto out;
        }

        /* back to waiting: a non-configured slave now resets itself and boots up */
        SEND(m, &s->tail_pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        if (!(s->flags & LSS_ASSIGN_VERIFY))
                goto out;
        m->step = (lss_step) { .kind = STEP_BOOTUP, .bootup_node = s->node_id,
                               .wait_us = m->timing.cfg.bootup_timeout_us };
        if (s->old != LSS_NODE_ID_UNCONFIGURED) {
                /* a configured slave applies the new ID at Reset Communication */
                lss_frame f;
                nmt_encode(&f, NMT_CS_RESET_COMMUNICATION, s->old);
                step_add_tx(m, &f);
        }
        step_start(m);
        PT_YIELD(&s->tail_pc);
        if (!step_answered(m)) {
                /* configured and stored, N is the device's now: what does it hold? */
                s->vpc = 0;
                PT_CALL(&s->tail_pc, proc_assign_unverified(m, s));
        } else if (step_conflict(m))
                master_fail_at(m, LSS_E_CONFLICT, LSS_SERVICE_VERIFY, LSS_REASON_SEVERAL_ANSWERS,
                               "more than one device booted up as node %u (duplicate identity?)", s->node_id);
        goto out;
dry:
        m->result.dry = true;
        SEND(m, &s->tail_pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
out:
        /* Configure Node-ID went out (answered, or asked in vain): whatever
         * failed after it, the device may hold the node-ID now */
        if (m->result.status != LSS_OK && !m->result.given_back &&
            ((m->result.changed && !m->result.dry) || (m->result.failed_service == LSS_SERVICE_CONFIGURE_NODE_ID &&
                                                       m->result.reason == LSS_REASON_NO_ANSWER)))
                m->result.may_hold = true;
        s->configuring = false;
        PT_END(&s->tail_pc);
}

static void identity_of_scan(lss_assign_state *s) {
        for (unsigned i = 0; i < LSS_FIELD_COUNT; i++)
                lss_identity_set_field(&s->id, i, s->fs.value[i]);
}

/* Each assignment reports only on itself (a pass runs many). */
static void result_reset(lss_master *m) {
        m->result.changed = m->result.in_use = m->result.not_stored = m->result.dry = false;
        m->result.pending_reset = m->result.may_hold = m->result.given_back = false;
        m->result.err = m->result.spec = 0;
        m->result.failed_service = LSS_SERVICE_NONE;
        m->result.reason = LSS_REASON_NONE;
        m->result.node_id = LSS_NODE_ID_UNCONFIGURED;
}

int proc_assign(lss_master *m, lss_assign_state *s) {
        PT_BEGIN(&s->pc);
        result_reset(m);
        m->result.id = s->id;
        /* Asked again for a lost frame. A first look whose asks wait the
         * timeout (nothing measured yet: a device not there costs them all)
         * asks twice, and a device not heard is looked for again, patiently,
         * at the pass's end; asks that wait as answers come cost a few ms,
         * and a device missed for a stall of the host would be found by
         * fastscan first, 70 steps and more (4 buses at once, N = 32: 0.35 s) */
        STEP_RETRIED_UP_TO(m, &s->pc, s->attempt,
                           s->first_look && m->timing.n_samples == 0 ? 1u : m->timing.cfg.retries,
                           step_selective(m, &s->id));
        /* a device just found is not missing for a silence: a stall, likely */
        if (!s->first_look)
                AGAIN_PATIENTLY_IF_SILENT(m, SELECT_RETRIED(m, &s->pc, s->attempt, &s->id));
        if (!step_answered(m)) {
                master_fail_at(m, LSS_E_NOT_FOUND, LSS_SERVICE_SWITCH_SELECTIVE, LSS_REASON_NO_ANSWER,
                               "no slave %08x:%08x:%08x:%08x answered the selective switch", s->id.vendor,
                               s->id.product, s->id.revision, s->id.serial);
                goto out;
        }
        s->tail_pc = 0;
        PT_CALL(&s->pc, assign_tail(m, s));
out:
        /* a pass goes on after a failed assignment: nobody may stay selected */
        if (m->result.status != LSS_OK)
                SEND(m, &s->pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        PT_END(&s->pc);
}

int proc_assign_selected(lss_master *m, lss_assign_state *s) {
        PT_BEGIN(&s->pc);
        result_reset(m);
        m->result.id = s->id;
        s->tail_pc = 0;
        PT_CALL(&s->pc, assign_tail(m, s));
        PT_END(&s->pc);
}

int proc_fastscan_assign(lss_master *m, lss_assign_state *s) {
        PT_BEGIN(&s->pc);
        result_reset(m);
        for (s->attempt = 0;; s->attempt++) {
                s->fs.pc = 0;
                PT_CALL(&s->pc, proc_fastscan(m, &s->fs));
                if (s->fs.none && !s->fs.ping_late_us) {
                        /* "nobody left" is a verdict (a caller's loop ends on
                         * it): a stalled host's answers come after a patient
                         * wait (a loaded VM: 6 of 8 assigned, then "not found") */
                        SEND(m, &s->pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                        s->fs.ping_again = true;
                        s->fs.ping_late_us = lss_timing_patient_wait(&m->timing, LSS_VERDICT_WAIT_FLOOR_US);
                        s->fs.pc = 0;
                        PT_CALL(&s->pc, proc_fastscan(m, &s->fs));
                }
                if (s->fs.none) {
                        master_fail_at(m, LSS_E_NOT_FOUND, LSS_SERVICE_FASTSCAN, LSS_REASON_NO_ANSWER,
                                       "no non-configured slave answered the fastscan");
                        goto out;
                }
                if (!s->fs.found) {
                        master_fail_at(m, LSS_E_INCOMPLETE, LSS_SERVICE_FASTSCAN, LSS_REASON_UNRESOLVED,
                                       "fastscan did not converge");
                        goto out;
                }
                identity_of_scan(s);
                /* read the identity back: it must be exactly what the scan found,
                 * from exactly one slave */
                for (s->field = 0; s->field < LSS_FIELD_COUNT; s->field++) {
                        STEP_REQUEST(m, &s->pc, lss_encode_inquire(&f__, s->field),
                                     LSS_CS_INQUIRE_VENDOR + (int) s->field);
                        if (!step_answered(m) || step_conflict(m) ||
                            lss_get_u32(m->step.answer.data + 1) != lss_identity_field(&s->id, s->field))
                                break;
                }
                if (s->field == LSS_FIELD_COUNT)
                        break;
                m->stats.retries++;
                if (s->attempt >= m->timing.cfg.retries) {
                        master_fail_at(m, LSS_E_CONFLICT, LSS_SERVICE_FASTSCAN, LSS_REASON_NOT_CONFIRMED,
                                    "the slave found by fastscan (%08x:%08x:%08x:%08x) did not confirm its identity",
                                    s->id.vendor, s->id.product, s->id.revision, s->id.serial);
                        goto out;
                }
                SEND(m, &s->pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        }
        m->result.id = s->id;
        s->tail_pc = 0;
        PT_CALL(&s->pc, assign_tail(m, s));
out:
        /* a pass goes on after a failed assignment: nobody may stay selected */
        if (m->result.status != LSS_OK)
                SEND(m, &s->pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        PT_END(&s->pc);
}
