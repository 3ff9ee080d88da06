/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include "lss/lss_proto.h"

#include <stdio.h>
#include <string.h>

void lss_put_u32(uint8_t *p, uint32_t v) {
        p[0] = v & 0xFF;
        p[1] = (v >> 8) & 0xFF;
        p[2] = (v >> 16) & 0xFF;
        p[3] = (v >> 24) & 0xFF;
}

uint32_t lss_get_u32(const uint8_t *p) {
        return (uint32_t) p[0] | (uint32_t) p[1] << 8 | (uint32_t) p[2] << 16 | (uint32_t) p[3] << 24;
}

static void lss_put_u16(uint8_t *p, uint16_t v) {
        p[0] = v & 0xFF;
        p[1] = v >> 8;
}

uint16_t lss_get_u16(const uint8_t *p) {
        return (uint16_t) (p[0] | p[1] << 8);
}

static void frame_init(lss_frame *f, uint32_t id, uint8_t cs) {
        memset(f, 0, sizeof(*f));
        f->id = id;
        f->len = 8;
        f->data[0] = cs;
}

void lss_frame_request(lss_frame *f, uint8_t cs) {
        frame_init(f, LSS_COB_MASTER, cs);
}

void lss_frame_response(lss_frame *f, uint8_t cs) {
        frame_init(f, LSS_COB_SLAVE, cs);
}

void lss_encode_switch_global(lss_frame *f, enum lss_mode mode) {
        lss_frame_request(f, LSS_CS_SWITCH_GLOBAL);
        f->data[1] = (uint8_t) mode;
}

void lss_encode_switch_selective(lss_frame *f, enum lss_field field, uint32_t value) {
        lss_frame_request(f, (uint8_t) (LSS_CS_SWITCH_SEL_VENDOR + field));
        lss_put_u32(f->data + 1, value);
}

void lss_encode_configure_node_id(lss_frame *f, uint8_t node_id) {
        lss_frame_request(f, LSS_CS_CONFIGURE_NODE_ID);
        f->data[1] = node_id;
}

void lss_encode_configure_bit_timing(lss_frame *f, uint8_t table, uint8_t index) {
        lss_frame_request(f, LSS_CS_CONFIGURE_BIT_TIMING);
        f->data[1] = table;
        f->data[2] = index;
}

void lss_encode_activate_bit_timing(lss_frame *f, uint16_t delay_ms) {
        lss_frame_request(f, LSS_CS_ACTIVATE_BIT_TIMING);
        lss_put_u16(f->data + 1, delay_ms);
}

void lss_encode_store(lss_frame *f) {
        lss_frame_request(f, LSS_CS_STORE);
}

void lss_encode_inquire(lss_frame *f, unsigned field) {
        lss_frame_request(f, (uint8_t) (LSS_CS_INQUIRE_VENDOR + (field > LSS_FIELD_COUNT ? LSS_FIELD_COUNT : field)));
}

void lss_encode_identify_remote(lss_frame *f, unsigned step, uint32_t value) {
        lss_frame_request(f, (uint8_t) (LSS_CS_IDENTIFY_VENDOR + (step > 5 ? 5 : step)));
        lss_put_u32(f->data + 1, value);
}

void lss_encode_identify_non_configured(lss_frame *f) {
        lss_frame_request(f, LSS_CS_IDENTIFY_NON_CONFIGURED);
}

void lss_encode_fastscan(lss_frame *f, uint32_t idnumber, uint8_t bitcheck, uint8_t lsssub, uint8_t lssnext) {
        lss_frame_request(f, LSS_CS_FASTSCAN);
        lss_put_u32(f->data + 1, idnumber);
        f->data[5] = bitcheck;
        f->data[6] = lsssub;
        f->data[7] = lssnext;
}

void nmt_encode(lss_frame *f, enum nmt_cs cs, uint8_t node_id) {
        memset(f, 0, sizeof(*f));
        f->id = NMT_COB;
        f->len = 2;
        f->data[0] = (uint8_t) cs;
        f->data[1] = node_id;
}

void bootup_encode(lss_frame *f, uint8_t node_id) {
        memset(f, 0, sizeof(*f));
        f->id = BOOTUP_COB_BASE + node_id;
        f->len = 1;
        f->data[0] = 0x00;
}

static bool plain_frame(const lss_frame *f) {
        return (f->flags & (LSS_FRAME_EFF | LSS_FRAME_RTR | LSS_FRAME_FD | LSS_FRAME_ERR | LSS_FRAME_ECHO)) == 0;
}

bool lss_is_response(const lss_frame *f) {
        return plain_frame(f) && f->id == LSS_COB_SLAVE && f->len == 8;
}

bool lss_is_request(const lss_frame *f) {
        return plain_frame(f) && f->id == LSS_COB_MASTER && f->len == 8;
}

bool lss_is_foreign_request(const lss_frame *f) {
        return plain_frame(f) && f->id == LSS_COB_MASTER;
}

bool bootup_decode(const lss_frame *f, uint8_t *node_id, uint8_t *nmt_state) {
        if (!plain_frame(f) || f->len != 1)
                return false;
        if (f->id <= BOOTUP_COB_BASE || f->id > BOOTUP_COB_BASE + LSS_NODE_ID_MAX)
                return false;
        if (node_id)
                *node_id = (uint8_t) (f->id - BOOTUP_COB_BASE);
        if (nmt_state)
                *nmt_state = f->data[0] & 0x7F;
        return true;
}

bool nmt_decode(const lss_frame *f, uint8_t *cs, uint8_t *node_id) {
        if (!plain_frame(f) || f->id != NMT_COB || f->len != 2)
                return false;
        if (cs)
                *cs = f->data[0];
        if (node_id)
                *node_id = f->data[1];
        return true;
}

bool lss_node_id_valid(unsigned node_id) {
        return node_id >= LSS_NODE_ID_MIN && node_id <= LSS_NODE_ID_MAX;
}

uint32_t lss_identity_field(const lss_identity *id, enum lss_field field) {
        switch (field) {
        case LSS_FIELD_VENDOR: return id->vendor;
        case LSS_FIELD_PRODUCT: return id->product;
        case LSS_FIELD_REVISION: return id->revision;
        default: return id->serial;
        }
}

void lss_identity_set_field(lss_identity *id, enum lss_field field, uint32_t value) {
        switch (field) {
        case LSS_FIELD_VENDOR: id->vendor = value; break;
        case LSS_FIELD_PRODUCT: id->product = value; break;
        case LSS_FIELD_REVISION: id->revision = value; break;
        default: id->serial = value; break;
        }
}

bool lss_identity_equal(const lss_identity *a, const lss_identity *b) {
        return lss_identity_compare(a, b) == 0;
}

bool lss_identity_matches(const lss_identity *entry, bool revision_known, const lss_identity *id) {
        return entry->vendor == id->vendor && entry->product == id->product && entry->serial == id->serial &&
               (!revision_known || entry->revision == id->revision);
}

int lss_identity_compare(const lss_identity *a, const lss_identity *b) {
        for (unsigned i = 0; i < LSS_FIELD_COUNT; i++) {
                uint32_t x = lss_identity_field(a, i), y = lss_identity_field(b, i);
                if (x != y)
                        return x < y ? -1 : 1;
        }
        return 0;
}

static const uint32_t bit_rates[] = { 1000000, 800000, 500000, 250000, 125000, 100000, 50000, 20000, 10000 };

uint32_t lss_bit_timing_rate(uint8_t index) {
        return index < sizeof(bit_rates) / sizeof(bit_rates[0]) ? bit_rates[index] : 0;
}

int lss_bit_timing_index(uint32_t bitrate) {
        for (unsigned i = 0; i < sizeof(bit_rates) / sizeof(bit_rates[0]); i++)
                if (bit_rates[i] == bitrate)
                        return (int) i;
        return -1;
}

/* CRC-15 over the stuffed region, needed to count the stuff bits exactly. */
static uint16_t crc15(const uint8_t *bits, unsigned n) {
        uint16_t crc = 0;
        for (unsigned i = 0; i < n; i++) {
                unsigned next = bits[i] ^ ((crc >> 14) & 1);
                crc = (uint16_t) ((crc << 1) & 0x7FFF);
                if (next)
                        crc ^= 0x4599;
        }
        return crc;
}

unsigned can_frame_bits(const lss_frame *f) {
        uint8_t bits[160];
        unsigned n = 0, len = f->len > 8 ? 8 : f->len;

        bits[n++] = 0; /* SOF */
        if (f->flags & LSS_FRAME_EFF) {
                uint32_t id = f->id & 0x1FFFFFFF;
                for (int i = 28; i >= 18; i--)
                        bits[n++] = (id >> i) & 1;
                bits[n++] = 1; /* SRR */
                bits[n++] = 1; /* IDE */
                for (int i = 17; i >= 0; i--)
                        bits[n++] = (id >> i) & 1;
                bits[n++] = (f->flags & LSS_FRAME_RTR) ? 1 : 0;
                bits[n++] = 0; /* r1 */
                bits[n++] = 0; /* r0 */
        } else {
                for (int i = 10; i >= 0; i--)
                        bits[n++] = (f->id >> i) & 1;
                bits[n++] = (f->flags & LSS_FRAME_RTR) ? 1 : 0;
                bits[n++] = 0; /* IDE */
                bits[n++] = 0; /* r0 */
        }
        for (int i = 3; i >= 0; i--)
                bits[n++] = (f->len >> i) & 1;
        if (!(f->flags & LSS_FRAME_RTR))
                for (unsigned b = 0; b < len; b++)
                        for (int i = 7; i >= 0; i--)
                                bits[n++] = (f->data[b] >> i) & 1;
        uint16_t crc = crc15(bits, n);
        for (int i = 14; i >= 0; i--)
                bits[n++] = (crc >> i) & 1;

        /* a stuff bit (the complement) follows every run of five equal bits
         * and itself starts the next run */
        unsigned stuff = 0, run = 0;
        int last = -1;
        for (unsigned i = 0; i < n; i++) {
                if (bits[i] == last)
                        run++;
                else {
                        last = bits[i];
                        run = 1;
                }
                if (run == 5) {
                        stuff++;
                        last = !last;
                        run = 1;
                }
        }
        /* + CRC delimiter, ACK slot, ACK delimiter, EOF (7), interframe space (3) */
        return n + stuff + 1 + 1 + 1 + 7 + 3;
}

const char *lss_frame_format(const lss_frame *f, char *buf, size_t size) {
        int n;
        if (f->flags & LSS_FRAME_EFF)
                n = snprintf(buf, size, "%08X#", (unsigned) f->id);
        else
                n = snprintf(buf, size, "%03X#", (unsigned) f->id);
        if (f->flags & LSS_FRAME_RTR) {
                if (n >= 0 && (size_t) n < size)
                        snprintf(buf + n, size - (size_t) n, "R");
                return buf;
        }
        for (unsigned i = 0; i < f->len && i < 8 && n >= 0 && (size_t) n + 2 < size; i++)
                n += snprintf(buf + n, size - (size_t) n, "%02X", f->data[i]);
        return buf;
}
