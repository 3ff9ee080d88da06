/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <math.h>
#include <string.h>

#include "daemon/lssd_bus_private.h"
#include "daemon/lssd_run.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_path.h"

/* ---- published state ---- */

const char *lssd_bus_state(const lssd_bus *b) {
        if (b->link != LSS_LINK_UP)
                return "down";
        if (b->bus_state == LSS_BUS_OFF)
                return "bus-off";
        if (b->bus_state == LSS_BUS_ERROR_PASSIVE)
                return "error-passive";
        if (b->job || b->queue.n > 0 || b->holder.name)
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
        return !b->job && b->queue.n == 0 && !b->engine_running && !bus_tx_pending(b);
}

void bus_update_published(lssd_bus *b) {
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

void bus_flush_changes(lssd_bus *b) {
        char *names[8];
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
        if (b->changed & LSSD_BUS_CHANGED_FOREIGN)
                names[n++] = (char *) "ForeignMaster";
        names[n] = NULL;
        b->changed = 0;
        int r = sd_bus_emit_properties_changed_strv(b->host.dbus, b->path, LSSD_BUS_IFACE, names);
        if (r < 0)
                log_debug("%s: failed to emit PropertiesChanged: %s", b->ifname, strerror(-r));
}

void bus_set_progress(lssd_bus *b, double p) {
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

void bus_on_engine_progress(void *userdata, double p) {
        lssd_bus *b = userdata;
        if (!b->job || b->job->n_stages == 0)
                return;
        /* the engine's estimate can shrink when a scan finds more to do; a bar
         * never goes back, and says 100 % only when the job is over */
        double v = b->job->type == LSSD_JOB_SCAN ? lssd_scan_progress(&b->env, b->job, p)
                : ((double) b->job->stage + p) / (double) b->job->n_stages;
        if (v > 0.99)
                v = 0.99;
        if (v > b->progress)
                bus_set_progress(b, v);
}

void bus_on_engine_found(void *userdata, const lss_device *d) {
        lssd_bus *b = userdata;
        /* Scan announces devices; the scans inside AutoAssign and SetBitrate do not */
        if (b->job && b->job->type == LSSD_JOB_SCAN)
                lssd_scan_found(&b->env, b->job, d);
}
