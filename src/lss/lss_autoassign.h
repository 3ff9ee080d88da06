/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Auto-assignment: make the bus match a node-ID map keyed by LSS identity.
 *
 *  1. NMT Stop to all first when asked (devices that take LSS only when stopped).
 *  2. Map entries with a full identity: selective switch (no scan), Inquire
 *     Node-ID; nothing is sent when it already matches (idempotent).
 *  3. Map entries without revision: identify-remote bisection over the
 *     revision for that vendor/product/serial (finds configured ones too).
 *  4. Non-configured devices left: enumeration by fastscan, with the known
 *     vendor/product bits of the map first, then blind when a ping still
 *     gets an answer. A device for the pool takes its node-ID the moment it
 *     is confirmed (alone in configuration after a selective switch); the
 *     others are set aside and handled by selective switch after it.
 *  5. Before a node-ID is given, the bus is asked whether some device
 *     already answers to it (SDO upload of object 0x1000 to that node, which
 *     every CANopen device must answer); if one does, the device is reported
 *     as a conflict and nothing is configured.
 *  6. Every assignment is verified by the boot-up of the new node-ID (NMT
 *     Reset Communication first for a device that was configured).
 *  7. With `replace`: a mapped device missing and exactly one device of its
 *     vendor/product the map does not know, non-configured or configured at
 *     the missing device's node-ID: that one gets (or keeps) the missing
 *     device's node-ID (lss_replace.h has the rule).
 *  8. Entries without revision steps 3 and 4 left (devices without identify
 *     services, CANopenNode), and for 7 the node-IDs of entries not found:
 *     1018h read by SDO, before the NMT Stop of step 1 or after step 4,
 *     only when needed (lss_autoassign_sdo.c).
 * Every slave ends in waiting state, whatever happens. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "lss/lss_master.h"

typedef struct lss_map_entry {
        lss_identity id;
        bool revision_known; /* false: any revision */
        uint8_t node_id;
} lss_map_entry;

/* Whether the map entry names this device (lss_identity_matches()). */
bool lss_map_entry_matches(const lss_map_entry *e, const lss_identity *id);

enum lss_unknown_policy { LSS_UNKNOWN_IGNORE = 0, LSS_UNKNOWN_POOL };

typedef struct lss_autoassign_plan {
        const lss_map_entry *map;
        size_t n_map;
        enum lss_unknown_policy unknown;
        uint8_t pool_lo, pool_hi; /* for LSS_UNKNOWN_POOL */
        bool store;
        bool nmt_stop;
        /* a broken device's replacement gets its node-ID (step 7); decided
         * before the pool takes an unknown device */
        bool replace;
        /* discovery only: no Configure, Store or NMT frame; the outcomes
         * say what a pass would do (lss_outcome.dry) */
        bool dry_run;
        /* 128 entries or NULL, may change while the pass runs: node-IDs a
         * device took from a pending ID that an interrupted pass configured
         * and may not have stored; a device found with its mapped node-ID
         * among them is stored again (with store on) instead of "unchanged". */
        const bool *unstored;
        /* Devices that did not boot up with the node-ID they were given but
         * hold it for their next reset (lss_outcome.pending_reset): one
         * broadcast NMT Reset Communication after the pass, then each is
         * verified by its boot-up (or given its old node-ID back). Resets
         * every device on the bus. */
        bool reset_after_pass;
} lss_autoassign_plan;

enum lss_outcome_kind {
        LSS_OUTCOME_UNCHANGED = 0, /* already had its mapped node-ID: nothing sent */
        LSS_OUTCOME_ASSIGNED,      /* got its mapped node-ID, verified by boot-up */
        LSS_OUTCOME_POOL,          /* not in the map, got a node-ID from the pool */
        LSS_OUTCOME_REPLACED,      /* not in the map, got the node-ID of the missing entry `replaced` */
        LSS_OUTCOME_UNKNOWN,       /* not in the map, left alone */
        LSS_OUTCOME_MISSING,       /* in the map, not on the bus */
        LSS_OUTCOME_CONFLICT,      /* its node-ID already answers on the bus: not assigned */
        LSS_OUTCOME_FAILED,        /* an LSS error (status, message) */
};

const char *lss_outcome_name(enum lss_outcome_kind k);

typedef struct lss_outcome {
        lss_identity id;
        uint8_t old_node_id; /* 0xFF non-configured, 0 unknown (missing) */
        uint8_t new_node_id; /* what it has now (0 if missing) */
        enum lss_outcome_kind kind;
        bool not_stored;     /* assigned/pool, but the device cannot store (err: its Store Configuration error) */
        bool pending_reset;  /* assigned/pool/replaced: the device holds new_node_id, in effect
                              * at its next reset (it did not boot up with it) */
        /* failed: a node-ID the device may hold (Configure Node-ID went out,
         * nothing confirmed or gave it back): no other device is given it
         * (lss_autoassign_plan.kept); 0 none */
        uint8_t kept_node_id;
        bool dry;            /* assigned/pool/replaced: would be, in a dry run (nothing was sent) */
        /* replaced (and a replacement that failed): the missing map entry's
         * identity, its revision 0 when the map has none */
        lss_identity replaced;
        bool replaced_revision_known;
        bool replacing;      /* `replaced` is set */
        uint8_t err;
        enum lss_status status;
        char message[400];
} lss_outcome;

/* Starts the pass. The plan (and its map) must stay valid until it is done. */
int lss_master_autoassign(lss_master *m, const lss_autoassign_plan *plan, uint64_t now);
/* The per-device outcomes of the last pass (valid until the next start). */
const lss_outcome *lss_master_outcomes(const lss_master *m, size_t *n);
