/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <time.h>

#include "daemon/lssd_bus_private.h"
#include "daemon/lssd_run.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_path.h"

/* ---- driving the engine ---- */

static int on_io(sd_event_source *s, int fd, uint32_t revents, void *userdata);

static void bus_arm_timer(lssd_bus *b) {
        /* a held frame stops the engine's clock until it is written */
        uint64_t t = bus_tx_pending(b) ? UINT64_MAX : lss_master_deadline(b->engine);
        uint64_t next = lss_transport_next_event(&b->transport); /* a transport without an fd */
        if (next < t)
                t = next;
        if (t == UINT64_MAX) {
                (void) sd_event_source_set_enabled(b->timer_source, SD_EVENT_OFF);
                return;
        }
        int r = sd_event_source_set_time(b->timer_source, t);
        if (r >= 0)
                r = sd_event_source_set_enabled(b->timer_source, SD_EVENT_ONESHOT);
        if (r < 0)
                log_error("%s: failed to arm the timer: %s", b->ifname, strerror(-r));
}

static void bus_job_end(lssd_bus *b) {
        lssd_job *j = b->job;
        const lss_master_stats *st = lss_master_get_stats(b->engine), *at = &b->job_stats;
        /* the engine counts over its life: this job's share */
        uint64_t late = st->late_answers - at->late_answers, stray = st->stray_answers - at->stray_answers;
        log_debug("%s: %s finished (%s); engine: %" PRIu64 " steps, %" PRIu64 " retries, %" PRIu64
                  " timeouts, %" PRIu64 " late, %" PRIu64 " stale, %" PRIu64 " ignored, %" PRIu64
                  " conflicts, wait %u us, latency %u..%u us", b->ifname, lssd_job_name(j),
                  j->result ? j->result : "failed", st->steps - at->steps, st->retries - at->retries,
                  st->timeouts - at->timeouts, late, st->stale_frames - at->stale_frames,
                  st->ignored_frames - at->ignored_frames, st->conflicts - at->conflicts, st->timeout_us,
                  st->latency_min_us, st->latency_max_us);
        /* Patience below the configured timeout only lengthened the adaptive
         * waits (docs/engine.md): nothing the configuration has to hear of. */
        if ((late || stray) && st->patience_us > (uint64_t) b->config->lss_timeout_ms * 1000)
                log_notice("%s: devices answered later than lss_timeout_ms = %u allows (%" PRIu64
                           " late, %" PRIu64 " after their step had ended): waited up to %u ms",
                           b->ifname, b->config->lss_timeout_ms, late, stray,
                           (unsigned) us_to_ms_up(st->patience_us));
        else if (late || stray)
                log_debug("%s: %" PRIu64 " answers came after the adaptive wait (%" PRIu64 " after their step had "
                          "ended): waited up to %u ms", b->ifname, late + stray, stray,
                          (unsigned) us_to_ms_up(st->patience_us));
        if (st->rechecks > at->rechecks)
                log_notice("%s: %" PRIu64 " enumeration rounds asked again with waits of a verdict before naming a "
                           "slave misbehaving (answers came 100 ms and more late: a loaded host?)",
                           b->ifname, st->rechecks - at->rechecks);
        b->job = NULL;
        b->changed |= LSSD_BUS_CHANGED_JOB;
        bus_set_progress(b, 0);
        if (j->type == LSSD_JOB_AUTO_ASSIGN && j->boot && j->result && strcmp(j->result, "foreign-master") == 0 &&
            !b->removing && !b->host.ops->stopping(b->host.userdata)) {
                /* another master broke it off: it runs again once that one is quiet */
                log_notice("%s: the boot pass runs again once no LSS request of another master was heard for %u s",
                           b->ifname, b->config->foreign_master_quiet_s);
                bus_queue_boot_pass(b);
        } else if (j->type == LSSD_JOB_AUTO_ASSIGN && j->boot) {
                /* finished or gave up: either way the boot pass is over */
                char *text = NULL;
                if (j->summary[0] && j->result && strcmp(j->result, "partial") != 0 &&
                    strcmp(j->result, "done") != 0) {
                        if (asprintf(&text, "%s: auto-assign gave up (%s)", b->ifname, j->result) < 0)
                                text = NULL;
                } else if (j->summary[0])
                        text = strdup(j->summary);
                else if (asprintf(&text, "%s: auto-assign %s", b->ifname, j->result ? j->result : "failed") < 0)
                        text = NULL;
                free(b->boot_status);
                b->boot_status = text;
                b->env.boot_pending = false;
                b->host.ops->boot_pass_done(b->host.userdata);
        }
        /* the boot pass has no caller but its end matters to everybody */
        if ((j->request || j->type == LSSD_JOB_AUTO_ASSIGN) && b->host.dbus && b->slot)
                (void) sd_bus_emit_signal(b->host.dbus, b->path, LSSD_BUS_IFACE, LSSD_SIGNAL_JOB_FINISHED, "ss",
                                          lssd_job_name(j), j->result ? j->result : "failed");
        lssd_job_free(j);
}

static void bus_job_continue(lssd_bus *b, const lss_result *r) {
        lss_result foreign;
        /* another master ended it: the bus's words, and the slaves it left set aside */
        if (r && r->status == LSS_E_FOREIGN_MASTER)
                r = bus_foreign_result(b, r, &foreign);
        int k = lssd_job_run(&b->env, b->job, r);
        if (k > 0)
                b->engine_running = true;
        else
                bus_job_end(b);
}

static void bus_job_begin(lssd_bus *b, lssd_job *j) {
        b->job = j;
        b->job_stats = *lss_master_get_stats(b->engine);
        j->stage = 0;
        b->changed |= LSSD_BUS_CHANGED_JOB | LSSD_BUS_CHANGED_QUEUE_LENGTH;
        bus_set_progress(b, 0);
        bus_job_continue(b, NULL);
}

static int on_remove(sd_event_source *s, void *userdata) {
        lssd_bus *b = userdata;
        b->host.ops->removed(b->host.userdata, b);
        return 0;
}

/* Everything that may have moved the engine ends here: send, collect the
 * result, continue the job or start the next one, re-arm the timer, publish. */
void bus_process(lssd_bus *b) {
        if (b->processing)
                return;
        b->processing = true;
        for (;;) {
                bus_flush_tx(b);
                /* the tx queue is full: nothing moves until the frame is written */
                if (bus_tx_pending(b))
                        break;
                if (b->engine_running && lss_master_done(b->engine)) {
                        b->engine_running = false;
                        bus_job_continue(b, lss_master_result(b->engine));
                        continue;
                }
                /* another master is active: only a switch to waiting goes out */
                if (!b->job && !b->engine_running && b->queue.n > 0 && !bus_foreign_holds(b)) {
                        bus_job_begin(b, lssd_job_queue_pop(&b->queue));
                        continue;
                }
                break;
        }
        b->processing = false;

        bus_arm_timer(b);
        bus_update_published(b);
        bus_flush_changes(b);

        if (lssd_bus_idle(b)) {
                if (b->removing && !b->remove_source) {
                        int r = sd_event_add_defer(b->host.event, &b->remove_source, on_remove, b);
                        if (r < 0)
                                log_error("%s: failed to schedule removal: %s", b->ifname, strerror(-r));
                }
                b->host.ops->idle(b->host.userdata);
        }
}

static void bus_poll_rx(lssd_bus *b) {
        lss_frame f;
        uint64_t rx;
        int r = 0;

        for (unsigned i = 0; i < RX_BATCH; i++) {
                r = lss_transport_recv(&b->transport, &f, &rx);
                if (r <= 0)
                        break;
                if (f.flags & LSS_FRAME_ECHO) {
                        /* our own request came back from the controller */
                        if (lss_tx_echo_confirms(&b->echo, &f, rx))
                                lss_master_on_tx_confirmed(b->engine, rx);
                } else if (lss_is_foreign_request(&f)) {
                        /* another master's: the bus stops taking jobs, the engine ends its own */
                        bus_foreign_heard(b, &f);
                        lss_master_on_frame(b->engine, &f, rx);
                } else {
                        lssd_unstored_note(&b->env.unstored, &f, rx);
                        lssd_heard_rx(&b->heard, &f, lssd_realtime_us());
                        lssd_devices_heard(&b->devices, &f);
                        lss_master_on_frame(b->engine, &f, rx);
                }
        }
        if (r < 0 && r != -EAGAIN && r != -EINTR && r != -ENETDOWN && r != -ENODEV)
                log_debug("%s: receive failed: %s", b->ifname, strerror(-r));
}

static void bus_check_status(lssd_bus *b) {
        lss_transport_status st;
        if (lss_transport_status_get(&b->transport, &st) < 0)
                return;
        uint64_t now = bus_now(b);
        if (st.rx_dropped != b->rx_dropped) {
                log_warning("%s: %" PRIu64 " received frames were lost", b->ifname, st.rx_dropped - b->rx_dropped);
                b->rx_dropped = st.rx_dropped;
                lss_master_on_rx_lost(b->engine, now);
        }
        if (st.bus != b->bus_state) {
                log_notice("%s: controller %s", b->ifname, lss_bus_state_to_string(st.bus));
                b->bus_state = st.bus;
                if (st.bus == LSS_BUS_OFF && b->engine_running)
                        lss_master_on_bus_error(b->engine, LSS_E_BUS_OFF, "the controller went bus-off", now);
        }
}

void bus_update_io(lssd_bus *b, bool force) {
        int fd = lss_transport_get_fd(&b->transport);
        /* a new socket may echo or not; the engine applies it from its next step */
        lss_master_set_tx_confirm(b->engine, lss_transport_echoes(&b->transport));
        if (fd != b->io_fd)
                lss_tx_echo_forget(&b->echo);
        if (fd == b->io_fd && !force)
                return;
        b->io_source = sd_event_source_disable_unref(b->io_source);
        b->io_fd = -1;
        if (fd < 0)
                return;
        int r = sd_event_add_io(b->host.event, &b->io_source, fd, EPOLLIN, on_io, b);
        if (r < 0) {
                log_error("%s: failed to watch the socket: %s", b->ifname, strerror(-r));
                return;
        }
        b->io_fd = fd;
        if (bus_tx_pending(b))
                (void) sd_event_source_set_enabled(b->io_source, SD_EVENT_OFF);
}

static int on_io(sd_event_source *s, int fd, uint32_t revents, void *userdata) {
        lssd_bus *b = userdata;
        bus_poll_rx(b);
        bus_check_status(b);
        bus_update_io(b, false);
        bus_process(b);
        return 0;
}

int bus_on_timer(sd_event_source *s, uint64_t usec, void *userdata) {
        lssd_bus *b = userdata;
        if (b->io_fd < 0)
                bus_poll_rx(b); /* no fd (simulated bus): frames are picked up on time */
        lss_master_on_time(b->engine, bus_now(b));
        bus_process(b);
        return 0;
}
