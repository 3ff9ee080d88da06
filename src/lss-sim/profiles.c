/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <stdio.h>
#include <string.h>

#include "lss-sim/profiles.h"

/* Vendor/product of servo-drive and encoder are the ones the example
 * configuration in the design uses (Elmo 0x9A / product 3, Baumer 0xEC /
 * 0x1234), so a demo bus matches conf/ out of the box. */
static const sim_profile profiles[] = {
        {
                .name = "servo-drive",
                .summary = "Elmo-like servo drive: the full DSP 305 set including identify",
                .fixed_vendor = true, .vendor = 0x0000009A,
                .fixed_product = true, .product = 0x00000003,
                .default_node_id = LSS_NODE_ID_UNCONFIGURED,
        },
        {
                .name = "encoder",
                .summary = "Baumer rotary encoder: vendor 0xEC, shipped at node-ID 1, LSS only in NMT Stopped",
                .fixed_vendor = true, .vendor = 0x000000EC,
                .fixed_product = true, .product = 0x00001234,
                .default_node_id = 1,
                .needs_nmt_stopped = true,
        },
        {
                .name = "transmitter",
                .summary = "WIKA pressure transmitter: bit timing index 5 (100 kbit/s) reserved, answered \"not supported\"",
                .default_node_id = LSS_NODE_ID_UNCONFIGURED,
                .bit_index_unsupported = 1u << 5,
        },
        {
                .name = "generic",
                .summary = "plain slave of the encoder manuals' node-ID and bit rate examples",
                .default_node_id = LSS_NODE_ID_UNCONFIGURED,
        },
        {
                .name = "canopennode",
                .summary = "CANopenNode v4 device: no identify services, Configure Bit Timing ignored, "
                           "answers every Fastscan in configuration state",
                .default_node_id = LSS_NODE_ID_UNCONFIGURED,
                .base = lss_slave_faults_canopennode,
        },
        {
                .name = "canopennode-bitrate",
                .summary = "CANopenNode v4 device with a bit-rate callback: as canopennode, but answers "
                           "Configure Bit Timing",
                .default_node_id = LSS_NODE_ID_UNCONFIGURED,
                .base = lss_slave_faults_canopennode,
                .bit_timing_answered = true,
        },
        {
                .name = "lely",
                .summary = "lely-core device with a store hook: answers Fastscan whatever its node-ID, takes a "
                           "new node-ID only at NMT reset, Configure Bit Timing \"not supported\"",
                .default_node_id = LSS_NODE_ID_UNCONFIGURED,
                .base = lss_slave_faults_lely,
        },
};

const sim_profile *sim_profile_all(size_t *n) {
        *n = sizeof(profiles) / sizeof(profiles[0]);
        return profiles;
}

const sim_profile *sim_profile_default(void) {
        return &profiles[0];
}

const sim_profile *sim_profile_find(const char *name) {
        for (size_t i = 0; i < sizeof(profiles) / sizeof(profiles[0]); i++)
                if (strcmp(profiles[i].name, name) == 0)
                        return &profiles[i];
        return NULL;
}

void sim_profile_names(char *buf, size_t size) {
        size_t used = 0;
        buf[0] = '\0';
        for (size_t i = 0; i < sizeof(profiles) / sizeof(profiles[0]) && used < size; i++) {
                int n = snprintf(buf + used, size - used, "%s%s", i ? ", " : "", profiles[i].name);
                if (n < 0)
                        return;
                used += (size_t) n;
        }
}

void sim_profile_faults(const sim_profile *p, lss_slave_faults *f) {
        if (p->base)
                p->base(f);
        else
                lss_slave_faults_default(f);
        if (p->bit_timing_answered)
                f->bit_timing_silent = false;
        f->needs_nmt_stopped = p->needs_nmt_stopped;
        /* added to the base's (lely's are all of them) */
        f->bit_index_unsupported |= p->bit_index_unsupported;
}
