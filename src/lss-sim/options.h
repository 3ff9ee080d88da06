/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* lss-sim command line: parsing and validation, no side effects beyond the
 * messages it prints, so the unit tests can drive it. */
#pragma once

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "lss/lss_proto.h"
#include "sim/lss_slave.h"

struct sim_profile;

/* --slave VENDOR:PRODUCT:REVISION:SERIAL[:NODEID] */
typedef struct sim_slave_spec {
        lss_identity id;
        bool node_id_given;       /* false: the profile's default node-ID */
        uint8_t node_id;          /* 1..127 or 0xFF */
} sim_slave_spec;

enum sim_knob {
        SIM_KNOB_SILENT,
        SIM_KNOB_IGNORE_CS,
        SIM_KNOB_WRONG_DLC,
        SIM_KNOB_FASTSCAN_WHEN_CONFIGURED,
        SIM_KNOB_STORE_UNSUPPORTED,
        SIM_KNOB_STORE_FAILS,
        SIM_KNOB_EARLY_CONFIG,
        SIM_KNOB_NEEDS_NMT_STOPPED,
        SIM_KNOB_NO_IDENTIFY,
        SIM_KNOB_BIT_TIMING_SILENT,
        SIM_KNOB_BIT_INDEX_UNSUPPORTED,
        SIM_KNOB_MISS_ACTIVATION,
        SIM_KNOB_DUPLICATE_ANSWERS,
        SIM_KNOB_CONFIGURE_ERROR_SPECIFIC,
        SIM_KNOB_CANOPENNODE_LSS,
        SIM_KNOB_LELY_LSS,
        SIM_KNOB_FASTSCAN_ANY,
        SIM_KNOB_LATENCY,
        SIM_KNOB_JITTER,
        SIM_KNOB_DROP,
        _SIM_KNOB_MAX,
};

/* --fault KNOB[=VALUE][@SERIAL] */
typedef struct sim_fault_spec {
        const char *arg;          /* the argument as given, for messages */
        enum sim_knob knob;
        uint32_t value;           /* bool 0/1, cs (or -1 as UINT32_MAX), enum, bitmask, µs, ppm */
        bool clear;               /* bit-index-unsupported=none */
        bool has_serial;
        uint32_t serial;
} sim_fault_spec;

typedef struct sim_options {
        const char *ifname;
        sim_slave_spec *slaves;
        size_t n_slaves;
        unsigned random_count;
        uint64_t seed;
        bool latency_given, jitter_given;
        uint32_t latency_us, jitter_us;
        const struct sim_profile *profile;
        const char *state_dir;
        uint32_t bitrate;
        sim_fault_spec *faults;
        size_t n_faults;
        bool follow_bitrate;      /* the simulated bus follows an activated bit rate */
        uint16_t heartbeat_ms;    /* heartbeat producer time, 0 = off */
        enum lss_slave_nmt nmt_state; /* after the boot-up at start */
        bool verbose;
} sim_options;

#define SIM_RANDOM_MAX 10000u
#define SIM_DEFAULT_BITRATE 125000u

/* 0: run; 1: --help/--version was printed to `out`, exit 0;
 * -EINVAL: a message naming the argument was printed to `err`, exit 2;
 * -ENOMEM. `o` must be released with sim_options_done() in every case. */
int sim_options_parse(sim_options *o, int argc, char **argv, FILE *out, FILE *err);
void sim_options_done(sim_options *o);

/* Value parsers shared with the state files. Hex with 0x/0X, else decimal;
 * no sign, no blanks, no trailing garbage. Return 0 or -EINVAL/-ERANGE. */
int sim_parse_u64(const char *s, uint64_t *ret);
int sim_parse_u32(const char *s, uint32_t *ret);
/* Milliseconds, optionally with up to three decimals ("2.5"), to µs. */
int sim_parse_ms(const char *s, uint32_t *ret_us);
/* A probability 0..1 with up to six decimals ("0.02", "1"), to parts per
 * million. */
int sim_parse_probability(const char *s, uint32_t *ret_ppm);
/* 1..127 or 0xFF */
int sim_parse_node_id(const char *s, uint8_t *ret);
/* VENDOR:PRODUCT:REVISION:SERIAL[:NODEID]; on failure *what says what was expected
 * and what came instead (a static buffer: valid until the next call). */
int sim_parse_slave(const char *s, sim_slave_spec *ret, const char **what);
/* KNOB[=VALUE][@SERIAL]; on failure *what says what is wrong. */
int sim_parse_fault(const char *s, sim_fault_spec *ret, const char **what);

/* Applies one knob to a fault set. */
void sim_fault_apply(const sim_fault_spec *spec, lss_slave_faults *f);
const char *sim_knob_name(enum sim_knob k);
