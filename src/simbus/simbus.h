/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The simulated bus of `lssd --simulate` (tests and demos without
 * SocketCAN): the in-memory bus and slave models of src/sim behind the
 * transport seam, its virtual time pinned to CLOCK_MONOTONIC. It has no fd:
 * its user wakes up at lss_transport_next_event() instead; its retune_start()
 * moves the simulated host controller to the new rate; its link is always up. */
#pragma once

#include <stdbool.h>
#include <stdint.h>

#include "can/transport.h"
#include "lss/lss_proto.h"
#include "sim/lss_slave.h"

typedef struct simbus simbus;

int simbus_new(uint32_t bitrate, simbus **ret);
/* How a simulated slave behaves (--sim-slave's last field). */
typedef enum simbus_profile {
        SIMBUS_PLAIN = 0,
        SIMBUS_CANOPENNODE,         /* "canopennode": lss_slave_faults_canopennode() */
        /* "canopennode-bitrate": the same with a bit-rate callback
         * (CO_LSSslave_initCheckBitRateCallback): answers Configure Bit Timing */
        SIMBUS_CANOPENNODE_BITRATE,
        /* "no-selective-switch": ignores Switch State Selective (lss-sim's
         * --fault ignore-cs=0x40): found by SDO only */
        SIMBUS_NO_SELECTIVE_SWITCH,
        SIMBUS_LELY,                /* "lely": lss_slave_faults_lely() */
} simbus_profile;

/* The slave model's faults of a profile (without the latency simbus adds). */
void simbus_profile_faults(simbus_profile profile, lss_slave_faults *f);

/* node_id 1..127 or 0xFF. */
int simbus_add_slave(simbus *s, const lss_identity *id, uint8_t node_id, simbus_profile profile);
/* Another LSS master on a simulated bus (lssd --sim-foreign-master): once
 * the bus's master (lssd) wrote `after` LSS requests (0: at once), or its
 * first request with cs `after_cs` (nonzero), the other master sends `count`
 * requests, `period_ms` apart: Inquire Vendor-ID with
 * its reserved bytes 0xF0 (SIMBUS_FOREIGN_FRAME), which tells it from
 * lssd's own in LSSD_SIM_TRACE's lines; slaves in configuration answer it. */
#define SIMBUS_FOREIGN_FRAME "7E5#5AF0F0F0F0F0F0F0"
typedef struct simbus_foreign {
        char ifname[16];
        unsigned after, count, period_ms;
        int after_cs;
} simbus_foreign;
/* Parses "IFACE:AFTER[:COUNT[:PERIOD_MS]]", AFTER a number of requests or
 * @CS, a command specifier (COUNT 1..100000, default 1; PERIOD_MS 1..60000,
 * default 100). -EINVAL if malformed. */
int simbus_foreign_parse(const char *spec, simbus_foreign *ret);
void simbus_add_foreign(simbus *s, const simbus_foreign *f);
/* The in-memory bus behind it, caught up to now (tests look at the slaves). */
struct membus *simbus_bus(simbus *s);

/* The simulated bus as a transport; the transport's close() frees it. */
void simbus_transport(simbus *s, lss_transport *ret);

/* Parses "IFACE:VENDOR:PRODUCT:REVISION:SERIAL[:NODEID[:PROFILE]]"
 * (numbers in C notation, NODEID absent = 0xFF, PROFILE one of
 * SIMBUS_PROFILES). -EINVAL if malformed. */
#define SIMBUS_PROFILES "canopennode, canopennode-bitrate, no-selective-switch, lely"
int simbus_slave_parse(const char *spec, char ifname[16], lss_identity *id, uint8_t *node_id,
                       simbus_profile *profile);
