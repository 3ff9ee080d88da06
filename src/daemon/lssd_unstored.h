/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Node-IDs that may not be stored, and the window in which lssd learns them.
 *
 * An AutoAssign pass that was cut off (lssd stopped, power lost) between
 * Configure Node-ID and Store Configuration leaves a device with a pending
 * node-ID it never stored. At lssd's next Reset (switch global waiting) the
 * device takes that pending ID and boots up under it, and the next pass
 * finds it under its mapped node-ID: "unchanged", though it would lose the
 * ID at its next power cycle. So a boot-up heard inside the window after
 * lssd's Reset marks its node-ID, and the next AutoAssign stores a device
 * found there again (lss_autoassign_plan.unstored) instead of leaving it.
 *
 * The window opens when the Reset's switch to waiting starts and lasts
 * LSSD_UNSTORED_WINDOW_US. Marks stay until an AutoAssign pass ends well
 * (everything it mapped is stored then).
 *
 * Owner: the bus (lssd_job_env.unstored). The Reset runner opens the window,
 * the bus shows it every frame it receives, the AutoAssign runner hands the
 * table to its plan and forgets it after a good pass. */
#pragma once

#include <stdbool.h>
#include <stdint.h>

#include "lss/lss_proto.h"

/* The same event the engine waits for after an assignment (a device that
 * takes a new node-ID at the switch to waiting resets its communication and
 * boots up), given the same time: the engine's default wait for that
 * boot-up (lss_timing_config_default(): 1 s). A longer window costs little
 * (a device that boots up in it for another reason is only stored once
 * more) but would mark the devices powered on together with lssd; a
 * shorter one misses slow devices, whose ID then stays unstored. */
#define LSSD_UNSTORED_WINDOW_US 1000000u

typedef struct lssd_unstored {
        bool ids[128];          /* by node-ID */
        uint64_t from, until;   /* the window (transport clock); until 0: never opened */
} lssd_unstored;

/* lssd's Reset (switch global waiting) goes out at `now`. */
void lssd_unstored_open(lssd_unstored *u, uint64_t now);
/* A frame received at `rx`: a boot-up inside the window marks its node-ID
 * (one received before the Reset went out is not its doing). */
void lssd_unstored_note(lssd_unstored *u, const lss_frame *f, uint64_t rx);
/* The marks, 128 entries, for lss_autoassign_plan.unstored. */
const bool *lssd_unstored_table(const lssd_unstored *u);
/* An AutoAssign pass ended well: every device it mapped is stored. */
void lssd_unstored_forget(lssd_unstored *u);
