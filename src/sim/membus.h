/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* In-memory CAN bus with virtual time, for unit tests and the engine bench.
 * One master port and many slave models. Frames go on the wire one at a time
 * in order of readiness (ties: lower identifier wins arbitration), each
 * taking its exact bit time at the bus bit rate; a frame is received by
 * every other node when its last bit is on the wire. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "lss/lss_proto.h"
#include "sim/lss_slave.h"

typedef struct membus membus;

typedef struct membus_stats {
        uint64_t frames;          /* all frames on the wire */
        uint64_t master_frames;   /* frames sent by the master port */
        uint64_t slave_frames;    /* frames sent by slaves */
        uint64_t injected_frames;
        uint64_t busy_us;         /* sum of frame times */
        uint64_t lss_requests;    /* 0x7E5 frames */
        uint64_t lss_responses;   /* 0x7E4 frames */
        uint64_t dropped_frames;  /* slave frames lost: sender off the bus (rate, activation window) */
        uint64_t merged_frames;   /* copies that went out inside an identical frame (see merge) */
} membus_stats;

/* NULL on bitrate 0 or out of memory. */
membus *membus_new(uint32_t bitrate);
void membus_free(membus *b);

/* Adds a slave; returns its index (SIZE_MAX when out of memory). bit_index
 * defaults to the bus's rate index. The slave is not powered on: no boot-up. */
size_t membus_add_slave(membus *b, const lss_identity *id, uint8_t node_id, const lss_slave_faults *faults);
size_t membus_slave_count(const membus *b);
lss_slave *membus_slave(membus *b, size_t i);
/* Find a slave by identity, NULL if none. */
lss_slave *membus_find(membus *b, const lss_identity *id);

uint64_t membus_now(const membus *b);
/* Master transmits now (queued behind frames already waiting for the wire). */
void membus_master_send(membus *b, const lss_frame *f);
/* A stranger puts a frame on the bus at time `at_us` (tests' fault injection). */
void membus_inject(membus *b, const lss_frame *f, uint64_t at_us);
/* Frames the master port received, oldest first, with their receive time. */
bool membus_master_recv(membus *b, lss_frame *f, uint64_t *rx_us);
/* Time of the next thing that will happen on the bus, UINT64_MAX if idle. */
uint64_t membus_next_event(const membus *b);
/* Run the bus until `t_us` (inclusive). Received frames queue at the master. */
void membus_advance(membus *b, uint64_t t_us);
const membus_stats *membus_get_stats(const membus *b);
void membus_reset_stats(membus *b);
/* Change the bus bit rate (slaves at another rate neither hear nor are heard). */
void membus_set_bitrate(membus *b, uint32_t bitrate);
uint32_t membus_bitrate(const membus *b);
/* Optional log of every frame on the wire (candump -L style lines). */
void membus_set_trace(membus *b, void (*trace)(void *ud, const lss_frame *f, uint64_t t_us), void *ud);
/* Seed of the slaves' jitter PRNGs; each slave added afterwards gets a seed
 * derived from this and its index (default 0). */
void membus_set_seed(membus *b, uint64_t seed);
/* Identical frames (same identifier, flags, DLC and data) from different
 * nodes that start on the same bit go out as one frame, as on a real bus
 * (e.g. many fastscan answers). Off by default: every copy is sent. */
void membus_set_merge_identical(membus *b, bool merge);
/* The master's frames leave in the order it sent them, as from a SocketCAN
 * socket (one FIFO queue to a controller with one transmit buffer): only
 * the oldest takes part in the arbitration. Off by default: all of its
 * frames ready compete by identifier. Set before the master sends. */
void membus_set_master_fifo(membus *b, bool fifo);
