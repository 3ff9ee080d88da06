/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include "lss/lss_timing.h"

#include <string.h>

void lss_timing_config_default(lss_timing_config *c) {
        *c = (lss_timing_config) {
                .timeout_us = 20000,
                .adaptive = true,
                .floor_us = 1000,
                .factor_pct = 150,
                .bit_factor_pct = 125,
                .guard_floor_us = 300,
                .bootup_timeout_us = 1000000,
                .bitrate = 125000,
                .retries = 3,
        };
}

void lss_timing_init(lss_timing *t, const lss_timing_config *cfg) {
        memset(t, 0, sizeof(*t));
        t->cfg = *cfg;
        if (t->cfg.retries == 0)
                t->cfg.retries = 1;
        if (t->cfg.factor_pct < 100)
                t->cfg.factor_pct = 100;
        if (t->cfg.bit_factor_pct == 0 || t->cfg.bit_factor_pct > t->cfg.factor_pct)
                t->cfg.bit_factor_pct = t->cfg.factor_pct;
        if (t->cfg.bit_factor_pct < 100)
                t->cfg.bit_factor_pct = 100;
}

void lss_timing_add_sample(lss_timing *t, uint32_t latency_us) {
        t->samples[t->next] = latency_us;
        t->next = (t->next + 1) % LSS_LATENCY_WINDOW;
        if (t->n_samples < LSS_LATENCY_WINDOW)
                t->n_samples++;
}

uint32_t lss_timing_max(const lss_timing *t) {
        uint32_t m = 0;
        for (unsigned i = 0; i < t->n_samples; i++)
                if (t->samples[i] > m)
                        m = t->samples[i];
        return m;
}

uint32_t lss_timing_min(const lss_timing *t) {
        uint32_t m = UINT32_MAX;
        for (unsigned i = 0; i < t->n_samples; i++)
                if (t->samples[i] < m)
                        m = t->samples[i];
        return t->n_samples ? m : 0;
}

/* The k+1-th fastest (or slowest) latency of the window; k < n_samples. */
static uint32_t ranked(const lss_timing *t, unsigned k, bool slowest) {
        uint32_t v[LSS_LATENCY_WINDOW];
        unsigned n = t->n_samples;
        memcpy(v, t->samples, n * sizeof(v[0]));
        for (unsigned i = 0; i <= k; i++)
                for (unsigned j = i + 1; j < n; j++)
                        if (slowest ? v[j] > v[i] : v[j] < v[i]) {
                                uint32_t x = v[i];
                                v[i] = v[j];
                                v[j] = x;
                        }
        return v[k];
}

/* The fastest answer of the window but for its fastest eighth: a late
 * answer of a step before, sampled as a step's own (a straggler of a ping
 * many slaves answered, in the step after it), must not let every late
 * answer after it pass for a step's own. */
static uint32_t fastest_of_most(const lss_timing *t) {
        return ranked(t, t->n_samples / 8, false);
}

/* What a bit step's silence waits for: the slowest answer but one, once
 * the window holds LSS_EARLY_MIN_SAMPLES. One answer stalled by the host
 * lengthened every wait for the next LSS_LATENCY_WINDOW answers (~0.25 s
 * in a VM pass of 3 s); a second stall in the window still does. A stall
 * the wait misses is an answer in the next step: caught as early, or a
 * bit read wrong that the field's confirmation finds. */
static uint32_t bit_slowest(const lss_timing *t) {
        return t->n_samples < LSS_EARLY_MIN_SAMPLES ? lss_timing_max(t) : ranked(t, 1, true);
}

/* ... and the slowest but two where the next step watches for a late
 * answer (one slave alone takes part): a stall it misses costs the bit
 * asked again, where two stalls in the window kept every silent bit step
 * long for 32 answers (1.0-1.6 s of a VM Scan of 127 net, replayed on
 * its candumps; bench/README, 2026-12-03 evening). */
static uint32_t watched_bit_slowest(const lss_timing *t) {
        return t->n_samples < LSS_EARLY_MIN_SAMPLES ? lss_timing_max(t) : ranked(t, 2, true);
}

uint32_t lss_timing_limit(const lss_timing *t) {
        return t->patience_us > t->cfg.timeout_us ? t->patience_us : t->cfg.timeout_us;
}

/* `patience`: whether the patience counts (the late guard leaves it out) */
static uint32_t wait_up_to(const lss_timing *t, enum lss_wait_kind kind, bool patience) {
        uint32_t limit = patience ? lss_timing_limit(t) : t->cfg.timeout_us;
        if (!t->cfg.adaptive || kind == LSS_WAIT_DISCOVERY || t->n_samples == 0)
                return limit;
        uint64_t w = kind == LSS_WAIT_BIT           ? (uint64_t) bit_slowest(t) * t->cfg.bit_factor_pct / 100
                     : kind == LSS_WAIT_WATCHED_BIT ? (uint64_t) watched_bit_slowest(t) * t->cfg.bit_factor_pct / 100
                                                    : (uint64_t) lss_timing_max(t) * t->cfg.factor_pct / 100;
        if (w < t->cfg.floor_us)
                w = t->cfg.floor_us;
        if (patience && w < t->patience_us)
                w = t->patience_us;
        /* the limit caps it: a stray frame taken for a very late answer must
         * not make every later wait longer and longer */
        if (w > limit)
                w = limit;
        return (uint32_t) w;
}

uint32_t lss_timing_wait(const lss_timing *t, enum lss_wait_kind kind) {
        return wait_up_to(t, kind, true);
}

/* Each late answer lengthens the waits, and the next late answer comes
 * after the longer wait: without a cap, answers that are not what they seem
 * (a frame of another master, a fault) would grow them step by step. */
uint32_t lss_timing_patience_cap(const lss_timing *t) {
        uint64_t cap = (uint64_t) LSS_PATIENCE_FACTOR * t->cfg.timeout_us;
        return (uint32_t) (cap < LSS_PATIENCE_MAX_US ? cap : LSS_PATIENCE_MAX_US);
}

uint32_t lss_timing_patient_wait(const lss_timing *t, uint32_t floor_us) {
        uint64_t w = (uint64_t) t->cfg.timeout_us * LSS_PATIENCE_FACTOR;
        uint64_t seen = 2ull * lss_timing_max(t);
        if (seen > w)
                w = seen;
        if (floor_us > w)
                w = floor_us;
        return (uint32_t) (w < LSS_PATIENCE_MAX_US ? w : LSS_PATIENCE_MAX_US);
}

static void set_patience(lss_timing *t, uint64_t p) {
        uint64_t cap = lss_timing_patience_cap(t);
        t->patience_us = (uint32_t) (p < cap ? p : cap);
        t->calm = 0;
        if (t->patience_us > t->cfg.timeout_us)
                t->stalled = true;
}

void lss_timing_on_answer(lss_timing *t, uint32_t latency_us, bool late) {
        if (late) {
                uint64_t p = (uint64_t) latency_us * 3 / 2;
                if (p > t->patience_us)
                        set_patience(t, p);
        } else if (t->patience_us && (uint64_t) latency_us * 2 <= t->patience_us && ++t->calm >= LSS_LATENCY_WINDOW) {
                /* spikes come seldom: only a run of answers in time without
                 * one says the slowness is over */
                uint32_t p = t->patience_us / 2;
                set_patience(t, p > t->cfg.floor_us ? p : 0);
        }
}

void lss_timing_on_stray(lss_timing *t) {
        uint32_t w = wait_up_to(t, LSS_WAIT_ANSWER, true);
        set_patience(t, 2ull * (w > t->patience_us ? w : t->patience_us));
}

/* Worst-case time of an 8-byte standard frame: 135 bits with stuffing. */
static uint32_t answer_frame_us(const lss_timing *t) {
        return t->cfg.bitrate ? (uint32_t) (135ull * 1000000 / t->cfg.bitrate) : 0;
}

uint32_t lss_timing_answer_guard(const lss_timing *t) {
        uint32_t spread = lss_timing_max(t) - lss_timing_min(t);
        uint32_t g = spread > t->cfg.guard_floor_us ? spread : t->cfg.guard_floor_us;
        return g + answer_frame_us(t);
}

/* Taken for early, a step's own answer costs one step asked again; taken
 * for its own, a late one costs a field read again: so not only the clearly
 * early count (a TCG VM's late answers came 0.3 to 0.9 ms into the next
 * step, its slaves' own after 1.5 ms at the least).
 * Latency counts to the end of the answer on the wire, so an answer that
 * waited behind the request (a late one) arrives one frame time after it:
 * what is compared is a latency without that frame (111 bits without stuff
 * bits), the slave's own part. Stuff bits leave up to 24 bit times of it
 * unknown: slaves faster than twice that (no latency of their own to speak
 * of) have no early answers. On vcan the frame time is 0. */
bool lss_timing_early(const lss_timing *t, uint32_t latency_us) {
        return latency_us < lss_timing_early_within(t);
}

uint32_t lss_timing_early_within(const lss_timing *t) {
        if (t->n_samples < LSS_EARLY_FIRST_SAMPLES)
                return 0;
        int64_t frame = t->cfg.bitrate ? 111ll * 1000000 / t->cfg.bitrate : 0;
        int64_t slack = t->cfg.bitrate ? 24ll * 1000000 / t->cfg.bitrate : 0;
        int64_t fastest = (int64_t) fastest_of_most(t) - frame;
        if (fastest <= 2 * slack)
                return 0;
        /* own * 4 < fastest * 3, own = latency - frame */
        return (uint32_t) (frame + (fastest * 3 + 3) / 4);
}

uint32_t lss_timing_late_guard(const lss_timing *t, enum lss_wait_kind kind) {
        /* patience lengthens the wait, not this */
        uint32_t g = wait_up_to(t, kind, false) / 4;
        return g > t->cfg.guard_floor_us ? g : t->cfg.guard_floor_us;
}

uint32_t lss_timing_watched_late_guard(const lss_timing *t, enum lss_wait_kind kind) {
        uint32_t g = lss_timing_late_guard(t, kind), e = lss_timing_early_within(t);
        return g > e ? g - e : 0;
}

uint32_t lss_timing_listen_guard(const lss_timing *t) {
        uint32_t cap = lss_timing_patience_cap(t), wait = lss_timing_wait(t, LSS_WAIT_DISCOVERY);
        uint32_t rule = lss_timing_late_guard(t, LSS_WAIT_DISCOVERY);
        return cap > wait + rule ? cap - wait : rule;
}

uint32_t lss_timing_frame_us(const lss_timing *t, const lss_frame *f) {
        if (!t->cfg.bitrate)
                return 0;
        return (uint32_t) (((uint64_t) can_frame_bits(f) * 1000000 + t->cfg.bitrate - 1) / t->cfg.bitrate);
}
