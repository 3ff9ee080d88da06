/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Which node-IDs does somebody answer to? An SDO upload of 1000h (device
 * type, every CANopen device has it) to each, up to LSS_MAX_TX at once with
 * one wait for all of them: the wait is the full configured one (a slow
 * device must not pass for absent), so probing one at a time cost that
 * wait per node-ID. The step ends at the first answer, so after a batch
 * somebody answered each node-ID of it is asked again on its own. */
#include "lss/lss_internal.h"

int proc_probe(lss_master *m, lss_probe_state *s) {
        PT_BEGIN(&s->pc);
        for (s->i = 0; s->i < s->n_ids; s->i += s->n_batch) {
                s->n_batch = s->n_ids - s->i < LSS_MAX_TX ? s->n_ids - s->i : LSS_MAX_TX;
                step_nodes_in_use(m, s->ids + s->i, s->n_batch);
                PT_YIELD(&s->pc);
                if (m->step.n_answers == 0 || s->n_batch == 1) {
                        for (s->k = 0; s->k < s->n_batch; s->k++) {
                                s->taken[s->ids[s->i + s->k]] = m->step.n_answers > 0;
                                s->free[s->ids[s->i + s->k]] = m->step.n_answers == 0;
                        }
                        continue;
                }
                for (s->k = 0; s->k < s->n_batch; s->k++) {
                        step_node_in_use(m, s->ids[s->i + s->k]);
                        PT_YIELD(&s->pc);
                        s->taken[s->ids[s->i + s->k]] = m->step.n_answers > 0;
                        s->free[s->ids[s->i + s->k]] = m->step.n_answers == 0;
                }
        }
        PT_END(&s->pc);
}
