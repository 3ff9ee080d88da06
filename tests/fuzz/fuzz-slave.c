/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The slave model fed arbitrary frames and time, with fault knobs from the input. */
#include <stdint.h>
#include <string.h>

#include "sim/lss_slave.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void emit(void *ud, const lss_frame *f, uint64_t delay) {
        (void) f;
        (void) delay;
        (*(unsigned *) ud)++;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
        if (size < 4)
                return 0;
        lss_slave_faults fl;
        lss_slave_faults_default(&fl);
        fl.fastscan_when_configured = data[0] & 1;
        fl.early_config = (enum lss_slave_early_config) ((data[0] >> 1) & 3);
        fl.needs_nmt_stopped = data[0] & 8;
        fl.no_identify = data[0] & 16;
        fl.duplicate_answers = data[0] & 32;
        fl.miss_activation = data[0] & 64;
        fl.lely_lss = data[0] & 128;
        fl.bit_index_unsupported = data[1];
        fl.jitter_us = data[2];
        lss_identity id = { 0xEC, 0x1234, 1, 0x1276 };
        unsigned n = 0;
        lss_slave s;
        lss_slave_init(&s, &id, data[3] & 1 ? 0xFF : (uint8_t) (data[3] % 127 + 1), 4, &fl, 1, emit, &n);
        lss_slave_power_on(&s, 0);
        uint64_t now = 0;
        for (size_t i = 4; i + 10 <= size; i += 10) {
                const uint8_t *r = data + i;
                now += r[0];
                lss_frame f = { .id = r[1] & 1 ? 0x7E5 : (r[1] & 2 ? 0x000 : 0x600u + (r[2] & 0x7F)), .len = 8 };
                if (r[1] & 4)
                        f.flags = r[2] & 0x0F;
                if (f.id == 0x000)
                        f.len = 2;
                memcpy(f.data, r + 2, 8);
                lss_slave_on_frame(&s, &f, now);
                if (lss_slave_deadline(&s) != UINT64_MAX && r[1] & 8)
                        lss_slave_on_time(&s, lss_slave_deadline(&s));
                (void) lss_slave_on_bus(&s, 4, now);
        }
        return 0;
}
