/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The one place where lssd's D-Bus error names live: the names, their errno
 * mapping (sd_bus_error_add_map) and the translation of engine results into
 * bus errors. Clients can add the same map to get errno values back. */
#pragma once

#include <systemd/sd-bus.h>

#include "lss/lss_master.h"

#define LSSD_ERROR_PREFIX          "org.lssd.LSS1.Error."
#define LSSD_ERROR_NO_RESPONSE     LSSD_ERROR_PREFIX "NoResponse"
#define LSSD_ERROR_REJECTED        LSSD_ERROR_PREFIX "Rejected"
#define LSSD_ERROR_BUSY            LSSD_ERROR_PREFIX "Busy"
#define LSSD_ERROR_BUS_DOWN        LSSD_ERROR_PREFIX "BusDown"
#define LSSD_ERROR_BUS_OFF         LSSD_ERROR_PREFIX "BusOff"
#define LSSD_ERROR_NOT_FOUND       LSSD_ERROR_PREFIX "NotFound"
#define LSSD_ERROR_CONFLICT        LSSD_ERROR_PREFIX "Conflict"
#define LSSD_ERROR_CANCELLED       LSSD_ERROR_PREFIX "Cancelled"
#define LSSD_ERROR_NOT_SUPPORTED   LSSD_ERROR_PREFIX "NotSupported"
#define LSSD_ERROR_LIMITS_EXCEEDED LSSD_ERROR_PREFIX "LimitsExceeded"
/* lssd itself lacks a privilege (CAP_NET_ADMIN to retune an interface);
 * not the caller's AccessDenied */
#define LSSD_ERROR_PERMISSION_DENIED LSSD_ERROR_PREFIX "PermissionDenied"
/* a raw service by a caller that does not hold the bus (Acquire()) */
#define LSSD_ERROR_NOT_HELD        LSSD_ERROR_PREFIX "NotHeld"

/* ReloadConfig() with a bad file (the standard D-Bus name, as dbus-daemon uses it). */
#define LSSD_ERROR_INVALID_FILE_CONTENT "org.freedesktop.DBus.Error.InvalidFileContent"

/* Name -> errno, terminated by SD_BUS_ERROR_MAP_END. */
extern const sd_bus_error_map lssd_error_map[];

/* The confirmed services whose answers carry error codes. */
typedef enum lssd_service {
        LSSD_SERVICE_CONFIGURE_NODE_ID,
        LSSD_SERVICE_CONFIGURE_BIT_TIMING,
        LSSD_SERVICE_STORE,
        _LSSD_SERVICE_MAX,
} lssd_service;

/* "Configure Node-ID", ...; NULL if out of range. */
const char *lssd_service_to_string(lssd_service s);
/* What the slave's error code means for this service ("node-ID out of
 * range", "reserved", "manufacturer-specific", ...). Never NULL. */
const char *lssd_lss_error_meaning(lssd_service s, uint8_t err);

/* D-Bus error name for an engine status; NULL for LSS_OK. */
const char *lssd_status_to_error_name(enum lss_status s);
/* Short word for logs and JobFinished: "done", "no-response", "rejected", ... */
const char *lssd_status_to_result(enum lss_status s);

/* Fills `error` from a failed engine result. `service` says which service's
 * error codes a Rejected result carries (_LSSD_SERVICE_MAX when none).
 * `prefix`, when not NULL, goes in front of the message (e.g. "Step 2
 * (ConfigureNodeId): "). Returns the negative errno of the error name. */
int lssd_error_from_result(sd_bus_error *error, const lss_result *r, lssd_service service, const char *prefix);
