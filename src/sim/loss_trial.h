/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* One run of a pass on a lossy in-memory bus, judged: did it report
 * success, and how many of the slaves did it really find? Every slave loses
 * each frame it receives and each it sends with one probability (lss-sim's
 * --fault drop=P). Shared by the unit test and bench/loss-bench. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

enum loss_trial_kind {
        LOSS_TRIAL_SCAN, /* a blind Scan: the enumeration of non-configured slaves */
        LOSS_TRIAL_POOL, /* a blind AutoAssign: empty map, every slave from the pool */
        LOSS_TRIAL_SLOWSCAN, /* a Scan of the slaves' vendor and product (identify remote) */
        LOSS_TRIAL_SDO,  /* the SDO discovery of 1..127, the slaves configured at 1..n */
        _LOSS_TRIAL_MAX,
};

typedef struct loss_trial {
        /* what the caller is told: the Scan's LSS_OK, AutoAssign's "done"
         * (LSS_OK and no outcome missing, conflict or failed) */
        bool success;
        /* slaves found as they are: a result device at its node-ID, a pool
         * outcome at the node-ID the slave holds */
        size_t found;
        size_t n;
        uint64_t virtual_us;
        char message[480];        /* the result's, or the first outcome that is not "done" */
} loss_trial;

/* n non-configured slaves (for LOSS_TRIAL_SDO at node-IDs 1..n) of one
 * vendor and product (revision and serial from the seed), answering in
 * 1..1.3 ms, each frame lost with `drop_ppm`
 * per million each way; the engine at its default timing. Returns 0, or
 * -ENOMEM. */
int loss_trial_run(enum loss_trial_kind kind, size_t n, uint32_t drop_ppm, uint64_t seed, loss_trial *out);

/* The failure this work is about: success reported, a slave not found. */
static inline bool loss_trial_silent_miss(const loss_trial *t) {
        return t->success && t->found < t->n;
}
