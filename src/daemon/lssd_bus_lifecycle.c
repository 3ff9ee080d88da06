/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "daemon/lssd_bus_private.h"
#include "daemon/lssd_job_reply.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_path.h"
#include "daemon/lssd_vtables.h"

uint64_t bus_now(lssd_bus *b) {
        return lss_transport_now(&b->transport);
}

static lssconf_bus *lssd_bus_config_dup(const lssconf_bus *c) {
        lssconf_bus *d = malloc(sizeof(*d));
        if (!d)
                return NULL;
        *d = *c;
        d->devices = NULL;
        if (c->n_devices > 0) {
                d->devices = malloc(c->n_devices * sizeof(*d->devices));
                if (!d->devices) {
                        free(d);
                        return NULL;
                }
                memcpy(d->devices, c->devices, c->n_devices * sizeof(*d->devices));
        }
        return d;
}

static lssconf_bus *lssd_bus_config_free(lssconf_bus *c) {
        if (c) {
                free(c->devices);
                free(c);
        }
        return NULL;
}

/* The engine's timing for a bus. lss_timeout_ms is the no-answer wait of
 * first contacts and the cap of the adaptive wait until late answers make
 * the engine patient (docs/engine.md); the adaptive wait follows the
 * measured latency with no floor of its own (a silence taken too early
 * costs a retry, never a wrong result), the guards never go below a
 * twentieth of the timeout. Frame times count at the bus's bit rate, except
 * on virtual interfaces, whose frames arrive the moment they are sent. */
static void bus_timing(const lssd_bus *b, lss_timing_config *tc) {
        const lssconf_bus *c = b->config;
        lss_timing_config_default(tc);
        tc->timeout_us = c->lss_timeout_ms * 1000u;
        tc->adaptive = c->lss_timing == LSSCONF_LSS_TIMING_ADAPTIVE;
        if (tc->guard_floor_us < tc->timeout_us / 20)
                tc->guard_floor_us = tc->timeout_us / 20;
        tc->bitrate = b->link_virtual ? 0 : lssd_bus_bitrate(b);
}

void bus_update_timing(lssd_bus *b) {
        lss_timing_config tc;
        bus_timing(b, &tc);
        lss_master_set_timing(b->engine, &tc);
}

/* ---- life cycle ---- */

/* The host picks what is behind the seam: SocketCAN, the simulated bus of
 * --simulate, a test's fake. 1: the host said why the link is gone. */
static int bus_open_transport(lssd_bus *b) {
        const lss_transport_hooks hooks = {
                .link_changed = bus_on_link_state,
                .userdata = b,
        };
        int r = b->host.ops->open_transport(b->host.userdata, b->ifname, b->config->bitrate, &hooks, &b->transport);
        if (r < 0)
                return r;
        b->link = lss_transport_link(&b->transport);
        return r;
}

int lssd_bus_new(const lssd_bus_host *host, const lssconf_bus *config, lssd_bus **ret) {
        lss_timing_config tc;
        lssd_bus *b;
        int r;

        b = calloc(1, sizeof(*b));
        if (!b)
                return -ENOMEM;
        b->host = *host;
        b->io_fd = -1;
        lssd_holder_init(&b->holder, NULL, bus_on_holder_gone, b);
        b->config = lssd_bus_config_dup(config);
        if (!b->config) {
                free(b);
                return -ENOMEM;
        }
        lssd_job_queue_init(&b->queue, host->args->queue_max);

        b->ifname = strdup(config->interface);
        if (!b->ifname) {
                r = -ENOMEM;
                goto fail;
        }
        r = lssd_bus_path(b->ifname, &b->path);
        if (r < 0)
                goto fail;

        bus_timing(b, &tc);
        b->engine = lss_master_new(&tc);
        if (!b->engine) {
                r = -ENOMEM;
                goto fail;
        }
        lssd_devices_init(&b->devices, b, b->ifname, &bus_devices_ops, b);
        lssd_devices_set_config(&b->devices, b->config);
        b->env = (lssd_job_env) {
                .ifname = b->ifname,
                .path = b->path,
                .dbus = host->dbus,
                .engine = b->engine,
                .config = b->config,
                .devices = &b->devices,
                .heard = &b->heard,
                .ops = &bus_env_ops,
                .userdata = b,
        };
        lss_master_set_progress(b->engine, bus_on_engine_progress, b);
        lss_master_set_found(b->engine, bus_on_engine_found, b);
        lss_master_set_retune(b->engine, bus_on_retune_wanted, b);

        r = bus_open_transport(b);
        if (r < 0) {
                log_error("%s: failed to open: %s", b->ifname, strerror(-r));
                goto fail;
        }
        bool explained = r > 0;

        r = sd_event_add_time(b->host.event, &b->timer_source, CLOCK_MONOTONIC, UINT64_MAX, 1, bus_on_timer, b);
        if (r < 0)
                goto fail;
        (void) sd_event_source_set_enabled(b->timer_source, SD_EVENT_OFF);
        r = bus_tx_init(b);
        if (r < 0)
                goto fail;
        bus_update_io(b, true);

        if (host->dbus) {
                r = sd_bus_add_object_vtable(host->dbus, &b->slot, b->path, LSSD_BUS_IFACE, lssd_bus_vtable, b);
                if (r < 0)
                        goto fail;
        }

        b->state = lssd_bus_state(b);
        b->bitrate = lssd_bus_bitrate(b);
        if (explained)
                ; /* the opener said why: no CAN in this kernel at all */
        else if (b->link == LSS_LINK_GONE)
                log_notice("%s: serving (%s, link gone): no interface %s (yet); served when it appears",
                           b->ifname, b->transport.ops->kind, b->ifname);
        else
                log_info("%s: serving (%s, link %s)", b->ifname, b->transport.ops->kind,
                         lss_link_state_to_string(b->link));

        /* a crash may have left slaves in configuration state */
        if (b->link == LSS_LINK_UP)
                bus_queue_reset(b, false);
        /* a bus that is not there yet gets its pass when the interface appears */
        b->env.boot_pending = config->auto_assign && !host->ops->started(host->userdata);
        if (b->link == LSS_LINK_UP)
                bus_queue_boot_pass(b);

        *ret = b;
        return 0;

fail:
        lssd_bus_free(b);
        return r;
}

void lssd_bus_set_config(lssd_bus *b, const lssconf_bus *config) {
        lssconf_bus *c = lssd_bus_config_dup(config);
        if (!c) {
                log_error("%s: out of memory, keeping the previous configuration", b->ifname);
                return;
        }
        lssd_bus_config_free(b->config);
        b->config = c;
        b->env.config = c;
        lssd_devices_set_config(&b->devices, c);
        if (b->bitrate_set && c->bitrate != b->bitrate_set) {
                log_notice("%s: keeping %u bit/s set by SetBitrate (the configuration says %u until lssd restarts)",
                           b->ifname, b->bitrate_set, c->bitrate);
                c->bitrate = b->bitrate_set;
        }
        bus_update_timing(b);
        lssd_devices_refresh(&b->devices);
        bus_update_published(b);
        bus_flush_changes(b);
}

void lssd_bus_set_bitrate(lssd_bus *b, uint32_t bitrate) {
        b->bitrate_set = bitrate;
        b->config->bitrate = bitrate;
        bus_update_timing(b);
        bus_update_published(b);
        bus_flush_changes(b);
}

/* Kicks off the queued first frames once everything is registered. */
void lssd_bus_start(lssd_bus *b, bool announce) {
        if (announce && b->host.dbus && b->slot) {
                int r = sd_bus_emit_object_added(b->host.dbus, b->path);
                if (r < 0)
                        log_debug("%s: failed to announce the bus: %s", b->ifname, strerror(-r));
        }
        bus_process(b);
}

lssd_bus *lssd_bus_free(lssd_bus *b) {
        lssd_job *j;

        if (!b)
                return NULL;

        while ((j = lssd_job_queue_pop(&b->queue))) {
                if (j->request)
                        lssd_job_abort(j, LSSD_ERROR_CANCELLED, "The bus was removed");
                lssd_job_free(j);
        }
        if (b->job) {
                if (b->job->request)
                        lssd_job_abort(b->job, LSSD_ERROR_CANCELLED, "The bus was removed");
                b->job = lssd_job_free(b->job);
        }

        lssd_devices_clear(&b->devices);
        if (b->host.dbus && b->slot)
                (void) sd_bus_emit_object_removed(b->host.dbus, b->path);
        b->slot = sd_bus_slot_unref(b->slot);

        lssd_holder_drop(&b->holder);
        b->remove_source = sd_event_source_disable_unref(b->remove_source);
        b->io_source = sd_event_source_disable_unref(b->io_source);
        b->timer_source = sd_event_source_disable_unref(b->timer_source);
        b->tx_retry_source = sd_event_source_disable_unref(b->tx_retry_source);
        bus_retune_free(b);
        bus_foreign_free(b);
        lss_transport_close(&b->transport);
        lss_master_free(b->engine);
        lssd_bus_config_free(b->config);
        free(b->boot_status);
        free(b->path);
        free(b->ifname);
        free(b);
        return NULL;
}
