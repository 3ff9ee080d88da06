/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* How long the master waits. Answer latency is measured from the end of the
 * request on the wire to the arrival of the answer; the window of recent
 * samples gives the worst (max) and best (min) latency seen on this bus.
 *
 *   limit              max(timeout, patience): the longest no-answer wait
 *   wait (no answer)   fixed: limit;
 *                      adaptive: min(limit, max(floor, factor * max, patience))
 *                      (limit until the first answer was measured); a step
 *                      whose silence is an answer (a fastscan bit step)
 *                      takes bit_factor instead of factor, and the
 *                      slowest but one for max (from LSS_EARLY_MIN_SAMPLES;
 *                      but two for a lone slave's, LSS_WAIT_WATCHED_BIT)
 *   answer guard       after the first answer: max(guard_floor, max - min)
 *                      + one answer frame (a second responder's answer
 *                      queues behind the first on the wire)
 *   late guard         after a wait ran out: max(guard_floor, wait / 4),
 *                      the wait taken without patience. An answer in it
 *                      still counts and raises `max`. A step whose late
 *                      answer the next step watches for (a lone fastscan
 *                      bit step) has it shortened by the early window.
 *   patience           what late answers showed the waits must be. A late
 *                      answer to a discovery step raises it to 1.5 x its
 *                      latency (the other steps' waits follow `max`); an LSS
 *                      answer no step could take (it came after its step
 *                      had ended) doubles the wait (once for the strays
 *                      of one stall: step_on_stray); after
 *                      LSS_LATENCY_WINDOW answers in a row within half of
 *                      it, it is halved. At most LSS_PATIENCE_FACTOR x timeout, never
 *                      above LSS_PATIENCE_MAX_US.
 *
 * Why this is safe is written down in docs/engine.md: a wrong wait costs a
 * retry, never a wrong identity or node-ID. */
#pragma once

#include <stdbool.h>
#include <stdint.h>

#include "lss/lss_master.h"

#define LSS_LATENCY_WINDOW 32
#define LSS_PATIENCE_MAX_US 1000000u
#define LSS_PATIENCE_FACTOR 4u
#define LSS_EARLY_MIN_SAMPLES 8u
/* A silence that ends in a verdict (a device missing, nobody left to find,
 * a slave named misbehaving) is waited for at least this long: a loaded
 * host stalls an answer for 100-200 ms, far beyond any timeout. */
#define LSS_VERDICT_WAIT_FLOOR_US 250000u
/* With tx confirmation a step's wait begins at its request's echo: one
 * whose echo a loaded host holds back waits for it, this long at most
 * after the write (then it is silent: never on the wire, no ACK, bus-off). */
#define LSS_ECHO_WAIT_MAX_US 1000000u
/* ... but an answer far sooner than the first few is judged early already:
 * a late answer taken for its own there read a bit of a pass's first
 * fastscan wrong (a VM candump: 0.15 ms into the step, with 3 samples of
 * 1.4-1.9 ms). Taken for early wrongly, an answer costs a step asked again. */
#define LSS_EARLY_FIRST_SAMPLES 2u

typedef struct lss_timing {
        lss_timing_config cfg;
        uint32_t samples[LSS_LATENCY_WINDOW];
        unsigned n_samples, next;
        uint32_t patience_us; /* the wait late answers called for; 0: none */
        unsigned calm;        /* answers in time since the patience last changed */
        bool stalled;         /* the patience went beyond the timeout once: answers came
                               * later than it allows (a host or bus that stalls) */
} lss_timing;

void lss_timing_init(lss_timing *t, const lss_timing_config *cfg);
void lss_timing_add_sample(lss_timing *t, uint32_t latency_us);
uint32_t lss_timing_max(const lss_timing *t);
uint32_t lss_timing_min(const lss_timing *t);
/* Sooner than 3/4 of the fastest answer of the window (once it holds
 * LSS_EARLY_FIRST_SAMPLES; both without the answer's frame time; the fastest
 * but for the window's fastest eighth, which may be late answers taken
 * for a step's own): too soon to be a slave's answer to the request just
 * sent, as far as this bus has shown. */
bool lss_timing_early(const lss_timing *t, uint32_t latency_us);
/* The latency below which an answer is judged early now; 0: none is. */
uint32_t lss_timing_early_within(const lss_timing *t);
/* The longest no-answer wait now: the timeout, or the patience if longer. */
uint32_t lss_timing_limit(const lss_timing *t);
/* A step's first answer came `latency_us` after its request: `late` when it
 * came after the step's wait had run out. */
void lss_timing_on_answer(lss_timing *t, uint32_t latency_us, bool late);
/* An LSS answer came that no step was waiting for (its step had ended). */
void lss_timing_on_stray(lss_timing *t);
/* What a step's silence means decides how long it is waited for. */
enum lss_wait_kind {
        LSS_WAIT_ANSWER,    /* silence is a failure (asked again, or an error): factor */
        LSS_WAIT_BIT,       /* silence is an answer (a fastscan bit reads 1): bit_factor;
                             * a late answer is caught as early in the next step */
        LSS_WAIT_WATCHED_BIT, /* ... of a lone slave, whose late answer the next step
                             * watches for: a miss costs the bit asked again */
        LSS_WAIT_DISCOVERY, /* first contact with unknown slaves: the configured
                             * timeout, so that slow slaves get measured */
};

/* The no-answer wait of a step of that kind. */
uint32_t lss_timing_wait(const lss_timing *t, enum lss_wait_kind kind);
uint32_t lss_timing_answer_guard(const lss_timing *t);
uint32_t lss_timing_late_guard(const lss_timing *t, enum lss_wait_kind kind);
/* The late guard of a step whose next step watches for its late answer
 * (one that lands there before that step's request is out, or within
 * lss_timing_early_within of it, is judged early: asked about, not taken
 * for that step's own), shortened by lss_timing_early_within: nothing on a
 * bus whose slaves take time of their own, the whole guard on one whose
 * answers cannot be told early. */
uint32_t lss_timing_watched_late_guard(const lss_timing *t, enum lss_wait_kind kind);
/* The longest wait patience may grow to: LSS_PATIENCE_FACTOR x timeout, at
 * most LSS_PATIENCE_MAX_US. */
uint32_t lss_timing_patience_cap(const lss_timing *t);
/* A wait for a verdict (a device missing, an assignment not verified): the
 * bus or the host was slower than the configured timeout allowed for, so
 * well beyond it: LSS_PATIENCE_FACTOR x timeout or twice the slowest answer
 * seen, at least `floor_us`, at most LSS_PATIENCE_MAX_US. */
uint32_t lss_timing_patient_wait(const lss_timing *t, uint32_t floor_us);
/* The late guard of a discovery step whose silence nothing checks later (a
 * Scan's last ping): with the wait, as long as patience may grow; a late
 * answer in it counts and makes the waits patient. */
uint32_t lss_timing_listen_guard(const lss_timing *t);
/* Time the frame takes on the wire at the configured bit rate (0 if unknown). */
uint32_t lss_timing_frame_us(const lss_timing *t, const lss_frame *f);
