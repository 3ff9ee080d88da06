/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Another LSS master on the bus (a PLC's CiA 302 boot-up, a commissioning
 * tool). LSS answers carry no request identifier: two masters take each
 * other's answers for their own, and one's Configure Node-ID reaches the
 * slaves the other selected. So a request lssd did not send (a 0x7E5 frame
 * that is not our echo) ends the running job at once (the engine's part,
 * lss_master.h), answers every job queued for a caller with ForeignMaster,
 * and the bus takes no LSS job until it heard none for
 * foreign_master_quiet_s; internal jobs wait for that (the boot pass, a
 * GiveBack), but for a Reset, a switch to waiting. */
#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_bus_private.h"
#include "daemon/lssd_job_reply.h"
#include "daemon/lssd_log.h"

void bus_foreign_text(const lssd_bus *b, char *buf, size_t size) {
        char at[32];
        snprintf(buf, size, "another LSS master is active on %s: %s at %s", b->ifname, b->foreign.now.frame,
                 lssd_clock_text(b->foreign.now.last_us, at, sizeof(at)));
}

static uint64_t quiet_us(const lssd_bus *b) {
        return (uint64_t) b->config->foreign_master_quiet_s * 1000000u;
}

static void publish(lssd_bus *b) {
        b->foreign.pub = b->foreign.now;
        b->foreign.pub_at = bus_now(b);
        b->changed |= LSSD_BUS_CHANGED_FOREIGN;
}

static int on_quiet(sd_event_source *s, uint64_t usec, void *userdata);

static void arm(lssd_bus *b) {
        uint64_t at = b->foreign.last_at + quiet_us(b);
        int r = 0;
        if (!b->foreign.timer)
                r = sd_event_add_time(b->host.event, &b->foreign.timer, CLOCK_MONOTONIC, at, 1000, on_quiet, b);
        else
                r = sd_event_source_set_time(b->foreign.timer, at);
        if (r >= 0)
                r = sd_event_source_set_enabled(b->foreign.timer, SD_EVENT_ONESHOT);
        if (r < 0)
                log_error("%s: failed to arm the end of the quiet after another LSS master: %s", b->ifname,
                          strerror(-r));
}

static int on_quiet(sd_event_source *s, uint64_t usec, void *userdata) {
        lssd_bus *b = userdata;
        char since[32], last[32];

        if (!b->foreign.now.active)
                return 0;
        if (bus_now(b) < b->foreign.last_at + quiet_us(b)) {
                arm(b); /* foreign_master_quiet_s grew at a reload */
                return 0;
        }
        b->foreign.now.active = false;
        log_notice("%s: no LSS request of another master for %u s (%" PRIu64 " heard from %s to %s, the last %s): "
                   "taking LSS jobs again", b->ifname, b->config->foreign_master_quiet_s, b->foreign.episode_count,
                   lssd_clock_text(b->foreign.now.since_us, since, sizeof(since)),
                   lssd_clock_text(b->foreign.now.last_us, last, sizeof(last)), b->foreign.now.frame);
        publish(b);
        if (!b->removing)
                b->host.ops->status_changed(b->host.userdata);
        bus_process(b);
        return 0;
}

void bus_foreign_heard(lssd_bus *b, const lss_frame *f) {
        lssd_bus_foreign *n = &b->foreign.now;
        bool start = !n->active;

        n->last_us = lssd_realtime_us();
        lss_frame_format(f, n->frame, sizeof(n->frame));
        n->count++;
        b->foreign.last_at = bus_now(b);
        arm(b);
        if (start) {
                char text[160];
                n->active = true;
                n->since_us = n->last_us;
                b->foreign.episode_count = 0;
                bus_foreign_text(b, text, sizeof(text));
                log_warning("%s: %s: LSS answers carry no request identifier, so lssd stops its job and takes none "
                            "until it heard no LSS request of another master for %u s", b->ifname, text,
                            b->config->foreign_master_quiet_s);
                if (b->holder.name)
                        log_info("%s: held by %s: its raw services are refused meanwhile", b->ifname,
                                 b->holder.name);
                publish(b);
                if (!b->removing)
                        b->host.ops->status_changed(b->host.userdata);
        } else {
                log_debug("%s: another LSS master: %s", b->ifname, n->frame);
                if (b->foreign.now.last_us >= b->foreign.pub.last_us + LSSD_FOREIGN_PUBLISH_US)
                        publish(b);
        }
        b->foreign.episode_count++;
        /* every job waiting for a caller gets the answer it would get now */
        char text[160];
        bus_foreign_text(b, text, sizeof(text));
        bus_queue_abort_requests(b, LSSD_ERROR_FOREIGN_MASTER, "foreign-master", text);
}

int bus_foreign_refuse(lssd_bus *b, sd_bus_error *error) {
        char text[160];
        if (!b->foreign.now.active)
                return 0;
        bus_foreign_text(b, text, sizeof(text));
        return sd_bus_error_setf(error, LSSD_ERROR_FOREIGN_MASTER, "%s; %s takes LSS jobs again once it heard no "
                                 "LSS request of another master for %u s", text, b->ifname,
                                 b->config->foreign_master_quiet_s);
}

bool bus_foreign_holds(const lssd_bus *b) {
        return b->foreign.now.active && b->queue.head && b->queue.head->type != LSSD_JOB_RESET;
}

/* The slaves the engine left set aside: a GiveBack, first once it is quiet. */
static void queue_give_back(lssd_bus *b) {
        size_t n;
        const lss_device *left = lss_master_left_aside(b->engine, &n);
        lssd_job *j = NULL;
        char ident[40];

        if (n == 0)
                return;
        for (size_t i = 0; i < n; i++)
                lssd_log_device(LOG_WARNING, b->ifname, &left[i].id, left[i].aside_node_id,
                                "%s: device %s keeps the temporary node-ID %u it was set aside with until the other "
                                "LSS master is quiet", b->ifname, lssd_identity_format(&left[i].id, ident,
                                                                                       sizeof(ident)),
                                left[i].aside_node_id);
        if (lssd_job_new(LSSD_JOB_GIVE_BACK, NULL, &j) < 0 || !(j->aside = malloc(n * sizeof(*j->aside)))) {
                lssd_job_free(j);
                log_error("%s: out of memory queueing the give-back of %zu slaves set aside", b->ifname, n);
                return;
        }
        memcpy(j->aside, left, n * sizeof(*j->aside));
        j->n_aside = n;
        j->id = b->host.ops->next_job_id(b->host.userdata);
        bus_queue_front(b, j, 1u << LSSD_JOB_RESET);
}

const lss_result *bus_foreign_result(lssd_bus *b, const lss_result *r, lss_result *copy) {
        char text[160];
        /* the engine says "another LSS master is active (FRAME)" and maybe more after it */
        const char *rest = strchr(r->message, ')');
        *copy = *r;
        bus_foreign_text(b, text, sizeof(text));
        snprintf(copy->message, sizeof(copy->message), "%s%.200s", text, rest ? rest + 1 : "");
        queue_give_back(b);
        return copy;
}

void lssd_bus_foreign_get(const lssd_bus *b, lssd_bus_foreign *ret) {
        *ret = b->foreign.pub;
}

void bus_foreign_free(lssd_bus *b) {
        b->foreign.timer = sd_event_source_disable_unref(b->foreign.timer);
}
