/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Run the engine against the in-memory bus on virtual time until the running
 * operation finishes. Shared by the unit tests and the engine bench. */
#pragma once

#include <stdint.h>

#include "lss/lss_master.h"
#include "sim/membus.h"

/* A hook the tests use to inject frames: called after every engine event
 * with the bus and the engine; may inject frames on the bus. */
typedef void (*lss_drive_hook)(void *ud, membus *bus, lss_master *m);

/* Returns the result of the operation started on `m` (already started).
 * Gives up after `limit_us` of virtual time (then the result is whatever the
 * engine reports after a cancel). */
const lss_result *lss_drive(lss_master *m, membus *bus, uint64_t limit_us, lss_drive_hook hook, void *ud);

/* Let the bus run (boot-ups, slave timers) for `us` with nobody listening. */
void lss_drive_idle(membus *bus, uint64_t us);
