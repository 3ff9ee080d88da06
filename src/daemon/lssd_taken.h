/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Which node-IDs lssd must not give on a bus, and who holds one: the
 * devices it knows and what it heard (lssd_heard). The SDO probe of the
 * engine adds whoever answers it. */
#pragma once

#include <systemd/sd-bus.h>

#include "daemon/lssd_bus.h"

/* For one assignment or raw Configure Node-ID: b->avoid becomes every
 * node-ID heard or held by a known device other than `except` (NULL: every
 * known device), and the engine checks against it
 * (lss_master_set_known_taken). */
void lssd_taken_refresh(lssd_bus *b, const lss_identity *except);
/* For AutoAssign, which moves known devices itself: only what is heard,
 * live (a node-ID lssd resets while the pass runs is free again). */
void lssd_taken_use_heard(lssd_bus *b);
/* org.lssd.LSS1.Error.Conflict naming who holds node_id (a known device
 * other than `except`, what was heard from it, or the probe's answer). */
int lssd_taken_error(lssd_bus *b, sd_bus_error *error, uint8_t node_id, const lss_identity *except,
                     const char *prefix);
