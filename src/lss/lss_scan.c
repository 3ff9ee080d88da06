/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Slowscan: identify-remote-slave bisection over revision, then serial, for
 * one vendor/product; finds configured and non-configured slaves that
 * implement the identify services. A silent range is asked twice (the
 * whole range 1 + cfg.retries times) before it is dropped: a missed answer
 * would lose a slave silently. A range that answered but neither of whose
 * halves did is asked again (its answer may have been a late one of another
 * step): split again if it answers (up to cfg.retries times), and reported
 * if that never resolves. A candidate is
 * verified as soon as the bisection singles it out, by selective switch (the
 * 0x44 answer can only come from a slave with that exact identity), and
 * asked its node-ID, then announced (lss_master_set_found); a step nobody
 * answers is asked again: one late or lost frame must not cost a slave. At
 * the end everything between the slaves found is asked once more
 * (docs/engine.md, "Slowscan and lost frames").
 * (Enumeration by fastscan is in lss_enumerate.c.) */
#include <errno.h>
#include <stdlib.h>

#include "lss/lss_internal.h"

int cand_add(lss_scan_state *s, const lss_identity *id) {
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

static int stack_push(lss_scan_state *s, lss_range_item it) {
        if (s->n_stack == s->cap_stack) {
                size_t cap = s->cap_stack ? s->cap_stack * 2 : 64;
                void *d = realloc(s->stack, cap * sizeof(*s->stack));
                if (!d)
                        return -ENOMEM;
                s->stack = d;
                s->cap_stack = cap;
        }
        s->stack[s->n_stack++] = it;
        return 0;
}

/* Both halves of a range, by revision until it is one value, then by
 * serial; the low half on top, so slaves are found in ascending order. */
static int split(lss_scan_state *s, const lss_range_item *p, unsigned rechecks) {
        lss_range_item lo = { .rlo = p->rlo, .rhi = p->rhi, .slo = p->slo, .shi = p->shi, .rechecks = rechecks };
        lss_range_item hi = lo;
        hi.high = true;
        if (p->rlo != p->rhi) {
                lo.rhi = p->rlo + (p->rhi - p->rlo) / 2;
                hi.rlo = lo.rhi + 1;
                hi.by_rev = true;
                hi.low_start = p->rlo;
        } else {
                lo.shi = p->slo + (p->shi - p->slo) / 2;
                hi.slo = lo.shi + 1;
                hi.low_start = p->slo;
        }
        return stack_push(s, hi) < 0 || stack_push(s, lo) < 0 ? -ENOMEM : 0;
}

/* The range a high half was split from. */
static lss_range_item parent_of(const lss_range_item *hi) {
        lss_range_item p = { .rlo = hi->rlo, .rhi = hi->rhi, .slo = hi->slo, .shi = hi->shi };
        if (hi->by_rev)
                p.rlo = hi->low_start;
        else
                p.slo = hi->low_start;
        return p;
}

/* The candidate just found did not verify (no answer to the selective
 * switch or to Inquire Node-ID): counted, the first one named, and the
 * scan's later verdicts wait patiently. */
static void drop(lss_scan_state *s) {
        s->misheard = true;
        if (s->dropped++ == 0)
                s->dropped_id = s->cand[s->n_cand - 1].id;
}

/* Identify Remote Slave for one range item. */
static void step_identify_item(lss_master *m, const lss_scan_state *s, const lss_range_item *it) {
        const lss_identify_range r = { s->range.vendor, s->range.product, it->rlo, it->rhi, it->slo, it->shi };
        step_identify(m, &r);
        step_start(m);
}

/* Selective switch to the candidate just found, read its node-ID, back to
 * waiting: verified, it is a result device and announced at once (the
 * bisection goes on from waiting state); else it is counted in `dropped`.
 * A one-identity range can answer without a slave of that identity: an
 * identify answer does not say which request it answers, and a late one of
 * the step before is heard in this one. So a candidate silent to the
 * selective switch is asked its range again: silent, it was nobody;
 * answering, it is selected once more with longer waits before it is
 * counted. */
static int verify_candidate(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->vpc);
        SELECT_RETRIED(m, &s->vpc, s->attempt, &s->cand[s->n_cand - 1].id);
        AGAIN_PATIENTLY_IF_SILENT(m, SELECT_RETRIED(m, &s->vpc, s->attempt, &s->cand[s->n_cand - 1].id));
        if (!step_answered(m)) {
                STEP_RETRIED(m, &s->vpc, s->attempt, step_identify_item(m, s, &s->cur));
                if (!step_answered(m)) {
                        s->n_cand--;
                        s->misheard = true;
                        goto out;
                }
                lss_timing_on_stray(&m->timing);
                note_patience(m);
                STEP_REQUEST(m, &s->vpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING), -1);
                SELECT_RETRIED(m, &s->vpc, s->attempt, &s->cand[s->n_cand - 1].id);
                if (!step_answered(m)) {
                        drop(s);
                        goto out;
                }
        }
        REQUEST_RETRIED(m, &s->vpc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                        LSS_CS_INQUIRE_NODE_ID);
        /* selected, it is there: its silence now would drop it */
        AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->vpc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                                                     LSS_CS_INQUIRE_NODE_ID));
        if (step_answered(m) && !step_conflict(m)) {
                lss_device *c = &s->cand[s->n_cand - 1];
                c->node_id = m->step.answer.data[1];
                if (master_add_device(m, &c->id, c->node_id) < 0)
                        master_fail(m, LSS_E_INCOMPLETE, "out of memory");
                else
                        master_found(m, &c->id, c->node_id, 0);
        } else
                drop(s);
out:
        /* also after a silent selective switch: a slave that took it and
         * whose answers were lost is in configuration, and may be the last
         * one selected (a scan that ends OK sends no switch after it) */
        STEP_REQUEST(m, &s->vpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING), -1);
        PT_END(&s->vpc);
}

static int push_box(lss_scan_state *s, uint32_t rlo, uint32_t rhi, uint32_t slo, uint32_t shi) {
        return stack_push(s, (lss_range_item) { .rlo = rlo, .rhi = rhi, .slo = slo, .shi = shi, .gap = true });
}

static int by_revision_serial(const void *a, const void *b) {
        const lss_identity *x = &((const lss_device *) a)->id, *y = &((const lss_device *) b)->id;
        if (x->revision != y->revision)
                return x->revision < y->revision ? -1 : 1;
        return x->serial < y->serial ? -1 : x->serial > y->serial;
}

/* Everything of the range between the slaves found, as boxes of
 * revisions x serials: a slave whose half was silent twice while the other
 * half answered lies in one of them. */
static int push_gaps(lss_scan_state *s) {
        const lss_identify_range *r = &s->range;
        uint32_t r1 = r->rev_lo, s1 = r->serial_lo;
        bool before_first = true;
        if (s->n_cand > 1) /* cand is NULL when nobody was found (the whole range again) */
                qsort(s->cand, s->n_cand, sizeof(*s->cand), by_revision_serial);
        for (size_t i = 0; i <= s->n_cand; i++) {
                bool end = i == s->n_cand;
                uint32_t r2 = end ? r->rev_hi : s->cand[i].id.revision;
                uint32_t s2 = end ? r->serial_hi : s->cand[i].id.serial;
                /* from just after (r1, s1) (or from (r1, s1) itself before the
                 * first slave) to just before (r2, s2) (or (r2, s2) itself at the end) */
                bool from_incl = before_first, to_incl = end;
                int e = 0;
                if (r1 == r2) {
                        uint64_t lo = (uint64_t) s1 + !from_incl, hi = (uint64_t) s2 + to_incl;
                        if (hi > lo)
                                e |= push_box(s, r1, r1, (uint32_t) lo, (uint32_t) (hi - 1));
                } else {
                        if (from_incl || s1 < r->serial_hi)
                                e |= push_box(s, r1, r1, from_incl ? s1 : s1 + 1, r->serial_hi);
                        if ((uint64_t) r2 > (uint64_t) r1 + 1)
                                e |= push_box(s, r1 + 1, r2 - 1, r->serial_lo, r->serial_hi);
                        if (to_incl || s2 > r->serial_lo)
                                e |= push_box(s, r2, r2, r->serial_lo, to_incl ? s2 : s2 - 1);
                }
                if (e)
                        return -ENOMEM;
                if (!end) {
                        r1 = r2;
                        s1 = s2;
                        before_first = false;
                }
        }
        return 0;
}

/* How often a gap between the slaves found is asked before its silence
 * ends the scan (lss_loss.h). */
static unsigned gap_asks(const lss_master *m) {
        return lss_loss_asks(&m->loss, LSS_IDENTIFY_TX, m->timing.cfg.retries + 1u);
}

/* The ask of a range asked again after its halves were silent, or of a gap
 * once answers went astray, whose silence is the verdict: the last. The
 * asks before it take the adaptive wait: lost frames, not a stall, are
 * what mostly silences them, and each verdict's wait (at least 250 ms)
 * made a slowscan of 16 losing 1 % of its frames 4.4x as long. */
static bool verdict_ask(const lss_master *m, const lss_scan_state *s) {
        return (s->cur.confirm || (s->cur.gap && s->misheard)) && !m->patient &&
               s->cur.asks + 1u >= (s->cur.gap ? gap_asks(m) : 2u);
}

int proc_slowscan(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->pc);
        s->misheard = s->silent_before = false;
        s->n_cand = s->n_stack = 0;
        s->unresolved = s->dropped = 0;
        m->n_devices = 0;
        if (stack_push(s, (lss_range_item) { .rlo = s->range.rev_lo, .rhi = s->range.rev_hi,
                                             .slo = s->range.serial_lo, .shi = s->range.serial_hi,
                                             .root = true }) < 0)
                goto oom;
        s->i = 0;
        s->gap_passes = 0;
        s->gap_heard = false;
        s->heard = false;
again:
        while (s->n_stack > 0) {
                s->cur = s->stack[--s->n_stack];
                /* A range asked again because its halves were silent: its
                 * silence now drops a slave that answered it, maybe held
                 * back by a stalled host far beyond the adaptive waits. So
                 * does a gap's, the last look, once answers in this scan
                 * went to the wrong step: a host or bus that holds them
                 * back (late ones are taken for the step they fall in).
                 * Its last ask waits as a verdict does. */
                s->patient_ask = verdict_ask(m, s);
                if (s->patient_ask)
                        master_patient_begin(m, lss_timing_patient_wait(&m->timing, LSS_VERDICT_WAIT_FLOOR_US));
                step_identify_item(m, s, &s->cur);
                m->step.discovery = s->i++ == 0;
                m->step.watch_early = s->silent_before;
                PT_YIELD(&s->pc);
                if (s->patient_ask)
                        master_patient_end(m);
                s->silent_before = !step_answered(m);
                if (step_answered(m) && m->step.early) {
                        /* sooner than slaves answer, after a silent step: that
                         * step's late answer, likely, not this range's. Asked
                         * again (the silent one may have been dropped: the
                         * verdicts after a mix-up are patient) */
                        s->misheard = true;
                        s->stack[s->n_stack++] = s->cur;
                        m->stats.retries++;
                        continue;
                }
                if (!step_answered(m) && (s->cur.gap || s->cur.confirm)) {
                        /* silent twice like any half (a gap 1 + retries
                         * times, more when the scan lost frames: it is the
                         * last look): nobody there */
                        if (++s->cur.asks < (s->cur.gap ? gap_asks(m) : 2))
                                s->stack[s->n_stack++] = s->cur;
                        continue;
                }
                if (!step_answered(m)) {
                        /* Unlike fastscan, nothing later would notice a missed
                         * answer (a slow slave): ask a silent range once more
                         * before giving it up, the whole range as often as
                         * any other step (it costs only an empty bus time). */
                        if (++s->cur.asks < (s->cur.root ? m->timing.cfg.retries + 1 : 2)) {
                                s->stack[s->n_stack++] = s->cur;
                                m->stats.retries++;
                        } else if (!s->cur.high) {
                                /* a low half: its high half, right below, must answer now */
                                if (s->n_stack > 0)
                                        s->stack[s->n_stack - 1].low_silent = true;
                        } else if (s->cur.low_silent) {
                                /* Was the range's answer its own? A late
                                 * answer to the step before is heard in the
                                 * next: the range is asked again, and split
                                 * again only if it answers. */
                                lss_range_item p = parent_of(&s->cur);
                                s->misheard = true;
                                p.rechecks = s->cur.rechecks + 1;
                                p.confirm = true;
                                if (s->cur.rechecks >= m->timing.cfg.retries)
                                        s->unresolved++;
                                else if (stack_push(s, p) < 0)
                                        goto oom;
                                else
                                        m->stats.retries++;
                        }
                        continue;
                }
                s->heard = true;
                s->gap_heard = s->gap_heard || s->cur.gap;
                if (s->cur.rlo == s->cur.rhi && s->cur.slo == s->cur.shi) {
                        lss_identity id = { s->range.vendor, s->range.product, s->cur.rlo, s->cur.slo };
                        if (cand_add(s, &id) < 0)
                                goto oom;
                        s->vpc = 0;
                        PT_CALL(&s->pc, verify_candidate(m, s));
                        if (m->result.status != LSS_OK)
                                goto out;
                        continue;
                }
                if (split(s, &s->cur, s->cur.confirm ? s->cur.rechecks : 0) < 0)
                        goto oom;
        }
        if ((s->n_cand > 0 || s->heard) && m->result.status == LSS_OK && !m->cancelling &&
            (s->gap_passes == 0 || ((s->n_cand > s->n_before_gaps || s->gap_heard) &&
                                    s->gap_passes <= m->timing.cfg.retries))) {
                /* A silent half is asked twice: a slave that lost both while
                 * the other half answered would be missed, and the scan say
                 * OK. Everything between the slaves found is asked again
                 * (one step per gap, a few per slave), and again while that
                 * finds somebody or is answered: a slave that answered a gap
                 * and was lost again on the way down is still there. */
                s->gap_passes++;
                s->n_before_gaps = s->n_cand;
                s->gap_heard = false;
                if (push_gaps(s) < 0)
                        goto oom;
                goto again;
        }
        if (s->n_cand > 0) {
                /* Each verification ended with a switch to waiting, and the
                 * later ones gave earlier slaves another; the last slave
                 * verified had only its own: once more, so that one frame it
                 * lost does not leave it in configuration. */
                STEP_REQUEST(m, &s->pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING), -1);
        }
        if (s->gap_heard && s->n_cand == s->n_before_gaps && s->unresolved == 0 && s->dropped == 0 &&
            m->result.status == LSS_OK) {
                /* the last look was answered, and nobody singled out */
                master_fail(m, LSS_E_INCOMPLETE, "a range between the slaves found answered identify %u times but "
                            "no slave in it was singled out (answers lost, or not CiA 305)", s->gap_passes);
                goto out;
        }
        if (s->unresolved > 0) {
                if (s->dropped > 0)
                        master_fail(m, LSS_E_INCOMPLETE,
                                    "%u ranges answered identify each time but neither half did (not CiA 305, or "
                                    "answers lost); %u slaves answered identify, then not the selective switch or "
                                    "Inquire Node-ID (%s%08x:%08x:%08x:%08x)", s->unresolved, s->dropped,
                                    s->dropped > 1 ? "first " : "", s->dropped_id.vendor, s->dropped_id.product,
                                    s->dropped_id.revision, s->dropped_id.serial);
                else
                        master_fail(m, LSS_E_INCOMPLETE,
                                    "%u ranges answered identify each time but neither half did (not CiA 305, or "
                                    "answers lost)", s->unresolved);
        } else if (s->dropped > 0)
                master_fail(m, LSS_E_INCOMPLETE,
                            "%u slaves answered identify, then not the selective switch or Inquire Node-ID "
                            "(%s%08x:%08x:%08x:%08x)",
                            s->dropped, s->dropped > 1 ? "first " : "", s->dropped_id.vendor, s->dropped_id.product,
                            s->dropped_id.revision, s->dropped_id.serial);
        goto out;
oom:
        master_fail(m, LSS_E_INCOMPLETE, "out of memory");
out:;
        PT_END(&s->pc);
}
