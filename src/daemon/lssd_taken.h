/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Which node-IDs lssd must not give on a bus, and who holds one: the
 * devices it knows and what it heard (lssd_heard). The SDO probe of the
 * engine adds whoever answers it. */
#pragma once

#include <systemd/sd-bus.h>

#include "daemon/lssd_job_env.h"

/* The engine's check for the next job (lss_master_set_taken_check): what
 * was heard from a device other than the one to be given the node-ID, what
 * another device holds without answering to it (lssd_devices_holding), and,
 * `with_devices`, the node-IDs of the known devices other than it
 * (AssignNodeId, the raw Configure Node-ID). AutoAssign, which moves known
 * devices itself, goes by what was heard alone; both are read live. */
void lssd_taken_check(lssd_job_env *e, bool with_devices);
/* org.lssd.LSS1.Error.Conflict naming who holds node_id (a known device
 * other than `except`, what was heard from it, or the probe's answer). */
int lssd_taken_error(lssd_job_env *e, sd_bus_error *error, uint8_t node_id, const lss_identity *except,
                     const char *prefix);
