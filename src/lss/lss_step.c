/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* One exchange on the bus: send the request frame(s), then wait for the
 * answer under the rules of lss_timing.h. Strict acceptance: a frame counts
 * only if it arrived after the request went out (stale frames are drained by
 * time), is a valid LSS response (0x7E4, DLC 8, no EFF/RTR/FD) and carries the
 * cs this step expects. Identical answers count once. */
#include <string.h>

#include "lss/lss_internal.h"

void step_lss(lss_master *m, int expect_cs) {
        m->step = (lss_step) {
                .kind = STEP_LSS,
                .expect_cs = expect_cs,
        };
}

void step_add_tx(lss_master *m, const lss_frame *f) {
        if (m->step.n_tx < LSS_MAX_TX)
                m->step.tx[m->step.n_tx++] = *f;
}

void step_selective(lss_master *m, const lss_identity *id) {
        step_lss(m, LSS_CS_SWITCH_SEL_RESPONSE);
        /* its answer says nothing but "here" (cs 0x44, the rest reserved): a
         * second slave's would be the same frame and count once */
        m->step.ends_at_answer = true;
        /* asked again, the slave that answered the ask before late is in
         * configuration and ignores this one: that answer is the answer */
        m->step.stale_is_answer = true;
        for (unsigned i = 0; i < LSS_FIELD_COUNT; i++) {
                lss_frame f;
                lss_encode_switch_selective(&f, i, lss_identity_field(id, i));
                step_add_tx(m, &f);
        }
        step_start(m);
}

void step_identify(lss_master *m, const lss_identify_range *r) {
        const uint32_t v[LSS_IDENTIFY_TX] = { r->vendor, r->product, r->rev_lo, r->rev_hi, r->serial_lo, r->serial_hi };
        step_lss(m, LSS_CS_IDENTIFY_SLAVE);
        for (unsigned i = 0; i < LSS_IDENTIFY_TX; i++) {
                lss_frame f;
                lss_encode_identify_remote(&f, i, v[i]);
                step_add_tx(m, &f);
        }
}

/* Every CANopen device has an SDO server: an expedited upload request of
 * object 0x1000 (device type) to a node-ID is answered by whoever has it. */
void step_nodes_in_use(lss_master *m, const uint8_t *ids, unsigned n) {
        m->step = (lss_step) { .kind = STEP_SDO, .discovery = true };
        for (unsigned i = 0; i < n && i < LSS_MAX_TX; i++) {
                lss_frame f = { .id = 0x600u + ids[i], .len = 8, .data = { 0x40, 0x00, 0x10, 0x00 } };
                step_add_tx(m, &f);
        }
        step_start(m);
}

void step_node_in_use(lss_master *m, uint8_t node_id) {
        step_nodes_in_use(m, &node_id, 1);
}

bool step_queue_tx(lss_master *m, const lss_frame *f) {
        if (m->txq_len >= sizeof(m->txq) / sizeof(m->txq[0]))
                return false;
        m->txq[(m->txq_head + m->txq_len) % LSS_TXQ_LEN] = *f;
        m->txq_len++;
        return true;
}

void step_event(lss_master *m, uint64_t until) {
        m->step = (lss_step) {
                .kind = STEP_EVENT,
                .sent_at = m->now,
                .wait_us = until <= m->now ? 0 : until - m->now > UINT32_MAX ? UINT32_MAX : (uint32_t) (until - m->now),
                .phase = PHASE_WAIT,
        };
}

void step_start(lss_master *m) {
        lss_step *s = &m->step;

        for (unsigned i = 0; i < s->n_tx; i++)
                (void) step_queue_tx(m, &s->tx[i]);
        /* everything still queued goes on the wire ahead of the answer
         * (e.g. an unconfirmed switch sent just before): in the engine's
         * queue, and handed out but not yet off the wire */
        if (m->wire_until > m->now)
                s->tx_us += m->wire_until - m->now;
        for (unsigned i = 0; i < m->txq_len; i++)
                s->tx_us += lss_timing_frame_us(&m->timing, &m->txq[(m->txq_head + i) % LSS_TXQ_LEN]);
        if (m->answers_until > m->now)
                s->busy_us = m->answers_until - m->now;
        s->sent_at = m->now;
        s->after_short_guard = m->short_guard_ended;
        m->short_guard_ended = false;
        if (s->kind == STEP_LSS && s->expect_cs >= 0)
                m->asked_at[s->expect_cs & 0xFF] = m->now + 1;
        s->needs_echo = s->kind == STEP_LSS && m->tx_confirm;
        s->phase = PHASE_WAIT;
        m->stats.steps++;
        /* unconfirmed request without a wait: done as soon as it is out */
        if (s->kind == STEP_LSS && s->expect_cs < 0)
                s->phase = PHASE_DONE;
}

void step_on_tx_confirmed(lss_master *m, uint64_t at) {
        lss_step *s = &m->step;

        /* an echo before this step's frames were written is an older frame's */
        if (!s->needs_echo || s->confirmed || !s->written)
                return;
        if (s->phase != PHASE_WAIT && s->phase != PHASE_LATE_GUARD)
                return;
        s->confirmed = true;
        /* the request is on the wire from now: the wait starts here, also
         * when a busy bus held it back past the estimated deadline */
        s->sent_at = at;
        s->tx_us = s->busy_us = 0;
        s->phase = PHASE_WAIT;
}

/* STEP_SDO: the bit of the node-ID asked that f answers for, 0: none */
static uint32_t sdo_bit(const lss_step *s, const lss_frame *f) {
        for (unsigned i = 0; i < s->n_tx; i++)
                if (f->id == s->tx[i].id - 0x80u && f->len == 8 && f->flags == 0)
                        return 1u << i;
        return 0;
}

static bool step_matches(const lss_step *s, const lss_frame *f) {
        if (s->kind == STEP_BOOTUP) {
                uint8_t node, state;
                return bootup_decode(f, &node, &state) && node == s->bootup_node && state == 0;
        }
        if (s->kind == STEP_SDO)
                return sdo_bit(s, f) != 0;
        return s->kind == STEP_LSS && lss_is_response(f) && f->data[0] == (uint8_t) s->expect_cs;
}

/* An SDO step asks several node-IDs and waits for all of them: it ends
 * early only when every one has answered. */
_Static_assert(LSS_MAX_TX < 32, "step.sdo_answered has a bit for each frame of a step");

static bool step_all_in(const lss_step *s) {
        return s->kind != STEP_SDO || s->sdo_answered == (1u << s->n_tx) - 1;
}

/* Could f be the late answer of a step of ours? Only if a step waited for
 * its cs lately: within twice the longest wait patience allows. A cs nobody
 * asked for (another master's, a fault) says nothing about our timing. */
static bool asked_lately(const lss_master *m, const lss_frame *f) {
        uint64_t at = m->asked_at[f->data[0]];
        return at != 0 && m->now + 1 - at <= 2ull * lss_timing_patience_cap(&m->timing);
}

/* An LSS answer that came when no step could take it was late for its own
 * step: the slaves or the host are slower than the waits. */
void step_on_stray(lss_master *m, const lss_frame *f) {
        if (!lss_is_response(f) || !asked_lately(m, f))
                return;
        /* the same answer again, in the time the skipped answer guard would
         * have taken it: another slave's or a duplicate, not a late answer */
        if (m->now <= m->answers_until && memcmp(f->data, m->final_answer.data, 8) == 0) {
                m->final_repeated = true;
                return;
        }
        /* before this step's request was out: the step before's, late */
        if (m->step.watch_early && step_matches(&m->step, f)) {
                bool first = !m->step.stale_answer;
                m->step.stale_answer = true;
                if (first)
                        m->step.stale_at = m->now;
                if (m->step.stale_is_answer && m->step.n_answers == 0 && m->step.phase == PHASE_WAIT) {
                        m->step.answer = *f;
                        m->step.n_answers = m->step.n_frames = 1;
                        m->step.first_at = m->now;
                        m->step.late = true;
                        m->step.phase = PHASE_DONE;
                }
                /* the one late answer the shortened guard of the step before
                 * left to this one (lss_timing_watched_late_guard): the
                 * procedure asks about it, as one in the guard would have
                 * been taken; a second one is a stall's */
                if (first && m->step.after_short_guard)
                        return;
        }
        m->stats.stray_answers++;
        /* One stall of the host delays every answer it holds: a crowded
         * step's come late together, and each doubling the waits took a
         * VM pass (8 slaves) to the cap, 80 ms a silent step for seconds.
         * Those within the wait the first one set are the same sign. */
        if (m->now < m->strays_until)
                return;
        lss_timing_on_stray(&m->timing);
        m->strays_until = m->now + lss_timing_wait(&m->timing, LSS_WAIT_ANSWER);
        note_patience(m);
}

void step_on_frame(lss_master *m, const lss_frame *f, uint64_t rx) {
        lss_step *s = &m->step;

        if (s->phase != PHASE_WAIT && s->phase != PHASE_ANSWER_GUARD && s->phase != PHASE_LATE_GUARD) {
                m->stats.ignored_frames++;
                step_on_stray(m, f);
                return;
        }
        if (s->kind == STEP_EVENT) {
                s->answer = *f;
                s->first_at = rx;
                s->n_answers = 1;
                s->phase = PHASE_DONE;
                return;
        }
        /* A slave answers only after the whole request is on the wire: anything
         * complete before that was queued earlier (the drain rule). With tx
         * confirmation the echo marks that moment in the socket's own order;
         * without it, the estimated wire time does. A boot-up may overtake
         * our queued frames (an NMT frame wins arbitration), so for it only
         * "before we sent" is stale. */
        if (s->needs_echo) {
                if (!s->confirmed) {
                        m->stats.stale_frames++;
                        step_on_stray(m, f);
                        return;
                }
        } else if (rx < s->sent_at + (s->kind == STEP_LSS ? s->tx_us : 0)) {
                m->stats.stale_frames++;
                step_on_stray(m, f);
                return;
        }
        if (!step_matches(s, f)) {
                m->stats.ignored_frames++;
                step_on_stray(m, f);
                return;
        }
        if (s->kind == STEP_SDO)
                s->sdo_answered |= sdo_bit(s, f);
        if (s->n_answers == 0) {
                /* the first answer decides the step: its latency is what the wait is for */
                /* (an rx time may read a little before the echo's: count 0) */
                if (s->kind == STEP_LSS) {
                        uint32_t latency = rx > s->sent_at + s->tx_us ? (uint32_t) (rx - s->sent_at - s->tx_us) : 0;
                        s->latency_us = latency;
                        s->early = s->watch_early && lss_timing_early(&m->timing, latency);
                        /* a step after a silent one, before the window can tell
                         * the step's own answer from the silent step's late one:
                         * no sample (taken wrongly, it would be the fastest of the
                         * window) */
                        bool doubtful = s->watch_early && m->timing.n_samples < LSS_EARLY_MIN_SAMPLES;
                        if (!s->early && !doubtful) {
                                lss_timing_add_sample(&m->timing, latency);
                                lss_timing_on_answer(&m->timing, latency,
                                                     s->phase == PHASE_LATE_GUARD && s->discovery);
                                note_patience(m);
                        }
                }
                s->answer = *f;
                s->n_answers = 1;
                s->n_frames = 1;
                s->first_at = rx;
                if (s->phase == PHASE_LATE_GUARD) {
                        s->late = true;
                        m->stats.late_answers++;
                }
                if (s->ends_at_answer) {
                        /* Further identical answers may still take the wire
                         * ahead of the next request (answers win arbitration):
                         * without tx confirmation that request's wait counts
                         * from when they would be off it. */
                        m->answers_until = rx + lss_timing_answer_guard(&m->timing);
                        m->final_answer = *f;
                        m->final_repeated = false;
                        s->phase = PHASE_DONE;
                } else if (step_all_in(s)) {
                        s->phase = PHASE_ANSWER_GUARD;
                        s->end_at = rx + lss_timing_answer_guard(&m->timing);
                }
                return;
        }
        /* more answers queue behind each other on the wire: wait until the
         * last one is in, so none of them leaks into the next step */
        if (s->phase == PHASE_WAIT && step_all_in(s)) {
                s->phase = PHASE_ANSWER_GUARD;
                s->end_at = 0;
        }
        if (s->phase != PHASE_WAIT) {
                uint64_t e = rx + lss_timing_answer_guard(&m->timing);
                if (e > s->end_at)
                        s->end_at = e;
        }
        s->n_frames++;
        /* two boot-ups of one node-ID: two devices took it (duplicate identity) */
        if (s->kind == STEP_BOOTUP || memcmp(s->answer.data, f->data, 8) != 0) {
                /* a second, different answer: more than one responder */
                if (s->n_answers == 1) {
                        m->stats.conflicts++;
                        s->other = *f;
                }
                s->n_answers = 2;
        }
}

static enum lss_wait_kind step_wait_kind(const lss_step *s) {
        if (s->discovery)
                return LSS_WAIT_DISCOVERY;
        if (!s->silence_answers)
                return LSS_WAIT_ANSWER;
        return s->next_watches ? LSS_WAIT_WATCHED_BIT : LSS_WAIT_BIT;
}

uint64_t step_deadline(const lss_master *m) {
        const lss_step *s = &m->step;

        switch (s->phase) {
        case PHASE_WAIT:
                if (s->kind == STEP_LSS || s->kind == STEP_SDO)
                        return s->sent_at + s->tx_us + s->busy_us + lss_timing_wait(&m->timing, step_wait_kind(s));
                return s->sent_at + s->tx_us + s->wait_us;
        case PHASE_ANSWER_GUARD:
        case PHASE_LATE_GUARD:
                return s->end_at;
        default:
                return UINT64_MAX;
        }
}

void step_on_time(lss_master *m, uint64_t now) {
        lss_step *s = &m->step;
        uint64_t d = step_deadline(m);

        if (d == UINT64_MAX || now < d)
                return;
        switch (s->phase) {
        case PHASE_WAIT:
                if (s->kind != STEP_LSS && s->kind != STEP_SDO) {
                        s->phase = PHASE_DONE;
                        return;
                }
                m->stats.timeouts++;
                s->phase = PHASE_LATE_GUARD;
                bool short_guard = s->next_watches && !s->late_us;
                s->end_at = d + (s->late_us     ? s->late_us
                                 : short_guard ? lss_timing_watched_late_guard(&m->timing, step_wait_kind(s))
                                               : lss_timing_late_guard(&m->timing, step_wait_kind(s)));
                m->short_guard_ended = short_guard;
                if (now >= s->end_at)
                        step_on_time(m, now);
                return;
        case PHASE_LATE_GUARD: {
                /* The request is not known to be on the wire, so its wait
                 * has not begun: not written yet (a host stalled between the
                 * step's start, whose clock is the last frame's receive time,
                 * and the write; the write puts the step back to its wait,
                 * lss_master_on_sent), or no echo yet (a loaded host delivers
                 * it late). Ended now, the next request would follow this one
                 * at once and overlap its answer (engine-vcan's witness:
                 * 0.2-0.95 ms after a silent bit step, after stalls of 7-8 ms). */
                bool unwritten = m->reports_writes && !s->written && s->n_tx > 0;
                if ((unwritten || (s->needs_echo && !s->confirmed)) && now < s->sent_at + LSS_ECHO_WAIT_MAX_US) {
                        s->end_at = s->sent_at + LSS_ECHO_WAIT_MAX_US;
                        return;
                }
                s->phase = PHASE_DONE;
                return;
        }
        case PHASE_ANSWER_GUARD:
                s->phase = PHASE_DONE;
                return;
        default:
                return;
        }
}

void step_sample(lss_master *m, uint32_t latency_us) {
        lss_timing_add_sample(&m->timing, latency_us);
        lss_timing_on_answer(&m->timing, latency_us, false);
        note_patience(m);
}

bool step_answered(const lss_master *m) {
        return m->step.n_answers > 0 && !m->step.void_;
}

bool step_conflict(const lss_master *m) {
        return m->step.n_answers > 1;
}
