/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* SetBitrate's host retune, driven by the event loop. The engine stops
 * talking and asks (lss_master_set_retune()); from a deferred event the bus
 * starts the transport's retune (rtnetlink on a real controller, the
 * simulated bus with --simulate; skipped on vcan), waits for its fd or
 * deadline between requests while every other bus and D-Bus caller is
 * served, and tells the engine how it ended (lss_master_retune_done()).
 * The link changes the retune makes are its own: the link handler asks
 * bus_retune_caused() about them, only while the job that retuned runs. */
#include <errno.h>
#include <string.h>
#include <sys/epoll.h>

#include "daemon/lssd_bus_private.h"
#include "daemon/lssd_log.h"

static void retune_wait(lssd_bus *b, const lss_retune_wait *w);

/* The transport may close its fd in the step: never watch it past here. */
static void retune_stop_waiting(lssd_bus *b) {
        b->retune.io = sd_event_source_disable_unref(b->retune.io);
        b->retune.timer = sd_event_source_disable_unref(b->retune.timer);
}

/* r: the transport's answer (1 done, <0 errno) or 0 when the bus did not retune. */
static void retune_end(lssd_bus *b, enum lss_retune how, int r) {
        lssd_job *j = b->job;
        uint64_t done = bus_now(b);

        b->retune.running = false;
        retune_stop_waiting(b);
        if (r < 0 && j && j->id == b->retune.job_id) {
                j->retune_error = -r;
                log_error("%s: retuning the interface to %u bit/s failed: %s%s", b->ifname, b->retune.rate,
                          strerror(-r), r == -EPERM ? " (lssd needs CAP_NET_ADMIN for bit-rate changes: "
                                                      "see the lssd-bitrate.conf drop-in)" : "");
        }
        if (how == LSS_RETUNE_DONE && done > b->retune.due)
                log_warning("%s: the interface was retuned %llu us after the slaves switched", b->ifname,
                            (unsigned long long) (done - b->retune.due));
        log_info("%s: SetBitrate: host interface retune: %s (%llu us)", b->ifname, lss_retune_name(how),
                 (unsigned long long) (done - b->retune.begun_at));
        lss_master_retune_done(b->engine, how, done);
        /* a retune re-opens the socket */
        bus_update_io(b, true);
        if (b->link_changed)
                bus_after_link_change(b);
        bus_process(b);
}

static void retune_result(lssd_bus *b, int r, const lss_retune_wait *w) {
        if (r == 0)
                retune_wait(b, w);
        else
                retune_end(b, r > 0 ? LSS_RETUNE_DONE : r == -EOPNOTSUPP ? LSS_RETUNE_SKIPPED : LSS_RETUNE_FAILED,
                           r == -EOPNOTSUPP ? 0 : r);
}

static void retune_step(lssd_bus *b) {
        lss_retune_wait w = { .fd = -1, .deadline = UINT64_MAX };
        retune_stop_waiting(b);
        retune_result(b, lss_transport_retune_step(&b->transport, &w), &w);
}

static int on_retune_io(sd_event_source *s, int fd, uint32_t revents, void *userdata) {
        retune_step(userdata);
        return 0;
}

static int on_retune_timer(sd_event_source *s, uint64_t usec, void *userdata) {
        retune_step(userdata);
        return 0;
}

static void retune_wait(lssd_bus *b, const lss_retune_wait *w) {
        int r = 0;
        if (w->fd >= 0)
                r = sd_event_add_io(b->host.event, &b->retune.io, w->fd, EPOLLIN, on_retune_io, b);
        if (r >= 0)
                r = sd_event_add_time(b->host.event, &b->retune.timer, CLOCK_MONOTONIC, w->deadline, 1,
                                      on_retune_timer, b);
        if (r < 0) {
                log_error("%s: failed to wait for the retune: %s", b->ifname, strerror(-r));
                retune_end(b, LSS_RETUNE_FAILED, r);
        }
}

static void retune_begin(lssd_bus *b) {
        lssd_job *j = b->job;
        lss_retune_wait w = { .fd = -1, .deadline = UINT64_MAX };

        if (b->retune.running || !lss_master_retune_wanted(b->engine, &b->retune.rate, &b->retune.due))
                return;
        b->retune.begun_at = bus_now(b);
        if (!j || j->type != LSSD_JOB_SET_BITRATE || !b->config->bitrate_change) {
                if (j)
                        j->retune_error = EPERM;
                retune_end(b, LSS_RETUNE_FAILED, 0);
                return;
        }
        if (b->link_virtual) {
                retune_end(b, LSS_RETUNE_SKIPPED, 0);
                return;
        }
        b->retune.job_id = j->id;
        b->retune.running = true;
        retune_result(b, lss_transport_retune_start(&b->transport, b->retune.rate, &w), &w);
}

static int on_retune_wanted(sd_event_source *s, void *userdata) {
        lssd_bus *b = userdata;
        b->retune.defer = sd_event_source_disable_unref(b->retune.defer);
        retune_begin(b);
        return 0;
}

/* The engine asks from inside a step: retune from the loop, right after. */
void bus_on_retune_wanted(void *userdata) {
        lssd_bus *b = userdata;
        if (b->retune.defer)
                return;
        int r = sd_event_add_defer(b->host.event, &b->retune.defer, on_retune_wanted, b);
        if (r < 0)
                log_error("%s: failed to schedule the retune: %s", b->ifname, strerror(-r));
}

bool bus_retune_caused(lssd_bus *b, lss_link_state new_state) {
        return b->job && b->job->id == b->retune.job_id && lss_transport_retune_caused(&b->transport, new_state);
}

void bus_retune_free(lssd_bus *b) {
        b->retune.defer = sd_event_source_disable_unref(b->retune.defer);
        retune_stop_waiting(b);
}
