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

typedef struct simbus simbus;

int simbus_new(uint32_t bitrate, simbus **ret);
/* node_id 1..127 or 0xFF; canopennode: lss_slave_faults_canopennode(). */
int simbus_add_slave(simbus *s, const lss_identity *id, uint8_t node_id, bool canopennode);
/* The simulated bus as a transport; the transport's close() frees it. */
void simbus_transport(simbus *s, lss_transport *ret);

/* Parses "IFACE:VENDOR:PRODUCT:REVISION:SERIAL[:NODEID[:canopennode]]"
 * (numbers in C notation, NODEID absent = 0xFF). -EINVAL if malformed. */
int simbus_slave_parse(const char *spec, char ifname[16], lss_identity *id, uint8_t *node_id, bool *canopennode);
