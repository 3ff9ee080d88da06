/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include "daemon/lssd_ready.h"

void lssd_ready_wait_start(lssd_ready_wait *w, uint64_t now, uint64_t steps) {
        *w = (lssd_ready_wait) { .since = now, .steps = steps, .moved_at = now, .extended_at = now };
}

lssd_ready_verdict lssd_ready_wait_tick(lssd_ready_wait *w, uint64_t now, bool hold, bool running, uint64_t steps,
                                        uint64_t limit_usec, uint64_t stall_usec) {
        if (!hold)
                return LSSD_READY_GO;
        if (now - w->since >= limit_usec)
                return LSSD_READY_AT_LIMIT;
        /* time without a running pass (an interface still down) is no stall */
        if (steps != w->steps || !running) {
                w->steps = steps;
                w->moved_at = now;
        }
        if (now - w->moved_at >= stall_usec)
                return LSSD_READY_STALLED;
        if (now - w->extended_at >= LSSD_EXTEND_EVERY_USEC) {
                w->extended_at = now;
                return LSSD_READY_HOLD_EXTEND;
        }
        return LSSD_READY_HOLD;
}
