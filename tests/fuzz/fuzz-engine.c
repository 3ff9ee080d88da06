/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The engine fed arbitrary frames and timer events during every service.
 * Input: byte 0 picks the operation; then records of 11 bytes:
 * [kind, dt (2), id (2), flags, len, data (4 -> replicated)]. */
#include <stdint.h>
#include <string.h>

#include "lss/lss_autoassign.h"
#include "lss/lss_master.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void start(lss_master *m, uint8_t op, uint64_t now) {
        static const lss_identity id = { 0xEC, 0x1234, 1, 0x1276 };
        static const lss_map_entry map[] = { { .id = { 0xEC, 0x1234, 1, 0x1276 }, .revision_known = true, .node_id = 5 },
                                             { .id = { 0xEC, 0x1234, 0, 17 }, .node_id = 6 } };
        static const lss_autoassign_plan plan = { .map = map, .n_map = 2, .unknown = LSS_UNKNOWN_POOL,
                                                  .pool_lo = 100, .pool_hi = 110, .store = true, .nmt_stop = true };
        lss_fastscan_known k = { .value = id, .known_bits = { 32, 32, 0, 16 } };
        lss_identify_range r = { 0xEC, 0x1234, 0, UINT32_MAX, 0, UINT32_MAX };
        switch (op % 17) {
        case 0: lss_master_switch_global(m, LSS_MODE_CONFIGURATION, now); break;
        case 1: lss_master_switch_selective(m, &id, now); break;
        case 2: lss_master_configure_node_id(m, 5, now); break;
        case 3: lss_master_configure_bit_timing(m, 0, 2, now); break;
        case 4: lss_master_activate_bit_timing(m, 16, now); break;
        case 5: lss_master_store(m, now); break;
        case 6: lss_master_inquire(m, op % 5, now); break;
        case 7: lss_master_inquire_identity(m, now); break;
        case 8: lss_master_identify_remote(m, &r, now); break;
        case 9: lss_master_identify_non_configured(m, now); break;
        case 10: lss_master_fastscan(m, op & 0x80 ? &k : NULL, now); break;
        case 11: lss_master_nmt(m, NMT_CS_STOP, 0, now); break;
        case 12: lss_master_enumerate(m, op & 0x80 ? &k : NULL, now); break;
        case 13: lss_master_slowscan(m, &r, now); break;
        case 14: lss_master_assign(m, &id, 7, LSS_ASSIGN_STORE | LSS_ASSIGN_VERIFY | LSS_ASSIGN_CHECK_FREE, now); break;
        case 15: lss_master_fastscan_assign(m, &k, 8, LSS_ASSIGN_VERIFY, now); break;
        default: lss_master_autoassign(m, &plan, now); break;
        }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
        if (size < 1)
                return 0;
        lss_timing_config c;
        lss_timing_config_default(&c);
        c.retries = 1;
        lss_master *m = lss_master_new(&c);
        uint64_t now = 1000;
        start(m, data[0], now);
        lss_frame f;
        for (size_t i = 1; i + 11 <= size && !lss_master_done(m); i += 11) {
                const uint8_t *r = data + i;
                while (lss_master_next_tx(m, &f))
                        ;
                lss_master_on_sent(m, now);
                now += (uint64_t) (r[1] | r[2] << 8);
                switch (r[0] % 8) {
                case 0:
                case 1:
                case 2:
                case 3: {
                        lss_frame in = { .id = (uint32_t) (r[3] | r[4] << 8) & 0x7FF, .flags = r[5] & 0x0F,
                                         .len = r[6] % 9 };
                        /* mostly well-formed answers, so the procedures get deep */
                        if (r[0] % 8 < 3) {
                                in.id = r[0] % 8 == 2 ? 0x700u + (r[4] & 0x7F) : 0x7E4;
                                in.flags = 0;
                                in.len = r[0] % 8 == 2 ? 1 : 8;
                        }
                        memcpy(in.data, r + 7, 4);
                        memcpy(in.data + 4, r + 7, 4);
                        lss_master_on_frame(m, &in, now);
                        break;
                }
                case 4:
                        lss_master_on_time(m, lss_master_deadline(m) == UINT64_MAX ? now : lss_master_deadline(m));
                        if (lss_master_deadline(m) != UINT64_MAX && lss_master_deadline(m) > now)
                                now = lss_master_deadline(m);
                        break;
                case 5:
                        lss_master_on_rx_lost(m, now);
                        break;
                case 6:
                        if (r[3] == 0x42)
                                lss_master_cancel(m, now);
                        else
                                lss_master_on_time(m, now);
                        break;
                default:
                        if (r[3] == 0x43)
                                lss_master_on_bus_error(m, LSS_E_BUS_DOWN, "down", now);
                        break;
                }
        }
        /* finish: time alone must end every operation */
        for (int i = 0; i < 100000 && !lss_master_done(m); i++) {
                while (lss_master_next_tx(m, &f))
                        ;
                uint64_t d = lss_master_deadline(m);
                if (d == UINT64_MAX)
                        break;
                now = d > now ? d : now + 1;
                lss_master_on_time(m, now);
        }
        while (lss_master_next_tx(m, &f))
                ;
        size_t n;
        (void) lss_master_outcomes(m, &n);
        (void) lss_master_result(m);
        lss_master_free(m);
        return 0;
}
