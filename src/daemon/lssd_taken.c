/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <stdio.h>

#include "daemon/lssd_device.h"
#include "daemon/lssd_errors.h"
#include "daemon/lssd_taken.h"

void lssd_taken_refresh(lssd_bus *b, const lss_identity *except) {
        for (unsigned n = 0; n < 128; n++)
                b->avoid[n] = b->heard.taken[n];
        for (lssd_device *d = b->devices; d; d = d->next)
                if (!d->missing && lss_node_id_valid(d->node_id) && !(except && lss_identity_equal(&d->id, except)))
                        b->avoid[d->node_id] = true;
        lss_master_set_known_taken(b->engine, b->avoid);
}

void lssd_taken_use_heard(lssd_bus *b) {
        lss_master_set_known_taken(b->engine, b->heard.taken);
}

int lssd_taken_error(lssd_bus *b, sd_bus_error *error, uint8_t node_id, const lss_identity *except,
                     const char *prefix) {
        char who[160], ident[40], heard[80];
        lssd_device *d = lssd_bus_device_with_node_id(b, node_id, except);

        if (d)
                snprintf(who, sizeof(who), "device %s has it", lssd_identity_format(&d->id, ident, sizeof(ident)));
        else if (b->heard.taken[node_id])
                snprintf(who, sizeof(who), "a device lssd does not know %s as node %u",
                         lssd_heard_describe(&b->heard, node_id, lssd_realtime_us(), heard, sizeof(heard)), node_id);
        else
                snprintf(who, sizeof(who), "a device lssd does not know answers to it");
        return sd_bus_error_setf(error, LSSD_ERROR_CONFLICT,
                                 "%sNode-ID %u is taken on %s: %s. Nothing was changed; the option 'force' gives "
                                 "it anyway.", prefix ? prefix : "", node_id, b->ifname, who);
}
