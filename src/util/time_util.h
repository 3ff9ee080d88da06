/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Time conversions. lssd, lss-sim and lssctl keep every time in
 * microseconds (uint64_t); these are the only places that turn a clock's
 * struct timespec or struct timeval into microseconds or back. */
#pragma once

#include <stdint.h>
#include <sys/time.h>
#include <time.h>

#define USEC_PER_SEC UINT64_C(1000000)
#define USEC_PER_MSEC UINT64_C(1000)
#define NSEC_PER_USEC UINT64_C(1000)

/* µs since the clock's epoch; 0 for a time before it (a clock read that
 * failed, or a stamp that makes no sense: "long ago" is the safe answer). */
static inline uint64_t timespec_to_us(const struct timespec *ts) {
        if (ts->tv_sec < 0)
                return 0;
        return (uint64_t) ts->tv_sec * USEC_PER_SEC + (uint64_t) ts->tv_nsec / NSEC_PER_USEC;
}

static inline struct timespec us_to_timespec(uint64_t us) {
        return (struct timespec) { .tv_sec = (time_t) (us / USEC_PER_SEC),
                                   .tv_nsec = (long) ((us % USEC_PER_SEC) * NSEC_PER_USEC) };
}

/* Signed: SO_TIMESTAMP's realtime stamps are compared with offsets. */
static inline int64_t timeval_to_us(const struct timeval *tv) {
        return (int64_t) tv->tv_sec * (int64_t) USEC_PER_SEC + tv->tv_usec;
}

static inline struct timeval us_to_timeval(uint64_t us) {
        return (struct timeval) { .tv_sec = (time_t) (us / USEC_PER_SEC),
                                  .tv_usec = (suseconds_t) (us % USEC_PER_SEC) };
}

/* The clock now, in µs; 0 should reading it fail. */
static inline uint64_t clock_now_us(clockid_t clock) {
        struct timespec ts;

        if (clock_gettime(clock, &ts) < 0)
                return 0;
        return timespec_to_us(&ts);
}

/* Whole ms, rounded up: a poll() timeout that never ends before the
 * deadline, a wait reported as no shorter than it was. */
static inline uint64_t us_to_ms_up(uint64_t us) {
        return (us + USEC_PER_MSEC - 1) / USEC_PER_MSEC;
}
