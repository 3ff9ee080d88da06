/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Scans that find slaves without configuring anything.
 *
 * Enumeration: fastscan again and again; each slave found stays in
 * configuration state, so it no longer takes part, until a ping gets no
 * answer. Then all go back to waiting and every identity found is verified
 * by selective switch (the 0x44 answer can only come from a slave with that
 * exact identity) and asked its node-ID. A candidate that fails verification
 * was a scan error: it is dropped and the whole pass is run again.
 *
 * Slowscan: identify-remote-slave bisection over revision, then serial, for
 * one vendor/product; finds configured and non-configured slaves that
 * implement the identify services. A silent range is asked twice before it
 * is dropped (a missed answer would lose a slave silently). Candidates are
 * verified the same way. */
#include <errno.h>
#include <stdlib.h>

#include "lss/lss_internal.h"

static int cand_add(lss_scan_state *s, const lss_identity *id) {
        if (s->n_cand == s->cap_cand) {
                size_t cap = s->cap_cand ? s->cap_cand * 2 : 16;
                lss_device *d = realloc(s->cand, cap * sizeof(*d));
                if (!d)
                        return -ENOMEM;
                s->cand = d;
                s->cap_cand = cap;
        }
        s->cand[s->n_cand++] = (lss_device) { .id = *id, .node_id = LSS_NODE_ID_UNCONFIGURED };
        return 0;
}

static int stack_push(lss_scan_state *s, uint32_t rlo, uint32_t rhi, uint32_t slo, uint32_t shi) {
        if (s->n_stack == s->cap_stack) {
                size_t cap = s->cap_stack ? s->cap_stack * 2 : 64;
                void *d = realloc(s->stack, cap * sizeof(*s->stack));
                if (!d)
                        return -ENOMEM;
                s->stack = d;
                s->cap_stack = cap;
        }
        s->stack[s->n_stack].rlo = rlo;
        s->stack[s->n_stack].rhi = rhi;
        s->stack[s->n_stack].slo = slo;
        s->stack[s->n_stack].shi = shi;
        s->stack[s->n_stack].asked_again = false;
        s->n_stack++;
        return 0;
}

/* Selective switch to each candidate, read its node-ID, back to waiting.
 * Verified ones become result devices; the others are counted in `dropped`. */
static int verify_candidates(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->vpc);
        s->dropped = 0;
        for (s->i = 0; s->i < s->n_cand; s->i++) {
                step_selective(m, &s->cand[s->i].id);
                PT_YIELD(&s->vpc);
                if (!step_answered(m)) {
                        s->dropped++;
                        continue;
                }
                STEP_REQUEST(m, &s->vpc, lss_encode_inquire(&f__, LSS_FIELD_COUNT), LSS_CS_INQUIRE_NODE_ID);
                if (step_answered(m) && !step_conflict(m)) {
                        s->cand[s->i].node_id = m->step.answer.data[1];
                        if (master_add_device(m, &s->cand[s->i].id, s->cand[s->i].node_id) < 0) {
                                master_fail(m, LSS_E_INCOMPLETE, "out of memory");
                                break;
                        }
                } else
                        s->dropped++;
                STEP_REQUEST(m, &s->vpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING), -1);
                master_progress(m, 0.9 + 0.1 * (s->i + 1) / (double) s->n_cand);
        }
        PT_END(&s->vpc);
}

int proc_enumerate(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->pc);
        for (s->pass = 0; s->pass <= m->timing.cfg.retries; s->pass++) {
                s->n_cand = 0;
                s->failed_scans = 0;
                m->n_devices = 0;
                for (;;) {
                        s->fs = (lss_fastscan_state) { .known = s->known };
                        PT_CALL(&s->pc, proc_fastscan(m, &s->fs));
                        if (s->fs.none)
                                break;
                        if (!s->fs.found) {
                                /* the slaves found so far stay out of it: just scan again */
                                if (++s->failed_scans <= m->timing.cfg.retries)
                                        continue;
                                master_fail(m, LSS_E_INCOMPLETE, "fastscan did not converge after %u slaves",
                                            (unsigned) s->n_cand);
                                goto out;
                        }
                        s->failed_scans = 0;
                        {
                                lss_identity id;
                                for (unsigned i = 0; i < LSS_FIELD_COUNT; i++)
                                        lss_identity_set_field(&id, i, s->fs.value[i]);
                                if (cand_add(s, &id) < 0) {
                                        master_fail(m, LSS_E_INCOMPLETE, "out of memory");
                                        goto out;
                                }
                        }
                        master_progress(m, 0.9 * (1.0 - 1.0 / (1.0 + (double) s->n_cand)));
                }
                STEP_REQUEST(m, &s->pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING), -1);
                s->vpc = 0;
                PT_CALL(&s->pc, verify_candidates(m, s));
                if (m->result.status != LSS_OK || s->dropped == 0)
                        goto out;
                m->stats.retries++;
        }
        master_fail(m, LSS_E_INCOMPLETE, "%u slaves found by fastscan could not be verified", s->dropped);
out:;
        PT_END(&s->pc);
}

static void split(lss_scan_state *s, uint32_t rlo, uint32_t rhi, uint32_t slo, uint32_t shi) {
        /* low half on top: found in ascending order */
        if (rlo != rhi) {
                uint32_t mid = rlo + (rhi - rlo) / 2;
                stack_push(s, mid + 1, rhi, slo, shi);
                stack_push(s, rlo, mid, slo, shi);
        } else {
                uint32_t mid = slo + (shi - slo) / 2;
                stack_push(s, rlo, rhi, mid + 1, shi);
                stack_push(s, rlo, rhi, slo, mid);
        }
}

int proc_slowscan(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->pc);
        s->n_cand = s->n_stack = 0;
        m->n_devices = 0;
        if (stack_push(s, s->range.rev_lo, s->range.rev_hi, s->range.serial_lo, s->range.serial_hi) < 0) {
                master_fail(m, LSS_E_INCOMPLETE, "out of memory");
                goto out;
        }
        s->i = 0;
        while (s->n_stack > 0) {
                s->n_stack--;
                s->cur = s->stack[s->n_stack];
                step_lss(m, LSS_CS_IDENTIFY_SLAVE);
                m->step.discovery = s->i++ == 0;
                {
                        const uint32_t v[6] = { s->range.vendor, s->range.product, s->cur.rlo,
                                                s->cur.rhi,      s->cur.slo,       s->cur.shi };
                        for (unsigned i = 0; i < 6; i++) {
                                lss_frame f;
                                lss_encode_identify_remote(&f, i, v[i]);
                                step_add_tx(m, &f);
                        }
                }
                step_start(m);
                PT_YIELD(&s->pc);
                if (!step_answered(m)) {
                        /* Unlike fastscan, nothing later would notice a missed
                         * answer (a slow slave): ask a silent range once more
                         * before giving it up. */
                        if (!s->cur.asked_again) {
                                s->cur.asked_again = true;
                                s->stack[s->n_stack++] = s->cur;
                                m->stats.retries++;
                        }
                        continue;
                }
                if (s->cur.rlo == s->cur.rhi && s->cur.slo == s->cur.shi) {
                        lss_identity id = { s->range.vendor, s->range.product, s->cur.rlo, s->cur.slo };
                        if (cand_add(s, &id) < 0) {
                                master_fail(m, LSS_E_INCOMPLETE, "out of memory");
                                goto out;
                        }
                        continue;
                }
                split(s, s->cur.rlo, s->cur.rhi, s->cur.slo, s->cur.shi);
        }
        s->vpc = 0;
        PT_CALL(&s->pc, verify_candidates(m, s));
        if (m->result.status == LSS_OK && s->dropped > 0)
                master_fail(m, LSS_E_INCOMPLETE, "%u slaves answered identify but not the selective switch",
                            s->dropped);
out:;
        PT_END(&s->pc);
}
