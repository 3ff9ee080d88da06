/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The one list of lssd's D-Bus names: the bus name, object paths, interface
 * and signal names, option names, and the org.lssd.LSS1.Error.* names with
 * their errno and the exit status lssctl gives each. The daemon (lssd_errors.c, lssd_path.c, the
 * vtables), lssctl (ctl_errors.c) and the Python test harness
 * (tests/integration/lssdtest.py reads this file) all take them from here.
 * Plain C preprocessor only: no sd-bus, so any layer may include it.
 * The names are part of the interface (org.lssd.LSS1(5), lssctl(1)). */
#pragma once

#include <errno.h>

#define LSSD_BUS_NAME       "org.lssd.LSS1"
#define LSSD_ROOT_PATH      "/org/lssd/LSS1"
#define LSSD_MANAGER_PATH   LSSD_ROOT_PATH "/Manager"
#define LSSD_BUSES_PATH     LSSD_ROOT_PATH "/buses"
#define LSSD_MANAGER_IFACE  LSSD_BUS_NAME ".Manager"
#define LSSD_BUS_IFACE      LSSD_BUS_NAME ".Bus"
#define LSSD_DEVICE_IFACE   LSSD_BUS_NAME ".Device"

/* The signals of org.lssd.LSS1.Bus */
#define LSSD_SIGNAL_DEVICE_FOUND     "DeviceFound"
#define LSSD_SIGNAL_NODE_ID_ASSIGNED "NodeIdAssigned"
#define LSSD_SIGNAL_UNKNOWN_DEVICE   "UnknownDevice"
#define LSSD_SIGNAL_DEVICE_REPLACED  "DeviceReplaced"
#define LSSD_SIGNAL_JOB_FINISHED     "JobFinished"

/* Device property FoundBy (as): how the last Scan that found the device
 * reached it, any of these */
#define LSSD_DEVICE_FOUND_BY "FoundBy"
#define LSSD_FOUND_BY_LSS    "lss"   /* it answered LSS: fastscan, slowscan, selective switch */
#define LSSD_FOUND_BY_SDO    "sdo"   /* it answered the SDO upload of its identity (1018h) */
/* Scan option (b, default true): also ask every node-ID 1..127 for 1018h by SDO */
#define LSSD_SCAN_OPTION_SDO "sdo"
/* SetBitrate option (b, default false): CiA 305's global procedure (all
 * devices at once) instead of one device after another */
#define LSSD_BITRATE_OPTION_GLOBAL "global"

#define LSSD_ERROR_PREFIX          LSSD_BUS_NAME ".Error."
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
/* another LSS master's request was heard: the job ended at once, or the bus
 * takes none until it heard none for foreign_master_quiet_s (lssd.conf) */
#define LSSD_ERROR_FOREIGN_MASTER  LSSD_ERROR_PREFIX "ForeignMaster"

/* ReloadConfig() with a bad file (the standard D-Bus name, as dbus-daemon uses it). */
#define LSSD_ERROR_INVALID_FILE_CONTENT "org.freedesktop.DBus.Error.InvalidFileContent"

/* Every lssd error, one row each: X(SYMBOL, errno, lssctl exit status,
 * what it means for people). The name is LSSD_ERROR_<SYMBOL>; lssctl's exit
 * status CTL_EXIT_<SYMBOL> (ctl_errors.h). */
#define LSSD_ERRORS(X) \
        X(NO_RESPONSE, ETIMEDOUT, 5, "no device answered") \
        X(REJECTED, EREMOTEIO, 6, "the device refused the request") \
        X(BUSY, EBUSY, 7, "the bus is held by another program, or lssd is stopping") \
        X(BUS_DOWN, ENETDOWN, 8, "the CAN interface is down or not there") \
        X(BUS_OFF, ENOLINK, 9, "the CAN controller is bus-off") \
        X(NOT_FOUND, ENXIO, 10, "no such device or bus") \
        X(CONFLICT, EADDRINUSE, 11, \
          "conflict: the node-ID is taken, several devices answered, or a bit-rate change left devices behind") \
        X(CANCELLED, ECANCELED, 12, "the job was cancelled") \
        X(NOT_SUPPORTED, EOPNOTSUPP, 13, "not supported by lssd, its configuration or the CAN interface") \
        X(LIMITS_EXCEEDED, ENOBUFS, 14, "too much at once: the job queue is full") \
        X(PERMISSION_DENIED, EPERM, 16, \
          "lssd itself is not permitted to do this (e.g. retune the CAN interface without CAP_NET_ADMIN)") \
        X(NOT_HELD, ENOLCK, 18, "the bus is not held: raw services need Acquire() first") \
        X(FOREIGN_MASTER, ENOTUNIQ, 19, \
          "another LSS master is active on the bus: lssd stopped and takes no LSS job until it is quiet")
