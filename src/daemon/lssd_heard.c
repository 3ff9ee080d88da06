/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <inttypes.h>
#include <stdio.h>

#include "daemon/lssd_heard.h"

/* standard frames only: a remote request (heartbeat polling) is not a device speaking */
static bool from_node(const lss_frame *f, uint32_t base, uint8_t *node) {
        if (f->flags != 0 || f->id <= base || f->id > base + 127u)
                return false;
        *node = (uint8_t) (f->id - base);
        return true;
}

void lssd_heard_rx(lssd_heard *h, const lss_frame *f, uint64_t realtime_us) {
        uint8_t node, state;
        lssd_heard_kind kind;

        if (bootup_decode(f, &node, &state)) {
                kind = state == 0 ? LSSD_HEARD_BOOTUP : LSSD_HEARD_HEARTBEAT;
                h->nmt_state[node] = state;
        } else if (from_node(f, 0x580u, &node) && f->len == 8)
                kind = LSSD_HEARD_SDO;
        else if (from_node(f, 0x080u, &node))
                kind = LSSD_HEARD_EMERGENCY;
        else
                return;
        h->taken[node] = true;
        h->kind[node] = (uint8_t) kind;
        h->at[node] = realtime_us;
}

static void forget(lssd_heard *h, uint8_t node) {
        h->taken[node] = false;
        h->kind[node] = LSSD_HEARD_NOTHING;
        h->owned[node] = false;
}

void lssd_heard_owner(lssd_heard *h, uint8_t node_id, const lss_identity *id) {
        for (unsigned n = 1; n < 128; n++)
                if (n != node_id && h->owned[n] && lss_identity_equal(&h->owner[n], id))
                        forget(h, (uint8_t) n);
        if (node_id == 0 || node_id >= 128)
                return;
        h->owned[node_id] = true;
        h->owner[node_id] = *id;
}

bool lssd_heard_taken(const lssd_heard *h, uint8_t node_id, const lss_identity *id) {
        if (node_id >= 128 || !h->taken[node_id])
                return false;
        return !(id && h->owned[node_id] && lss_identity_equal(&h->owner[node_id], id));
}

void lssd_heard_tx(lssd_heard *h, const lss_frame *f) {
        uint8_t cs, node;
        if (!nmt_decode(f, &cs, &node) || (cs != NMT_CS_RESET_COMMUNICATION && cs != NMT_CS_RESET_NODE))
                return;
        if (node == 0) {
                for (unsigned n = 1; n < 128; n++)
                        forget(h, (uint8_t) n);
        } else if (node < 128)
                forget(h, node);
}

static const char *nmt_state_name(uint8_t s) {
        switch (s & 0x7F) {
        case 0x04: return " (stopped)";
        case 0x05: return " (operational)";
        case 0x7F: return " (pre-operational)";
        default: return "";
        }
}

const char *lssd_heard_describe(const lssd_heard *h, uint8_t node_id, uint64_t now_realtime_us, char *buf,
                                size_t size) {
        if (node_id >= 128 || !h->taken[node_id]) {
                snprintf(buf, size, "%s", "");
                return buf;
        }
        uint64_t ago_s = now_realtime_us > h->at[node_id] ? (now_realtime_us - h->at[node_id]) / 1000000u : 0;
        char when[48];
        if (ago_s == 0)
                snprintf(when, sizeof(when), "just now");
        else
                snprintf(when, sizeof(when), "%" PRIu64 " s ago", ago_s);
        switch ((lssd_heard_kind) h->kind[node_id]) {
        case LSSD_HEARD_BOOTUP:
                snprintf(buf, size, "booted up %s", when);
                break;
        case LSSD_HEARD_HEARTBEAT:
                snprintf(buf, size, "sent a heartbeat%s %s", nmt_state_name(h->nmt_state[node_id]), when);
                break;
        case LSSD_HEARD_SDO:
                snprintf(buf, size, "answered an SDO request %s", when);
                break;
        case LSSD_HEARD_EMERGENCY:
                snprintf(buf, size, "sent an emergency message %s", when);
                break;
        default:
                snprintf(buf, size, "was heard %s", when);
        }
        return buf;
}
