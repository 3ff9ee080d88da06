/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_bus_private.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_path.h"

/* ---- holder ---- */

static void bus_drop_holder(lssd_bus *b, const char *why) {
        if (!b->holder.name)
                return;
        log_info("%s: released by %s (%s); switching every slave to waiting", b->ifname, b->holder.name, why);
        lssd_holder_drop(&b->holder);
        bus_queue_reset(b, false);
}

void bus_on_holder_gone(lssd_holder *h, void *userdata) {
        lssd_bus *b = userdata;
        /* a raw service of the vanished holder has nobody to answer to */
        if (b->job && b->job->type == LSSD_JOB_RAW && b->engine_running)
                lss_master_cancel(b->engine, bus_now(b));
        bus_drop_holder(b, "the holder left the bus");
        bus_process(b);
}

int lssd_bus_acquire(lssd_bus *b, sd_bus_message *m, sd_bus_error *error) {
        const char *sender = sd_bus_message_get_sender(m);
        int r;

        if (!sender)
                return sd_bus_error_set(error, SD_BUS_ERROR_ACCESS_DENIED, "Acquire() needs a bus connection");
        if (lssd_holder_is(&b->holder, sender))
                return 0;
        if (b->host.ops->stopping(b->host.userdata) || b->removing)
                return sd_bus_error_setf(error, LSSD_ERROR_BUSY, "%s: lssd is stopping serving this bus", b->ifname);
        if (b->holder.name)
                return sd_bus_error_setf(error, LSSD_ERROR_BUSY, "%s is held by %s already", b->ifname,
                                         b->holder.name);

        r = lssd_holder_take(&b->holder, sender, m);
        if (r < 0)
                return r;
        log_info("%s: held by %s", b->ifname, sender);
        bus_process(b);
        return 0;
}

int lssd_bus_release(lssd_bus *b, const char *sender, sd_bus_error *error) {
        if (!b->holder.name)
                return 0;
        if (!lssd_holder_is(&b->holder, sender))
                return sd_bus_error_setf(error, LSSD_ERROR_BUSY, "%s is held by %s, not by the caller", b->ifname,
                                         b->holder.name);
        bus_drop_holder(b, "Release()");
        bus_process(b);
        return 0;
}

int lssd_bus_cancel(lssd_bus *b, const char *sender, sd_bus_error *error) {
        if (!b->job || b->job->type == LSSD_JOB_RESET || !b->engine_running)
                return 0;
        if (b->holder.name && !lssd_holder_is(&b->holder, sender))
                return sd_bus_error_setf(error, LSSD_ERROR_BUSY, "%s is held by %s (Acquire)", b->ifname,
                                         b->holder.name);
        if ((b->engine_running && lssd_job_uncancellable(b->job)))
                return sd_bus_error_setf(error, LSSD_ERROR_BUSY,
                                         "%s: the bit-rate change is under way and cannot be cancelled (devices "
                                         "would keep a pending rate or the bus stay split); it ends soon",
                                         b->ifname);
        log_info("%s: cancelling %s for %s", b->ifname, lssd_job_name(b->job), sender ? sender : "?");
        lss_master_cancel(b->engine, bus_now(b));
        bus_process(b);
        return 0;
}
