/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* What lssd publishes, read in one go: the manager's properties and every
 * bus and device object (ObjectManager.GetManagedObjects). */
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "ctl/ctl.h"
#include "ctl/ctl_errors.h"

typedef struct ctl_bus_info {
        char *path;
        char *ifname;
        char *state;
        char *job;
        uint32_t bitrate;
        uint32_t queue_length;
        double progress;
        /* LastPass: started 0 when there was none */
        uint64_t pass_started, pass_duration;  /* µs */
        char pass_kind[8];                     /* "boot" or "call" */
        char pass_result[24];
        char pass_counts[160];                 /* "6 assigned, 2 unchanged" (non-zero ones) */
        /* ForeignMaster: another LSS master; since 0 when none was heard */
        bool foreign_active;
        uint64_t foreign_since, foreign_last;  /* µs since the epoch */
        char foreign_frame[32];
} ctl_bus_info;

typedef struct ctl_device_info {
        char *path;
        char *ifname;             /* of its bus */
        uint32_t id[4];           /* vendor, product, revision, serial */
        bool revision_unknown;    /* RevisionKnown false: id[2] means nothing */
        uint8_t node_id;          /* 255: non-configured */
        uint8_t mapped_node_id;   /* 0: not in the map */
        char *state;
        uint64_t last_seen;       /* µs since the epoch, 0: never */
        bool found_lss, found_sdo; /* FoundBy: how the last Scan that found it reached it */
} ctl_device_info;

typedef struct ctl_objects {
        char *version;
        ctl_bus_info *buses;      /* in the order of Manager.Buses */
        size_t n_buses;
        ctl_device_info *devices; /* by bus, then identity */
        size_t n_devices;
} ctl_objects;

/* Reads everything; errors are reported (ctl_bus_fail) and returned. */
int ctl_objects_load(ctl_context *c, ctl_objects *ret);
void ctl_objects_done(ctl_objects *o);
