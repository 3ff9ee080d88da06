/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Which node-IDs does somebody answer to? An SDO upload of 1000h (device
 * type, every CANopen device has it) to each, up to LSS_MAX_TX at once with
 * one wait for all of them: the wait is the full configured one (a slow
 * device must not pass for absent), so probing one at a time cost that
 * wait per node-ID. The step ends early once every node-ID asked has
 * answered (a plant at boot: all of them), otherwise when the wait runs
 * out; either way it says who answered. */
#include "lss/lss_internal.h"

int proc_probe(lss_master *m, lss_probe_state *s) {
        PT_BEGIN(&s->pc);
        for (s->i = 0; s->i < s->n_ids; s->i += s->n_batch) {
                s->n_batch = s->n_ids - s->i < LSS_MAX_TX ? s->n_ids - s->i : LSS_MAX_TX;
                step_nodes_in_use(m, s->ids + s->i, s->n_batch);
                PT_YIELD(&s->pc);
                for (s->k = 0; s->k < s->n_batch; s->k++) {
                        bool answered = m->step.sdo_answered & (1u << s->k);
                        s->taken[s->ids[s->i + s->k]] = answered;
                        s->free[s->ids[s->i + s->k]] = !answered;
                }
        }
        PT_END(&s->pc);
}
