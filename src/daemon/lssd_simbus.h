/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* A simulated bus for tests and demos without SocketCAN (`lssd --simulate`):
 * the in-memory bus and slave models behind the transport seam, its virtual
 * time pinned to CLOCK_MONOTONIC. It has no fd: the daemon wakes up at
 * lssd_simbus_next_event() instead. */
#pragma once

#include <stdbool.h>
#include <stdint.h>

#include "can/transport.h"
#include "lss/lss_proto.h"

typedef struct lssd_simbus lssd_simbus;

int lssd_simbus_new(uint32_t bitrate, lssd_simbus **ret);
/* node_id 1..127 or 0xFF; canopennode: lss_slave_faults_canopennode(). */
int lssd_simbus_add_slave(lssd_simbus *s, const lss_identity *id, uint8_t node_id, bool canopennode);
/* The simulated bus as a transport; the transport's close() frees it. */
void lssd_simbus_transport(lssd_simbus *s, lss_transport *ret);
/* The simulated host controller to another rate (SetBitrate's retune). */
void lssd_simbus_set_bitrate(lssd_simbus *s, uint32_t bitrate);
/* When something happens next on the bus (CLOCK_MONOTONIC µs), UINT64_MAX if idle. */
uint64_t lssd_simbus_next_event(lssd_simbus *s);

/* Parses "IFACE:VENDOR:PRODUCT:REVISION:SERIAL[:NODEID[:canopennode]]"
 * (numbers in C notation, NODEID absent = 0xFF). -EINVAL if malformed. */
int lssd_sim_slave_parse(const char *spec, char ifname[16], lss_identity *id, uint8_t *node_id, bool *canopennode);
