/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <stdio.h>
#include <time.h>

#include "daemon/lssd_device.h"
#include "daemon/lssd_errors.h"
#include "daemon/lssd_taken.h"
#include "util/time_util.h"

static bool taken(void *userdata, uint8_t node_id, const lss_identity *id) {
        lssd_job_env *e = userdata;
        return lssd_heard_taken(e->heard, node_id, id) || lssd_devices_holding(e->devices, node_id, id) != NULL ||
               (e->taken_with_devices && lssd_devices_with_node_id(e->devices, node_id, id) != NULL);
}

void lssd_taken_check(lssd_job_env *e, bool with_devices) {
        e->taken_with_devices = with_devices;
        lss_master_set_taken_check(e->engine, taken, e);
}

int lssd_taken_error(lssd_job_env *e, sd_bus_error *error, uint8_t node_id, const lss_identity *except,
                     const char *prefix) {
        char who[160], ident[40], heard[80];
        lssd_device *d = lssd_devices_with_node_id(e->devices, node_id, except);
        lssd_device *h = lssd_devices_holding(e->devices, node_id, except);

        if (h)
                snprintf(who, sizeof(who), "device %s holds it %s", lssd_identity_format(&h->id, ident, sizeof(ident)),
                         h->pending_reset ? "for its next reset" : "maybe (lssd configured it there, unverified)");
        else if (d)
                snprintf(who, sizeof(who), "device %s has it", lssd_identity_format(&d->id, ident, sizeof(ident)));
        else if (lssd_heard_taken(e->heard, node_id, except))
                snprintf(who, sizeof(who), "a device lssd does not know %s as node %u",
                         lssd_heard_describe(e->heard, node_id, clock_now_us(CLOCK_REALTIME), heard, sizeof(heard)), node_id);
        else
                snprintf(who, sizeof(who), "a device lssd does not know answers to it");
        return sd_bus_error_setf(error, LSSD_ERROR_CONFLICT,
                                 "%sNode-ID %u is taken on %s: %s. Nothing was changed (to give it anyway: "
                                 "AssignNodeId's option 'force', or ConfigureNodeId as (yb) in Execute()).",
                                 prefix ? prefix : "", node_id, e->ifname, who);
}
