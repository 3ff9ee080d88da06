/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Failure reporting and finding the bus to act on, for every verb. */
#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "ctl/ctl.h"
#include "ctl/ctl_errors.h"
#include "ctl/ctl_table.h"

_sd_printf_(2, 0) static void vreport(ctl_context *c, const char *fmt, va_list ap) {
        if (c->err_colors)
                fputs(CTL_ANSI_RED, stderr);
        fputs("lssctl: ", stderr);
        vfprintf(stderr, fmt, ap);
        if (c->err_colors)
                fputs(CTL_ANSI_NORMAL, stderr);
        fputc('\n', stderr);
}

int ctl_fail(ctl_context *c, int exit_code, int err, const char *fmt, ...) {
        va_list ap;

        va_start(ap, fmt);
        vreport(c, fmt, ap);
        va_end(ap);
        c->exit_code = exit_code;
        return err < 0 ? err : -EINVAL;
}

int ctl_usage(ctl_context *c, const char *fmt, ...) {
        va_list ap;

        va_start(ap, fmt);
        vreport(c, fmt, ap);
        va_end(ap);
        fputs("Try 'lssctl --help' for more information.\n", stderr);
        c->exit_code = CTL_EXIT_USAGE;
        return -EINVAL;
}

int ctl_bus_fail(ctl_context *c, const sd_bus_error *error, int r, const char *what) {
        const char *name = error && sd_bus_error_is_set(error) ? error->name : NULL;
        const ctl_error_info *e = ctl_error_lookup(name);

        if (e->exit_code == CTL_EXIT_NOT_RUNNING)
                return ctl_fail(c, e->exit_code, r, "lssd is not running.");
        if (!name)
                return ctl_fail(c, CTL_EXIT_FAILURE, r, "%s: %s", what, strerror(r < 0 ? -r : EIO));
        /* dbus-daemon's own refusal is a dump of its matched rule: the
         * sentence says it all (lssd's own AccessDenied messages stay) */
        if (e->exit_code == CTL_EXIT_ACCESS_DENIED && error->message &&
            strncmp(error->message, "Rejected send message", strlen("Rejected send message")) == 0)
                return ctl_fail(c, e->exit_code, r, "%s: %s.", what, e->sentence);
        if (error->message && *error->message)
                return ctl_fail(c, e->exit_code, r, "%s: %s (%s)", what, e->sentence, error->message);
        return ctl_fail(c, e->exit_code, r, "%s: %s (%s)", what, e->sentence, name);
}

int ctl_connect(ctl_context *c) {
        int r;

        if (c->bus)
                return 0;
        r = sd_bus_open_system(&c->bus);
        if (r < 0)
                return ctl_fail(c, CTL_EXIT_NOT_RUNNING, r,
                                "Failed to connect to the system bus (%s): lssd is not running.", strerror(-r));
        /* polkit may ask the caller for a password (the agent of ctl_agent.h) */
        r = sd_bus_set_allow_interactive_authorization(c->bus, !c->no_ask_password);
        if (r < 0)
                return ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to allow interactive authorization: %s", strerror(-r));
        return 0;
}

void ctl_strv_free(char **v, size_t n) {
        if (!v)
                return;
        for (size_t i = 0; i < n; i++)
                free(v[i]);
        free(v);
}

int ctl_path_parse(const char *path, char **ret_ifname, char **ret_device) {
        const char *p, *slash;
        char *prefix, *ifname = NULL;
        int r;

        /* <prefix><escaped ifname>[/devices/<label>]; the label is plain
         * hex and underscores, not escaped */
        if (strncmp(path, LSSD_BUSES_PATH "/", strlen(LSSD_BUSES_PATH "/")) != 0)
                return -EINVAL;
        p = path + strlen(LSSD_BUSES_PATH "/");
        slash = strchr(p, '/');
        if (slash && strncmp(slash, "/devices/", strlen("/devices/")) != 0)
                return -EINVAL;
        if (slash && (!slash[strlen("/devices/")] || strchr(slash + strlen("/devices/"), '/')))
                return -EINVAL;
        prefix = strndup(path, slash ? (size_t) (slash - path) : strlen(path));
        if (!prefix)
                return -ENOMEM;
        r = sd_bus_path_decode(prefix, LSSD_BUSES_PATH, &ifname);
        free(prefix);
        if (r < 0)
                return r;
        if (r == 0 || !ifname || !*ifname) {
                free(ifname);
                return -EINVAL;
        }
        if (ret_device) {
                *ret_device = slash ? strdup(slash + strlen("/devices/")) : NULL;
                if (slash && !*ret_device) {
                        free(ifname);
                        return -ENOMEM;
                }
        }
        *ret_ifname = ifname;
        return 0;
}

int ctl_path_ifname(const char *path, char **ret) {
        return ctl_path_parse(path, ret, NULL);
}

static int get_bus(ctl_context *c, const char *ifname, char **ret) {
        sd_bus_error error = SD_BUS_ERROR_NULL;
        sd_bus_message *reply = NULL;
        const char *path;
        int r;

        r = sd_bus_call_method(c->bus, LSSD_BUS_NAME, LSSD_MANAGER_PATH, LSSD_MANAGER_IFACE, "GetBus", &error, &reply,
                               "s", ifname);
        if (r < 0) {
                if (sd_bus_error_has_name(&error, LSSD_ERROR_NOT_FOUND))
                        r = ctl_fail(c, CTL_EXIT_NOT_FOUND, r, "lssd does not serve interface '%s'.", ifname);
                else if (sd_bus_error_has_name(&error, SD_BUS_ERROR_INVALID_ARGS))
                        r = ctl_usage(c, "Invalid interface name '%s'.", ifname);
                else
                        r = ctl_bus_fail(c, &error, r, "Failed to look up the bus");
                goto finish;
        }
        r = sd_bus_message_read(reply, "o", &path);
        if (r < 0)
                goto finish;
        *ret = strdup(path);
        r = *ret ? 0 : -ENOMEM;
finish:
        sd_bus_message_unref(reply);
        sd_bus_error_free(&error);
        return r;
}

int ctl_buses(ctl_context *c, char ***ret_paths, char ***ret_ifnames, size_t *ret_n) {
        sd_bus_error error = SD_BUS_ERROR_NULL;
        char **paths = NULL, **ifnames = NULL;
        size_t n = 0;
        int r;

        r = ctl_connect(c);
        if (r < 0)
                return r;
        if (c->bus_name) {
                paths = calloc(1, sizeof(char *));
                if (!paths)
                        return -ENOMEM;
                r = get_bus(c, c->bus_name, &paths[0]);
                if (r < 0) {
                        free(paths);
                        return r;
                }
                n = 1;
        } else {
                r = sd_bus_get_property_strv(c->bus, LSSD_BUS_NAME, LSSD_MANAGER_PATH, LSSD_MANAGER_IFACE, "Buses",
                                             &error, &paths);
                if (r < 0) {
                        r = ctl_bus_fail(c, &error, r, "Failed to read the list of buses");
                        sd_bus_error_free(&error);
                        return r;
                }
                while (paths && paths[n])
                        n++;
        }

        ifnames = calloc(n + 1, sizeof(char *));
        if (!ifnames) {
                ctl_strv_free(paths, n);
                return -ENOMEM;
        }
        for (size_t i = 0; i < n; i++) {
                r = ctl_path_ifname(paths[i], &ifnames[i]);
                if (r < 0) {
                        ctl_strv_free(paths, n);
                        ctl_strv_free(ifnames, n);
                        return ctl_fail(c, CTL_EXIT_FAILURE, r, "Unexpected bus object path from lssd.");
                }
        }
        *ret_paths = paths;
        *ret_ifnames = ifnames;
        *ret_n = n;
        return 0;
}

int ctl_pick_bus(ctl_context *c, char **ret_path, char **ret_ifname) {
        char **paths, **ifnames;
        size_t n;
        int r;

        r = ctl_buses(c, &paths, &ifnames, &n);
        if (r < 0)
                return r;
        if (n == 0)
                r = ctl_fail(c, CTL_EXIT_NOT_FOUND, -ENXIO, "lssd serves no bus.");
        else if (n > 1)
                r = ctl_usage(c, "lssd serves %zu buses: say which one with --bus IFACE.", n);
        else {
                *ret_path = paths[0];
                *ret_ifname = ifnames[0];
                paths[0] = ifnames[0] = NULL;
        }
        ctl_strv_free(paths, n);
        ctl_strv_free(ifnames, n);
        return r;
}
