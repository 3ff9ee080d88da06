/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Telling systemd how lssd is: STATUS= always, READY=1 once start-up is done
 * and the boot auto-assign passes on buses that are up have ended, and
 * meanwhile EXTEND_TIMEOUT_USEC= every LSSD_EXTEND_EVERY_USEC. READY=1 goes
 * anyway, with a warning, boot_ready_limit_s (lssd.conf) after start-up or
 * once the passes made no engine step for LSSD_BOOT_STALL_USEC (longer on
 * buses with long LSS timeouts); the passes go on and STATUS= says so. READY=1
 * goes once; the journal says "Ready" when it goes. */
#pragma once

#include <stdbool.h>
#include <stdint.h>

#define LSSD_READY_TICK_USEC (1u * 1000000u)              /* how often the wait looks at the passes */
#define LSSD_EXTEND_EVERY_USEC (10u * 1000000u)           /* how often a running pass extends */
#define LSSD_EXTEND_BY_USEC (30u * 1000000u)              /* by how much each time */
/* a bus that is there but down at start holds READY=1 this long */
#define LSSD_LINK_GRACE_USEC (10u * 1000000u)
/* passes that made no engine step (an exchange answered or timed out) this
 * long are taken as stuck: READY=1 anyway. At least LSSD_STALL_TIMEOUTS
 * times the longest lss_timeout_ms of the buses in their pass, whose single
 * steps may take that long (AutoAssign's second look waits twice it). */
#define LSSD_BOOT_STALL_USEC (10u * 1000000u)
#define LSSD_STALL_TIMEOUTS 3u

/* The wait for READY=1 in numbers (CLOCK_MONOTONIC µs), apart from the
 * daemon so that the decisions can be tested alone. */
typedef struct lssd_ready_wait {
        uint64_t since;       /* start-up done */
        uint64_t steps;       /* the passes' engine steps when last seen to change */
        uint64_t moved_at;    /* when they changed (or no pass ran) */
        uint64_t extended_at; /* the last EXTEND_TIMEOUT_USEC= */
} lssd_ready_wait;

typedef enum lssd_ready_verdict {
        LSSD_READY_HOLD,        /* keep waiting */
        LSSD_READY_HOLD_EXTEND, /* keep waiting; ask systemd for more time now */
        LSSD_READY_GO,          /* nothing holds READY=1 back any more */
        LSSD_READY_AT_LIMIT,    /* boot_ready_limit_s is over: READY=1, the passes go on */
        LSSD_READY_STALLED,     /* no step in stall_usec: READY=1, the passes go on */
} lssd_ready_verdict;

/* Start-up is done at `now` (EXTEND_TIMEOUT_USEC= goes at once). */
void lssd_ready_wait_start(lssd_ready_wait *w, uint64_t now, uint64_t steps);
/* One look at `now`: `hold` whether anything holds READY=1 back, `running`
 * whether a boot pass runs on a bus that is up, `steps` the engine steps of
 * the buses in their boot pass. */
lssd_ready_verdict lssd_ready_wait_tick(lssd_ready_wait *w, uint64_t now, bool hold, bool running, uint64_t steps,
                                        uint64_t limit_usec, uint64_t stall_usec);
