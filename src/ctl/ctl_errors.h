/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Exit codes of lssctl and the one sentence each D-Bus error gets. The
 * numbers are part of the interface (lssctl(1), EXIT STATUS). */
#pragma once

#include <systemd/sd-bus.h>

#include "names/lssd_names.h"

/* The exit status of each lssd error, CTL_EXIT_<SYMBOL> (5..14, 16, 18, 19),
 * comes from its row in names/lssd_names.h. */
#define CTL_EXIT_ENTRY(sym, errno_, exit_status, sentence) CTL_EXIT_##sym = exit_status,
enum {
        CTL_EXIT_SUCCESS = 0,
        CTL_EXIT_FAILURE = 1,          /* anything not listed below */
        CTL_EXIT_USAGE = 2,            /* bad command line, InvalidArgs */
        CTL_EXIT_NOT_RUNNING = 3,      /* lssd is not running */
        CTL_EXIT_ACCESS_DENIED = 4,    /* AccessDenied */
        LSSD_ERRORS(CTL_EXIT_ENTRY)
        CTL_EXIT_BAD_CONFIG = 15,      /* ReloadConfig: InvalidFileContent */
        CTL_EXIT_PARTIAL = 17,         /* auto-assign: a mapped device missing, in conflict or failed */
        CTL_EXIT_INTERRUPTED = 130,    /* ^C: the job was cancelled */
};
#undef CTL_EXIT_ENTRY

typedef struct ctl_error_info {
        const char *name;      /* D-Bus error name */
        int exit_code;
        const char *sentence;  /* what it means, for people */
} ctl_error_info;

/* The entry for a D-Bus error name: never NULL (a generic one for names
 * not known). "lssd is not running" covers the bus daemon's
 * ServiceUnknown, NameHasNoOwner and failed activation. */
const ctl_error_info *ctl_error_lookup(const char *name);
