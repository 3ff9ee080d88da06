/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <string.h>

#include "daemon/lssd_bus_private.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_path.h"
#include "daemon/lssd_vtables.h"

/* ---- devices: the registry publishes on D-Bus ---- */

static int devices_add(void *userdata, lssd_device *d) {
        lssd_bus *b = userdata;
        if (!b->host.dbus)
                return 0;
        return sd_bus_add_object_vtable(b->host.dbus, &d->slot, d->path, LSSD_DEVICE_IFACE, lssd_device_vtable, d);
}

static void devices_added(void *userdata, lssd_device *d) {
        lssd_bus *b = userdata;
        if (!b->host.dbus)
                return;
        int r = sd_bus_emit_object_added(b->host.dbus, d->path);
        if (r < 0)
                log_debug("%s: failed to announce %s: %s", b->ifname, d->path, strerror(-r));
}

static void devices_changed(void *userdata, lssd_device *d, char **names) {
        lssd_bus *b = userdata;
        if (b->host.dbus && d->slot)
                (void) sd_bus_emit_properties_changed_strv(b->host.dbus, d->path, LSSD_DEVICE_IFACE, names);
}

static void devices_removed(void *userdata, lssd_device *d) {
        lssd_bus *b = userdata;
        if (b->host.dbus && d->slot)
                (void) sd_bus_emit_object_removed(b->host.dbus, d->path);
}

const lssd_devices_ops bus_devices_ops = {
        .add = devices_add,
        .added = devices_added,
        .changed = devices_changed,
        .removed = devices_removed,
};

/* ---- what the job runners see ---- */

static uint64_t env_now(void *userdata) {
        return bus_now(userdata);
}

static uint32_t env_bitrate(void *userdata) {
        return lssd_bus_bitrate(userdata);
}

static const char *env_holder(void *userdata) {
        const lssd_bus *b = userdata;
        return b->holder.name;
}

static void env_host_link(void *userdata, lssd_host_link *ret) {
        const lssd_bus *b = userdata;
        *ret = (lssd_host_link) {
                .ifname = b->ifname,
                .link = b->link,
                .bus_state = b->bus_state,
                .simulated = b->host.args->simulate,
                .virtual_link = b->link_virtual,
                .bitrate = lssd_bus_bitrate(b),
        };
}

static void env_set_bitrate(void *userdata, uint32_t bitrate) {
        lssd_bus_set_bitrate(userdata, bitrate);
}

static void env_last_pass_changed(void *userdata) {
        lssd_bus *b = userdata;
        b->changed |= LSSD_BUS_CHANGED_LAST_PASS;
}

const lssd_job_env_ops bus_env_ops = {
        .now = env_now,
        .bitrate = env_bitrate,
        .holder = env_holder,
        .host_link = env_host_link,
        .set_bitrate = env_set_bitrate,
        .last_pass_changed = env_last_pass_changed,
};

/* ---- what other files may read ---- */

const char *lssd_bus_ifname(const lssd_bus *b) {
        return b->ifname;
}

const char *lssd_bus_object_path(const lssd_bus *b) {
        return b->path;
}

const lssconf_bus *lssd_bus_config_of(const lssd_bus *b) {
        return b->config;
}

lssd_auth *lssd_bus_auth(lssd_bus *b) {
        return b->host.auth;
}

lssd_devices *lssd_bus_devices(lssd_bus *b) {
        return &b->devices;
}

lssd_job_env *lssd_bus_job_env(lssd_bus *b) {
        return &b->env;
}

const lssd_job *lssd_bus_running_job(const lssd_bus *b) {
        return b->job;
}

size_t lssd_bus_queue_length(const lssd_bus *b) {
        return b->queue.n;
}

double lssd_bus_progress(const lssd_bus *b) {
        return b->progress;
}

const char *lssd_bus_holder(const lssd_bus *b) {
        return b->holder.name;
}

bool lssd_bus_removing(const lssd_bus *b) {
        return b->removing;
}

void lssd_bus_set_removing(lssd_bus *b, bool removing) {
        b->removing = removing;
}

void lssd_bus_boot_get(const lssd_bus *b, lssd_bus_boot *ret) {
        *ret = (lssd_bus_boot) {
                .pending = b->env.boot_pending,
                .link = b->link,
                .status = b->boot_status,
                .pass_started_us = b->env.pass_started_us,
                .engine_steps = lss_master_get_stats(b->engine)->steps + b->foreign.now.count,
                .lss_timeout_ms = b->config->lss_timeout_ms,
                .foreign = b->foreign.now.active,
                .foreign_since_us = b->foreign.now.since_us,
        };
}
