/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include "daemon/lssd_bus.h"
#include "daemon/lssd_context.h"
#include "daemon/lssd_errors.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_path.h"
#include "daemon/lssd_ready.h"
#include "daemon/lssd_transport_open.h"
#include "daemon/lssd_vtables.h"

static void lssd_context_emit_buses_changed(lssd_context *ctx);

void lssd_args_done(lssd_args *a) {
        free(a->config_path);
        for (size_t i = 0; i < a->n_buses; i++)
                free(a->buses[i]);
        free(a->buses);
        free(a->sim_slaves);
        free(a->sim_foreign);
        *a = (lssd_args) { 0 };
}

int lssd_context_new(lssd_args *args, lssd_context **ret) {
        lssd_context *ctx = calloc(1, sizeof(*ctx));
        if (!ctx)
                return -ENOMEM;
        ctx->args = *args;
        *args = (lssd_args) { 0 };
        if (ctx->args.queue_max == 0)
                ctx->args.queue_max = LSSD_QUEUE_MAX_DEFAULT;
        lssd_auth_init(&ctx->auth);
        *ret = ctx;
        return 0;
}

lssd_context *lssd_context_free(lssd_context *ctx) {
        if (!ctx)
                return NULL;
        for (size_t i = 0; i < ctx->n_buses; i++)
                lssd_bus_free(ctx->buses[i]);
        free(ctx->buses);
        lssd_auth_done(&ctx->auth);
        ctx->manager_slot = sd_bus_slot_unref(ctx->manager_slot);
        ctx->object_manager_slot = sd_bus_slot_unref(ctx->object_manager_slot);
        ctx->dbus = sd_bus_flush_close_unref(ctx->dbus);
        ctx->rtnl_source = sd_event_source_disable_unref(ctx->rtnl_source);
        ctx->stop_timeout = sd_event_source_disable_unref(ctx->stop_timeout);
        ctx->ready_timer = sd_event_source_disable_unref(ctx->ready_timer);
        rtnl_watch_free(ctx->rtnl);
        sd_event_unref(ctx->event);
        lssconf_free(ctx->config);
        free(ctx->config_path);
        lssd_args_done(&ctx->args);
        free(ctx);
        return NULL;
}

/* ---- configuration ---- */

static const char *config_file(const lssd_context *ctx) {
        if (ctx->args.config_path)
                return ctx->args.config_path;
        if (access(LSSD_DEFAULT_CONFIG, F_OK) == 0)
                return LSSD_DEFAULT_CONFIG;
        return NULL;
}

int lssd_context_read_config(lssd_context *ctx, lssconf **ret, lssconf_diag *diag) {
        const char *path = config_file(ctx);
        lssconf *c = NULL;
        int r;

        if (path)
                r = lssconf_load_file(path, &c, diag);
        else
                r = lssconf_new(&c);
        if (r < 0)
                return r;

        for (size_t i = 0; i < ctx->args.n_buses; i++) {
                const char *name = ctx->args.buses[i];
                if (lssconf_find_bus(c, name))
                        continue; /* the file says more about it */
                lssconf_bus *b = NULL;
                r = lssconf_add_default_bus(c, name, &b);
                if (r >= 0 && ctx->args.lss_timeout_ms > 0)
                        b->lss_timeout_ms = ctx->args.lss_timeout_ms;
                if (r < 0) {
                        lssconf_diag_add(diag, LSSCONF_DIAG_ERROR, "--bus %s: %s", name,
                                      r == -EINVAL ? "invalid interface name" : strerror(-r));
                        lssconf_free(c);
                        return r;
                }
        }
        *ret = c;
        return 0;
}

static void log_diag(const lssconf_diag *d) {
        for (size_t i = 0; i < d->n_messages; i++)
                lssd_log(d->messages[i].severity == LSSCONF_DIAG_ERROR ? LOG_ERR : LOG_WARNING, "%s",
                         d->messages[i].text);
        if (d->n_dropped > 0)
                log_warning("(%zu more configuration messages not shown)", d->n_dropped);
}

/* ---- what the buses need of the context ---- */

static uint64_t host_next_job_id(void *userdata) {
        lssd_context *ctx = userdata;
        return ++ctx->next_job_id;
}

static bool host_stopping(void *userdata) {
        const lssd_context *ctx = userdata;
        return ctx->stopping;
}

static bool host_started(void *userdata) {
        const lssd_context *ctx = userdata;
        return ctx->started;
}

static void host_status_changed(void *userdata) {
        lssd_ready_status(userdata, false);
}

static void host_boot_pass_done(void *userdata) {
        lssd_ready_boot_pass_done(userdata);
}

static void host_removed(void *userdata, lssd_bus *b) {
        lssd_context_bus_removed(userdata, b);
}

static void host_idle(void *userdata) {
        lssd_context *ctx = userdata;
        if (ctx->stopping)
                lssd_context_check_stopped(ctx);
}

static int host_open_transport(void *userdata, const char *ifname, uint32_t bitrate,
                               const lss_transport_hooks *hooks, lss_transport *ret) {
        lssd_context *ctx = userdata;
        return lssd_transport_open(&ctx->args, ifname, bitrate, hooks, ret);
}

static const lssd_bus_host_ops bus_host_ops = {
        .next_job_id = host_next_job_id,
        .stopping = host_stopping,
        .started = host_started,
        .status_changed = host_status_changed,
        .boot_pass_done = host_boot_pass_done,
        .removed = host_removed,
        .idle = host_idle,
        .open_transport = host_open_transport,
};

static int context_add_bus(lssd_context *ctx, const lssconf_bus *c) {
        const lssd_bus_host host = {
                .event = ctx->event,
                .dbus = ctx->dbus,
                .auth = &ctx->auth,
                .args = &ctx->args,
                .ops = &bus_host_ops,
                .userdata = ctx,
        };
        lssd_bus **a = realloc(ctx->buses, (ctx->n_buses + 1) * sizeof(*a));
        if (!a)
                return -ENOMEM;
        ctx->buses = a;
        lssd_bus *b;
        int r = lssd_bus_new(&host, c, &b);
        if (r < 0)
                return r;
        ctx->buses[ctx->n_buses++] = b;
        char desc[LSSCONF_BUS_DESCRIBE_MAX];
        log_info("%s", lssconf_bus_describe(c, desc, sizeof(desc)));
        if (ctx->name_owned)
                lssd_bus_start(b, true);
        return 0;
}

void lssd_context_start_buses(lssd_context *ctx) {
        ctx->name_owned = true;
        for (size_t i = 0; i < ctx->n_buses; i++)
                lssd_bus_start(ctx->buses[i], false);
}

int lssd_context_apply_config(lssd_context *ctx, lssconf *config) {
        bool changed = false;
        int ret = 0;

        for (size_t i = 0; i < ctx->n_buses; i++) {
                lssd_bus *b = ctx->buses[i];
                const lssconf_bus *c = lssconf_find_bus(config, lssd_bus_ifname(b));
                if (c) {
                        if (lssd_bus_removing(b)) {
                                lssd_bus_set_removing(b, false);
                                changed = true;
                        }
                        lssd_bus_set_config(b, c);
                } else if (!lssd_bus_removing(b)) {
                        log_info("%s: no longer in the configuration, removing", lssd_bus_ifname(b));
                        lssd_bus_set_removing(b, true);
                        changed = true;
                        lssd_bus_stop(b, "The bus was removed from the configuration");
                }
        }

        for (size_t i = 0; i < config->n_buses; i++) {
                const lssconf_bus *c = &config->buses[i];
                if (lssd_context_find_bus(ctx, c->interface))
                        continue;
                int r = context_add_bus(ctx, c);
                if (r < 0) {
                        log_error("%s: failed to add the bus: %s", c->interface, strerror(-r));
                        if (ret == 0)
                                ret = r;
                        continue;
                }
                changed = true;
        }

        lssconf_free(ctx->config);
        ctx->config = config;
        if (changed)
                lssd_context_emit_buses_changed(ctx);
        return ret;
}

int lssd_context_reload(lssd_context *ctx, sd_bus_error *error) {
        lssconf_diag diag = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        const char *path = config_file(ctx);
        int r;

        log_info("Reloading the configuration%s%s", path ? " from " : "", path ? path : "");
        r = lssd_context_read_config(ctx, &c, &diag);
        log_diag(&diag);
        if (r < 0) {
                const char *first = "cannot be read";
                for (size_t i = 0; i < diag.n_messages; i++)
                        if (diag.messages[i].severity == LSSCONF_DIAG_ERROR) {
                                first = diag.messages[i].text;
                                break;
                        }
                log_error("The new configuration is bad, keeping the previous one");
                r = sd_bus_error_setf(error, LSSD_ERROR_INVALID_FILE_CONTENT,
                                      "Configuration %s: %s (%zu error%s); the previous configuration stays",
                                      path ? path : "(command line)", first, diag.n_errors,
                                      diag.n_errors == 1 ? "" : "s");
                lssconf_diag_clear(&diag);
                return r;
        }
        lssconf_diag_clear(&diag);

        r = lssd_context_apply_config(ctx, c);
        if (r < 0)
                return sd_bus_error_setf(error, LSSD_ERROR_BUS_DOWN,
                                         "The configuration was loaded but a bus could not be opened: %s",
                                         strerror(-r));
        lssd_ready_status(ctx, false);
        return 0;
}

/* ---- buses ---- */

lssd_bus *lssd_context_find_bus(lssd_context *ctx, const char *ifname) {
        for (size_t i = 0; i < ctx->n_buses; i++)
                if (strcmp(lssd_bus_ifname(ctx->buses[i]), ifname) == 0)
                        return ctx->buses[i];
        return NULL;
}

void lssd_context_bus_removed(lssd_context *ctx, lssd_bus *b) {
        for (size_t i = 0; i < ctx->n_buses; i++)
                if (ctx->buses[i] == b) {
                        memmove(ctx->buses + i, ctx->buses + i + 1, (ctx->n_buses - i - 1) * sizeof(*ctx->buses));
                        ctx->n_buses--;
                        break;
                }
        log_info("%s: removed", lssd_bus_ifname(b));
        lssd_bus_free(b);
        lssd_context_emit_buses_changed(ctx);
        lssd_ready_status(ctx, false);
}

static void lssd_context_emit_buses_changed(lssd_context *ctx) {
        if (!ctx->dbus || !ctx->manager_slot)
                return;
        int r = sd_bus_emit_properties_changed(ctx->dbus, LSSD_MANAGER_PATH, LSSD_MANAGER_IFACE, "Buses", NULL);
        if (r < 0)
                log_debug("Failed to emit PropertiesChanged for Buses: %s", strerror(-r));
}

/* ---- link watching ---- */

static void on_rtnl_link(const rtnl_link *link, void *userdata) {
        lssd_context *ctx = userdata;
        for (size_t i = 0; i < ctx->n_buses; i++)
                lssd_bus_link_event(ctx->buses[i], link);
}

static int on_rtnl_io(sd_event_source *s, int fd, uint32_t revents, void *userdata) {
        lssd_context *ctx = userdata;
        int r = rtnl_watch_process(ctx->rtnl);
        if (r < 0)
                log_warning("Failed to read link events: %s", strerror(-r));
        return 0;
}

int lssd_context_open_rtnl(lssd_context *ctx) {
        int r;

        if (ctx->args.simulate)
                return 0;
        r = rtnl_watch_new(NULL, on_rtnl_link, ctx, &ctx->rtnl);
        if (r < 0)
                return log_error_errno(r, "Failed to watch network links");
        r = sd_event_add_io(ctx->event, &ctx->rtnl_source, rtnl_watch_fd(ctx->rtnl), EPOLLIN, on_rtnl_io, ctx);
        if (r < 0)
                return log_error_errno(r, "Failed to watch network links");
        return 0;
}

/* Current link states, once the buses exist (events from now on come from the watch). */
int lssd_context_dump_links(lssd_context *ctx) {
        if (!ctx->rtnl)
                return 0;
        int r = rtnl_dump_links(NULL, on_rtnl_link, ctx);
        if (r < 0)
                return log_warning_errno(r, "Failed to read the state of the network links");
        return 0;
}

/* ---- D-Bus ---- */

int lssd_context_connect_bus(lssd_context *ctx) {
        int r;

        r = sd_bus_open_system(&ctx->dbus);
        if (r < 0)
                return log_error_errno(r, "Failed to connect to the system bus");
        (void) sd_bus_set_description(ctx->dbus, "lssd");
        r = sd_bus_attach_event(ctx->dbus, ctx->event, SD_EVENT_PRIORITY_NORMAL);
        if (r < 0)
                return log_error_errno(r, "Failed to attach the bus to the event loop");
        /* without the bus nobody can reach us: exit and let systemd restart us */
        r = sd_bus_set_exit_on_disconnect(ctx->dbus, true);
        if (r < 0)
                return log_error_errno(r, "Failed to set exit-on-disconnect");
        r = sd_bus_add_object_manager(ctx->dbus, &ctx->object_manager_slot, LSSD_ROOT_PATH);
        if (r < 0)
                return log_error_errno(r, "Failed to add the object manager");
        r = sd_bus_add_object_vtable(ctx->dbus, &ctx->manager_slot, LSSD_MANAGER_PATH, LSSD_MANAGER_IFACE,
                                     lssd_manager_vtable, ctx);
        if (r < 0)
                return log_error_errno(r, "Failed to register the manager object");
        return 0;
}

/* The PID of the process that owns `name`, 0 when it cannot be told. */
static pid_t name_owner_pid(sd_bus *bus, const char *name) {
        sd_bus_creds *creds = NULL;
        pid_t pid = 0;

        if (sd_bus_get_name_creds(bus, name, SD_BUS_CREDS_PID, &creds) >= 0)
                (void) sd_bus_creds_get_pid(creds, &pid);
        sd_bus_creds_unref(creds);
        return pid;
}

int lssd_context_request_name(lssd_context *ctx) {
        int r = sd_bus_request_name(ctx->dbus, LSSD_BUS_NAME, 0);
        if (r == -EEXIST) {
                pid_t pid = name_owner_pid(ctx->dbus, LSSD_BUS_NAME);
                if (pid > 0)
                        log_error("lssd is already running (PID %d owns %s): exiting without touching any bus",
                                  (int) pid, LSSD_BUS_NAME);
                else
                        log_error("lssd is already running (%s has an owner): exiting without touching any bus",
                                  LSSD_BUS_NAME);
                return r;
        }
        if (r == -EACCES || r == -EPERM)
                return log_error_errno(r, "Not allowed to own %s (the D-Bus policy lets only user lssd and root "
                                       "own it)", LSSD_BUS_NAME);
        if (r < 0)
                return log_error_errno(r, "Failed to own the name %s", LSSD_BUS_NAME);
        return 0;
}

/* ---- stopping ---- */

static void context_exit(lssd_context *ctx) {
        if (sd_event_get_state(ctx->event) == SD_EVENT_FINISHED)
                return;
        if (ctx->dbus) {
                int r = sd_bus_release_name(ctx->dbus, LSSD_BUS_NAME);
                if (r < 0)
                        log_debug("Failed to release %s: %s", LSSD_BUS_NAME, strerror(-r));
                (void) sd_bus_flush(ctx->dbus);
        }
        log_info("Stopped");
        (void) sd_event_exit(ctx->event, 0);
}

static int on_stop_timeout(sd_event_source *s, uint64_t usec, void *userdata) {
        lssd_context *ctx = userdata;
        log_warning("Buses did not become idle in time, exiting anyway");
        context_exit(ctx);
        return 0;
}

void lssd_context_stop(lssd_context *ctx) {
        if (ctx->stopping)
                return;
        log_info("Stopping: cancelling jobs, switching every slave to waiting");
        (void) sd_notify(0, "STOPPING=1\nSTATUS=Stopping: switching every slave to waiting");
        for (size_t i = 0; i < ctx->n_buses; i++)
                lssd_bus_stop(ctx->buses[i], "lssd is stopping");
        ctx->stopping = true;

        uint64_t now;
        if (sd_event_now(ctx->event, CLOCK_MONOTONIC, &now) >= 0)
                (void) sd_event_add_time(ctx->event, &ctx->stop_timeout, CLOCK_MONOTONIC,
                                         now + LSSD_STOP_TIMEOUT_USEC, 0, on_stop_timeout, ctx);
        lssd_context_check_stopped(ctx);
}

void lssd_context_check_stopped(lssd_context *ctx) {
        if (!ctx->stopping)
                return;
        for (size_t i = 0; i < ctx->n_buses; i++)
                if (!lssd_bus_idle(ctx->buses[i]))
                        return;
        context_exit(ctx);
}
