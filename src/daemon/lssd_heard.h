/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* What lssd heard from each node-ID on a bus: the frames a CANopen device
 * sends under its own node-ID (boot-up and heartbeat 0x700+n, SDO answers
 * 0x580+n, emergencies 0x080+n). A node-ID heard is taken: that is how a
 * device in NMT Stopped, which answers no SDO probe, is still seen, by its
 * boot-up or heartbeat. lssd forgets a node-ID when it resets it itself (NMT
 * Reset Communication or Reset Node, e.g. after moving a device away or
 * giving a temporary node-ID back): whoever is still there boots up again
 * and is heard again. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "lss/lss_proto.h"

typedef enum lssd_heard_kind {
        LSSD_HEARD_NOTHING = 0,
        LSSD_HEARD_BOOTUP,
        LSSD_HEARD_HEARTBEAT,
        LSSD_HEARD_SDO,
        LSSD_HEARD_EMERGENCY,
} lssd_heard_kind;

typedef struct lssd_heard {
        bool taken[128];         /* heard and not reset by lssd since */
        uint8_t kind[128];       /* lssd_heard_kind of the last frame */
        uint8_t nmt_state[128];  /* from the last heartbeat */
        uint64_t at[128];        /* CLOCK_REALTIME, µs */
        bool owned[128];         /* the device lssd knows speaks as that node: */
        lss_identity owner[128];
} lssd_heard;

/* A frame received from the bus (not an echo of our own). */
void lssd_heard_rx(lssd_heard *h, const lss_frame *f, uint64_t realtime_us);
/* A frame lssd sent: NMT resets make it forget. */
void lssd_heard_tx(lssd_heard *h, const lss_frame *f);
/* lssd learnt where device `id` is (node_id, 255 non-configured): what was
 * heard at its other node-IDs was that device, now gone from there, and is
 * forgotten; what is heard at node_id is that device's. */
void lssd_heard_owner(lssd_heard *h, uint8_t node_id, const lss_identity *id);
/* Whether something other than device `id` (NULL: anybody) was heard at node_id. */
bool lssd_heard_taken(const lssd_heard *h, uint8_t node_id, const lss_identity *id);
/* "sent a heartbeat (stopped) 12 s ago"; "" if nothing was heard. */
const char *lssd_heard_describe(const lssd_heard *h, uint8_t node_id, uint64_t now_realtime_us, char *buf,
                                size_t size);
