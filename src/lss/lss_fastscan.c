/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* LSS Fastscan: find one non-configured slave in waiting state and leave it in
 * configuration state. The ping (bitcheck 0x80) resets every participating
 * slave and is a discovery step (full configured wait, so slow slaves get
 * measured). Unknown bits are scanned from 31 down to 0; every field is then
 * confirmed with bitcheck 0 before the next one is started. A field whose
 * confirmation fails is retried from a new ping, with the fields confirmed
 * so far confirmed directly; if such a field fails too, everything is scanned
 * again. A guess (vendor, product, revision of the last find) is confirmed
 * directly before a field is scanned; scanned when nobody confirms it. A
 * run of silent bits is checked on the way (check_field_read): a bit read
 * wrong is searched for, not the whole field read again.
 * Nothing is reported found unless all four confirmations succeeded (a
 * late answer counts, below); callers check the identity again by inquiry
 * before configuring anything. */
#include <string.h>

#include "lss/lss_internal.h"

/* Every answered step narrows the slaves taking part to those that answered
 * it (a bit read 0, a field confirmed: the others no longer match what is
 * asked). So once one slave alone answered a step (one frame in the full
 * answer guard), only it can answer the steps after: a bit step then ends at
 * its answer, without the guard that waits for other slaves' answers. One
 * frame may still be several slaves (identical frames sent at once merge on
 * CAN) whose answers part later; such an answer lands in the next step and
 * reads a bit wrong. So the last bit of a field and every confirmation keep
 * the guard: a field is only ever confirmed once every answer before it is
 * in, and a wrong bit costs what a late answer costs, a field nobody
 * confirms and a retry. After one, the guard stays for the rest of this
 * fastscan; also on a sign of other answers (the same answer again, a stray
 * one, frames lost), a new ping, or a slave kept in configuration that
 * answered Fastscan there (it answers any request). Never in a patient
 * round (a verdict's re-check): it runs because a stall was seen, and a
 * stall's queued answers come in a burst; a step that ended at one of them
 * left the next for the step after, and each read a bit 0 that no slave
 * has (a Lely bus with answers 100-200 ms late on 5 %: 13 of 3000 pool
 * passes ended "found ... but no slave confirmed it" before). */
static void judge_lone(lss_master *m, lss_fastscan_state *s) {
        if (m->patient || m->final_repeated || m->stats.stray_answers != s->strays || m->step.void_ ||
            s->others_answer || s->lone_failed)
                s->lone = false;
        else if (step_answered(m) && !m->step.ends_at_answer)
                s->lone = m->step.n_frames == 1;
        s->strays = m->stats.stray_answers;
}

/* While one slave alone takes part, a silent bit step's late answer lands
 * in the step after it, which watches for it (an early answer after a
 * silent step, below) and asks the bit again: two steps, where the late
 * guard cost every silent bit step (4-8 s of a VM Scan of 127); so its
 * guard is shortened by what that watch tells (lss_timing_watched_late_guard).
 * Not a field's bit 0 (its late answer in the confirmation confirms a value
 * nobody has: an attempt), nor the bit whose silence starts a check
 * (check_field_read does not watch), nor in a patient round (a verdict's
 * re-check waits for every answer). */
static bool late_answer_watched(const lss_master *m, const lss_fastscan_state *s) {
        return s->lone && !m->patient && s->bit > 0 &&
               !(s->silent_run + 1 == LSS_FASTSCAN_CHECK_RUN && s->searches < LSS_FASTSCAN_SEARCHES);
}

/* `unguarded`: the step may end at its answer when one slave alone takes
 * part. `bit`: a bit step, whose silence is an answer (the shorter wait).
 * A bit step after a silent one watches for an early answer (below). */
#define FASTSCAN_STEP(m, s, frame_expr, unguarded, bit) FASTSCAN_STEP_AT(m, s, &(s)->pc, frame_expr, unguarded, bit)
#define FASTSCAN_STEP_AT(m, s, pc, frame_expr, unguarded, bit) \
        do { lss_frame f__; frame_expr; step_lss(m, LSS_CS_IDENTIFY_SLAVE); step_add_tx(m, &f__); \
             m->step.ends_at_answer = (s)->lone && (unguarded); m->step.silence_answers = (bit); \
             m->step.next_watches = (bit) && late_answer_watched(m, s); \
             m->step.watch_early = (s)->watch_next; (s)->watch_next = false; \
             step_start(m); PT_YIELD(pc); (s)->steps_since++; \
             judge_lone(m, s); (s)->before_sent_us = (s)->sent_us; \
             (s)->sent_us = m->step.sent_at + m->step.tx_us; (s)->after = AFTER_ANSWER; } while (0)

/* An answer too soon to be a step's own (lss_step.early), or one before its
 * request was out (lss_step.stale_answer), right after a silent step is most
 * likely that step's, late: taken for the next step's it reads a bit wrong
 * and a field nobody confirms follows. So a silent bit step is asked again;
 * a silent confirmation (or guess) has moved the slaves on and is taken as confirmed
 * (docs/engine.md, "An early answer after a silence"). This is the late
 * answer's latency from its own request. */
static uint32_t late_latency(const lss_master *m, const lss_fastscan_state *s) {
        uint64_t at = m->step.stale_answer ? m->step.stale_at : m->step.first_at;
        uint64_t l = at > s->before_sent_us ? at - s->before_sent_us : 0;
        return l > UINT32_MAX ? UINT32_MAX : (uint32_t) l;
}

/* The early answer after a silent confirmation (or guess) is its own, late:
 * the slaves moved on, the field is confirmed. */
static void take_late_confirmation(lss_master *m, lss_fastscan_state *s) {
        m->stats.late_answers++;
        if (m->step.early)
                step_sample(m, late_latency(m, s));
        s->value[s->sub] = s->confirm_value;
        s->late_confirmed = true;
        /* a guess that held, late: guessing goes on */
        s->guessing = s->confirm_guessed;
}

static uint32_t low_bits(int n) {
        return n >= 32 ? UINT32_MAX : (1u << n) - 1;
}

static int fs_mid(const lss_fastscan_state *s) {
        return (s->match_lo + s->match_hi) / 2;
}

/* Asked after LSS_FASTSCAN_CHECK_RUN silent bit steps in a row (s->bit the
 * last): does anybody match the bits as read? If nobody does, one above was
 * read wrong (a late answer missed, a straggler taken), and the longest
 * prefix somebody has ends just above it: found by asking shorter prefixes
 * (the answer wait: a silence taken too early here flips a right bit), it
 * costs a few steps instead of every bit after it, a confirmation and the
 * field read again. Answers out of step meanwhile (early, stale, strays: a
 * slave whose answers queue behind a stalled one) leave it unfound, and the
 * read goes on as before. */
static int check_field_read(lss_master *m, lss_fastscan_state *s) {
        PT_BEGIN(&s->check_pc);
        s->check = CHECK_HELD;
        s->silent_run = 0;
        FASTSCAN_STEP_AT(m, s, &s->check_pc,
                         lss_encode_fastscan(&f__, s->value[s->sub], (uint8_t) s->bit, (uint8_t) s->sub,
                                             (uint8_t) s->sub), false, false);
        if (step_answered(m))
                goto out;
        m->stats.retries++;
        s->searches++;
        s->lone_failed = s->lone_failed || s->lone;
        s->lone = false;
        s->check = CHECK_DOUBT;
        s->search_strays = m->stats.stray_answers;
        s->match_lo = s->bit;
        s->match_hi = 32 - (int) s->top;
        while (s->match_hi - s->match_lo > 1) {
                s->watch_next = true;
                FASTSCAN_STEP_AT(m, s, &s->check_pc,
                                 lss_encode_fastscan(&f__, s->value[s->sub] & ~low_bits(fs_mid(s)), (uint8_t) fs_mid(s),
                                                     (uint8_t) s->sub, (uint8_t) s->sub), false, false);
                if (m->step.stale_answer || (step_answered(m) && m->step.early))
                        goto out;
                if (step_answered(m))
                        s->match_hi = fs_mid(s);
                else
                        s->match_lo = fs_mid(s);
        }
        if (m->stats.stray_answers != s->search_strays)
                goto out;
        if (s->match_hi == 32 - (int) s->top) {
                /* not even the first bit, either way: nobody takes part in
                 * this field now (the confirmation before it was a
                 * straggler's, or a stalled slave's answers queue) */
                s->check = CHECK_NOBODY;
                goto out;
        }
        /* flipped, that bit matches them; the bits below are read again */
        s->check = CHECK_FIXED;
        s->bit = s->match_hi - 1;
        s->value[s->sub] = (s->value[s->sub] ^ (1u << s->bit)) & ~low_bits(s->bit);
        s->after = AFTER_ANSWER;
out:;
        PT_END(&s->check_pc);
}

/* A field's confirmation (bitcheck 0, LSSNext the next field), watched
 * after a silent step. A direct confirmation asked again after a silent one
 * takes that one's late answer as confirming (the slaves moved on). After
 * the last bit read silent, an early answer is that bit's, late, or the
 * confirmation's own: taken for the confirmation's when it was the bit's,
 * it confirmed a field nobody has, and nobody took part in the next (in VM
 * candumps about one pass in ten, 0.15-0.5 s each). So that bit is asked
 * again: answered, it reads 0 and the field is confirmed again; silent, the
 * slaves moved on with the confirmation: confirmed. */
static int confirm_field(lss_master *m, lss_fastscan_state *s) {
        PT_BEGIN(&s->confirm_pc);
        s->sent_last = s->sent_last || s->sub == LSS_FIELD_COUNT - 1;
        for (;;) {
                s->confirm_after = s->after;
                s->watch_next = s->after != AFTER_ANSWER;
                FASTSCAN_STEP_AT(m, s, &s->confirm_pc,
                                 lss_encode_fastscan(&f__, s->value[s->sub], 0, (uint8_t) s->sub,
                                                     (uint8_t) ((s->sub + 1) % LSS_FIELD_COUNT)), false, false);
                if (!m->step.watch_early || !(m->step.stale_answer || (step_answered(m) && m->step.early)))
                        break;
                if (s->confirm_after == AFTER_SILENT_CONFIRM) {
                        m->stats.late_answers++;
                        if (m->step.early)
                                step_sample(m, late_latency(m, s));
                        s->late_confirmed = true;
                        break;
                }
                FASTSCAN_STEP_AT(m, s, &s->confirm_pc,
                                 lss_encode_fastscan(&f__, s->value[s->sub] & ~1u, 0, (uint8_t) s->sub,
                                                     (uint8_t) s->sub), false, true);
                if (!step_answered(m)) {
                        s->late_confirmed = true;
                        break;
                }
                m->stats.late_answers++;
                s->value[s->sub] &= ~1u;
        }
        PT_END(&s->confirm_pc);
}

static uint32_t known_prefix(const lss_fastscan_known *k, unsigned sub) {
        unsigned n = k->known_bits[sub];
        if (n == 0)
                return 0;
        uint32_t mask = n >= 32 ? UINT32_MAX : ~(UINT32_MAX >> n);
        return lss_identity_field(&k->value, sub) & mask;
}

/* An answered step of this field read with two frames or more: another
 * slave has the top `bits` of value[sub] too (a late answer of a step before
 * looks the same: a hint, never a fact). */
static void note_crowd(const lss_master *m, lss_fastscan_state *s, unsigned bits) {
        if (step_answered(m) && m->step.n_frames >= 2 && !m->step.void_ && bits > s->crowd_bits[s->sub])
                s->crowd_bits[s->sub] = (uint8_t) bits;
}

/* The top bits of field `sub` another slave shared with the last find, when
 * the fields before are the last find's too: that slave is still there
 * (it answered, and the last find took its place in the search, not it). */
static unsigned hint_bits(const lss_fastscan_state *s) {
        unsigned n = s->hint.known_bits[s->sub];
        for (unsigned i = 0; n > 0 && i < s->sub; i++)
                if (s->value[i] != lss_identity_field(&s->hint.value, i))
                        return 0;
        return n > 31 ? 31 : n;
}

/* Fastscan finds the least identity taking part (each bit is asked 0
 * first, the fields in order), so after a find every slave still taking
 * part is above it, the floor. While the fields and bits read so far are
 * the floor's, a bit the floor has 1 is 1 for every such slave: it is not
 * asked (about half the bits the next find shares with the last: each a
 * silent step, the longest kind). A slave below the floor (its answers
 * were lost when it was the least) does not match after that bit: a run
 * of silent bits is checked and the bit searched for (check_field_read),
 * or the field is not confirmed and is read again, every bit asked; a
 * failed fastscan drops the floor (lss_enumerate.c). Only the first read
 * of a field, and never bit 0: the last bit asked keeps its guard. */
static bool floor_forces(const lss_fastscan_state *s) {
        if (!s->floored || s->attempt > 0 || s->field_try > 0 || s->bit == 0)
                return false;
        for (unsigned i = 0; i < s->sub; i++)
                if (s->value[i] != lss_identity_field(&s->hint.value, i))
                        return false;
        uint32_t f = lss_identity_field(&s->hint.value, s->sub);
        return ((s->value[s->sub] ^ f) & ~low_bits(s->bit + 1)) == 0 && (f >> s->bit & 1u);
}

/* The steps field `sub` takes as planned now: one, its confirmation, when
 * it was confirmed in an attempt before, is known or is to be guessed;
 * else its unknown bits and the confirmation. */
static unsigned field_steps(const lss_fastscan_state *s, unsigned sub) {
        unsigned known = s->known.known_bits[sub];
        if (sub < s->confirmed || known >= 32 || (s->guessing && sub < s->n_guess && known == 0))
                return 1;
        return 33 - known;
}

static unsigned steps_from(const lss_fastscan_state *s, unsigned sub) {
        unsigned n = 0;
        for (; sub < LSS_FIELD_COUNT; sub++)
                n += field_steps(s, sub);
        return n;
}

/* A fastscan's progress by its steps: those taken since the last report
 * get their share of what was left, against the `ahead` steps still
 * planned. So it never goes back, reaches 1 with the last confirmation,
 * and moves on, slower, while a find asks again (a guess nobody has, bits
 * read again). By field position instead, a find whose vendor, product
 * and revision were guessed made 3/4 of its way in its first 4 steps and
 * the serial's 32 bits the rest: a slow find stood still (issue 39). */
static void fastscan_progress(lss_master *m, lss_fastscan_state *s, unsigned ahead) {
        unsigned k = s->steps_since;
        if (k == 0)
                return;
        s->steps_since = 0;
        s->prog += (1.0 - s->prog) * k / (double) (k + ahead);
        master_progress(m, s->prog);
}

int proc_fastscan(lss_master *m, lss_fastscan_state *s) {
        PT_BEGIN(&s->pc);
        s->found = s->none = s->silent = s->heard = s->sent_last = false;
        s->prog = 0;
        s->steps_since = 0;
        memset(s->crowd_bits, 0, sizeof(s->crowd_bits));
        s->guessing = s->n_guess > 0;
        for (s->attempt = 0; s->attempt < m->timing.cfg.retries + 1; s->attempt++) {
                /* from this ping on: signs of other slaves from before say nothing */
                s->lone = false;
                s->strays = m->stats.stray_answers;
                s->after = AFTER_ANSWER;
                m->final_repeated = false;
                step_lss(m, LSS_CS_IDENTIFY_SLAVE);
                m->step.discovery = !s->ping_again || s->attempt > 0;
                m->step.late_us = s->ping_late_us;
                {
                        lss_frame f;
                        lss_encode_fastscan(&f, 0, LSS_FASTSCAN_PING, 0, 0);
                        step_add_tx(m, &f);
                }
                step_start(m);
                PT_YIELD(&s->pc);
                s->steps_since++;
                judge_lone(m, s);
                if (m->step.void_)
                        continue;
                if (!step_answered(m)) {
                        s->none = s->silent = true;
                        break;
                }
                s->heard = true;
                fastscan_progress(m, s, steps_from(s, 0));
                for (s->sub = 0; s->sub < LSS_FIELD_COUNT; s->sub++) {
                        if (s->guessing && s->sub < s->n_guess && s->sub >= s->confirmed &&
                            s->known.known_bits[s->sub] == 0) {
                                /* Devices on one bus mostly share vendor, product
                                 * and revision: the caller's guess (the last find)
                                 * is confirmed directly, one step instead of 33;
                                 * scanned only when nobody has it. */
                                s->value[s->sub] = lss_identity_field(&s->guess, s->sub);
                                FASTSCAN_STEP(m, s,
                                             lss_encode_fastscan(&f__, s->value[s->sub], 0, (uint8_t) s->sub,
                                                                 (uint8_t) ((s->sub + 1) % LSS_FIELD_COUNT)), false, false);
                                if (step_answered(m)) {
                                        fastscan_progress(m, s, steps_from(s, s->sub + 1));
                                        continue;
                                }
                                s->guessing = false;
                                fastscan_progress(m, s, steps_from(s, s->sub));
                                s->after = AFTER_SILENT_CONFIRM;
                                s->confirm_value = s->value[s->sub];
                                s->confirm_guessed = true;
                        }
                        for (s->field_try = 0;; s->field_try++) {
                                s->check = CHECK_HELD;
                                if (s->sub < s->confirmed) {
                                        /* confirmed in an earlier attempt: confirm directly */
                                } else if (s->known.known_bits[s->sub] >= 32) {
                                        s->value[s->sub] = lss_identity_field(&s->known.value, s->sub);
                                } else {
                                        s->top = s->known.known_bits[s->sub];
                                        s->value[s->sub] = known_prefix(&s->known, s->sub);
                                        /* Slaves that shared the last find's top bits
                                         * are searched for below them: the steps above
                                         * were answered by several, each with the guard
                                         * (about log2 of the slaves left, a find). Only
                                         * the first read of a field: a read again scans
                                         * it whole. */
                                        s->hinted = s->top == 0 && s->field_try == 0 && hint_bits(s) > 0;
                                        if (s->hinted) {
                                                s->top = hint_bits(s);
                                                s->value[s->sub] = known_prefix(&s->hint, s->sub) &
                                                                   ~(UINT32_MAX >> s->top);
                                        }
                                        if (s->top > 0) {
                                                /* does anybody have the known top bits at all?
                                                 * (watched as a bit step after a silent one) */
                                                s->early_after = s->after;
                                                s->watch_next = s->after != AFTER_ANSWER;
                                                FASTSCAN_STEP(m, s,
                                                             lss_encode_fastscan(&f__, s->value[s->sub],
                                                                                 (uint8_t) (32 - s->top),
                                                                                 (uint8_t) s->sub, (uint8_t) s->sub), true, false);
                                                note_crowd(m, s, s->top);
                                                if ((m->step.stale_answer || (step_answered(m) && m->step.early)) &&
                                                    s->early_after == AFTER_SILENT_CONFIRM) {
                                                        take_late_confirmation(m, s);
                                                        break;
                                                }
                                                if (!step_answered(m) && s->hinted) {
                                                        /* they were found meanwhile, or the hint was a
                                                         * late answer: the whole field */
                                                        s->top = 0;
                                                        s->value[s->sub] = 0;
                                                } else if (!step_answered(m) && s->field_try >= m->timing.cfg.retries) {
                                                        s->none = true;
                                                        goto out;
                                                } else if (!step_answered(m)) {
                                                        continue;
                                                }
                                        }
                                        s->silent_run = 0;
                                        s->searches = 0;
                                        for (s->bit = 31 - (int) s->top; s->bit >= 0; s->bit--) {
                                                if (floor_forces(s)) {
                                                        s->value[s->sub] |= 1u << s->bit;
                                                        continue;
                                                }
                                                s->early_after = s->after;
                                                s->watch_next = s->after != AFTER_ANSWER;
                                                FASTSCAN_STEP(m, s,
                                                             lss_encode_fastscan(&f__, s->value[s->sub],
                                                                                 (uint8_t) s->bit, (uint8_t) s->sub,
                                                                                 (uint8_t) s->sub), s->bit > 0, true);
                                                s->bit_answered = step_answered(m);
                                                note_crowd(m, s, 32u - (unsigned) s->bit);
                                                s->doubt_run = false;
                                                s->late_before = m->step.stale_answer ||
                                                                 (s->bit_answered && m->step.early);
                                                if (s->late_before && s->early_after == AFTER_SILENT_CONFIRM) {
                                                        take_late_confirmation(m, s);
                                                        break;
                                                }
                                                if (s->late_before && s->early_after == AFTER_SILENT_BIT) {
                                                        s->early_latency_us = m->step.early ? m->step.latency_us : 0;
                                                        s->late_latency_us =
                                                                s->late_before ? late_latency(m, s) : 0;
                                                        FASTSCAN_STEP(m, s,
                                                                     lss_encode_fastscan(&f__,
                                                                                         s->value[s->sub] & ~(1u << s->silent_bit),
                                                                                         (uint8_t) s->silent_bit, (uint8_t) s->sub,
                                                                                         (uint8_t) s->sub), false, false);
                                                        if (step_answered(m)) {
                                                                /* it was the silent step's: its bit is 0, and
                                                                 * the bits below it are read again (those the
                                                                 * floor set too) */
                                                                m->stats.late_answers++;
                                                                if (s->late_latency_us)
                                                                        step_sample(m, s->late_latency_us);
                                                                s->value[s->sub] &= ~low_bits(s->silent_bit + 1);
                                                                s->silent_run = 0;
                                                                s->bit = s->silent_bit;
                                                                continue;
                                                        }
                                                        /* the early answer was this bit's own, or
                                                         * the late one of a silent step before the
                                                         * last (a stall longer than a step): then
                                                         * the bits as read are checked */
                                                        if (s->early_latency_us)
                                                                step_sample(m, s->early_latency_us);
                                                        s->doubt_run = s->silent_run >= 2;
                                                }
                                                if (!s->bit_answered) {
                                                        s->value[s->sub] |= 1u << s->bit;
                                                        s->silent_bit = s->bit;
                                                        s->after = AFTER_SILENT_BIT;
                                                        s->silent_run++;
                                                } else {
                                                        s->silent_run = 0;
                                                }
                                                if ((s->silent_run == LSS_FASTSCAN_CHECK_RUN || s->doubt_run) &&
                                                    s->bit > 0 && s->searches < LSS_FASTSCAN_SEARCHES) {
                                                        s->check_pc = 0;
                                                        PT_CALL(&s->pc, check_field_read(m, s));
                                                        if (s->check == CHECK_FIXED)
                                                                continue;
                                                        if (s->check == CHECK_NOBODY)
                                                                break;
                                                }
                                                if (m->cancelling)
                                                        goto out;
                                                fastscan_progress(m, s, (unsigned) s->bit + 1 +
                                                                                steps_from(s, s->sub + 1));
                                        }
                                }
                                if (s->late_confirmed)
                                        break;
                                if (s->check != CHECK_NOBODY) {
                                        s->confirm_pc = 0;
                                        PT_CALL(&s->pc, confirm_field(m, s));
                                        if (!s->late_confirmed)
                                                note_crowd(m, s, 32);
                                        if (s->late_confirmed || step_answered(m)) {
                                                fastscan_progress(m, s, steps_from(s, s->sub + 1));
                                                break;
                                        }
                                        m->stats.retries++;
                                }
                                /* Nobody matched (the confirmation, or not even the
                                 * first bit in the check's search), so the slaves still
                                 * expect this field: scan it again without a new ping. */
                                s->after = s->check == CHECK_NOBODY ? AFTER_ANSWER : AFTER_SILENT_CONFIRM;
                                s->confirm_value = s->value[s->sub];
                                s->confirm_guessed = false;
                                s->lone_failed = s->lone_failed || s->lone;
                                s->lone = false;
                                if (s->known.known_bits[s->sub] >= 32 && s->sub >= s->confirmed &&
                                    s->field_try >= m->timing.cfg.retries) {
                                        /* a known value nobody confirms: no such slave
                                         * (others answered the ping) */
                                        s->none = true;
                                        goto out;
                                }
                                if (s->field_try >= m->timing.cfg.retries || s->sub < s->confirmed)
                                        break;
                        }
                        if (!step_answered(m) && !s->late_confirmed)
                                break;
                        s->late_confirmed = false;
                }
                if (s->sub == LSS_FIELD_COUNT) {
                        s->found = true;
                        break;
                }
                /* keep what was confirmed, unless a kept field just failed or a
                 * guess held: one answer confirms a guess, and with many slaves
                 * answering the step before, that one may be a late answer of
                 * theirs (a stall) and no slave has the guess; kept, it would be
                 * confirmed again the same way each attempt. Scan them. */
                if (s->guessing) {
                        s->guessing = false;
                        s->confirmed = 0;
                } else {
                        s->confirmed = s->sub < s->confirmed ? 0 : s->sub;
                }
        }
out:;
        PT_END(&s->pc);
}
