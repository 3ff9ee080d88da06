/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>

#include "daemon/lssd_device.h"
#include "daemon/lssd_path.h"

const char *lssd_device_state(uint8_t node_id, uint8_t mapped_node_id, bool missing, bool conflict,
                              bool assigned, bool pooled, bool pending_reset) {
        if (missing)
                return "missing";
        if (pending_reset && node_id != LSS_NODE_ID_UNCONFIGURED)
                return "pending-reset";
        if (node_id == LSS_NODE_ID_UNCONFIGURED)
                return "non-configured";
        if (conflict)
                return "conflict";
        if (mapped_node_id != 0)
                return node_id == mapped_node_id ? "assigned" : "mismatch";
        if (pooled)
                return "pool";
        return assigned ? "assigned" : "configured";
}

int lssd_device_new(lssd_bus *bus, const char *ifname, const lss_identity *id, lssd_device **ret) {
        lssd_device *d = calloc(1, sizeof(*d));
        if (!d)
                return -ENOMEM;
        int r = lssd_device_path(ifname, id, &d->path);
        if (r < 0) {
                free(d);
                return r;
        }
        d->bus = bus;
        d->id = *id;
        d->node_id = LSS_NODE_ID_UNCONFIGURED;
        d->state = "non-configured";
        *ret = d;
        return 0;
}

lssd_device *lssd_device_free(lssd_device *d) {
        if (!d)
                return NULL;
        sd_bus_slot_unref(d->slot);
        free(d->path);
        free(d);
        return NULL;
}

const char *lssd_identity_format(const lss_identity *id, char *buf, size_t size) {
        snprintf(buf, size, "%08x:%08x:%08x:%08x", id->vendor, id->product, id->revision, id->serial);
        return buf;
}
