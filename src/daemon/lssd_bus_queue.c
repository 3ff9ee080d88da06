/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_bus_private.h"
#include "daemon/lssd_job_reply.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_path.h"

/* ---- jobs ---- */

int lssd_bus_check_available(lssd_bus *b, const char *sender, bool raw, sd_bus_error *error) {
        if (b->host.ops->stopping(b->host.userdata) || b->removing)
                return sd_bus_error_setf(error, LSSD_ERROR_BUSY, "%s: lssd is stopping serving this bus", b->ifname);
        if (b->holder.name && !lssd_holder_is(&b->holder, sender))
                return sd_bus_error_setf(error, LSSD_ERROR_BUSY, "%s is held by %s (Acquire)", b->ifname,
                                         b->holder.name);
        if (raw && !lssd_holder_is(&b->holder, sender))
                return sd_bus_error_setf(error, LSSD_ERROR_NOT_HELD,
                                         "Raw LSS services need the bus held: call Acquire() on %s first, "
                                         "or use Execute()", b->ifname);
        if (b->link != LSS_LINK_UP)
                return sd_bus_error_setf(error, LSSD_ERROR_BUS_DOWN, "%s is %s", b->ifname,
                                         b->link == LSS_LINK_GONE ? "not there" : "down");
        if (b->bus_state == LSS_BUS_OFF)
                return sd_bus_error_setf(error, LSSD_ERROR_BUS_OFF, "%s: the controller is bus-off", b->ifname);
        return bus_foreign_refuse(b, error);
}

/* Internal jobs that must precede everything queued go first, behind those
 * of the kinds in `behind` already at the head (a Reset before all). */
void bus_queue_front(lssd_bus *b, lssd_job *j, unsigned behind) {
        lssd_job *head[8];
        size_t n = 0;
        while (n < sizeof(head) / sizeof(head[0]) && b->queue.head && (behind & (1u << b->queue.head->type)))
                head[n++] = lssd_job_queue_pop(&b->queue);
        lssd_job_queue_push_front(&b->queue, j);
        while (n > 0)
                lssd_job_queue_push_front(&b->queue, head[--n]);
        b->changed |= LSSD_BUS_CHANGED_QUEUE_LENGTH;
}

/* Drops queued jobs, every one (`all`) or those of callers; each caller is
 * answered `error` and told by JobFinished `result`. */
static void drop_queued(lssd_bus *b, bool all, const char *error, const char *result, const char *why) {
        lssd_job *j, *next;
        for (j = b->queue.head; j; j = next) {
                next = j->next;
                if (!all && !j->request)
                        continue;
                lssd_job_queue_remove(&b->queue, j);
                b->changed |= LSSD_BUS_CHANGED_QUEUE_LENGTH;
                if (j->request) {
                        lssd_job_abort(j, error, why);
                        if (b->host.dbus && b->slot)
                                (void) sd_bus_emit_signal(b->host.dbus, b->path, LSSD_BUS_IFACE,
                                                          LSSD_SIGNAL_JOB_FINISHED, "ss", lssd_job_name(j), result);
                }
                lssd_job_free(j);
        }
}

void bus_queue_abort_requests(lssd_bus *b, const char *error, const char *result, const char *why) {
        drop_queued(b, false, error, result, why);
}

void bus_queue_reset(lssd_bus *b, bool front) {
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
void bus_queue_boot_pass(lssd_bus *b) {
        lssd_job *j;

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
        /* behind the switch to waiting, and 255 back to slaves a pass broken off left set aside */
        bus_queue_front(b, j, 1u << LSSD_JOB_RESET | 1u << LSSD_JOB_GIVE_BACK);
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

/* ---- stopping ---- */

void lssd_bus_stop(lssd_bus *b, const char *why) {
        drop_queued(b, true, LSSD_ERROR_CANCELLED, "cancelled", why);
        b->changed |= LSSD_BUS_CHANGED_QUEUE_LENGTH;
        if (b->holder.name) {
                log_info("%s: dropping holder %s: %s", b->ifname, b->holder.name, why);
                lssd_holder_drop(&b->holder);
        }
        /* a bit-rate change runs to its end (seconds): cut off it could
         * leave devices with a pending rate or the bus split */
        if (b->engine_running && !lssd_job_uncancellable(b->job)) {
                log_info("%s: cancelling %s: %s", b->ifname, lssd_job_name(b->job), why);
                lss_master_cancel(b->engine, bus_now(b));
        }
        if (b->link == LSS_LINK_UP)
                bus_queue_reset(b, false);
        bus_process(b);
}
