/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The CiA 305 LSS slave model (plus the CiA 301 a master meets: NMT states,
 * boot-up, heartbeat, an SDO server for 1000h, 1017h and 1018h). Sans-I/O:
 * frames and time come in, answers go out through the emit callback. */
#include "sim/lss_slave.h"
#include "sim/sim_random.h"

#include <string.h>

#define NO_DEADLINE UINT64_MAX
#define FASTSCAN_MAX_BIT 31u
#define BIT_TIMING_TABLE_MAX 8u /* table 0 index 9 (auto) is not supported */

void lss_slave_faults_default(lss_slave_faults *f) {
        memset(f, 0, sizeof(*f));
        f->ignore_cs = -1;
        f->early_config = SLAVE_EARLY_NONE;
}

void lss_slave_faults_canopennode(lss_slave_faults *f) {
        lss_slave_faults_default(f);
        f->no_identify = true;
        f->canopennode_lss = true;
        f->bit_timing_silent = true;
}

void lss_slave_faults_lely(lss_slave_faults *f) {
        lss_slave_faults_default(f);
        f->lely_lss = true;
        /* without a bit-rate hook lely answers every Configure Bit Timing
         * with error 1 and ignores Activate Bit Timing */
        f->bit_index_unsupported = UINT32_MAX;
        f->miss_activation = true;
}

/* Fastscan's position on entering waiting: none until a ping; lely's
 * starts at the vendor. */
static int fastscan_start(const lss_slave *s) {
        return s->faults.lely_lss ? LSS_FIELD_VENDOR : -1;
}

void lss_slave_init(lss_slave *s, const lss_identity *id, uint8_t node_id, uint8_t bit_index,
                    const lss_slave_faults *faults, uint64_t seed, lss_slave_emit_fn emit, void *userdata) {
        memset(s, 0, sizeof(*s));
        s->id = *id;
        if (faults)
                s->faults = *faults;
        else
                lss_slave_faults_default(&s->faults);
        s->st.active_node_id = s->st.pending_node_id = s->st.stored_node_id = node_id;
        s->st.bit_index = s->st.pending_bit_index = s->st.stored_bit_index = bit_index;
        s->st.configuration = false;
        s->st.nmt = SLAVE_NMT_PRE_OPERATIONAL;
        s->fs_sub = fastscan_start(s);
        s->switch_at_us = NO_DEADLINE;
        s->rng = seed;
        s->emit = emit;
        s->userdata = userdata;
        lss_slave_set_heartbeat(s, s->faults.heartbeat_ms);
}

void lss_slave_set_heartbeat(lss_slave *s, uint16_t period_ms) {
        s->faults.heartbeat_ms = period_ms;
        s->heartbeat_at_us = period_ms ? s->now_us + (uint64_t) period_ms * 1000 : NO_DEADLINE;
}

static bool state_equal(const lss_slave_state *a, const lss_slave_state *b) {
        return a->active_node_id == b->active_node_id &&
                a->pending_node_id == b->pending_node_id &&
                a->stored_node_id == b->stored_node_id &&
                a->bit_index == b->bit_index &&
                a->pending_bit_index == b->pending_bit_index &&
                a->stored_bit_index == b->stored_bit_index &&
                a->configuration == b->configuration &&
                a->nmt == b->nmt;
}

/* Delay of the next frame: latency + jitter, never ahead of a frame the
 * slave already queued (one transmit queue, sent in order). */
static uint64_t tx_delay(lss_slave *s) {
        uint64_t d = s->faults.latency_us;
        if (s->faults.jitter_us > 0)
                d += sim_random_next(&s->rng) % ((uint64_t) s->faults.jitter_us + 1);
        if (s->faults.spike_ppm > 0 && sim_random_next(&s->rng) % 1000000 < s->faults.spike_ppm)
                d += s->faults.spike_us;
        uint64_t at = s->now_us + d;
        if (at < s->tx_ready_us)
                at = s->tx_ready_us;
        s->tx_ready_us = at;
        return at - s->now_us;
}

/* tx_loss_ppm: the frame never leaves the slave */
static bool tx_lost(lss_slave *s) {
        return s->faults.tx_loss_ppm > 0 && sim_random_next(&s->rng) % 1000000 < s->faults.tx_loss_ppm;
}

static void send_frame(lss_slave *s, const lss_frame *f) {
        if (s->emit && !tx_lost(s))
                s->emit(s->userdata, f, tx_delay(s));
}

/* An LSS answer, subject to the answer faults (boot-ups are not). */
static void answer(lss_slave *s, const lss_frame *f) {
        if (s->faults.silent || !s->emit || tx_lost(s))
                return;
        lss_frame a = *f;
        if (s->faults.wrong_dlc)
                a.len = 7;
        uint64_t d = tx_delay(s);
        s->emit(s->userdata, &a, d);
        if (s->faults.duplicate_answers)
                s->emit(s->userdata, &a, d);
}

static void answer_cs(lss_slave *s, uint8_t cs, uint8_t b1, uint8_t b2) {
        lss_frame f;
        lss_frame_response(&f, cs);
        f.data[1] = b1;
        f.data[2] = b2;
        answer(s, &f);
}

static void answer_u32(lss_slave *s, uint8_t cs, uint32_t v) {
        lss_frame f;
        lss_frame_response(&f, cs);
        lss_put_u32(f.data + 1, v);
        answer(s, &f);
}

static bool in_window(const lss_slave *s, uint64_t now_us) {
        return now_us >= s->activate_at_us && now_us < s->silent_until_us;
}

/* NMT state as heartbeats carry it (CiA 301) */
static uint8_t nmt_state_byte(enum lss_slave_nmt nmt) {
        switch (nmt) {
        case SLAVE_NMT_OPERATIONAL: return 0x05;
        case SLAVE_NMT_STOPPED: return 0x04;
        default: return 0x7F;
        }
}

/* The heartbeat producer: 0x700 + node-ID, the NMT state, every period
 * (also in Stopped; not without a node-ID, nor while retuning). One that
 * is overdue goes out once, the next one a period later. */
static void heartbeat(lss_slave *s) {
        if (s->heartbeat_at_us == NO_DEADLINE || s->now_us < s->heartbeat_at_us)
                return;
        uint64_t period = (uint64_t) s->faults.heartbeat_ms * 1000;
        s->heartbeat_at_us += period;
        if (s->heartbeat_at_us <= s->now_us)
                s->heartbeat_at_us = s->now_us + period;
        if (!lss_node_id_valid(s->st.active_node_id) || in_window(s, s->now_us))
                return;
        lss_frame f = { .id = BOOTUP_COB_BASE + s->st.active_node_id, .len = 1,
                        .data = { nmt_state_byte(s->st.nmt) } };
        send_frame(s, &f);
}

/* The switch of Activate Bit Timing, once its first delay has passed; the
 * heartbeat when it is due. */
static void process_time(lss_slave *s) {
        if (s->switch_at_us != NO_DEADLINE && s->now_us >= s->switch_at_us) {
                s->st.bit_index = s->st.pending_bit_index;
                s->switch_at_us = NO_DEADLINE;
        }
        heartbeat(s);
}

static void reset_protocol_progress(lss_slave *s) {
        s->fs_sub = fastscan_start(s);
        s->ident_step = 0;
        s->ident_match = false;
        s->sel_step = 0;
}

/* NMT Reset Communication: the pending node-ID becomes active, LSS is back
 * in waiting, the node announces itself when it has an ID. */
static void reset_communication(lss_slave *s) {
        s->st.active_node_id = s->st.pending_node_id;
        s->st.configuration = false;
        s->st.nmt = SLAVE_NMT_PRE_OPERATIONAL;
        reset_protocol_progress(s);
        if (lss_node_id_valid(s->st.active_node_id)) {
                lss_frame f;
                bootup_encode(&f, s->st.active_node_id);
                send_frame(s, &f);
        }
        /* the heartbeat starts over after the boot-up */
        lss_slave_set_heartbeat(s, s->faults.heartbeat_ms);
}

/* Power-on: everything comes back from storage. */
static void load_stored(lss_slave *s) {
        s->st.pending_node_id = s->st.stored_node_id;
        s->st.bit_index = s->st.pending_bit_index = s->st.stored_bit_index;
        s->switch_at_us = NO_DEADLINE;
        s->activate_at_us = s->silent_until_us = 0;
}

/* NMT Reset Node reloads the stored values too; lely's reloads its object
 * dictionary but keeps the pending node-ID, which the reset of
 * communication then makes active. */
static void reset_node(lss_slave *s) {
        if (!s->faults.lely_lss)
                load_stored(s);
        reset_communication(s);
}

/* lely keeps a device without a node-ID in NMT initialisation (its boot-up
 * state waits for one); a device with one is past it. */
static bool lely_initialising(const lss_slave *s) {
        return s->faults.lely_lss && s->st.active_node_id == LSS_NODE_ID_UNCONFIGURED;
}

static void enter_configuration(lss_slave *s) {
        s->st.configuration = true;
        s->fs_sub = -1;
        s->sel_step = 0;
}

static void switch_global(lss_slave *s, uint8_t mode) {
        if (mode == LSS_MODE_CONFIGURATION) {
                enter_configuration(s);
                return;
        }
        if (mode != LSS_MODE_WAITING)
                return;
        bool was_configuring = s->st.configuration;
        s->st.configuration = false;
        s->sel_step = 0;
        /* lely enters waiting anew, also from waiting */
        if (s->faults.lely_lss)
                reset_protocol_progress(s);
        /* a node that had no ID and just got one starts using it at once
         * (lely's waits for an NMT reset) */
        if (was_configuring && !s->faults.lely_lss && s->st.active_node_id == LSS_NODE_ID_UNCONFIGURED &&
            lss_node_id_valid(s->st.pending_node_id))
                reset_communication(s);
}

/* lely keeps one expected command specifier for the selective switch and
 * identify remote slave: a frame of one breaks a sequence of the other. */
static void lely_forget_identify(lss_slave *s) {
        if (s->faults.lely_lss) {
                s->ident_step = 0;
                s->ident_match = false;
        }
}

static void switch_selective(lss_slave *s, unsigned field, uint32_t value) {
        lely_forget_identify(s);
        bool hit = value == lss_identity_field(&s->id, field);
        if (field == LSS_FIELD_VENDOR) {
                s->sel_step = hit ? 1 : 0;
                return;
        }
        if (!hit || s->sel_step != field) {
                s->sel_step = 0;
                return;
        }
        if (field < LSS_FIELD_SERIAL) {
                s->sel_step = field + 1;
                return;
        }
        enter_configuration(s);
        answer_cs(s, LSS_CS_SWITCH_SEL_RESPONSE, 0, 0);
}

static void identify_remote(lss_slave *s, unsigned step, uint32_t value) {
        if (s->faults.lely_lss)
                s->sel_step = 0; /* see lely_forget_identify() */
        if (step == 0) {
                s->ident_step = 1;
                s->ident_match = value == s->id.vendor;
                return;
        }
        if (s->ident_step != step) {
                s->ident_step = 0;
                s->ident_match = false;
                return;
        }
        bool ok;
        switch (step) {
        case 1: ok = s->id.product == value; break;
        case 2: ok = s->faults.identify_strict_rev ? s->id.revision > value : s->id.revision >= value; break;
        case 3: ok = s->faults.identify_strict_rev ? s->id.revision < value : s->id.revision <= value; break;
        case 4: ok = s->id.serial >= value; break;
        default: ok = s->id.serial <= value; break;
        }
        s->ident_match = s->ident_match && ok;
        if (step < 5) {
                s->ident_step = step + 1;
                return;
        }
        if (s->ident_match)
                answer_cs(s, LSS_CS_IDENTIFY_SLAVE, 0, 0);
        s->ident_step = 0;
        s->ident_match = false;
}

static bool early_config_after(const lss_slave *s, unsigned sub) {
        return s->faults.early_config != SLAVE_EARLY_NONE && sub == (unsigned) s->faults.early_config - 1;
}

/* Whether a slave in waiting takes part in Fastscan with the node-IDs it
 * has: only without one (CANopenNode: without a pending one either);
 * lely's whatever they are. */
static bool fastscan_takes_part(const lss_slave *s) {
        if (s->faults.lely_lss)
                return true;
        if (s->st.active_node_id != LSS_NODE_ID_UNCONFIGURED && !s->faults.fastscan_when_configured)
                return false;
        return !s->faults.canopennode_lss || s->st.pending_node_id == LSS_NODE_ID_UNCONFIGURED;
}

/* The late_fs fault: this answer, and those queued behind it, late. */
static void late_fastscan_answer(lss_slave *s, uint8_t bitcheck, uint8_t sub) {
        if (s->faults.late_fs_us > 0 && bitcheck == s->faults.late_fs_check && sub == s->faults.late_fs_sub &&
            ++s->late_fs_seen == s->faults.late_fs_nth)
                s->tx_ready_us = s->now_us + tx_delay(s) + s->faults.late_fs_us;
}

static void fastscan(lss_slave *s, const lss_frame *f) {
        uint32_t idnumber = lss_get_u32(f->data + 1);
        uint8_t bitcheck = f->data[5], sub = f->data[6], next = f->data[7];

        if (s->faults.fastscan_any) {
                answer_cs(s, LSS_CS_IDENTIFY_SLAVE, 0, 0);
                if (bitcheck == 0 && next < sub)
                        enter_configuration(s);
                return;
        }
        if (s->st.configuration) {
                if (s->faults.canopennode_lss)
                        answer_cs(s, LSS_CS_IDENTIFY_SLAVE, 0, 0);
                return;
        }
        if (!fastscan_takes_part(s))
                return;
        if (bitcheck > FASTSCAN_MAX_BIT && bitcheck != LSS_FASTSCAN_PING)
                return;
        /* lely answers a ping whatever its lsssub and lssnext, and follows
         * any lssnext: one past the serial matches nothing until a ping */
        if (!s->faults.lely_lss && (sub >= LSS_FIELD_COUNT || next >= LSS_FIELD_COUNT))
                return;
        if (bitcheck == LSS_FASTSCAN_PING) {
                s->fs_sub = LSS_FIELD_VENDOR;
                late_fastscan_answer(s, bitcheck, sub);
                answer_cs(s, LSS_CS_IDENTIFY_SLAVE, 0, 0);
                return;
        }
        if (s->fs_sub != (int) sub || sub >= LSS_FIELD_COUNT)
                return;
        uint32_t mask = UINT32_MAX << bitcheck;
        if ((lss_identity_field(&s->id, sub) ^ idnumber) & mask)
                return;
        /* lssnext going back (to vendor) after the last field: found */
        bool found = bitcheck == 0 && (next < sub || early_config_after(s, sub));
        if (found && s->faults.late_found_us > 0 && !s->late_found_sent) {
                /* the confirmation a master must not take for the next step's answer */
                s->late_found_sent = true;
                s->tx_ready_us = s->now_us + tx_delay(s) + s->faults.late_found_us;
        }
        late_fastscan_answer(s, bitcheck, sub);
        answer_cs(s, LSS_CS_IDENTIFY_SLAVE, 0, 0);
        /* lely moves to lssnext at every step, not at the field's last only */
        if (bitcheck != 0 && !s->faults.lely_lss)
                return;
        s->fs_sub = next;
        if (found)
                enter_configuration(s);
}

static void configure_node_id(lss_slave *s, uint8_t nid) {
        if (s->faults.configure_error_specific) {
                answer_cs(s, LSS_CS_CONFIGURE_NODE_ID, LSS_ERR_SPECIFIC, 0x42);
                return;
        }
        if (!lss_node_id_valid(nid) && nid != LSS_NODE_ID_UNCONFIGURED) {
                answer_cs(s, LSS_CS_CONFIGURE_NODE_ID, LSS_ERR_NODE_ID_OUT_OF_RANGE, 0);
                return;
        }
        s->st.pending_node_id = nid;
        answer_cs(s, LSS_CS_CONFIGURE_NODE_ID, LSS_ERR_OK, 0);
}

static void configure_bit_timing(lss_slave *s, uint8_t table, uint8_t index) {
        if (s->faults.bit_timing_silent)
                return;
        if (table != 0 || index > BIT_TIMING_TABLE_MAX || (s->faults.bit_index_unsupported & (UINT32_C(1) << index))) {
                answer_cs(s, LSS_CS_CONFIGURE_BIT_TIMING, LSS_ERR_BIT_RATE_NOT_SUPPORTED, 0);
                return;
        }
        s->st.pending_bit_index = index;
        answer_cs(s, LSS_CS_CONFIGURE_BIT_TIMING, LSS_ERR_OK, 0);
}

static void activate_bit_timing(lss_slave *s, uint16_t delay_ms) {
        if (s->faults.miss_activation)
                return;
        uint64_t d = (uint64_t) delay_ms * 1000;
        s->activate_at_us = s->now_us;
        s->switch_at_us = s->now_us + d;
        s->silent_until_us = s->now_us + 2 * d;
        process_time(s); /* a zero delay switches at once */
}

static void store(lss_slave *s) {
        if (s->faults.store_unsupported) {
                answer_cs(s, LSS_CS_STORE, LSS_ERR_STORE_NOT_SUPPORTED, 0);
                return;
        }
        if (s->faults.store_fails) {
                answer_cs(s, LSS_CS_STORE, LSS_ERR_STORE_MEDIA, 0);
                return;
        }
        s->st.stored_node_id = s->st.pending_node_id;
        s->st.stored_bit_index = s->st.pending_bit_index;
        answer_cs(s, LSS_CS_STORE, LSS_ERR_OK, 0);
}

/* Services only the slave(s) in configuration state carry out. */
static void configuration_service(lss_slave *s, const lss_frame *f) {
        uint8_t cs = f->data[0];
        switch (cs) {
        case LSS_CS_CONFIGURE_NODE_ID:
                configure_node_id(s, f->data[1]);
                break;
        case LSS_CS_CONFIGURE_BIT_TIMING:
                configure_bit_timing(s, f->data[1], f->data[2]);
                break;
        case LSS_CS_ACTIVATE_BIT_TIMING:
                activate_bit_timing(s, lss_get_u16(f->data + 1));
                break;
        case LSS_CS_STORE:
                store(s);
                break;
        case LSS_CS_INQUIRE_VENDOR:
        case LSS_CS_INQUIRE_PRODUCT:
        case LSS_CS_INQUIRE_REVISION:
        case LSS_CS_INQUIRE_SERIAL:
                answer_u32(s, cs, lss_identity_field(&s->id, cs - LSS_CS_INQUIRE_VENDOR));
                break;
        case LSS_CS_INQUIRE_NODE_ID:
                answer_cs(s, cs, lely_initialising(s) ? s->st.pending_node_id : s->st.active_node_id, 0);
                break;
        default:
                break;
        }
}

/* Who answers Identify Non-Configured Remote Slave: a slave without a
 * node-ID; lely's without a pending one either (and in NMT initialisation,
 * where it is while it has no node-ID). */
static bool non_configured(const lss_slave *s) {
        if (s->st.active_node_id != LSS_NODE_ID_UNCONFIGURED)
                return false;
        return !s->faults.lely_lss || s->st.pending_node_id == LSS_NODE_ID_UNCONFIGURED;
}

static void lss_request(lss_slave *s, const lss_frame *f) {
        uint8_t cs = f->data[0];

        if (s->faults.ignore_cs >= 0 && cs == s->faults.ignore_cs)
                return;
        if (s->faults.needs_nmt_stopped && s->st.nmt != SLAVE_NMT_STOPPED)
                return;

        switch (cs) {
        case LSS_CS_SWITCH_GLOBAL:
                switch_global(s, f->data[1]);
                break;
        case LSS_CS_SWITCH_SEL_VENDOR:
        case LSS_CS_SWITCH_SEL_PRODUCT:
        case LSS_CS_SWITCH_SEL_REVISION:
        case LSS_CS_SWITCH_SEL_SERIAL:
                /* selection is a waiting-state service */
                if (!s->st.configuration)
                        switch_selective(s, cs - LSS_CS_SWITCH_SEL_VENDOR, lss_get_u32(f->data + 1));
                else if (s->faults.canopennode_lss && cs == LSS_CS_SWITCH_SEL_SERIAL)
                        answer_cs(s, LSS_CS_SWITCH_SEL_RESPONSE, 0, 0);
                break;
        case LSS_CS_IDENTIFY_VENDOR:
        case LSS_CS_IDENTIFY_PRODUCT:
        case LSS_CS_IDENTIFY_REV_LOW:
        case LSS_CS_IDENTIFY_REV_HIGH:
        case LSS_CS_IDENTIFY_SERIAL_LOW:
        case LSS_CS_IDENTIFY_SERIAL_HIGH:
                if (!s->faults.no_identify)
                        identify_remote(s, cs - LSS_CS_IDENTIFY_VENDOR, lss_get_u32(f->data + 1));
                break;
        case LSS_CS_IDENTIFY_NON_CONFIGURED:
                if (!s->faults.no_identify && non_configured(s))
                        answer_cs(s, LSS_CS_IDENTIFY_NON_CONFIGURED_SLAVE, 0, 0);
                break;
        case LSS_CS_FASTSCAN:
                fastscan(s, f);
                break;
        default:
                if (s->st.configuration)
                        configuration_service(s, f);
                break;
        }
}

/* Whether an NMT command for `node` is for this slave: node 0 is everyone;
 * lely compares with its own node-ID even when that is 255. */
static bool nmt_addressed(const lss_slave *s, uint8_t node) {
        if (node == 0)
                return true;
        return node == s->st.active_node_id && (lss_node_id_valid(node) || s->faults.lely_lss);
}

static void nmt_command(lss_slave *s, uint8_t cs, uint8_t node) {
        if (!nmt_addressed(s, node))
                return;
        /* lely's boot-up state, where a device without node-ID waits, obeys only the resets */
        if (lely_initialising(s) && cs != NMT_CS_RESET_NODE && cs != NMT_CS_RESET_COMMUNICATION)
                return;
        switch (cs) {
        case NMT_CS_START:
                s->st.nmt = SLAVE_NMT_OPERATIONAL;
                break;
        case NMT_CS_STOP:
                s->st.nmt = SLAVE_NMT_STOPPED;
                break;
        case NMT_CS_PRE_OPERATIONAL:
                s->st.nmt = SLAVE_NMT_PRE_OPERATIONAL;
                break;
        case NMT_CS_RESET_NODE:
                reset_node(s);
                break;
        case NMT_CS_RESET_COMMUNICATION:
                reset_communication(s);
                break;
        default:
                break;
        }
}

static void note_change(lss_slave *s, const lss_slave_state *before) {
        if (!state_equal(before, &s->st))
                s->changes++;
}

void lss_slave_power_on(lss_slave *s, uint64_t now_us) {
        lss_slave_state before = s->st;
        s->now_us = now_us;
        load_stored(s);
        reset_communication(s);
        note_change(s, &before);
}

/* The SDO server every CANopen device has (CiA 301), as far as a master
 * meets it: expedited upload of 1000h (device type), 1017h (heartbeat
 * producer time) and 1018h (identity, sub 0..4, from the LSS address).
 * Everything else is aborted: an object that does not exist, a sub-index
 * that does not exist, a download (the objects are read-only here: lssd
 * never writes), any other command. No SDO in NMT Stopped. */
#define SDO_ABORT_CS 0x05040001u        /* command specifier not valid */
#define SDO_ABORT_READ_ONLY 0x06010002u /* attempt to write a read-only object */
#define SDO_ABORT_NO_OBJECT 0x06020000u /* object does not exist */
#define SDO_ABORT_NO_SUB 0x06090011u    /* sub-index does not exist */
#define SDO_CCS_DOWNLOAD 1u
#define SDO_CCS_UPLOAD 2u
#define SDO_CCS_ABORT 4u

/* 0 and the value and its size, or the abort code */
static uint32_t sdo_read(const lss_slave *s, uint16_t index, uint8_t sub, uint32_t *value, unsigned *size) {
        switch (index) {
        case 0x1000:
                *value = 0x00000192u; /* device profile 402 */
                *size = 4;
                return sub == 0 ? 0 : SDO_ABORT_NO_SUB;
        case 0x1017:
                *value = s->faults.heartbeat_ms;
                *size = 2;
                return sub == 0 ? 0 : SDO_ABORT_NO_SUB;
        case 0x1018:
                if (sub > LSS_FIELD_COUNT)
                        return SDO_ABORT_NO_SUB;
                *value = sub == 0 ? LSS_FIELD_COUNT : lss_identity_field(&s->id, sub - 1);
                *size = sub == 0 ? 1 : 4;
                return 0;
        default:
                return SDO_ABORT_NO_OBJECT;
        }
}

static void sdo_request(lss_slave *s, const lss_frame *f) {
        if (s->st.nmt == SLAVE_NMT_STOPPED || !s->emit)
                return;
        unsigned ccs = f->data[0] >> 5;
        if (ccs == SDO_CCS_ABORT)
                return; /* the client ends a transfer: nothing to answer */
        uint16_t index = lss_get_u16(f->data + 1);
        uint8_t sub = f->data[3];
        uint32_t value = 0, code;
        unsigned size = 0;
        lss_frame a = { .id = 0x580u + s->st.active_node_id, .len = 8 };
        memcpy(a.data + 1, f->data + 1, 3); /* index, sub-index */
        if (ccs == SDO_CCS_UPLOAD)
                code = sdo_read(s, index, sub, &value, &size);
        else if (ccs == SDO_CCS_DOWNLOAD)
                code = sdo_read(s, index, sub, &value, &size) ?: SDO_ABORT_READ_ONLY;
        else
                code = SDO_ABORT_CS;
        if (code == 0) {
                /* expedited, size indicated: 0x43, 0x47, 0x4B, 0x4F for 4..1 bytes */
                a.data[0] = (uint8_t) (0x43u | (4u - size) << 2);
                lss_put_u32(a.data + 4, value);
        } else {
                a.data[0] = 0x80;
                lss_put_u32(a.data + 4, code);
        }
        if (!tx_lost(s))
                s->emit(s->userdata, &a, tx_delay(s));
}

static bool is_sdo_request(const lss_slave *s, const lss_frame *f) {
        return f->flags == 0 && f->len == 8 && lss_node_id_valid(s->st.active_node_id) &&
                f->id == 0x600u + s->st.active_node_id;
}

void lss_slave_on_frame(lss_slave *s, const lss_frame *f, uint64_t now_us) {
        lss_slave_state before = s->st;
        uint8_t cs, node;

        s->now_us = now_us;
        process_time(s);
        bool lost = s->faults.rx_loss_ppm > 0 && sim_random_next(&s->rng) % 1000000 < s->faults.rx_loss_ppm;
        /* inside the activation window the controller is being retuned */
        if (!lost && !in_window(s, now_us)) {
                if (lss_is_request(f))
                        lss_request(s, f);
                else if (nmt_decode(f, &cs, &node))
                        nmt_command(s, cs, node);
                else if (is_sdo_request(s, f))
                        sdo_request(s, f);
        }
        note_change(s, &before);
}

void lss_slave_on_time(lss_slave *s, uint64_t now_us) {
        lss_slave_state before = s->st;
        s->now_us = now_us;
        process_time(s);
        note_change(s, &before);
}

uint64_t lss_slave_deadline(const lss_slave *s) {
        return s->switch_at_us < s->heartbeat_at_us ? s->switch_at_us : s->heartbeat_at_us;
}

bool lss_slave_on_bus(const lss_slave *s, uint8_t bus_bit_index, uint64_t now_us) {
        if (in_window(s, now_us))
                return false;
        /* the switch may be due without on_time() having been called yet */
        uint8_t idx = s->switch_at_us != NO_DEADLINE && now_us >= s->switch_at_us ?
                s->st.pending_bit_index : s->st.bit_index;
        return idx == bus_bit_index;
}
