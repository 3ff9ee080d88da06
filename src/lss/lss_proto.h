/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* CiA 305 LSS wire format: frames, command specifiers, encoders, decoders.
 * Pure functions, no state: both the master engine and the slave model use it. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define LSS_COB_MASTER  0x7E5u  /* master -> slave */
#define LSS_COB_SLAVE   0x7E4u  /* slave -> master */
#define NMT_COB         0x000u
#define BOOTUP_COB_BASE 0x700u  /* NMT error control: 0x700 + node-ID */

#define LSS_NODE_ID_UNCONFIGURED 0xFFu
#define LSS_NODE_ID_MIN 1u
#define LSS_NODE_ID_MAX 127u

/* Frame flags: anything carrying one of these is never an LSS frame. */
#define LSS_FRAME_EFF 0x01u /* 29-bit identifier */
#define LSS_FRAME_RTR 0x02u /* remote request */
#define LSS_FRAME_FD  0x04u /* CAN FD */
#define LSS_FRAME_ERR 0x08u /* error frame reported by the controller */
#define LSS_FRAME_ECHO 0x10u /* our own frame, back from the controller: it is on the wire */

typedef struct lss_frame {
        uint32_t id;     /* identifier without flag bits */
        uint8_t flags;   /* LSS_FRAME_* */
        uint8_t len;     /* DLC, 0..8 */
        uint8_t data[8];
} lss_frame;

typedef struct lss_identity {
        uint32_t vendor, product, revision, serial;
} lss_identity;

enum lss_mode { LSS_MODE_WAITING = 0, LSS_MODE_CONFIGURATION = 1 };

enum lss_field { LSS_FIELD_VENDOR = 0, LSS_FIELD_PRODUCT, LSS_FIELD_REVISION, LSS_FIELD_SERIAL, LSS_FIELD_COUNT };

/* Command specifiers (byte 0). */
enum lss_cs {
        LSS_CS_SWITCH_GLOBAL = 0x04,
        LSS_CS_CONFIGURE_NODE_ID = 0x11,
        LSS_CS_CONFIGURE_BIT_TIMING = 0x13,
        LSS_CS_ACTIVATE_BIT_TIMING = 0x15,
        LSS_CS_STORE = 0x17,
        LSS_CS_SWITCH_SEL_VENDOR = 0x40,
        LSS_CS_SWITCH_SEL_PRODUCT = 0x41,
        LSS_CS_SWITCH_SEL_REVISION = 0x42,
        LSS_CS_SWITCH_SEL_SERIAL = 0x43,
        LSS_CS_SWITCH_SEL_RESPONSE = 0x44,
        LSS_CS_IDENTIFY_VENDOR = 0x46,
        LSS_CS_IDENTIFY_PRODUCT = 0x47,
        LSS_CS_IDENTIFY_REV_LOW = 0x48,
        LSS_CS_IDENTIFY_REV_HIGH = 0x49,
        LSS_CS_IDENTIFY_SERIAL_LOW = 0x4A,
        LSS_CS_IDENTIFY_SERIAL_HIGH = 0x4B,
        LSS_CS_IDENTIFY_NON_CONFIGURED = 0x4C,
        LSS_CS_IDENTIFY_SLAVE = 0x4F,      /* answer to 0x46..0x4B and to fastscan */
        LSS_CS_IDENTIFY_NON_CONFIGURED_SLAVE = 0x50,
        LSS_CS_FASTSCAN = 0x51,
        LSS_CS_INQUIRE_VENDOR = 0x5A,
        LSS_CS_INQUIRE_PRODUCT = 0x5B,
        LSS_CS_INQUIRE_REVISION = 0x5C,
        LSS_CS_INQUIRE_SERIAL = 0x5D,
        LSS_CS_INQUIRE_NODE_ID = 0x5E,
};

#define LSS_FASTSCAN_PING 0x80u /* bitcheck that resets the slaves' fastscan state */

/* NMT command specifiers (frame 0x000, data: cs node). */
enum nmt_cs {
        NMT_CS_START = 0x01,
        NMT_CS_STOP = 0x02,
        NMT_CS_PRE_OPERATIONAL = 0x80,
        NMT_CS_RESET_NODE = 0x81,
        NMT_CS_RESET_COMMUNICATION = 0x82,
};

/* Error codes of confirmed configuration services. */
#define LSS_ERR_OK 0u
#define LSS_ERR_NODE_ID_OUT_OF_RANGE 1u
#define LSS_ERR_BIT_RATE_NOT_SUPPORTED 1u
#define LSS_ERR_STORE_NOT_SUPPORTED 1u
#define LSS_ERR_STORE_MEDIA 2u
#define LSS_ERR_SPECIFIC 255u

/* ---- building frames ---- */
void lss_frame_request(lss_frame *f, uint8_t cs);  /* 0x7E5, DLC 8, all zero but cs */
void lss_frame_response(lss_frame *f, uint8_t cs); /* 0x7E4, DLC 8 */
void lss_put_u32(uint8_t *p, uint32_t v);
uint32_t lss_get_u32(const uint8_t *p);
uint16_t lss_get_u16(const uint8_t *p);

void lss_encode_switch_global(lss_frame *f, enum lss_mode mode);
/* field 0..3 -> cs 0x40..0x43 */
void lss_encode_switch_selective(lss_frame *f, enum lss_field field, uint32_t value);
void lss_encode_configure_node_id(lss_frame *f, uint8_t node_id);
void lss_encode_configure_bit_timing(lss_frame *f, uint8_t table, uint8_t index);
void lss_encode_activate_bit_timing(lss_frame *f, uint16_t delay_ms);
void lss_encode_store(lss_frame *f);
/* field 0..3 -> cs 0x5A..0x5D; LSS_FIELD_COUNT -> 0x5E (node-ID) */
void lss_encode_inquire(lss_frame *f, unsigned field);
/* step 0..5 -> cs 0x46..0x4B */
void lss_encode_identify_remote(lss_frame *f, unsigned step, uint32_t value);
void lss_encode_identify_non_configured(lss_frame *f);
void lss_encode_fastscan(lss_frame *f, uint32_t idnumber, uint8_t bitcheck, uint8_t lsssub, uint8_t lssnext);
void nmt_encode(lss_frame *f, enum nmt_cs cs, uint8_t node_id);
void bootup_encode(lss_frame *f, uint8_t node_id);

/* ---- reading frames ---- */
/* A valid LSS response: standard ID 0x7E4, DLC 8, no EFF/RTR/FD/ERR flag. */
bool lss_is_response(const lss_frame *f);
/* A valid LSS request: standard ID 0x7E5, DLC 8, no flags. */
bool lss_is_request(const lss_frame *f);
/* An LSS request of another master: a standard data frame at 0x7E5 (any
 * DLC) that is not our own echo (LSS_FRAME_ECHO). Whoever drives the
 * engine hands it only frames it did not send, so any such frame is
 * somebody else's: a second LSS master on the bus. */
bool lss_is_foreign_request(const lss_frame *f);
/* Boot-up (or heartbeat) frame of a node: 0x701..0x77F, DLC 1, standard, not RTR. */
bool bootup_decode(const lss_frame *f, uint8_t *node_id, uint8_t *nmt_state);
/* NMT command frame: id 0, DLC 2. */
bool nmt_decode(const lss_frame *f, uint8_t *cs, uint8_t *node_id);

/* ---- helpers ---- */
bool lss_node_id_valid(unsigned node_id); /* 1..127 */
uint32_t lss_identity_field(const lss_identity *id, enum lss_field field);
void lss_identity_set_field(lss_identity *id, enum lss_field field, uint32_t value);
bool lss_identity_equal(const lss_identity *a, const lss_identity *b);
int lss_identity_compare(const lss_identity *a, const lss_identity *b);
/* The map-matching rule, its one home: `id` is the device a map entry for
 * `entry` names when vendor, product and serial are equal, and the revision
 * too unless the entry has none (`revision_known` false: any revision). */
bool lss_identity_matches(const lss_identity *entry, bool revision_known, const lss_identity *id);
/* Table 0 (CiA 301/305): bit rate for index, 0 if none/auto. */
uint32_t lss_bit_timing_rate(uint8_t index);
/* Table 0 index for a bit rate, -1 if the table has none. */
int lss_bit_timing_index(uint32_t bitrate);
/* Bits a classic CAN data frame occupies on the wire, with bit stuffing and
 * the 3-bit interframe space. Used for bus-time accounting. */
unsigned can_frame_bits(const lss_frame *f);
/* "7E5#0401000000000000" style; buf >= 32 bytes */
const char *lss_frame_format(const lss_frame *f, char *buf, size_t size);
