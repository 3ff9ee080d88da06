/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* What the daemon knows about one LSS slave on one bus; published as an
 * org.lssd.LSS1.Device object. Device objects stay while their bus exists;
 * a device a later scan should have found but did not is "missing". */
#pragma once

#include <stdbool.h>
#include <stdint.h>
#include <systemd/sd-bus.h>

#include "lss/lss_proto.h"
#include "names/lssd_names.h"

typedef struct lssd_bus lssd_bus;
typedef struct lssd_device lssd_device;

/* PropertiesChanged bookkeeping. */
#define LSSD_DEVICE_CHANGED_NODE_ID        (1u << 0)
#define LSSD_DEVICE_CHANGED_MAPPED_NODE_ID (1u << 1)
#define LSSD_DEVICE_CHANGED_STATE          (1u << 2)
#define LSSD_DEVICE_CHANGED_LAST_SEEN      (1u << 3)
#define LSSD_DEVICE_CHANGED_FOUND_BY       (1u << 4)

/* How a Scan reached a device (property FoundBy, names/lssd_names.h). */
#define LSSD_FOUND_LSS (1u << 0)  /* answered LSS (fastscan, slowscan, selective switch) */
#define LSSD_FOUND_SDO (1u << 1)  /* answered the SDO upload of 1018h */

struct lssd_device {
        lssd_bus *bus;
        lssd_device *next;
        lss_identity id;
        /* only known from a map entry without revision (a missing device never
         * seen): id.revision is 0 and means nothing (RevisionKnown false) */
        bool revision_unknown;
        char *path;
        uint8_t node_id;        /* last known; 0xFF non-configured */
        uint8_t mapped_node_id; /* from the bus's map; 0 = not in the map */
        bool missing;           /* a scan that covers it did not find it */
        bool assigned;          /* its node-ID came from this daemon (AssignNodeId) */
        bool pooled;            /* ... from the pool (AutoAssign, unknown = "pool") */
        bool blocked;           /* the last auto-assign pass found its mapped node-ID taken */
        bool pending_reset;     /* holds node_id, which lssd gave it, for its next reset: it
                                 * did not boot up with it (a slave such as Lely's) */
        /* a node-ID lssd configured into it that nothing verified nor gave
         * back: it may hold it, so no other device is given it; 0 none */
        uint8_t kept_node_id;
        const char *state;      /* as published */
        uint64_t last_seen;     /* µs, CLOCK_REALTIME; 0 = never */
        uint8_t found_by;       /* LSSD_FOUND_*: in the last Scan that found it; 0 = no Scan did */
        unsigned changed;       /* LSSD_DEVICE_CHANGED_* not yet signalled */
        sd_bus_slot *slot;
};

/* The State property:
 *   missing         a scan that covers it did not find it
 *   non-configured  node-ID 0xFF
 *   conflict        another present device on the bus has the same node-ID
 *   assigned        it has the node-ID the map (or an AssignNodeId call) gave
 *   pending-reset   it holds the node-ID lssd gave it, in effect at its next reset
 *   mismatch        it is in the map with another node-ID
 *   pool            not in the map, it has a node-ID AutoAssign gave from the pool
 *   configured      it has a node-ID and is not in the map */
const char *lssd_device_state(uint8_t node_id, uint8_t mapped_node_id, bool missing, bool conflict,
                              bool assigned, bool pooled, bool pending_reset);

int lssd_device_new(lssd_bus *bus, const char *ifname, const lss_identity *id, lssd_device **ret);
lssd_device *lssd_device_free(lssd_device *d);

/* "vendor:product:revision:serial" as 8 hex digits each, for logs; buf >= 36. */
const char *lssd_identity_format(const lss_identity *id, char *buf, size_t size);
