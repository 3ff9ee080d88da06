/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Exit codes of lssctl and the one sentence each D-Bus error gets. The
 * numbers are part of the interface (lssctl(1), EXIT STATUS). */
#pragma once

#include <systemd/sd-bus.h>

enum {
        CTL_EXIT_SUCCESS = 0,
        CTL_EXIT_FAILURE = 1,          /* anything not listed below */
        CTL_EXIT_USAGE = 2,            /* bad command line, InvalidArgs */
        CTL_EXIT_NOT_RUNNING = 3,      /* lssd is not running */
        CTL_EXIT_ACCESS_DENIED = 4,    /* AccessDenied */
        CTL_EXIT_NO_RESPONSE = 5,
        CTL_EXIT_REJECTED = 6,
        CTL_EXIT_BUSY = 7,
        CTL_EXIT_BUS_DOWN = 8,
        CTL_EXIT_BUS_OFF = 9,
        CTL_EXIT_NOT_FOUND = 10,
        CTL_EXIT_CONFLICT = 11,
        CTL_EXIT_CANCELLED = 12,
        CTL_EXIT_NOT_SUPPORTED = 13,
        CTL_EXIT_LIMITS_EXCEEDED = 14,
        CTL_EXIT_BAD_CONFIG = 15,      /* ReloadConfig: InvalidFileContent */
        CTL_EXIT_PERMISSION_DENIED = 16, /* lssd's own PermissionDenied, not the caller's */
        CTL_EXIT_PARTIAL = 17,         /* auto-assign: a mapped device missing, in conflict or failed */
        CTL_EXIT_NOT_HELD = 18,        /* a raw service without holding the bus */
        CTL_EXIT_INTERRUPTED = 130,    /* ^C: the job was cancelled */
};

typedef struct ctl_error_info {
        const char *name;      /* D-Bus error name */
        int exit_code;
        const char *sentence;  /* what it means, for people */
} ctl_error_info;

/* The entry for a D-Bus error name: never NULL (a generic one for names
 * not known). "lssd is not running" covers the bus daemon's
 * ServiceUnknown, NameHasNoOwner and failed activation. */
const ctl_error_info *ctl_error_lookup(const char *name);

/* The table itself, terminated by an entry with name NULL (for tests and
 * the manual). */
extern const ctl_error_info ctl_error_table[];
