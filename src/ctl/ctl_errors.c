/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <string.h>

#include "ctl/ctl_errors.h"

#define LSS_ERR(x) "org.lssd.LSS1.Error." x
#define DBUS_ERR(x) "org.freedesktop.DBus.Error." x

const ctl_error_info ctl_error_table[] = {
        { LSS_ERR("NoResponse"), CTL_EXIT_NO_RESPONSE, "no device answered" },
        { LSS_ERR("Rejected"), CTL_EXIT_REJECTED, "the device refused the request" },
        { LSS_ERR("Busy"), CTL_EXIT_BUSY, "the bus is held by another program, or lssd is stopping" },
        { LSS_ERR("BusDown"), CTL_EXIT_BUS_DOWN, "the CAN interface is down or not there" },
        { LSS_ERR("BusOff"), CTL_EXIT_BUS_OFF, "the CAN controller is bus-off" },
        { LSS_ERR("NotFound"), CTL_EXIT_NOT_FOUND, "no such device or bus" },
        { LSS_ERR("Conflict"), CTL_EXIT_CONFLICT,
          "conflict: the node-ID is taken, several devices answered, or a bit-rate change left devices behind" },
        { LSS_ERR("Cancelled"), CTL_EXIT_CANCELLED, "the job was cancelled" },
        { LSS_ERR("NotSupported"), CTL_EXIT_NOT_SUPPORTED,
          "not supported by lssd, its configuration or the CAN interface" },
        { LSS_ERR("LimitsExceeded"), CTL_EXIT_LIMITS_EXCEEDED, "too much at once: the job queue is full" },
        { LSS_ERR("PermissionDenied"), CTL_EXIT_PERMISSION_DENIED,
          "lssd itself is not permitted to do this (e.g. retune the CAN interface without CAP_NET_ADMIN)" },
        { LSS_ERR("NotHeld"), CTL_EXIT_NOT_HELD, "the bus is not held: raw services need Acquire() first" },
        { DBUS_ERR("InvalidArgs"), CTL_EXIT_USAGE, "invalid argument" },
        { DBUS_ERR("AccessDenied"), CTL_EXIT_ACCESS_DENIED,
          "permission denied: lssd allows this to root and group 'lssd' (usermod -aG lssd USER, then log in again)" },
        { DBUS_ERR("InvalidFileContent"), CTL_EXIT_BAD_CONFIG,
          "the configuration file is invalid; lssd keeps the previous one" },
        { DBUS_ERR("ServiceUnknown"), CTL_EXIT_NOT_RUNNING, "lssd is not running" },
        { DBUS_ERR("NameHasNoOwner"), CTL_EXIT_NOT_RUNNING, "lssd is not running" },
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
