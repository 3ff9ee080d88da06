/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <stdio.h>
#include <string.h>
#include <systemd/sd-daemon.h>

#include "daemon/lssd_bus.h"
#include "daemon/lssd_context.h"
#include "daemon/lssd_devices.h"
#include "daemon/lssd_job_queue.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_ready.h"

void lssd_ready_status(lssd_context *ctx, bool ready) {
        char status[512];
        size_t n = 0;
        size_t served = 0;

        ready = ready && !ctx->ready_sent; /* once */

        for (size_t i = 0; i < ctx->n_buses; i++)
                if (!lssd_bus_removing(ctx->buses[i]))
                        served++;
        n += (size_t) snprintf(status, sizeof(status), "Serving %zu bus%s", served, served == 1 ? "" : "es");
        for (size_t i = 0; i < ctx->n_buses && n < sizeof(status); i++) {
                const lssd_bus *b = ctx->buses[i];
                if (lssd_bus_removing(b))
                        continue;
                n += (size_t) snprintf(status + n, sizeof(status) - n, "%s %s (%s)", i == 0 ? ":" : ",", lssd_bus_ifname(b),
                                       lssd_bus_state(b));
        }
        for (size_t i = 0; i < ctx->n_buses && n < sizeof(status); i++) {
                const lssd_bus *b = ctx->buses[i];
                lssd_bus_boot boot;
                if (lssd_bus_removing(b))
                        continue;
                lssd_bus_boot_get(b, &boot);
                char since[32];
                if (boot.foreign)
                        lssd_clock_text(boot.foreign_since_us, since, sizeof(since));
                if (boot.pending && boot.link == LSS_LINK_UP && boot.foreign)
                        n += (size_t) snprintf(status + n, sizeof(status) - n, "; %s: auto-assign waits until "
                                               "another LSS master (active since %s) is quiet for %u s",
                                               lssd_bus_ifname(b), since,
                                               lssd_bus_config_of(b)->foreign_master_quiet_s);
                else if (boot.pending && boot.link == LSS_LINK_UP)
                        n += (size_t) snprintf(status + n, sizeof(status) - n, "; %s: auto-assigning", lssd_bus_ifname(b));
                else if (boot.foreign)
                        n += (size_t) snprintf(status + n, sizeof(status) - n, "; %s: another LSS master active "
                                               "since %s", lssd_bus_ifname(b), since);
                else if (boot.pending)
                        n += (size_t) snprintf(status + n, sizeof(status) - n, "; waiting for %s", lssd_bus_ifname(b));
                if (!boot.pending && boot.status && n < sizeof(status))
                        n += (size_t) snprintf(status + n, sizeof(status) - n, "; %s", boot.status);
        }
        /* the line first: whoever sees READY=1 finds it in the log already */
        if (ready) {
                log_info("Ready: %s", status);
                ctx->ready_sent = true;
        }
        (void) sd_notifyf(0, "%sSTATUS=%s", ready ? "READY=1\n" : "", status);
}

/* A boot pass that runs (or is about to) on a bus that is up. */
static bool boot_pass_counts(const lssd_bus *b) {
        lssd_bus_boot boot;
        lssd_bus_boot_get(b, &boot);
        return boot.pending && boot.link == LSS_LINK_UP && !lssd_bus_removing(b);
}

static bool boot_passes_running(const lssd_context *ctx) {
        for (size_t i = 0; i < ctx->n_buses; i++)
                if (boot_pass_counts(ctx->buses[i]))
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
                lssd_bus_boot boot;
                lssd_bus_boot_get(ctx->buses[i], &boot);
                if (!boot.pending || lssd_bus_removing(ctx->buses[i]))
                        continue;
                if (boot.link == LSS_LINK_UP)
                        return true;
                if (boot.link == LSS_LINK_DOWN && now - ctx->ready_wait.since < LSSD_LINK_GRACE_USEC)
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
        for (size_t i = 0; i < ctx->n_buses; i++) {
                lssd_bus_boot boot;
                lssd_bus_boot_get(ctx->buses[i], &boot);
                if (boot.pending)
                        steps += boot.engine_steps;
        }
        return steps;
}

static uint64_t ready_limit_usec(const lssd_context *ctx) {
        uint32_t s = ctx->config ? ctx->config->boot_ready_limit_s : LSSCONF_BOOT_READY_LIMIT_S_DEFAULT;
        return (uint64_t) s * 1000000u;
}

/* A single step may wait a few LSS timeouts: a bus with long ones is not stuck sooner. */
static uint64_t stall_usec(const lssd_context *ctx) {
        uint64_t stall = LSSD_BOOT_STALL_USEC;
        for (size_t i = 0; i < ctx->n_buses; i++) {
                const lssd_bus *b = ctx->buses[i];
                uint64_t t = (uint64_t) lssd_bus_config_of(b)->lss_timeout_ms * 1000u * LSSD_STALL_TIMEOUTS;
                if (boot_pass_counts(b) && t > stall)
                        stall = t;
        }
        return stall;
}

static void ready_now(lssd_context *ctx) {
        ctx->ready_deferred = false;
        ctx->ready_timer = sd_event_source_disable_unref(ctx->ready_timer);
        lssd_ready_status(ctx, true);
}

/* "vcan0 (auto-assigning for 12.5 s), vcan1 (pass not started yet)" */
static void describe_passes(const lssd_context *ctx, char *buf, size_t size) {
        uint64_t now = lssd_realtime_us();
        size_t n = 0;

        buf[0] = '\0';
        for (size_t i = 0; i < ctx->n_buses && n < size; i++) {
                const lssd_bus *b = ctx->buses[i];
                const lssd_job *j = lssd_bus_running_job(b);
                lssd_bus_boot boot;
                if (!boot_pass_counts(b))
                        continue;
                lssd_bus_boot_get(b, &boot);
                int k;
                if (j && j->type == LSSD_JOB_AUTO_ASSIGN && j->boot && boot.pass_started_us > 0)
                        k = snprintf(buf + n, size - n, "%s%s (auto-assigning for %.1f s)", n ? ", " : "",
                                     lssd_bus_ifname(b), now > boot.pass_started_us ?
                                     (double) (now - boot.pass_started_us) / 1e6 : 0.0);
                else
                        k = snprintf(buf + n, size - n, "%s%s (its pass has not started yet)", n ? ", " : "",
                                     lssd_bus_ifname(b));
                if (k < 0)
                        break;
                n += (size_t) k;
        }
}

/* READY=1 before the passes ended: say why, where and how long. */
static void ready_early(lssd_context *ctx, uint64_t now, const char *why) {
        char passes[400];
        describe_passes(ctx, passes, sizeof(passes));
        log_warning("Reporting ready %.1f s after start-up although the boot auto-assignment has not ended: %s; "
                    "still in their pass: %s. The passes go on and their results follow in the journal; units "
                    "ordered after lssd.service may start before every device has its node-ID",
                    (double) (now - ctx->ready_wait.since) / 1e6, why, passes[0] ? passes : "none");
        ready_now(ctx);
}

static int on_ready_tick(sd_event_source *s, uint64_t usec, void *userdata) {
        lssd_context *ctx = userdata;
        char why[160];

        if (!ctx->ready_deferred)
                return 0;
        uint64_t now = now_usec(ctx);
        uint64_t limit = ready_limit_usec(ctx), stall = stall_usec(ctx);
        switch (lssd_ready_wait_tick(&ctx->ready_wait, now, boot_passes_hold(ctx, now), boot_passes_running(ctx),
                                     boot_pass_steps(ctx), limit, stall)) {
        case LSSD_READY_GO: /* the grace for a bus that is down is over */
                ready_now(ctx);
                return 0;
        case LSSD_READY_AT_LIMIT:
                snprintf(why, sizeof(why), "boot_ready_limit_s = %u s reached",
                         (unsigned) (limit / 1000000u));
                ready_early(ctx, now, why);
                return 0;
        case LSSD_READY_STALLED:
                snprintf(why, sizeof(why), "the passes made no step (no LSS exchange answered or timed out) in %.1f s",
                         (double) (now - ctx->ready_wait.moved_at) / 1e6);
                ready_early(ctx, now, why);
                return 0;
        case LSSD_READY_HOLD_EXTEND:
                (void) sd_notifyf(0, "EXTEND_TIMEOUT_USEC=%u", LSSD_EXTEND_BY_USEC);
                break;
        case LSSD_READY_HOLD:
                break;
        }
        (void) sd_event_source_set_time(s, usec + LSSD_READY_TICK_USEC);
        return 0;
}

void lssd_ready_startup_done(lssd_context *ctx) {
        ctx->started = true;
        uint64_t now = now_usec(ctx);
        lssd_ready_wait_start(&ctx->ready_wait, now, boot_pass_steps(ctx));
        if (!boot_passes_hold(ctx, now)) {
                lssd_ready_status(ctx, true);
                return;
        }
        ctx->ready_deferred = true;
        (void) sd_notifyf(0, "EXTEND_TIMEOUT_USEC=%u", LSSD_EXTEND_BY_USEC);
        lssd_ready_status(ctx, false);
        if (boot_passes_running(ctx))
                log_info("Auto-assigning before reporting ready (at the latest in %u s: boot_ready_limit_s)",
                         (unsigned) (ready_limit_usec(ctx) / 1000000u));
        else
                log_info("An interface is down: waiting up to %u s for it to come up before reporting ready",
                         LSSD_LINK_GRACE_USEC / 1000000u);
        int r = sd_event_add_time(ctx->event, &ctx->ready_timer, CLOCK_MONOTONIC, now + LSSD_READY_TICK_USEC, 0,
                                  on_ready_tick, ctx);
        if (r >= 0)
                r = sd_event_source_set_enabled(ctx->ready_timer, SD_EVENT_ON);
        if (r < 0)
                log_warning("Failed to arm the wait for the boot passes: %s", strerror(-r));
}

void lssd_ready_boot_pass_done(lssd_context *ctx) {
        if (ctx->ready_deferred && !boot_passes_hold(ctx, now_usec(ctx))) {
                ready_now(ctx);
                return;
        }
        lssd_ready_status(ctx, false);
}
