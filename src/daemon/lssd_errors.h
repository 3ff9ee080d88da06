/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* lssd's D-Bus errors: the errno map of the names (sd_bus_error_add_map)
 * and the translation of engine results into bus errors. The names and
 * their errno live in names/lssd_names.h. Clients can add the same map to
 * get errno values back. */
#pragma once

#include <systemd/sd-bus.h>

#include "lss/lss_master.h"
#include "names/lssd_names.h"

/* Name -> errno, terminated by SD_BUS_ERROR_MAP_END. */
extern const sd_bus_error_map lssd_error_map[];

/* What the slave's error code means for this service ("node-ID out of
 * range", "reserved", "manufacturer-specific", ...); only Configure Node-ID,
 * Configure Bit Timing and Store Configuration answer with codes. Never NULL. */
const char *lssd_lss_error_meaning(enum lss_service s, uint8_t err);

/* D-Bus error name for an engine status; NULL for LSS_OK. */
const char *lssd_status_to_error_name(enum lss_status s);
/* Short word for logs and JobFinished: "done", "no-response", "rejected", ... */
const char *lssd_status_to_result(enum lss_status s);

/* Fills `error` from a failed engine result. `service` says which service's
 * error codes a Rejected result carries (the engine's code,
 * r->failed_service, or the raw service's; LSS_SERVICE_NONE: the engine's
 * message as it is).
 * `prefix`, when not NULL, goes in front of the message (e.g. "Step 2
 * (ConfigureNodeId): "). Returns the negative errno of the error name. */
int lssd_error_from_result(sd_bus_error *error, const lss_result *r, enum lss_service service, const char *prefix);
