/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <string.h>

#include "ctl/ctl_errors.h"

#define DBUS_ERR(x) "org.freedesktop.DBus.Error." x

#define CTL_ERROR_ENTRY(sym, errno_, exit_status, sentence) { LSSD_ERROR_##sym, exit_status, sentence },
static const ctl_error_info ctl_error_table[] = {
        LSSD_ERRORS(CTL_ERROR_ENTRY)
        /* the standard names lssd replies with, and the bus daemon's */
        { SD_BUS_ERROR_INVALID_ARGS, CTL_EXIT_USAGE, "invalid argument" },
        { SD_BUS_ERROR_ACCESS_DENIED, CTL_EXIT_ACCESS_DENIED, "permission denied" },
        { SD_BUS_ERROR_INTERACTIVE_AUTHORIZATION_REQUIRED, CTL_EXIT_ACCESS_DENIED,
          "authentication required (lssctl asks on the terminal of a login session, unless --no-ask-password)" },
        { LSSD_ERROR_INVALID_FILE_CONTENT, CTL_EXIT_BAD_CONFIG,
          "the configuration file is invalid; lssd keeps the previous one" },
        { SD_BUS_ERROR_SERVICE_UNKNOWN, CTL_EXIT_NOT_RUNNING, "lssd is not running" },
        { SD_BUS_ERROR_NAME_HAS_NO_OWNER, CTL_EXIT_NOT_RUNNING, "lssd is not running" },
        { NULL, 0, NULL }
};

static const ctl_error_info not_running = { NULL, CTL_EXIT_NOT_RUNNING, "lssd is not running" };
static const ctl_error_info generic = { NULL, CTL_EXIT_FAILURE, "the call failed" };

const ctl_error_info *ctl_error_lookup(const char *name) {
        if (!name)
                return &generic;
        for (const ctl_error_info *e = ctl_error_table; e->name; e++)
                if (strcmp(e->name, name) == 0)
                        return e;
        /* bus activation of lssd.service failed: as good as not running */
        if (strncmp(name, DBUS_ERR("Spawn."), strlen(DBUS_ERR("Spawn."))) == 0 ||
            strncmp(name, "org.freedesktop.systemd1.", strlen("org.freedesktop.systemd1.")) == 0)
                return &not_running;
        return &generic;
}
