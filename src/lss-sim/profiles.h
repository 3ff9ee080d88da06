/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Device profiles: the behaviour of the devices in the source documents
 * (seeds), expressed as identity defaults and slave-model fault knobs. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "sim/lss_slave.h"

typedef struct sim_profile {
        const char *name;
        const char *summary;
        /* identities made up by --random take these when set */
        bool fixed_vendor, fixed_product;
        uint32_t vendor, product;
        /* node-ID of a --slave without NODEID and of --random slaves */
        uint8_t default_node_id;
        /* deviations from a plain CiA 305 slave */
        bool needs_nmt_stopped;
        /* the model's faults the profile starts from (e.g.
         * lss_slave_faults_canopennode); NULL: lss_slave_faults_default */
        void (*base)(lss_slave_faults *f);
        bool bit_timing_answered;  /* ... but answers Configure Bit Timing (a bit-rate callback) */
        uint32_t bit_index_unsupported;
} sim_profile;

const sim_profile *sim_profile_find(const char *name);
const sim_profile *sim_profile_default(void);
/* All profiles, default first. */
const sim_profile *sim_profile_all(size_t *n);
/* "servo-drive, encoder, ...": every profile's name, in buf (cut to size). */
void sim_profile_names(char *buf, size_t size);
/* The profile's base faults plus its deviations. */
void sim_profile_faults(const sim_profile *p, lss_slave_faults *f);
