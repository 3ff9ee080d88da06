/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <stdio.h>
#include <string.h>
#include <systemd/sd-daemon.h>

#include "daemon/lssd_bus.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_ready.h"

void lssd_ready_status(lssd_context *ctx, bool ready) {
        char status[512];
        size_t n = 0;
        size_t served = 0;

        for (size_t i = 0; i < ctx->n_buses; i++)
                if (!ctx->buses[i]->removing)
                        served++;
        n += (size_t) snprintf(status, sizeof(status), "Serving %zu bus%s", served, served == 1 ? "" : "es");
        for (size_t i = 0; i < ctx->n_buses && n < sizeof(status); i++) {
                const lssd_bus *b = ctx->buses[i];
                if (b->removing)
                        continue;
                n += (size_t) snprintf(status + n, sizeof(status) - n, "%s %s (%s)", i == 0 ? ":" : ",", b->ifname,
                                       lssd_bus_state(b));
        }
        for (size_t i = 0; i < ctx->n_buses && n < sizeof(status); i++) {
                const lssd_bus *b = ctx->buses[i];
                if (b->removing)
                        continue;
                if (b->boot_pending && b->link == LSS_LINK_UP)
                        n += (size_t) snprintf(status + n, sizeof(status) - n, "; %s: auto-assigning", b->ifname);
                else if (b->boot_pending)
                        n += (size_t) snprintf(status + n, sizeof(status) - n, "; waiting for %s", b->ifname);
                else if (b->boot_status)
                        n += (size_t) snprintf(status + n, sizeof(status) - n, "; %s", b->boot_status);
        }
        /* the line first: whoever sees READY=1 finds it in the log already */
        if (ready)
                log_info("Ready: %s", status);
        (void) sd_notifyf(0, "%sSTATUS=%s", ready ? "READY=1\n" : "", status);
}

static bool boot_passes_running(const lssd_context *ctx) {
        for (size_t i = 0; i < ctx->n_buses; i++)
                if (ctx->buses[i]->boot_pending && ctx->buses[i]->link == LSS_LINK_UP && !ctx->buses[i]->removing)
                        return true;
        return false;
}

/* What holds READY=1 back: a boot pass on a bus that is up, and for the
 * first LSSD_LINK_GRACE_USEC a bus whose interface is there but down: at
 * boot that is systemd-networkd bringing it up (bit rate, up, then the
 * carrier; the boot test saw lssd start in between and report READY with
 * "waiting for can0" before the pass). A missing interface does not. */
static bool boot_passes_hold(const lssd_context *ctx, uint64_t now) {
        for (size_t i = 0; i < ctx->n_buses; i++) {
                const lssd_bus *b = ctx->buses[i];
                if (!b->boot_pending || b->removing)
                        continue;
                if (b->link == LSS_LINK_UP)
                        return true;
                if (b->link == LSS_LINK_DOWN && now - ctx->deferred_since < LSSD_LINK_GRACE_USEC)
                        return true;
        }
        return false;
}

static uint64_t now_usec(const lssd_context *ctx) {
        uint64_t now = 0;
        (void) sd_event_now(ctx->event, CLOCK_MONOTONIC, &now);
        return now;
}

static uint64_t boot_pass_steps(const lssd_context *ctx) {
        uint64_t steps = 0;
        for (size_t i = 0; i < ctx->n_buses; i++)
                if (ctx->buses[i]->boot_pending)
                        steps += lss_master_get_stats(ctx->buses[i]->engine)->steps;
        return steps;
}

static void ready_now(lssd_context *ctx) {
        ctx->ready_deferred = false;
        ctx->extend_timer = sd_event_source_disable_unref(ctx->extend_timer);
        lssd_ready_status(ctx, true);
}

/* While READY=1 waits: more time from systemd as long as the passes move. */
static int on_extend(sd_event_source *s, uint64_t usec, void *userdata) {
        lssd_context *ctx = userdata;

        if (!ctx->ready_deferred)
                return 0;
        if (!boot_passes_hold(ctx, usec)) { /* the grace for a bus that is down is over */
                ready_now(ctx);
                return 0;
        }
        if (usec - ctx->deferred_since >= LSSD_BOOT_READY_LIMIT_USEC) {
                log_warning("Boot auto-assignment still running after %llu s: reporting ready without it",
                            (unsigned long long) (LSSD_BOOT_READY_LIMIT_USEC / 1000000u));
                ready_now(ctx);
                return 0;
        }
        uint64_t steps = boot_pass_steps(ctx);
        if (steps != ctx->boot_steps)
                (void) sd_notifyf(0, "EXTEND_TIMEOUT_USEC=%u", LSSD_EXTEND_BY_USEC);
        else
                log_warning("Boot auto-assignment made no progress in %u s: not asking systemd for more time",
                            LSSD_EXTEND_EVERY_USEC / 1000000u);
        ctx->boot_steps = steps;
        (void) sd_event_source_set_time(s, usec + LSSD_EXTEND_EVERY_USEC);
        return 0;
}

void lssd_ready_startup_done(lssd_context *ctx) {
        ctx->started = true;
        uint64_t now = now_usec(ctx);
        ctx->deferred_since = now;
        if (!boot_passes_hold(ctx, now)) {
                lssd_ready_status(ctx, true);
                return;
        }
        ctx->ready_deferred = true;
        ctx->boot_steps = boot_pass_steps(ctx);
        (void) sd_notifyf(0, "EXTEND_TIMEOUT_USEC=%u", LSSD_EXTEND_BY_USEC);
        lssd_ready_status(ctx, false);
        if (boot_passes_running(ctx))
                log_info("Auto-assigning before reporting ready");
        else
                log_info("An interface is down: waiting up to %u s for it to come up before reporting ready",
                         LSSD_LINK_GRACE_USEC / 1000000u);
        int r = sd_event_add_time(ctx->event, &ctx->extend_timer, CLOCK_MONOTONIC, now + LSSD_EXTEND_EVERY_USEC, 0,
                                  on_extend, ctx);
        if (r >= 0)
                r = sd_event_source_set_enabled(ctx->extend_timer, SD_EVENT_ON);
        if (r < 0)
                log_warning("Failed to arm the start-timeout extension: %s", strerror(-r));
}

void lssd_ready_boot_pass_done(lssd_context *ctx) {
        if (ctx->ready_deferred && !boot_passes_hold(ctx, now_usec(ctx))) {
                ready_now(ctx);
                return;
        }
        lssd_ready_status(ctx, false);
}
