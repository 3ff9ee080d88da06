/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The slave model: a CiA 305 LSS slave (plus the bits of CiA 301 a master
 * meets: NMT states, boot-up, heartbeat producer, an SDO server with the
 * identity object 1018h) with fault knobs. Sans-I/O: fed frames and time, it emits frames through a
 * callback with the delay after which they go on the bus. Used in-process by
 * the unit tests (membus) and on SocketCAN by lss-sim. */
#pragma once

#include <stdbool.h>
#include <stdint.h>

#include "lss/lss_proto.h"

enum lss_slave_nmt { SLAVE_NMT_PRE_OPERATIONAL = 0, SLAVE_NMT_OPERATIONAL, SLAVE_NMT_STOPPED };

enum lss_slave_early_config {
        SLAVE_EARLY_NONE = 0,
        /* enters configuration after the field named here was confirmed,
         * before all four fields matched (a known field deviation) */
        SLAVE_EARLY_AFTER_VENDOR,
        SLAVE_EARLY_AFTER_PRODUCT,
        SLAVE_EARLY_AFTER_REVISION,
};

typedef struct lss_slave_faults {
        uint32_t latency_us;      /* fixed answer latency */
        uint32_t jitter_us;       /* + uniform random 0..jitter */
        bool silent;              /* never answers anything (still obeys) */
        int ignore_cs;            /* -1: none; else this request cs is ignored entirely */
        bool wrong_dlc;           /* answers with DLC 7 */
        bool fastscan_when_configured; /* takes part in fastscan with a node-ID */
        /* CANopenNode v4 (305/CO_LSSslave.c): in waiting, fastscan only while
         * pending and active node-ID are both 255; in configuration every
         * request goes to its process step, which answers any Fastscan with
         * 0x4F and any Switch Selective serial with 0x44, matching or not */
        bool canopennode_lss;
        /* lely-core's LSS slave and the NMT around it (src/co/lss.c, nmt.c,
         * read at 620d1858eb8520dbc3dc5e1a7314565becd54199): a configured
         * node-ID takes effect only at NMT Reset Communication or Reset Node
         * (never at the switch to waiting), and Reset Node keeps the pending
         * node-ID; Inquire Node-ID gives the pending one while the device has
         * no active one (NMT initialising); Fastscan in waiting whatever the
         * node-IDs, its position the vendor on entering waiting and lssnext
         * after every answered step; Identify Non-Configured only while both
         * node-IDs are 255; one progress for Switch Selective and Identify */
        bool lely_lss;
        /* worst case: answers every Fastscan request in every state, whatever
         * its node-ID or identity; a confirmation that goes back to the
         * vendor field (bitcheck 0, lssnext < lsssub) puts it in configuration */
        bool fastscan_any;
        bool store_unsupported;   /* store -> error 1 */
        bool store_fails;         /* store -> error 2 (media access) */
        enum lss_slave_early_config early_config;
        bool needs_nmt_stopped;   /* accepts LSS only in NMT Stopped */
        bool no_identify;         /* no 0x46..0x4B, 0x4C services (CANopenNode) */
        bool identify_strict_rev; /* identify remote: revision strictly inside the
                                   * bounds (an off-by-one), so no range of
                                   * one revision answers */
        bool bit_timing_silent;   /* Configure Bit Timing ignored, no answer */
        uint32_t bit_index_unsupported; /* bitmask of table-0 indexes answered err 1 */
        bool miss_activation;     /* does not hear Activate Bit Timing */
        bool duplicate_answers;   /* every answer sent twice */
        bool configure_error_specific; /* configure node-ID -> 255/spec 0x42 */
        uint32_t late_found_us;   /* the first answer to the fastscan request that
                                   * completes its identity comes this much later */
        uint32_t late_fs_us;      /* the late_fs_nth (from 1) answer to a Fastscan
                                   * request with bitcheck late_fs_check in field
                                   * late_fs_sub comes this much later (0: off) */
        uint8_t late_fs_check, late_fs_sub, late_fs_nth;
        uint32_t spike_ppm;       /* each answer is spike_us late with this probability */
        uint32_t spike_us;        /* (per million): a host that stalls now and then */
        uint32_t rx_loss_ppm;     /* each received frame is lost with this probability
                                   * (per million): a receive FIFO overrun */
        uint32_t tx_loss_ppm;     /* each frame the slave sends is lost with this
                                   * probability (per million): a full transmit queue */
        /* not a fault, a setting: heartbeat producer time (object 1017h) in
         * ms, 0 = no heartbeat */
        uint16_t heartbeat_ms;
} lss_slave_faults;

void lss_slave_faults_default(lss_slave_faults *f);
/* The defaults plus the ways of a CANopenNode v4 device (lss-sim --profile
 * canopennode, lssd --sim-slave ...:canopennode): no identify services,
 * Configure Bit Timing ignored, any Fastscan answered in configuration. */
void lss_slave_faults_canopennode(lss_slave_faults *f);
/* The defaults plus the ways of a device on lely-core's LSS slave with a
 * store hook and no bit-rate hook (lss-sim --profile lely, lssd --sim-slave
 * ...:lely): lely_lss, every Configure Bit Timing answered "not supported",
 * Activate Bit Timing not acted on. */
void lss_slave_faults_lely(lss_slave_faults *f);

/* Persistent and volatile state; lss-sim writes it to the state files. */
typedef struct lss_slave_state {
        uint8_t active_node_id;   /* 0xFF non-configured */
        uint8_t pending_node_id;
        uint8_t stored_node_id;   /* applied at power-on; 0xFF none */
        uint8_t bit_index;        /* active table-0 index */
        uint8_t pending_bit_index;
        uint8_t stored_bit_index;
        bool configuration;       /* LSS configuration state */
        enum lss_slave_nmt nmt;
} lss_slave_state;

/* Emit a frame `delay_us` after the frame or time event being processed. */
typedef void (*lss_slave_emit_fn)(void *userdata, const lss_frame *f, uint64_t delay_us);

typedef struct lss_slave {
        lss_identity id;
        lss_slave_faults faults;
        lss_slave_state st;
        /* fastscan progress: next lsssub expected, or -1 when not scanning
         * (lely_lss: the vendor on entering waiting, any lssnext after) */
        int fs_sub;
        /* identify-remote progress: which of 0x46..0x4B matched so far */
        unsigned ident_step;
        bool ident_match;
        /* selective switch progress: next field expected */
        unsigned sel_step;
        /* activate bit timing: times of the switch and the end of silence */
        uint64_t switch_at_us, silent_until_us;
        uint64_t now_us;
        uint64_t rng;
        /* time the Activate Bit Timing frame was heard: the window off the
         * bus is [activate_at_us, silent_until_us) */
        uint64_t activate_at_us;
        /* the slave has one transmit queue: a later frame is never ready
         * before an earlier one, whatever the jitter */
        uint64_t tx_ready_us;
        unsigned changes;         /* incremented on every persistent state change */
        bool late_found_sent;     /* late_found_us used up */
        unsigned late_fs_seen;    /* answers that matched late_fs_check/sub so far */
        uint64_t heartbeat_at_us; /* next heartbeat, UINT64_MAX none */
        lss_slave_emit_fn emit;
        void *userdata;
} lss_slave;

/* node_id 1..127 or 0xFF; bit_index is the table-0 index the slave runs at. */
void lss_slave_init(lss_slave *s, const lss_identity *id, uint8_t node_id, uint8_t bit_index,
                    const lss_slave_faults *faults, uint64_t seed, lss_slave_emit_fn emit, void *userdata);
/* Power cycle: stored values become active, boot-up is sent when configured.
 * NMT Reset Node does the same (it reloads the stored values, so a pending
 * node-ID that was not stored is lost), but on lely_lss, which keeps it. */
void lss_slave_power_on(lss_slave *s, uint64_t now_us);
/* Heartbeat producer time (1017h) in ms, 0 = off: the next heartbeat is
 * one period after the slave's current time (and after every boot-up). */
void lss_slave_set_heartbeat(lss_slave *s, uint16_t period_ms);
/* Every frame on the bus (the slave's own excepted). */
void lss_slave_on_frame(lss_slave *s, const lss_frame *f, uint64_t now_us);
/* Time passed; call at lss_slave_deadline(). */
void lss_slave_on_time(lss_slave *s, uint64_t now_us);
/* Next time the slave needs lss_slave_on_time(), UINT64_MAX if none. */
uint64_t lss_slave_deadline(const lss_slave *s);
/* Whether the slave can hear/be heard at the bus's bit timing index right now
 * (bit rate differs or it is inside an activation window -> false). */
bool lss_slave_on_bus(const lss_slave *s, uint8_t bus_bit_index, uint64_t now_us);
