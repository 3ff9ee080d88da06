/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The device registry of one bus: the devices lssd knows there, in the order
 * they were found, with their mapped node-IDs and states kept up to date
 * against the bus's map. What it publishes goes through its ops (sd-bus in
 * lssd, a recorder in the unit tests): a new device, properties that
 * changed, a device gone. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <time.h>

#include "config/lssconf.h"
#include "daemon/lssd_device.h"
#include "util/time_util.h"

typedef struct lssd_devices_ops {
        /* a new device, before it is in the list: register its object;
         * negative errno refuses it */
        int (*add)(void *userdata, lssd_device *d);
        /* it is in the list now: announce it */
        void (*added)(void *userdata, lssd_device *d);
        /* these properties of d changed (NULL-terminated names) */
        void (*changed)(void *userdata, lssd_device *d, char **names);
        /* d is about to be freed */
        void (*removed)(void *userdata, lssd_device *d);
} lssd_devices_ops;

typedef struct lssd_devices {
        lssd_device *head;
        size_t n;
        lssd_bus *owner;                 /* what the device objects belong to */
        const char *ifname;
        const lssconf_bus *config;   /* the map: mapped node-IDs */
        const lssd_devices_ops *ops;     /* NULL: nothing published */
        void *userdata;
} lssd_devices;

void lssd_devices_init(lssd_devices *ds, lssd_bus *owner, const char *ifname, const lssd_devices_ops *ops,
                       void *userdata);
/* Removes every device (ops->removed for each). */
void lssd_devices_clear(lssd_devices *ds);
/* A new map (after a reload or SetBitrate): devices known only from an
 * entry of the old map that is gone (never seen) are removed; call
 * lssd_devices_refresh() after. */
void lssd_devices_set_config(lssd_devices *ds, const lssconf_bus *config);

lssd_device *lssd_devices_find(const lssd_devices *ds, const lss_identity *id);
/* A present device other than `except` answering to node_id, NULL if none. */
lssd_device *lssd_devices_with_node_id(const lssd_devices *ds, uint8_t node_id, const lss_identity *except);
/* A device other than `except` that holds node_id without answering to it
 * (yet): for its next reset (pending_reset), or maybe (kept_node_id). Such a
 * node-ID is never given to another device. NULL if none. */
lssd_device *lssd_devices_holding(const lssd_devices *ds, uint8_t node_id, const lss_identity *except);
/* The device with this identity, created (with node_id) and announced if
 * new: 1 when new, 0 when known. A new one made with !revision_known (from
 * a map entry without revision, never seen) publishes RevisionKnown false. */
int lssd_devices_get(lssd_devices *ds, const lss_identity *id, bool revision_known, uint8_t node_id,
                     uint64_t now_realtime, lssd_device **ret);
/* Recomputes mapped node-IDs and states of every device and publishes what
 * changed. */
void lssd_devices_refresh(lssd_devices *ds);
/* A frame from the bus: the boot-up of a device that held its node-ID for
 * its next reset (pending_reset) says the node-ID is in effect now. */
void lssd_devices_heard(lssd_devices *ds, const lss_frame *f);

/* CLOCK_REALTIME µs, for LastSeen. */
static inline uint64_t lssd_realtime_us(void) {
        return clock_now_us(CLOCK_REALTIME);
}
