/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <time.h>

#include "can/rtnl_watch.h"
#include "can/socketcan.h"
#include "can/transport.h"
#include "daemon/lssd_bus.h"
#include "daemon/lssd_errors.h"
#include "daemon/lssd_job_runners.h"
#include "daemon/lssd_jobs.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_path.h"
#include "daemon/lssd_heard.h"
#include "daemon/lssd_simbus.h"
#include "daemon/lssd_vtables.h"
#include "lss/lss_proto.h"
#include "util/time_util.h"

/* Frames read per wake-up before the other buses get their turn. */
#define RX_BATCH 64u
/* how much earlier than its write an echo may read (clock conversion error), see bus_on_echo() */
#define ECHO_CLOCK_SLACK_US 1000u
/* Link events this long after our own retune are taken for it. */
#define RETUNE_LINK_GRACE_US (5u * 1000000u)

/* Bus PropertiesChanged bookkeeping. */
#define LSSD_BUS_CHANGED_STATE        (1u << 0)
#define LSSD_BUS_CHANGED_BITRATE      (1u << 1)
#define LSSD_BUS_CHANGED_JOB          (1u << 2)
#define LSSD_BUS_CHANGED_PROGRESS     (1u << 3)
#define LSSD_BUS_CHANGED_QUEUE_LENGTH (1u << 4)
#define LSSD_BUS_CHANGED_LAST_PASS    (1u << 5)

struct lssd_bus {
        lssd_bus_host host;              /* the daemon around it */
        lssd_job_env env;                /* what the job runners see (points into this bus) */
        char *ifname;
        char *path;
        lssd_bus_config *config;         /* own copy: a bus being removed outlives its configuration */

        lss_transport transport;
        socketcan_port *port;            /* behind transport, NULL when simulated */
        lssd_simbus *sim;                /* behind transport when simulated */
        sd_event_source *io_source;
        int io_fd;
        sd_event_source *timer_source;
        lss_link_state link;
        lss_bus_state bus_state;
        uint64_t rx_dropped;
        uint32_t link_bitrate;           /* from rtnetlink for real controllers, 0 otherwise */
        bool link_virtual;               /* vcan/vxcan: frames take no time on the "wire" */
        bool link_changed;               /* socketcan reported a change: handle it outside the callback */

        lss_master *engine;
        bool engine_running;             /* we started an operation and did not collect it yet */
        lss_frame echo_want;             /* last LSS request written: its echo confirms it is on the wire */
        uint64_t echo_want_at;           /* when it was written */
        bool echo_pending;

        lssd_job_queue queue;
        lssd_job *job;                   /* running */
        double progress;

        sd_bus_track *holder;            /* Acquire() */
        char *holder_name;

        lssd_devices devices;            /* the registry */

        sd_bus_slot *slot;
        const char *state;               /* as published */
        uint32_t bitrate;                /* as published */
        uint32_t bitrate_set;            /* by SetBitrate: outlives reloads of the file's value; 0 none */
        unsigned changed;                /* LSSD_BUS_CHANGED_* not yet signalled */
        bool processing;                 /* bus_process() is on the stack */
        bool removing;                   /* dropped from the configuration: free when idle */
        sd_event_source *remove_source;  /* frees the bus outside of its own callbacks */

        char *boot_status;               /* how the boot pass ended, for STATUS= */
        lssd_heard heard;                /* node-IDs other devices speak under */
};

static void bus_process(lssd_bus *b);
static void bus_update_io(lssd_bus *b, bool force);
static bool bus_retune(lssd_bus *b);
static int on_io(sd_event_source *s, int fd, uint32_t revents, void *userdata);

static uint64_t lssd_bus_now(lssd_bus *b) {
        return lss_transport_now(&b->transport);
}

static lssd_bus_config *lssd_bus_config_dup(const lssd_bus_config *c) {
        lssd_bus_config *d = malloc(sizeof(*d));
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

static lssd_bus_config *lssd_bus_config_free(lssd_bus_config *c) {
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
        const lssd_bus_config *c = b->config;
        lss_timing_config_default(tc);
        tc->timeout_us = c->lss_timeout_ms * 1000u;
        tc->adaptive = c->lss_timing == LSSD_LSS_TIMING_ADAPTIVE;
        if (tc->guard_floor_us < tc->timeout_us / 20)
                tc->guard_floor_us = tc->timeout_us / 20;
        tc->bitrate = b->link_virtual ? 0 : lssd_bus_bitrate(b);
}

static void bus_update_timing(lssd_bus *b) {
        lss_timing_config tc;
        bus_timing(b, &tc);
        lss_master_set_timing(b->engine, &tc);
}

/* ---- published state ---- */

const char *lssd_bus_state(const lssd_bus *b) {
        if (b->link != LSS_LINK_UP)
                return "down";
        if (b->bus_state == LSS_BUS_OFF)
                return "bus-off";
        if (b->bus_state == LSS_BUS_ERROR_PASSIVE)
                return "error-passive";
        if (b->job || b->queue.n > 0 || b->holder_name)
                return "busy";
        return "idle";
}

uint32_t lssd_bus_bitrate(const lssd_bus *b) {
        return b->link_bitrate ? b->link_bitrate : b->config->bitrate;
}

const char *lssd_bus_job_name(const lssd_bus *b) {
        return b->job ? lssd_job_name(b->job) : "";
}

bool lssd_bus_idle(const lssd_bus *b) {
        return !b->job && b->queue.n == 0 && !b->engine_running;
}

static void bus_update_published(lssd_bus *b) {
        const char *s = lssd_bus_state(b);
        if (!b->state || strcmp(s, b->state) != 0) {
                /* STATUS= tells about trouble, not about every job */
                bool trouble = !b->state || (strcmp(s, "idle") != 0 && strcmp(s, "busy") != 0) ||
                               (strcmp(b->state, "idle") != 0 && strcmp(b->state, "busy") != 0);
                b->state = s;
                b->changed |= LSSD_BUS_CHANGED_STATE;
                if (trouble && !b->removing)
                        b->host.ops->status_changed(b->host.userdata);
        }
        uint32_t rate = lssd_bus_bitrate(b);
        if (rate != b->bitrate) {
                b->bitrate = rate;
                b->changed |= LSSD_BUS_CHANGED_BITRATE;
        }
}

static void lssd_bus_flush_changes(lssd_bus *b) {
        char *names[7];
        size_t n = 0;

        if (!b->changed || !b->host.dbus || !b->slot)
                return;
        if (b->changed & LSSD_BUS_CHANGED_STATE)
                names[n++] = (char *) "State";
        if (b->changed & LSSD_BUS_CHANGED_BITRATE)
                names[n++] = (char *) "Bitrate";
        if (b->changed & LSSD_BUS_CHANGED_JOB)
                names[n++] = (char *) "Job";
        if (b->changed & LSSD_BUS_CHANGED_PROGRESS)
                names[n++] = (char *) "Progress";
        if (b->changed & LSSD_BUS_CHANGED_QUEUE_LENGTH)
                names[n++] = (char *) "QueueLength";
        if (b->changed & LSSD_BUS_CHANGED_LAST_PASS)
                names[n++] = (char *) "LastPass";
        names[n] = NULL;
        b->changed = 0;
        int r = sd_bus_emit_properties_changed_strv(b->host.dbus, b->path, LSSD_BUS_IFACE, names);
        if (r < 0)
                log_debug("%s: failed to emit PropertiesChanged: %s", b->ifname, strerror(-r));
}

static void set_progress(lssd_bus *b, double p) {
        if (p < 0)
                p = 0;
        if (p > 1)
                p = 1;
        /* whole percents are enough for a progress bar and keep the signal rate sane */
        if (fabs(p - b->progress) < 0.01 && !(p == 0 && b->progress != 0) && !(p == 1 && b->progress != 1))
                return;
        b->progress = p;
        b->changed |= LSSD_BUS_CHANGED_PROGRESS;
}

static void on_engine_progress(void *userdata, double p) {
        lssd_bus *b = userdata;
        if (!b->job || b->job->n_stages == 0)
                return;
        /* the engine's estimate can shrink when a scan finds more to do; a bar
         * never goes back, and says 100 % only when the job is over */
        double v = ((double) b->job->stage + p) / (double) b->job->n_stages;
        if (v > 0.99)
                v = 0.99;
        if (v > b->progress)
                set_progress(b, v);
}

static void on_engine_found(void *userdata, const lss_device *d) {
        lssd_bus *b = userdata;
        /* Scan announces devices; the scans inside AutoAssign and SetBitrate do not */
        if (b->job && b->job->type == LSSD_JOB_SCAN)
                lssd_scan_found(&b->env, b->job, d);
}

/* ---- driving the engine ---- */

static void bus_arm_timer(lssd_bus *b) {
        uint64_t t = lss_master_deadline(b->engine);
        if (b->sim) {
                uint64_t s = lssd_simbus_next_event(b->sim);
                if (s < t)
                        t = s;
        }
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

/* Sends what the engine wants sent. A transport error ends the running
 * operation (the frames behind the failed one are dropped, never reordered). */
static void bus_flush_tx(lssd_bus *b) {
        lss_frame f;
        uint64_t sent_at = 0;
        int err = 0;

        while (lss_master_next_tx(b->engine, &f)) {
                if (err < 0)
                        continue;
                /* An answer may arrive before send() even returns (a slave on
                 * another CPU, a virtual bus): the frame counts as sent when
                 * we hand it over, or the engine would take the answer for a
                 * stale frame. */
                uint64_t t = lssd_bus_now(b);
                int r = lss_transport_send(&b->transport, &f);
                if (r < 0)
                        err = r;
                else {
                        sent_at = t;
                        lssd_heard_tx(&b->heard, &f);
                        if (f.id == LSS_COB_MASTER && f.flags == 0) {
                                b->echo_want = f;
                                b->echo_want_at = t;
                                b->echo_pending = true;
                        }
                }
        }
        /* only when something went out: on_sent() restarts the running wait */
        if (sent_at > 0)
                lss_master_on_sent(b->engine, sent_at);
        if (err >= 0)
                return;
        uint64_t now = lssd_bus_now(b);

        char why[128];
        enum lss_status st = b->bus_state == LSS_BUS_OFF ? LSS_E_BUS_OFF : LSS_E_BUS_DOWN;
        if (err == -ENETDOWN)
                snprintf(why, sizeof(why), "%s is down", b->ifname);
        else if (err == -ENODEV || err == -ENXIO)
                snprintf(why, sizeof(why), "%s does not exist", b->ifname);
        else if (err == -ETIMEDOUT)
                snprintf(why, sizeof(why), "%s: transmit queue stayed full (is any other node acknowledging?)",
                         b->ifname);
        else
                snprintf(why, sizeof(why), "%s: send failed: %s", b->ifname, strerror(-err));
        log_warning("%s", why);
        lss_master_on_bus_error(b->engine, st, why, now);
        while (lss_master_next_tx(b->engine, &f))
                ;
}

static void bus_job_end(lssd_bus *b) {
        lssd_job *j = b->job;
        const lss_master_stats *st = lss_master_get_stats(b->engine);
        log_debug("%s: %s finished (%s); engine: %" PRIu64 " steps, %" PRIu64 " retries, %" PRIu64
                  " timeouts, %" PRIu64 " late, %" PRIu64 " stale, %" PRIu64 " ignored, %" PRIu64
                  " conflicts, wait %u us, latency %u..%u us", b->ifname, lssd_job_name(j),
                  j->result ? j->result : "failed", st->steps, st->retries, st->timeouts, st->late_answers,
                  st->stale_frames, st->ignored_frames, st->conflicts, st->timeout_us, st->latency_min_us,
                  st->latency_max_us);
        if (st->patience_us)
                log_notice("%s: devices answered later than lss_timeout_ms = %u allows (%" PRIu64
                           " late, %" PRIu64 " after their step had ended): waited up to %u ms",
                           b->ifname, b->config->lss_timeout_ms, st->late_answers, st->stray_answers,
                           (unsigned) us_to_ms_up(st->patience_us));
        b->job = NULL;
        b->changed |= LSSD_BUS_CHANGED_JOB;
        set_progress(b, 0);
        if (j->type == LSSD_JOB_AUTO_ASSIGN && j->boot) {
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
                (void) sd_bus_emit_signal(b->host.dbus, b->path, LSSD_BUS_IFACE, "JobFinished", "ss", lssd_job_name(j),
                                          j->result ? j->result : "failed");
        lssd_job_free(j);
}

static void bus_job_continue(lssd_bus *b, const lss_result *r) {
        int k = lssd_job_run(&b->env, b->job, r);
        if (k > 0)
                b->engine_running = true;
        else
                bus_job_end(b);
}

static void bus_job_begin(lssd_bus *b, lssd_job *j) {
        b->job = j;
        j->stage = 0;
        b->changed |= LSSD_BUS_CHANGED_JOB | LSSD_BUS_CHANGED_QUEUE_LENGTH;
        set_progress(b, 0);
        bus_job_continue(b, NULL);
}

static int on_remove(sd_event_source *s, void *userdata) {
        lssd_bus *b = userdata;
        b->host.ops->removed(b->host.userdata, b);
        return 0;
}

/* Everything that may have moved the engine ends here: send, collect the
 * result, continue the job or start the next one, re-arm the timer, publish. */
static void bus_process(lssd_bus *b) {
        if (b->processing)
                return;
        b->processing = true;
        for (;;) {
                bus_flush_tx(b);
                /* SetBitrate: the engine is silent and waits for the host interface */
                if (b->engine_running && lss_master_retune_wanted(b->engine, NULL, NULL)) {
                        if (bus_retune(b))
                                bus_update_io(b, true);
                        continue;
                }
                if (b->engine_running && lss_master_done(b->engine)) {
                        b->engine_running = false;
                        bus_job_continue(b, lss_master_result(b->engine));
                        continue;
                }
                if (!b->job && !b->engine_running && b->queue.n > 0) {
                        bus_job_begin(b, lssd_job_queue_pop(&b->queue));
                        continue;
                }
                break;
        }
        b->processing = false;

        bus_arm_timer(b);
        bus_update_published(b);
        lssd_bus_flush_changes(b);

        if (lssd_bus_idle(b)) {
                if (b->removing && !b->remove_source) {
                        int r = sd_event_add_defer(b->host.event, &b->remove_source, on_remove, b);
                        if (r < 0)
                                log_error("%s: failed to schedule removal: %s", b->ifname, strerror(-r));
                }
                b->host.ops->idle(b->host.userdata);
        }
}

/* Our own request came back from the controller. Only the echo of the last
 * one written confirms the running step; an older identical request's echo
 * is told apart by its time (a receive time may read up to the clock
 * conversion's error early, hence the slack). */
static void bus_on_echo(lssd_bus *b, const lss_frame *f, uint64_t rx) {
        if (!b->echo_pending || f->id != b->echo_want.id || f->len != b->echo_want.len ||
            memcmp(f->data, b->echo_want.data, sizeof(f->data)) != 0)
                return;
        if (rx + ECHO_CLOCK_SLACK_US < b->echo_want_at)
                return;
        b->echo_pending = false;
        lss_master_on_tx_confirmed(b->engine, rx);
}

static void bus_note_bootup(lssd_bus *b, const lss_frame *f, uint64_t rx) {
        uint8_t node, state;
        if (rx <= b->env.unstored_until && bootup_decode(f, &node, &state) && state == 0)
                b->env.unstored[node] = true;
}

static void bus_poll_rx(lssd_bus *b) {
        lss_frame f;
        uint64_t rx;
        int r = 0;

        for (unsigned i = 0; i < RX_BATCH; i++) {
                r = lss_transport_recv(&b->transport, &f, &rx);
                if (r <= 0)
                        break;
                if (f.flags & LSS_FRAME_ECHO)
                        bus_on_echo(b, &f, rx);
                else {
                        bus_note_bootup(b, &f, rx);
                        lssd_heard_rx(&b->heard, &f, lssd_realtime_us());
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
        uint64_t now = lssd_bus_now(b);
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

static void bus_update_io(lssd_bus *b, bool force) {
        int fd = lss_transport_get_fd(&b->transport);
        /* a new socket may echo or not; the engine applies it from its next step */
        lss_master_set_tx_confirm(b->engine, b->port && socketcan_port_echoes(b->port));
        if (fd != b->io_fd)
                b->echo_pending = false;
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
}

static int on_io(sd_event_source *s, int fd, uint32_t revents, void *userdata) {
        lssd_bus *b = userdata;
        bus_poll_rx(b);
        bus_check_status(b);
        bus_update_io(b, false);
        bus_process(b);
        return 0;
}

static int on_timer(sd_event_source *s, uint64_t usec, void *userdata) {
        lssd_bus *b = userdata;
        if (b->io_fd < 0)
                bus_poll_rx(b); /* simulated bus: frames are picked up on time */
        lss_master_on_time(b->engine, lssd_bus_now(b));
        bus_process(b);
        return 0;
}

/* ---- jobs ---- */

static bool is_holder(const lssd_bus *b, const char *sender) {
        return b->holder_name && sender && strcmp(b->holder_name, sender) == 0;
}

int lssd_bus_check_available(lssd_bus *b, const char *sender, bool raw, sd_bus_error *error) {
        if (b->host.ops->stopping(b->host.userdata) || b->removing)
                return sd_bus_error_setf(error, LSSD_ERROR_BUSY, "%s: lssd is stopping serving this bus", b->ifname);
        if (b->holder_name && !is_holder(b, sender))
                return sd_bus_error_setf(error, LSSD_ERROR_BUSY, "%s is held by %s (Acquire)", b->ifname,
                                         b->holder_name);
        if (raw && !is_holder(b, sender))
                return sd_bus_error_setf(error, LSSD_ERROR_NOT_HELD,
                                         "Raw LSS services need the bus held: call Acquire() on %s first, "
                                         "or use Execute()", b->ifname);
        if (b->link != LSS_LINK_UP)
                return sd_bus_error_setf(error, LSSD_ERROR_BUS_DOWN, "%s is %s", b->ifname,
                                         b->link == LSS_LINK_GONE ? "not there" : "down");
        if (b->bus_state == LSS_BUS_OFF)
                return sd_bus_error_setf(error, LSSD_ERROR_BUS_OFF, "%s: the controller is bus-off", b->ifname);
        return 0;
}

static void bus_queue_reset(lssd_bus *b, bool front) {
        lssd_job *j;
        /* one queued where it would go is enough (Acquire/Release in a loop must not grow the queue) */
        j = front ? b->queue.head : b->queue.tail;
        if (j && j->type == LSSD_JOB_RESET)
                return;
        if (lssd_job_new(LSSD_JOB_RESET, NULL, &j) < 0) {
                log_error("%s: out of memory queueing the switch to waiting", b->ifname);
                return;
        }
        j->id = b->host.ops->next_job_id(b->host.userdata);
        if (front)
                lssd_job_queue_push_front(&b->queue, j);
        else
                (void) lssd_job_queue_push(&b->queue, j, true);
        b->changed |= LSSD_BUS_CHANGED_QUEUE_LENGTH;
}

/* The boot pass goes right behind the switch to waiting at the head. */
static void bus_queue_boot_pass(lssd_bus *b) {
        lssd_job *j, *reset;

        if (!b->env.boot_pending || b->removing || b->host.ops->stopping(b->host.userdata))
                return;
        for (j = b->job; j; j = NULL)
                if (j->type == LSSD_JOB_AUTO_ASSIGN && j->boot)
                        return;
        for (j = b->queue.head; j; j = j->next)
                if (j->type == LSSD_JOB_AUTO_ASSIGN && j->boot)
                        return;
        if (lssd_job_new(LSSD_JOB_AUTO_ASSIGN, NULL, &j) < 0 || lssd_job_set_plan(j, b->config) < 0) {
                lssd_job_free(j);
                log_error("%s: out of memory queueing the auto-assign pass", b->ifname);
                b->env.boot_pending = false;
                return;
        }
        j->boot = true;
        j->id = b->host.ops->next_job_id(b->host.userdata);
        reset = b->queue.head && b->queue.head->type == LSSD_JOB_RESET ? lssd_job_queue_pop(&b->queue) : NULL;
        lssd_job_queue_push_front(&b->queue, j);
        if (reset)
                lssd_job_queue_push_front(&b->queue, reset);
        b->changed |= LSSD_BUS_CHANGED_QUEUE_LENGTH;
}

int lssd_bus_submit(lssd_bus *b, lssd_job *j, sd_bus_error *error) {
        if (lssd_job_queue_push(&b->queue, j, false) < 0)
                return sd_bus_error_setf(error, LSSD_ERROR_LIMITS_EXCEEDED,
                                         "%s: %zu jobs are queued already, try again later", b->ifname, b->queue.n);
        j->id = b->host.ops->next_job_id(b->host.userdata);
        b->changed |= LSSD_BUS_CHANGED_QUEUE_LENGTH;
        bus_process(b);
        return 0;
}

int lssd_bus_queue_job(lssd_bus *b, sd_bus_message *m, lssd_job *j, bool raw, sd_bus_error *error) {
        int r = lssd_bus_check_available(b, sd_bus_message_get_sender(m), raw, error);
        if (r >= 0)
                r = lssd_bus_submit(b, j, error);
        if (r < 0) {
                lssd_job_free(j);
                return r;
        }
        return 1; /* the job answers */
}

/* ---- holder ---- */

static void bus_drop_holder(lssd_bus *b, const char *why) {
        if (!b->holder_name)
                return;
        log_info("%s: released by %s (%s); switching every slave to waiting", b->ifname, b->holder_name, why);
        b->holder = sd_bus_track_unref(b->holder);
        free(b->holder_name);
        b->holder_name = NULL;
        bus_queue_reset(b, false);
}

static int on_holder_gone(sd_bus_track *t, void *userdata) {
        lssd_bus *b = userdata;
        /* a raw service of the vanished holder has nobody to answer to */
        if (b->job && b->job->type == LSSD_JOB_RAW && b->engine_running)
                lss_master_cancel(b->engine, lssd_bus_now(b));
        bus_drop_holder(b, "the holder left the bus");
        bus_process(b);
        return 0;
}

int lssd_bus_acquire(lssd_bus *b, sd_bus_message *m, sd_bus_error *error) {
        const char *sender = sd_bus_message_get_sender(m);
        int r;

        if (!sender)
                return sd_bus_error_set(error, SD_BUS_ERROR_ACCESS_DENIED, "Acquire() needs a bus connection");
        if (is_holder(b, sender))
                return 0;
        if (b->host.ops->stopping(b->host.userdata) || b->removing)
                return sd_bus_error_setf(error, LSSD_ERROR_BUSY, "%s: lssd is stopping serving this bus", b->ifname);
        if (b->holder_name)
                return sd_bus_error_setf(error, LSSD_ERROR_BUSY, "%s is held by %s already", b->ifname,
                                         b->holder_name);

        r = sd_bus_track_new(sd_bus_message_get_bus(m), &b->holder, on_holder_gone, b);
        if (r < 0)
                return r;
        r = sd_bus_track_add_sender(b->holder, m);
        if (r >= 0) {
                b->holder_name = strdup(sender);
                if (!b->holder_name)
                        r = -ENOMEM;
        }
        if (r < 0) {
                b->holder = sd_bus_track_unref(b->holder);
                return r;
        }
        log_info("%s: held by %s", b->ifname, sender);
        bus_process(b);
        return 0;
}

int lssd_bus_release(lssd_bus *b, const char *sender, sd_bus_error *error) {
        if (!b->holder_name)
                return 0;
        if (!is_holder(b, sender))
                return sd_bus_error_setf(error, LSSD_ERROR_BUSY, "%s is held by %s, not by the caller", b->ifname,
                                         b->holder_name);
        bus_drop_holder(b, "Release()");
        bus_process(b);
        return 0;
}

int lssd_bus_cancel(lssd_bus *b, const char *sender, sd_bus_error *error) {
        if (!b->job || b->job->type == LSSD_JOB_RESET || !b->engine_running)
                return 0;
        if (b->holder_name && !is_holder(b, sender))
                return sd_bus_error_setf(error, LSSD_ERROR_BUSY, "%s is held by %s (Acquire)", b->ifname,
                                         b->holder_name);
        if ((b->engine_running && lssd_job_uncancellable(b->job)))
                return sd_bus_error_setf(error, LSSD_ERROR_BUSY,
                                         "%s: the bit-rate change is under way and cannot be cancelled (devices "
                                         "would keep a pending rate or the bus stay split); it ends soon",
                                         b->ifname);
        log_info("%s: cancelling %s for %s", b->ifname, lssd_job_name(b->job), sender ? sender : "?");
        lss_master_cancel(b->engine, lssd_bus_now(b));
        bus_process(b);
        return 0;
}

/* ---- link ---- */

/* SetBitrate: the engine is silent and waits for the host interface to be
 * retuned: do it (rtnetlink on a real controller, the simulated bus with
 * --simulate; skipped on vcan) and tell the engine. Returns true when the
 * socket changed. */
static bool bus_retune(lssd_bus *b) {
        lssd_job *j = b->job;
        enum lss_retune how = LSS_RETUNE_FAILED;
        uint32_t rate;
        uint64_t deadline, now, done;
        bool reopened = false;
        int r;

        if (!lss_master_retune_wanted(b->engine, &rate, &deadline))
                return false;
        now = lssd_bus_now(b);
        if (!j || j->type != LSSD_JOB_SET_BITRATE || !b->config->bitrate_change) {
                if (j)
                        j->retune_error = EPERM;
        } else if (b->sim) {
                lssd_simbus_set_bitrate(b->sim, rate);
                how = LSS_RETUNE_DONE;
        } else if (b->link_virtual) {
                how = LSS_RETUNE_SKIPPED;
        } else {
                j->retune_until = now + RETUNE_LINK_GRACE_US;
                r = rtnl_set_can_bitrate(NULL, b->ifname, rate);
                if (r == 0) {
                        how = LSS_RETUNE_DONE;
                        /* the old socket carries a pending ENETDOWN from the link going down */
                        if (b->port) {
                                r = socketcan_port_reopen(b->port);
                                if (r < 0)
                                        log_warning("%s: re-opening after the retune failed: %s", b->ifname,
                                                    strerror(-r));
                                reopened = true;
                        }
                } else if (r == -EOPNOTSUPP) {
                        how = LSS_RETUNE_SKIPPED;
                } else {
                        j->retune_error = -r;
                        log_error("%s: retuning the interface to %u bit/s failed: %s%s", b->ifname, rate,
                                  strerror(-r), r == -EPERM ? " (lssd needs CAP_NET_ADMIN for bit-rate changes: "
                                                              "see the lssd-bitrate.conf drop-in)" : "");
                }
        }
        done = lssd_bus_now(b);
        if (how == LSS_RETUNE_DONE && done > deadline)
                log_warning("%s: the interface was retuned %llu us after the slaves switched", b->ifname,
                            (unsigned long long) (done - deadline));
        log_info("%s: SetBitrate: host interface retune: %s (%llu us)", b->ifname, lss_retune_name(how),
                 (unsigned long long) (done - now));
        lss_master_retune_done(b->engine, how, done);
        return reopened;
}

static void on_link_state(socketcan_port *p, lss_link_state old_state, lss_link_state new_state, void *userdata) {
        lssd_bus *b = userdata;
        /* the fd is still open now but not after we return: forget it here */
        if (new_state == LSS_LINK_GONE) {
                b->io_source = sd_event_source_disable_unref(b->io_source);
                b->io_fd = -1;
        }
        b->link_changed = true;
}

static void bus_after_link_change(lssd_bus *b) {
        lss_link_state old = b->link, now_state = socketcan_port_state(b->port);
        b->link_changed = false;
        b->link = now_state;
        bus_update_io(b, true);
        if (old == now_state)
                return;

        if (lssd_job_retuning(b->job, lssd_bus_now(b))) {
                /* our own retune (down, bit timing, up): the job goes on */
                log_info("%s: link %s (SetBitrate retune)", b->ifname, lss_link_state_to_string(now_state));
                bus_process(b);
                return;
        }
        if (now_state == LSS_LINK_GONE)
                log_notice("%s: link gone: no interface %s any more; served again when it appears", b->ifname,
                           b->ifname);
        else
                log_notice("%s: link %s", b->ifname, lss_link_state_to_string(now_state));
        if (now_state != LSS_LINK_UP && b->engine_running) {
                char why[64];
                snprintf(why, sizeof(why), "%s went %s", b->ifname, lss_link_state_to_string(now_state));
                lss_master_on_bus_error(b->engine, LSS_E_BUS_DOWN, why, lssd_bus_now(b));
        }
        /* whatever happened while we could not talk: the first frame is switch-global waiting */
        if (now_state == LSS_LINK_UP) {
                bus_queue_reset(b, true);
                bus_queue_boot_pass(b);
        }
        bus_process(b);
}

void lssd_bus_link_event(lssd_bus *b, const rtnl_link *link) {
        if (!b->port)
                return;
        if (link->ifname[0] && strcmp(link->ifname, b->ifname) == 0 && !link->removed) {
                uint32_t rate = strcmp(link->kind, "can") == 0 ? link->bitrate : 0;
                bool virt = strcmp(link->kind, "vcan") == 0 || strcmp(link->kind, "vxcan") == 0;
                if (rate != b->link_bitrate || virt != b->link_virtual) {
                        b->link_bitrate = rate;
                        b->link_virtual = virt;
                        bus_update_timing(b);
                        bus_update_published(b);
                        lssd_bus_flush_changes(b);
                }
        }
        int r = socketcan_port_link_event(b->port, link->ifindex, link->ifname, !link->removed, link->flags);
        if (r < 0)
                log_warning("%s: failed to re-open: %s", b->ifname, strerror(-r));
        if (r != 0 || b->link_changed)
                bus_after_link_change(b);
}

/* ---- stopping ---- */

void lssd_bus_stop(lssd_bus *b, const char *why) {
        lssd_job *j;
        while ((j = lssd_job_queue_pop(&b->queue))) {
                if (j->request) {
                        lssd_job_abort(j, LSSD_ERROR_CANCELLED, why);
                        if (b->host.dbus && b->slot)
                                (void) sd_bus_emit_signal(b->host.dbus, b->path, LSSD_BUS_IFACE, "JobFinished", "ss",
                                                          lssd_job_name(j), "cancelled");
                }
                lssd_job_free(j);
        }
        b->changed |= LSSD_BUS_CHANGED_QUEUE_LENGTH;
        if (b->holder_name) {
                log_info("%s: dropping holder %s: %s", b->ifname, b->holder_name, why);
                b->holder = sd_bus_track_unref(b->holder);
                free(b->holder_name);
                b->holder_name = NULL;
        }
        /* a bit-rate change runs to its end (seconds): cut off it could
         * leave devices with a pending rate or the bus split */
        if (b->engine_running && !lssd_job_uncancellable(b->job)) {
                log_info("%s: cancelling %s: %s", b->ifname, lssd_job_name(b->job), why);
                lss_master_cancel(b->engine, lssd_bus_now(b));
        }
        if (b->link == LSS_LINK_UP)
                bus_queue_reset(b, false);
        bus_process(b);
}

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

static const lssd_devices_ops devices_ops = {
        .add = devices_add,
        .added = devices_added,
        .changed = devices_changed,
        .removed = devices_removed,
};

/* ---- what the job runners see ---- */

static uint64_t env_now(void *userdata) {
        return lssd_bus_now(userdata);
}

static uint32_t env_bitrate(void *userdata) {
        return lssd_bus_bitrate(userdata);
}

static const char *env_holder(void *userdata) {
        const lssd_bus *b = userdata;
        return b->holder_name;
}

static void env_host_link(void *userdata, lssd_host_link *ret) {
        const lssd_bus *b = userdata;
        *ret = (lssd_host_link) {
                .ifname = b->ifname,
                .link = b->link,
                .bus_state = b->bus_state,
                .simulated = b->sim != NULL,
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

static const lssd_job_env_ops env_ops = {
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

const lssd_bus_config *lssd_bus_config_of(const lssd_bus *b) {
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
        return b->holder_name;
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
                .engine_steps = lss_master_get_stats(b->engine)->steps,
                .lss_timeout_ms = b->config->lss_timeout_ms,
        };
}

/* ---- life cycle ---- */

static int bus_open_transport(lssd_bus *b) {
        int r;

        if (b->host.args->simulate) {
                r = lssd_simbus_new(b->config->bitrate, &b->sim);
                if (r < 0)
                        return r;
                for (size_t i = 0; i < b->host.args->n_sim_slaves; i++) {
                        const lssd_sim_slave *s = &b->host.args->sim_slaves[i];
                        if (strcmp(s->ifname, b->ifname) != 0)
                                continue;
                        r = lssd_simbus_add_slave(b->sim, &s->id, s->node_id);
                        if (r < 0)
                                return r;
                }
                lssd_simbus_transport(b->sim, &b->transport);
                b->link = LSS_LINK_UP;
                return 0;
        }

        socketcan_config sc = {
                .on_link_state = on_link_state,
                .userdata = b,
        };
        r = socketcan_port_open(b->ifname, &sc, &b->port);
        if (r < 0)
                return r;
        socketcan_port_transport(b->port, &b->transport);
        b->link = socketcan_port_state(b->port);
        return 0;
}

int lssd_bus_new(const lssd_bus_host *host, const lssd_bus_config *config, lssd_bus **ret) {
        lss_timing_config tc;
        lssd_bus *b;
        int r;

        b = calloc(1, sizeof(*b));
        if (!b)
                return -ENOMEM;
        b->host = *host;
        b->io_fd = -1;
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
        lssd_devices_init(&b->devices, b, b->ifname, &devices_ops, b);
        lssd_devices_set_config(&b->devices, b->config);
        b->env = (lssd_job_env) {
                .ifname = b->ifname,
                .path = b->path,
                .dbus = host->dbus,
                .engine = b->engine,
                .config = b->config,
                .devices = &b->devices,
                .heard = &b->heard,
                .ops = &env_ops,
                .userdata = b,
        };
        lss_master_set_progress(b->engine, on_engine_progress, b);
        lss_master_set_found(b->engine, on_engine_found, b);

        r = bus_open_transport(b);
        if (r < 0) {
                log_error("%s: failed to open: %s", b->ifname, strerror(-r));
                goto fail;
        }

        r = sd_event_add_time(b->host.event, &b->timer_source, CLOCK_MONOTONIC, UINT64_MAX, 1, on_timer, b);
        if (r < 0)
                goto fail;
        (void) sd_event_source_set_enabled(b->timer_source, SD_EVENT_OFF);
        bus_update_io(b, true);

        if (host->dbus) {
                r = sd_bus_add_object_vtable(host->dbus, &b->slot, b->path, LSSD_BUS_IFACE, lssd_bus_vtable, b);
                if (r < 0)
                        goto fail;
        }

        b->state = lssd_bus_state(b);
        b->bitrate = lssd_bus_bitrate(b);
        /* "link gone" alone does not say why: no such interface, or no CAN in this kernel at all */
        if (!b->sim && b->link == LSS_LINK_GONE && !socketcan_kernel_has_can(NULL))
                log_warning("%s: serving (SocketCAN, link gone): this kernel has no CAN support (no AF_CAN "
                            "sockets; modprobe can can-raw?): %s cannot appear until it has; lssd --simulate "
                            "runs without CAN", b->ifname, b->ifname);
        else if (!b->sim && b->link == LSS_LINK_GONE)
                log_notice("%s: serving (SocketCAN, link gone): no interface %s (yet); served when it appears",
                           b->ifname, b->ifname);
        else
                log_info("%s: serving (%s, link %s)", b->ifname, b->sim ? "simulated" : "SocketCAN",
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

void lssd_bus_set_config(lssd_bus *b, const lssd_bus_config *config) {
        lssd_bus_config *c = lssd_bus_config_dup(config);
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
        lssd_bus_flush_changes(b);
}

void lssd_bus_set_bitrate(lssd_bus *b, uint32_t bitrate) {
        b->bitrate_set = bitrate;
        b->config->bitrate = bitrate;
        bus_update_timing(b);
        bus_update_published(b);
        lssd_bus_flush_changes(b);
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

        b->holder = sd_bus_track_unref(b->holder);
        free(b->holder_name);
        b->remove_source = sd_event_source_disable_unref(b->remove_source);
        b->io_source = sd_event_source_disable_unref(b->io_source);
        b->timer_source = sd_event_source_disable_unref(b->timer_source);
        lss_transport_close(&b->transport);
        b->port = NULL;
        b->sim = NULL;
        lss_master_free(b->engine);
        lssd_bus_config_free(b->config);
        free(b->boot_status);
        free(b->path);
        free(b->ifname);
        free(b);
        return NULL;
}
