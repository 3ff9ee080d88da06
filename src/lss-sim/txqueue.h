/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Frames the simulated slaves want on the bus, ordered by the time they are
 * due. Identical frames from different slaves that start together become one
 * frame on a real CAN bus (they win arbitration together and their bits are
 * the same), so popping merges them. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "lss/lss_proto.h"

/* Identical frames due within this of the first one are merged. */
#define TXQ_MERGE_WINDOW_US 100u

typedef struct txq_entry {
        uint64_t due_us;
        uint64_t seq;             /* FIFO among equal due times */
        uint32_t from;            /* sender (slave index) */
        lss_frame frame;
} txq_entry;

typedef struct txqueue {
        txq_entry *v;
        size_t n, cap;
        uint64_t seq;
        uint32_t *senders;        /* scratch for merging */
        size_t senders_cap;
} txqueue;

int txq_push(txqueue *q, uint64_t due_us, uint32_t from, const lss_frame *f);
/* Earliest due time, UINT64_MAX when empty. */
uint64_t txq_next_due(const txqueue *q);
/* Takes the earliest entry due at or before now_us into *ret together with
 * the identical frames of other senders due within TXQ_MERGE_WINDOW_US of it
 * (at most one per sender: a sender's second copy is a frame of its own).
 * *merged (optional) gets how many entries were folded into *ret.
 * Returns false when nothing is due. */
bool txq_pop(txqueue *q, uint64_t now_us, txq_entry *ret, size_t *merged);
/* Removes the earliest entry without merging (its sender cannot send). */
void txq_drop_front(txqueue *q);
size_t txq_size(const txqueue *q);
void txq_done(txqueue *q);
