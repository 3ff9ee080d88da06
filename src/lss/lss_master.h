/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The LSS master engine. Sans-I/O: it is fed received frames and the passing of
 * time, and in return hands out frames to send and the next time it wants to be
 * woken. It never sleeps, never touches a socket, so unit tests drive it on
 * virtual time and the daemon drives it from sd-event.
 *
 * One operation at a time (the daemon serialises jobs per bus). Driving loop:
 *
 *     lss_master_start_xxx(m, ..., now);
 *     for (;;) {
 *             while (lss_master_next_tx(m, &f)) {
 *                     t = now();                   // before each write: an
 *                     send(f);                     // answer may arrive before
 *             }                                    // write() returns
 *             lss_master_on_sent(m, t);            // t of the last frame
 *             if (lss_master_done(m)) break;
 *             wait for a frame or until lss_master_deadline(m);
 *             frame ? lss_master_on_frame(m, &f, rx_time) : lss_master_on_time(m, now());
 *     }
 *     result = lss_master_result(m);
 *
 * The rules that make late and stale answers harmless are in docs/engine.md. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "lss/lss_proto.h"

enum lss_status {
        LSS_OK = 0,
        LSS_E_NO_RESPONSE,   /* nobody answered a confirmed service */
        LSS_E_REJECTED,      /* the slave answered with an error code (result.err/spec) */
        LSS_E_CONFLICT,      /* more than one slave answered where exactly one may, or identities disagree */
        LSS_E_NOT_FOUND,     /* the addressed slave or a slave to scan is not there */
        LSS_E_BUS_DOWN,      /* the transport reported the interface down or gone */
        LSS_E_BUS_OFF,       /* the controller went bus-off */
        LSS_E_CANCELLED,
        LSS_E_INVALID,       /* a bad argument */
        LSS_E_VERIFY,        /* the assignment was not confirmed by a boot-up */
        LSS_E_INCOMPLETE,    /* a scan could not finish cleanly (see message) */
        LSS_E_FOREIGN_MASTER, /* another LSS master's request was heard: the operation ended at once */
};

const char *lss_status_name(enum lss_status s);

/* Which service a failure is about (lss_result.failed_service), as a code:
 * callers classify failures by it, never by the message text. */
enum lss_service {
        LSS_SERVICE_NONE = 0,            /* not one service's failure (a scan, a cancel, the transport) */
        LSS_SERVICE_SWITCH_SELECTIVE,    /* Switch State Selective: the addressed slave */
        LSS_SERVICE_CONFIGURE_NODE_ID,
        LSS_SERVICE_CONFIGURE_BIT_TIMING,
        LSS_SERVICE_ACTIVATE_BIT_TIMING, /* the switch to the new rate (SetBitrate's verification) */
        LSS_SERVICE_STORE,               /* Store Configuration */
        LSS_SERVICE_INQUIRE,             /* Inquire Vendor-ID .. Node-ID */
        LSS_SERVICE_FASTSCAN,
        LSS_SERVICE_VERIFY,              /* the check after a change: boot-up, or Inquire Node-ID after a reset */
        _LSS_SERVICE_MAX,
};

/* Why that service failed (lss_result.reason). */
enum lss_reason {
        LSS_REASON_NONE = 0,
        LSS_REASON_NO_ANSWER,            /* nobody answered */
        LSS_REASON_REFUSED,              /* the slave answered with error code result.err (result.spec) */
        LSS_REASON_SEVERAL_ANSWERS,      /* more than one slave answered where one may */
        LSS_REASON_IN_USE,               /* the node-ID already answers on the bus (result.in_use) */
        LSS_REASON_NOT_CONFIRMED,        /* an answer came, but not the one that confirms it */
        LSS_REASON_UNRESOLVED,           /* the answers did not add up to one identity (fastscan) */
        _LSS_REASON_MAX,
};

/* "Configure Node-ID", "Store Configuration", ...; "none" for
 * LSS_SERVICE_NONE, NULL when out of range. */
const char *lss_service_name(enum lss_service s);
/* "no-answer", "refused", ...; NULL when out of range. */
const char *lss_reason_name(enum lss_reason r);
/* CiA 305's meaning of a Store Configuration error code. */
const char *lss_store_error_name(uint8_t err);

typedef struct lss_timing_config {
        uint32_t timeout_us;        /* fixed no-answer wait; also the adaptive start value */
        bool adaptive;              /* derive the wait from measured answer latency */
        uint32_t floor_us;          /* adaptive: never wait less than this */
        uint32_t factor_pct;        /* adaptive: wait = factor * worst latency seen (150 = 1.5x) */
        uint32_t bit_factor_pct;    /* the same for fastscan bit steps, where silence is an
                                     * answer (0: factor_pct; never above it) */
        uint32_t guard_floor_us;    /* minimum answer guard and late guard */
        uint32_t bootup_timeout_us; /* wait for the boot-up that verifies an assignment */
        uint32_t bitrate;           /* bit/s of the bus, 0 = unknown (frame times then count as 0) */
        unsigned retries;           /* attempts per step / per fastscan field before giving up */
} lss_timing_config;

void lss_timing_config_default(lss_timing_config *c);

/* Known fields for fastscan: a field with its bit set in `known_mask` is
 * confirmed directly (bitcheck 0) instead of being scanned bit by bit;
 * `known_bits` gives, per field, how many of its top bits are known (0..32)
 * when the field is not fully known (the rest is scanned). */
typedef struct lss_fastscan_known {
        lss_identity value;
        uint8_t known_bits[LSS_FIELD_COUNT]; /* 32 = fully known */
} lss_fastscan_known;

/* Ranges for identify remote slaves / slowscan (inclusive). */
typedef struct lss_identify_range {
        uint32_t vendor, product;
        uint32_t rev_lo, rev_hi, serial_lo, serial_hi;
} lss_identify_range;

typedef struct lss_device {
        lss_identity id;
        uint8_t node_id;     /* 0xFF non-configured */
        /* enumeration: the volatile node-ID it was set aside with while the
         * pass went on (then given back 255 and reset); 0 = not touched */
        uint8_t aside_node_id;
} lss_device;

/* A node-ID the SDO identity discovery got an answer from or heard
 * (lss_master_sdo_discover). */
enum lss_sdo_source {
        LSS_SDO_FROM_SDO = 1u << 0,   /* answered an upload of 1018h (a value or an abort) */
        LSS_SDO_FROM_HEARD = 1u << 1, /* a boot-up, heartbeat or an SDO answer to another client */
};

typedef struct lss_sdo_node {
        uint8_t node_id;
        uint8_t known;        /* bit LSS_FIELD_x: field x read from 1018h sub-index x + 1 (id) */
        uint8_t aborted;      /* bit LSS_FIELD_x: its upload was aborted (abort_code: the first abort) */
        uint8_t source;       /* LSS_SDO_FROM_* */
        /* two different answers to one request: more than one device has
         * this node-ID; `known` keeps only the fields all answers agree on */
        bool conflict;
        uint8_t nmt_state;    /* last boot-up (0x00) or heartbeat state heard (0x04 stopped,
                               * 0x05 operational, 0x7F pre-operational); 0xFF: none */
        uint32_t abort_code;
        lss_identity id;
} lss_sdo_node;

typedef struct lss_result {
        enum lss_status status;
        uint8_t err, spec;   /* LSS_E_REJECTED: the slave's error and manufacturer code */
        bool found;          /* identify services, selective switch */
        uint32_t value;      /* inquire */
        uint8_t node_id;     /* inquire node-ID; assign: old node-ID */
        bool changed;        /* assign: something was configured (dry: would be) */
        bool dry;            /* assign: LSS_ASSIGN_DRY_RUN, nothing was configured */
        bool in_use;         /* assign: the node-ID already answers on the bus */
        bool not_stored;     /* assign: configured and verified, but the slave cannot store
                              * (Store Configuration error 1 or 2 in err): volatile until a power cycle */
        /* assign, no boot-up at the new node-ID (docs/engine.md, "A node-ID
         * configured is the device's"): */
        bool pending_reset;  /* LSS_OK: the device answers Inquire Node-ID with it, and takes
                              * it at its next reset (a slave such as Lely's) */
        bool may_hold;       /* a failure after Configure Node-ID was answered: the device may
                              * hold the new node-ID, which no other device may be given */
        bool given_back;     /* a failure: the device was given its old node-ID back
                              * (configured, stored when asked, read back) */
        bool stored;         /* unassign: Store Configuration of 255 answered with success */
        bool in_effect;      /* unassign: the slave was seen running non-configured (Inquire Node-ID 255) */
        lss_identity id;     /* fastscan, inquire identity */
        lss_device *devices; /* scans: every slave found (owned by the engine until next start) */
        size_t n_devices;
        /* a failure: which service, why (codes; the message says it for people) */
        enum lss_service failed_service;
        enum lss_reason reason;
        /* SDO identity discovery: every node-ID that answered or was heard,
         * ascending (owned by the engine until the next start) */
        lss_sdo_node *sdo_nodes;
        size_t n_sdo_nodes;
        char message[400];   /* human-readable detail for errors */
} lss_result;

typedef struct lss_master_stats {
        uint64_t steps, retries, timeouts, late_answers, ignored_frames, stale_frames, conflicts;
        uint64_t stray_answers;                  /* LSS answers that came after their step had ended */
        uint64_t rechecks;                       /* enumeration rounds asked again with patient waits
                                                    before a verdict on a slave (lss_enumerate.c) */
        uint32_t patience_us;                    /* the operation's longest wait beyond the configured
                                                    timeout that late answers called for (0: none) */
        uint32_t latency_min_us, latency_max_us; /* recent answer latency window */
        uint32_t timeout_us;                     /* the no-answer wait in force now */
        uint32_t patient_wait_us;                /* AutoAssign looked again for mapped devices it had
                                                    not found, with this wait (0: no second look) */
        uint64_t foreign_requests;               /* LSS requests of another master heard (lss_master_on_frame) */
} lss_master_stats;

/* Progress callback (0..1) for the long operations; optional. */
typedef void (*lss_progress_fn)(void *userdata, double progress);

typedef struct lss_master lss_master;

lss_master *lss_master_new(const lss_timing_config *cfg);
void lss_master_free(lss_master *m);
void lss_master_set_timing(lss_master *m, const lss_timing_config *cfg);
void lss_master_set_progress(lss_master *m, lss_progress_fn fn, void *userdata);
/* Whether the caller knows another device answers to node_id (heard on the
 * bus, a known device): `id` is the slave about to be given it (NULL when
 * not known, the raw Configure Node-ID), so that what was heard from that
 * very slave does not count against it. */
typedef bool (*lss_taken_fn)(void *userdata, uint8_t node_id, const lss_identity *id);
/* An assignment with LSS_ASSIGN_CHECK_FREE and a checked Configure Node-ID
 * refuse a node-ID `fn` says is taken before they probe; NULL: none. */
void lss_master_set_taken_check(lss_master *m, lss_taken_fn fn, void *userdata);
/* A device a scan found, the moment it is confirmed: enumeration once its
 * identity was read back from exactly one slave (Inquire Identity, or a
 * selective switch) and its node-ID asked; slowscan once it answered the
 * selective switch and its node-ID inquiry. Never for a made-up candidate
 * nobody confirms. Called at most once per identity per operation (a pass
 * that is run again does not repeat it), also in the enumerations and
 * slowscans of AutoAssign. `d->node_id` is what the result will say (255 for
 * a slave set aside: it gets 255 back), but for a slave kept in configuration
 * beside others, which cannot be asked its node-ID there: 255, as CiA 305
 * has only non-configured slaves answer Fastscan (one that answers it with a
 * node-ID, such as Lely's, has that in the result); the result can still leave out a
 * device announced here when it fails the final verification (e.g. it left
 * the bus). Called from inside lss_master_on_frame/on_time/start: do not
 * start or cancel operations from it. */
typedef void (*lss_found_fn)(void *userdata, const lss_device *d);
void lss_master_set_found(lss_master *m, lss_found_fn fn, void *userdata);
/* How many slaves an enumeration (Scan, AutoAssign) will likely find, e.g.
 * the non-configured devices seen last time: its progress is measured
 * against it (0, or more found: twice as many as found so far). */
void lss_master_set_expected_finds(lss_master *m, unsigned n);

/* ---- raw services (each one operation) ---- */
int lss_master_switch_global(lss_master *m, enum lss_mode mode, uint64_t now);
int lss_master_switch_selective(lss_master *m, const lss_identity *id, uint64_t now);
int lss_master_configure_node_id(lss_master *m, uint8_t node_id, uint64_t now);
/* The same, but never giving a node-ID a device answers to: first the slave
 * in configuration state is asked its serial (different answers: several
 * slaves would all take the node-ID, LSS_E_CONFLICT) and node-ID (already
 * the one asked for: configured again, nothing else), then node-IDs known
 * taken (lss_master_set_taken_check) and the SDO probe refuse it with
 * LSS_E_CONFLICT and result.in_use. 255 (unconfigure) is never checked. */
int lss_master_configure_node_id_checked(lss_master *m, uint8_t node_id, uint64_t now);
int lss_master_configure_bit_timing(lss_master *m, uint8_t table, uint8_t index, uint64_t now);
int lss_master_activate_bit_timing(lss_master *m, uint16_t delay_ms, uint64_t now);
int lss_master_store(lss_master *m, uint64_t now);
/* field LSS_FIELD_VENDOR..SERIAL, or LSS_FIELD_COUNT for the node-ID */
int lss_master_inquire(lss_master *m, unsigned field, uint64_t now);
/* all four fields of the slave in configuration, each answer checked */
int lss_master_inquire_identity(lss_master *m, uint64_t now);
int lss_master_identify_remote(lss_master *m, const lss_identify_range *r, uint64_t now);
int lss_master_identify_non_configured(lss_master *m, uint64_t now);
/* one slave found by fastscan is left in configuration state (result.id) */
int lss_master_fastscan(lss_master *m, const lss_fastscan_known *known, uint64_t now);
/* NMT command (unconfirmed) */
int lss_master_nmt(lss_master *m, enum nmt_cs cs, uint8_t node_id, uint64_t now);

/* ---- procedures ---- */
/* Every non-configured slave by fastscan, nothing assigned; all back in
 * waiting (lss_enumerate.c). Each slave found stays in configuration state,
 * where a CiA 305 slave takes no part in Fastscan, confirmed by inquiry (by
 * Identify Remote Slave of its identity while others are kept there too);
 * only one that answers Fastscan in configuration state (CANopenNode's:
 * one request only it could match tells) is set aside before the next round
 * with a volatile pending node-ID from the top of the range that no device
 * answers to, and at the end, also on failure or cancel, gets 255 back and
 * NMT Reset Communication (result devices[].aside_node_id). Every slave
 * found is verified by selective switch and Inquire Node-ID at the end. The pass ends when
 * more rounds found nobody new than found a slave (plus a margin), or
 * at its deadline (lss_enumerate_deadline_us), and a slave that answers for
 * identities not its own (found twice, or confirming another identity) ends
 * it with LSS_E_CONFLICT naming it (result.id). */
int lss_master_enumerate(lss_master *m, const lss_fastscan_known *known, uint64_t now);
/* The same after the caller stopped every device (NMT) for slaves that take
 * LSS only when stopped: those set aside are stopped again after taking
 * their temporary node-ID and, all together, after the give-back. */
int lss_master_enumerate_stopped(lss_master *m, const lss_fastscan_known *known, uint64_t now);
#define LSS_ENUMERATE_MAX_FINDS 127u
/* The enumeration's deadline for this timing, from its start. */
uint64_t lss_enumerate_deadline_us(const lss_timing_config *c);
/* Every slave (configured or not) in the ranges by identify-remote bisection,
 * each verified by selective switch and asked its node-ID; all back in waiting. */
int lss_master_slowscan(lss_master *m, const lss_identify_range *r, uint64_t now);

/* Confirms identities learnt another way (SDO discovery) through LSS
 * (lss_confirm.c): for each, everybody to waiting, selective switch and
 * Inquire Node-ID, each asked again while nobody answers. result.devices:
 * those that answered, with the node-ID they answered (announced as found);
 * an identity nobody answers is left out, not a failure. All back in
 * waiting. `ids` is copied. */
int lss_master_confirm(lss_master *m, const lss_identity *ids, size_t n, uint64_t now);

enum lss_assign_flags {
        LSS_ASSIGN_STORE = 1u << 0,  /* Store Configuration after configuring */
        LSS_ASSIGN_VERIFY = 1u << 1, /* wait for the boot-up at the new node-ID */
        /* refuse a node-ID known taken (lss_master_set_taken_check), then ask
         * the bus whether a device already answers to it (SDO upload of
         * 0x1000); if one does: LSS_E_CONFLICT, result.in_use */
        LSS_ASSIGN_CHECK_FREE = 1u << 2,
        /* everything up to the check that the node-ID is free, then back to
         * waiting: result.changed says whether it would configure */
        LSS_ASSIGN_DRY_RUN = 1u << 3,
};
/* Give the slave with this identity a node-ID: selective switch, inquire the
 * node-ID (nothing is sent if it already has it), configure, store, back to
 * waiting, verify by boot-up (NMT Reset Communication for a configured slave). */
int lss_master_assign(lss_master *m, const lss_identity *id, uint8_t node_id, unsigned flags, uint64_t now);
/* Find one non-configured slave by fastscan, check it by inquiry, give it a
 * node-ID as lss_master_assign() does. result.id tells which slave it was. */
int lss_master_fastscan_assign(lss_master *m, const lss_fastscan_known *known, uint8_t node_id, unsigned flags,
                               uint64_t now);

enum lss_unassign_flags {
        LSS_UNASSIGN_STORE = 1u << 0, /* Store Configuration after configuring 255 */
        /* NMT Reset Communication at the old node-ID, then selective switch
         * and Inquire Node-ID until the slave answers 255 (within the
         * boot-up timeout; else LSS_E_VERIFY) */
        LSS_UNASSIGN_RESET = 1u << 1,
};
/* Make the slave with this identity non-configured: selective switch,
 * inquire the node-ID (result.node_id: the old one), Configure Node-ID 255,
 * Store Configuration, back to waiting. CiA 305: a configured slave keeps
 * answering to its old node-ID until NMT Reset Communication (or a reset or
 * power cycle); with LSS_UNASSIGN_RESET the engine sends it and checks the
 * slave comes back at 255. result.in_effect: the slave was seen at 255 (it
 * was non-configured already, or after the reset); result.stored: the store
 * succeeded; result.not_stored: the slave cannot store (error 1 or 2 in err:
 * it gets its old node-ID back at the next power cycle; not a failure). */
int lss_master_unassign(lss_master *m, const lss_identity *id, unsigned flags, uint64_t now);

/* ---- SDO identity discovery (lss_sdo_discover.c) ---- */

#define LSS_SDO_WINDOW_DEFAULT 16u
#define LSS_SDO_WINDOW_MAX 16u
typedef struct lss_sdo_discover_params {
        uint8_t first, last;  /* node-IDs to ask, 1..127, first <= last */
        unsigned window;      /* node-IDs asked at once, 1..LSS_SDO_WINDOW_MAX; 0: the default */
} lss_sdo_discover_params;
/* Learns the identity of every device at a node-ID in [first, last] by
 * expedited SDO upload of 1018h sub-indexes 1..4 (vendor, product,
 * revision, serial), up to `window` node-IDs in flight at once (one request
 * per node-ID: an SDO server serves one transfer at a time); a silent
 * request is sent once more. Boot-ups, heartbeats and SDO answers to other
 * clients heard meanwhile are recorded too, at any node-ID. Writes no
 * object, sends no NMT command: a device in NMT Stopped is not found (unless
 * its heartbeat is heard). result.sdo_nodes lists what answered or was
 * heard; status LSS_OK but for a bad argument, out of memory or cancel.
 * The rules are in docs/engine.md. */
int lss_master_sdo_discover(lss_master *m, const lss_sdo_discover_params *p, uint64_t now);

/* ---- changing the bit rate of the whole network (lss_bitrate.c) ---- */

enum lss_bitrate_outcome {
        LSS_BITRATE_PENDING = 0,    /* not got to (an earlier device stopped the procedure) */
        LSS_BITRATE_REACHED,        /* answered the selective switch at the old rate */
        LSS_BITRATE_UNREACHABLE,    /* no answer to the selective switch: nothing was changed */
        LSS_BITRATE_REFUSED,        /* Configure Bit Timing answered with an error (err, spec) */
        LSS_BITRATE_SILENT,         /* no answer to Configure Bit Timing: a refusal, never a success */
        LSS_BITRATE_CONFIGURED,     /* accepted Configure Bit Timing (not activated) */
        LSS_BITRATE_REVERTED,       /* had accepted, was configured back to the old rate after a refusal */
        LSS_BITRATE_SWITCHED,       /* answers at the new rate */
        LSS_BITRATE_STORED,         /* answers at the new rate, timing stored */
        LSS_BITRATE_STORE_FAILED,   /* answers at the new rate, Store Configuration refused/unanswered */
        LSS_BITRATE_LOST,           /* silent at the new rate (missed the activation?) */
};

const char *lss_bitrate_outcome_name(enum lss_bitrate_outcome o);

/* One device of the network; the engine writes outcome/err/spec in place. */
typedef struct lss_bitrate_device {
        lss_identity id;
        enum lss_bitrate_outcome outcome;
        uint8_t err, spec;          /* REFUSED, STORE_FAILED: the slave's codes */
        /* global only: the device does not take a selective switch (found by
         * SDO alone), so it is checked at the new rate by an SDO upload at
         * node_id instead, and not stored */
        bool no_select;
        uint8_t node_id;
} lss_bitrate_device;

typedef struct lss_bitrate_params {
        uint32_t bitrate;           /* new rate, a table-0 rate (100000 is index 5) */
        uint32_t old_bitrate;       /* rate now (to configure devices back after a refusal; 0 = unknown) */
        uint16_t delay_ms;          /* switch delay of Activate Bit Timing, 1.. */
        bool store;                 /* Store Configuration in every switched device */
        lss_bitrate_device *devices; /* the caller's; must live until the operation is done */
        size_t n_devices;
        /* CiA 305's global procedure instead of steps 1 and 2 below (for
         * devices that cannot be selected one by one; lss_bitrate_global.c):
         * Switch State Global configuration, Configure Bit Timing to all at
         * once, every answer counted (lss_master_bitrate_answers); any
         * refusal, or no answer at all, activates nothing (all are
         * configured back to old_bitrate). Asked again while fewer answer
         * than n_devices (identical answers can merge into one frame on a
         * real bus, so fewer is no refusal). Who did not hear it, or does
         * not answer at all, cannot be told before the activation: step 4
         * finds it (LOST). */
        bool global;
} lss_bitrate_params;

/* The host interface retune the engine asks its caller for, between the
 * activation and the verification. */
enum lss_retune {
        LSS_RETUNE_NONE = 0,        /* not asked (yet) */
        LSS_RETUNE_WANTED,          /* asked, waiting for lss_master_retune_done() */
        LSS_RETUNE_DONE,            /* the interface runs at the new rate */
        LSS_RETUNE_SKIPPED,         /* nothing to retune (virtual interface: no bit timing) */
        LSS_RETUNE_FAILED,          /* the interface could not be retuned */
        LSS_RETUNE_TIMEOUT,         /* the caller never answered */
};

const char *lss_retune_name(enum lss_retune r);

/* The whole network to a new bit rate:
 *   1. every device answers a selective switch (else LSS_E_NOT_FOUND, nothing changed);
 *   2. each in turn: selective switch, Configure Bit Timing (table 0); the first
 *      refusal or silence stops it (LSS_E_REJECTED), the devices that had
 *      accepted are configured back to old_bitrate, nothing is activated;
 *   3. switch global configuration, Activate Bit Timing (delay), silence; the
 *      caller retunes the host interface when lss_master_retune_wanted() says
 *      so and reports with lss_master_retune_done(); silence until 2 x delay;
 *   4. switch global waiting, each device verified by selective switch and
 *      Inquire Node-ID at the new rate (and stored when asked). A device
 *      silent at the new rate makes the result LSS_E_INCOMPLETE (a partial
 *      switch), a refused store LSS_E_REJECTED. Ends with every slave in
 *      waiting. Outcomes are written into p->devices. A no_select device
 *      (global only) is checked by SDO upload of 1000h at its node-ID. */
int lss_master_set_bitrate(lss_master *m, const lss_bitrate_params *p, uint64_t now);
/* True while the engine waits for the host interface to be retuned: to
 * `*bitrate`, best before `*deadline` (end of the first delay period). */
bool lss_master_retune_wanted(const lss_master *m, uint32_t *bitrate, uint64_t *deadline);
/* Called once when the engine starts waiting for the retune (from inside
 * lss_master_on_time/on_frame: retune later, from the caller's own loop). */
typedef void (*lss_retune_fn)(void *userdata);
void lss_master_set_retune(lss_master *m, lss_retune_fn fn, void *userdata);
/* The caller's answer: LSS_RETUNE_DONE, _SKIPPED or _FAILED. */
void lss_master_retune_done(lss_master *m, enum lss_retune how, uint64_t now);
/* What happened to the host retune in the last bit-rate change. */
enum lss_retune lss_master_retune_state(const lss_master *m);
/* From the activation until the window is over: the bus is split if the
 * operation stops now, so callers do not cancel it. */
bool lss_master_bitrate_committed(const lss_master *m);
/* Global procedure: the most answers to one Configure Bit Timing (a lower
 * bound of the devices that took it). */
unsigned lss_master_bitrate_answers(const lss_master *m);

/* ---- another LSS master ---- */
/* LSS answers carry no request identifier: with a second master on the bus
 * (a PLC's CiA 302 boot-up, a commissioning tool) each takes the other's
 * answers for its own, and its Configure Node-ID reaches the slaves this
 * engine selected. So a request of another master fed to
 * lss_master_on_frame() (lss_is_foreign_request(): only frames we did not
 * send are fed) ends the running operation at once, LSS_E_FOREIGN_MASTER:
 * nothing more goes out (frames not yet handed out are dropped) but, for a
 * procedure, one switch to waiting, so that no slave it selected stays in
 * configuration where the other master's Configure Node-ID would reach it.
 * No Configure Node-ID, Configure Bit Timing, Activate or Store follows:
 * slaves set aside keep their temporary node-ID (lss_master_left_aside()),
 * a slave whose assignment had sent Configure Node-ID may hold it
 * (result.may_hold; AutoAssign: a failed outcome with kept_node_id), a
 * bit-rate change before its activation leaves the devices that accepted
 * Configure Bit Timing with that rate pending (not configured back). The one
 * exception: a bit-rate change in its committed window
 * (lss_master_bitrate_committed()) is past the point of no return: the
 * devices switch after the delay whatever the master does, and cut off then
 * the bus stays split. It keeps to the window (silence, the host retune)
 * and then ends with LSS_E_FOREIGN_MASTER: a switch to waiting at the new
 * rate, no verification, no Store. */
/* Slaves the operation that ended with LSS_E_FOREIGN_MASTER left with the
 * volatile node-ID an enumeration set them aside with (aside_node_id; their
 * give-back is at the enumeration's end, which it did not reach). Until the
 * next start. */
const lss_device *lss_master_left_aside(const lss_master *m, size_t *n);
/* Gives those back (a procedure): each, by selective switch, Configure
 * Node-ID 255 and NMT Reset Communication on its temporary node-ID, is
 * verified by selective switch and Inquire Node-ID as at an enumeration's
 * end. result.devices: those verified back (node_id as inquired); one that
 * kept its temporary node-ID makes it LSS_E_INCOMPLETE. `d` is copied. */
int lss_master_give_back(lss_master *m, const lss_device *d, size_t n, uint64_t now);

/* ---- driving ---- */
/* A frame received (not our own echo: lss_master_on_tx_confirmed()). An LSS
 * request among them is another master's (above). */
void lss_master_on_frame(lss_master *m, const lss_frame *f, uint64_t rx_us);
void lss_master_on_time(lss_master *m, uint64_t now);
/* The frames handed out were written; `now` is the time taken just before
 * the LAST of them was written (timeouts run from here; frames received
 * earlier are stale: no slave answers before it has the whole request, so
 * this must never be later than that write). */
void lss_master_on_sent(lss_master *m, uint64_t now);
/* The transport hands back our own frames once the controller has sent
 * them (SocketCAN's echo). Then an LSS step drains by order instead of by
 * the estimated wire time: every frame received before the echo of the
 * step's last request is stale, whatever its time stamp, and the wait runs
 * from the echo. */
void lss_master_set_tx_confirm(lss_master *m, bool on);
/* The echo of the last frame handed out arrived, received at `at`. */
void lss_master_on_tx_confirmed(lss_master *m, uint64_t at);
/* The transport lost received frames (SO_RXQ_OVFL): the running step is void. */
void lss_master_on_rx_lost(lss_master *m, uint64_t now);
/* The transport failed: ends the operation with LSS_E_BUS_DOWN or LSS_E_BUS_OFF. */
void lss_master_on_bus_error(lss_master *m, enum lss_status status, const char *why, uint64_t now);
/* Stop the running operation; slaves are switched back to waiting, the
 * result is LSS_E_CANCELLED. */
void lss_master_cancel(lss_master *m, uint64_t now);

bool lss_master_next_tx(lss_master *m, lss_frame *f);
uint64_t lss_master_deadline(const lss_master *m); /* UINT64_MAX: none */
bool lss_master_busy(const lss_master *m);
bool lss_master_done(const lss_master *m);          /* an operation finished and its result is there */
const lss_result *lss_master_result(const lss_master *m);
const lss_master_stats *lss_master_get_stats(const lss_master *m);
