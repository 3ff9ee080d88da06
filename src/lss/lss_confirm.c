/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Confirming identities learnt another way (SDO discovery) through LSS
 * (lss_master_confirm). For each: everybody to waiting (twice: a
 * CANopenNode slave left in configuration answers any selective switch),
 * selective switch, asked again while nobody answers; if the slave answered,
 * Inquire Node-ID, asked again too. Confirmed, it is a result device with
 * the node-ID it answered, announced (lss_master_set_found). An identity
 * nobody answers is not confirmed: not a failure (a device without LSS, or
 * in a state where it does not take it). Everybody ends in waiting. */
#include <errno.h>

#include "lss/lss_internal.h"

#define SEND_WAITING(m, pc) STEP_REQUEST(m, pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING), -1)

static int proc_confirm(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->pc);
        m->n_devices = 0;
        if (s->n_cand == 0)
                goto out;
        for (s->i = 0; s->i < s->n_cand; s->i++) {
                master_progress(m, (double) s->i / (double) s->n_cand);
                s->found = s->cand[s->i].id;
                s->cpc = 0;
                PT_CALL(&s->pc, proc_confirm_by_selection(m, s));
                /* silent, the device is left out: asked again patiently */
                AGAIN_PATIENTLY_IF_SILENT(m, SELECT_RETRIED(m, &s->pc, s->attempt, &s->found));
                if (!step_answered(m))
                        continue;
                REQUEST_RETRIED(m, &s->pc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                                LSS_CS_INQUIRE_NODE_ID);
                /* selected, it is there: silent now, or answered by a late
                 * answer of the one before too, it would be left out */
                AGAIN_PATIENTLY_IF_UNCLEAR(m, REQUEST_RETRIED(m, &s->pc, s->attempt,
                                                             lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                                                             LSS_CS_INQUIRE_NODE_ID));
                if (!step_answered(m) || step_conflict(m))
                        continue;
                s->cand[s->i].node_id = m->step.answer.data[1];
                if (master_add_device(m, &s->cand[s->i].id, s->cand[s->i].node_id) < 0) {
                        master_fail(m, LSS_E_INCOMPLETE, "out of memory");
                        goto out;
                }
                master_found(m, &s->cand[s->i].id, s->cand[s->i].node_id, 0);
        }
        /* the last one selected had no switch to waiting after it yet: two,
         * so that one lost frame does not leave it in configuration */
        SEND_WAITING(m, &s->pc);
        SEND_WAITING(m, &s->pc);
        master_progress(m, 1);
out:;
        PT_END(&s->pc);
}

static int proc_confirm_top(lss_master *m) {
        PT_BEGIN(&m->pc);
        PT_CALL(&m->pc, proc_confirm(m, &m->sc));
        PT_END(&m->pc);
}

int lss_master_confirm(lss_master *m, const lss_identity *ids, size_t n, uint64_t now) {
        if (n > 0 && !ids)
                return -EINVAL;
        if (m->running)
                return -EBUSY;
        lss_scan_state *s = &m->sc;
        s->n_cand = 0;
        for (size_t i = 0; i < n; i++)
                if (cand_add(s, &ids[i]) < 0)
                        return -ENOMEM;
        s->pc = 0;
        return master_start_procedure(m, proc_confirm_top, now);
}
