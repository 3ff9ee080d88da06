/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* CiA 305's global procedure for a new bit rate, steps 1 and 2 of
 * lss_master_set_bitrate() for devices that cannot be selected one by one
 * (option `global`): Switch State Global to configuration, Configure Bit
 * Timing to everybody at once. Every answer is counted, identical ones too,
 * but a count is only a lower bound: identical answers that start on the
 * same bit are one frame on a real bus. So fewer answers than devices is
 * asked again (harmless: the same pending timing) but is no refusal; a
 * refusal, or no answer at all, is: nothing is activated, and everybody is
 * configured back to the old rate (globally: who refused cannot be told
 * when several answer). A device that did not hear the request, or never
 * answers it, is not seen here; the check at the new rate finds it. */
#include "lss/lss_internal.h"

#define SEND(m, pc, frame_expr) STEP_REQUEST(m, pc, frame_expr, -1)

/* The refusal among the step's answers (data[1] != 0), or NULL. */
static const lss_frame *refusal(const lss_master *m) {
        if (!step_answered(m))
                return NULL;
        if (m->step.answer.data[1] != 0)
                return &m->step.answer;
        if (step_conflict(m) && m->step.other.data[1] != 0)
                return &m->step.other;
        return NULL;
}

int proc_bitrate_global_configure(lss_master *m, lss_bitrate_state *s) {
        const lss_frame *no;

        PT_BEGIN(&s->gpc);
        s->answers = 0;
        for (s->attempt = 0;; s->attempt++) {
                master_progress(m, (1.0 + (double) s->attempt / (double) (m->timing.cfg.retries + 1)) / 3.0);
                SEND(m, &s->gpc, lss_encode_switch_global(&f__, LSS_MODE_CONFIGURATION));
                /* the full wait: how fast the slowest device answers is unknown */
                step_lss(m, LSS_CS_CONFIGURE_BIT_TIMING);
                m->step.discovery = true;
                {
                        lss_frame f;
                        lss_encode_configure_bit_timing(&f, 0, s->index);
                        step_add_tx(m, &f);
                }
                step_start(m);
                PT_YIELD(&s->gpc);
                no = refusal(m);
                if (no) {
                        m->result.err = no->data[1];
                        m->result.spec = no->data[2];
                        master_fail_at(m, LSS_E_REJECTED, LSS_SERVICE_CONFIGURE_BIT_TIMING, LSS_REASON_REFUSED,
                                       "a device refused %u bit/s (table 0, index %u) in the global procedure: "
                                       "error %u, spec %u; which one cannot be told; nothing activated",
                                       s->p.bitrate, s->index, m->result.err, m->result.spec);
                        goto revert;
                }
                if (step_answered(m) && m->step.n_frames > s->answers)
                        s->answers = m->step.n_frames;
                if (s->answers >= s->p.n_devices || s->attempt >= m->timing.cfg.retries)
                        break;
                /* fewer than expected: lost, or merged on the wire; once more */
                m->stats.retries++;
        }
        if (s->answers == 0) {
                master_fail_at(m, LSS_E_REJECTED, LSS_SERVICE_CONFIGURE_BIT_TIMING, LSS_REASON_NO_ANSWER,
                               "nobody answered Configure Bit Timing (table 0, index %u) in the global procedure: "
                               "taken as a refusal, nothing activated", s->index);
                goto revert;
        }
        for (s->i = 0; s->i < s->p.n_devices; s->i++)
                s->p.devices[s->i].outcome = LSS_BITRATE_CONFIGURED;
        goto out;

revert:
        /* whoever took the new timing gives it back: a later Store
         * Configuration must not persist a rate nobody activated */
        if (s->can_revert) {
                SEND(m, &s->gpc, lss_encode_switch_global(&f__, LSS_MODE_CONFIGURATION));
                STEP_REQUEST(m, &s->gpc, lss_encode_configure_bit_timing(&f__, 0, s->old_index),
                             LSS_CS_CONFIGURE_BIT_TIMING);
        }
out:;
        PT_END(&s->gpc);
}

unsigned lss_master_bitrate_answers(const lss_master *m) {
        return m->br.answers;
}
