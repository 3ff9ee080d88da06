/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* How long the master waits. Answer latency is measured from the end of the
 * request on the wire to the arrival of the answer; the window of recent
 * samples gives the worst (max) and best (min) latency seen on this bus.
 *
 *   wait (no answer)   fixed: timeout;
 *                      adaptive: min(timeout, max(floor, factor * max))
 *                      (timeout until the first answer was measured)
 *   answer guard       after the first answer: max(guard_floor, max - min)
 *                      + one answer frame (a second responder's answer
 *                      queues behind the first on the wire)
 *   late guard         after a wait ran out: max(guard_floor, wait / 4);
 *                      an answer in it still counts and raises `max`
 *
 * Why this is safe is written down in docs/engine.md: a wrong wait costs a
 * retry, never a wrong identity or node-ID. */
#pragma once

#include <stdbool.h>
#include <stdint.h>

#include "lss/lss_master.h"

#define LSS_LATENCY_WINDOW 32

typedef struct lss_timing {
        lss_timing_config cfg;
        uint32_t samples[LSS_LATENCY_WINDOW];
        unsigned n_samples, next;
} lss_timing;

void lss_timing_init(lss_timing *t, const lss_timing_config *cfg);
void lss_timing_add_sample(lss_timing *t, uint32_t latency_us);
uint32_t lss_timing_max(const lss_timing *t);
uint32_t lss_timing_min(const lss_timing *t);
/* The no-answer wait; `discovery` steps (first contact with unknown slaves)
 * always wait the configured timeout so that slow slaves get measured. */
uint32_t lss_timing_wait(const lss_timing *t, bool discovery);
uint32_t lss_timing_answer_guard(const lss_timing *t);
uint32_t lss_timing_late_guard(const lss_timing *t, bool discovery);
/* Time the frame takes on the wire at the configured bit rate (0 if unknown). */
uint32_t lss_timing_frame_us(const lss_timing *t, const lss_frame *f);
