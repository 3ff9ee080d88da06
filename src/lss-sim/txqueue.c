/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "lss-sim/txqueue.h"

/* A sorted array: the queue holds at most a few entries per slave, and a
 * sorted array makes the merge scan a plain walk from the front. */

static bool same_frame(const lss_frame *a, const lss_frame *b) {
        return a->id == b->id && a->flags == b->flags && a->len == b->len &&
               memcmp(a->data, b->data, a->len <= 8 ? a->len : 8) == 0;
}

int txq_push(txqueue *q, uint64_t due_us, uint32_t from, const lss_frame *f) {
        size_t lo = 0, hi;

        if (q->n == q->cap) {
                size_t cap = q->cap ? q->cap * 2 : 64;
                txq_entry *v = reallocarray(q->v, cap, sizeof(*v));
                if (!v)
                        return -ENOMEM;
                q->v = v;
                q->cap = cap;
        }
        /* after every entry due at or before due_us: equal times stay FIFO */
        hi = q->n;
        while (lo < hi) {
                size_t mid = lo + (hi - lo) / 2;
                if (q->v[mid].due_us <= due_us)
                        lo = mid + 1;
                else
                        hi = mid;
        }
        memmove(q->v + lo + 1, q->v + lo, (q->n - lo) * sizeof(*q->v));
        q->v[lo] = (txq_entry) { .due_us = due_us, .seq = q->seq++, .from = from, .frame = *f };
        q->n++;
        return 0;
}

uint64_t txq_next_due(const txqueue *q) {
        return q->n > 0 ? q->v[0].due_us : UINT64_MAX;
}

void txq_drop_front(txqueue *q) {
        if (q->n == 0)
                return;
        q->n--;
        memmove(q->v, q->v + 1, q->n * sizeof(*q->v));
}

size_t txq_size(const txqueue *q) {
        return q->n;
}

static bool sender_seen(const txqueue *q, size_t n, uint32_t from) {
        for (size_t i = 0; i < n; i++)
                if (q->senders[i] == from)
                        return true;
        return false;
}

bool txq_pop(txqueue *q, uint64_t now_us, txq_entry *ret, size_t *merged) {
        size_t n_senders = 0, kept, i;
        uint64_t limit;

        if (q->n == 0 || q->v[0].due_us > now_us)
                return false;
        *ret = q->v[0];
        limit = ret->due_us + TXQ_MERGE_WINDOW_US;

        /* Walk the window, dropping identical frames of senders not yet in
         * the merged frame; everything else keeps its place. If the sender
         * list cannot grow, merging stops early, which only costs a frame. */
        if (q->senders_cap == 0) {
                q->senders = malloc(16 * sizeof(*q->senders));
                q->senders_cap = q->senders ? 16 : 0;
        }
        if (q->senders_cap > 0)
                q->senders[n_senders++] = ret->from;

        kept = 0;
        for (i = 1; i < q->n && q->v[i].due_us <= limit; i++) {
                txq_entry *e = &q->v[i];
                if (n_senders > 0 && same_frame(&e->frame, &ret->frame) && !sender_seen(q, n_senders, e->from)) {
                        if (n_senders == q->senders_cap) {
                                uint32_t *s = reallocarray(q->senders, q->senders_cap * 2, sizeof(*s));
                                if (s) {
                                        q->senders = s;
                                        q->senders_cap *= 2;
                                }
                        }
                        if (n_senders < q->senders_cap) {
                                q->senders[n_senders++] = e->from;
                                continue;
                        }
                }
                q->v[kept++] = *e;
        }
        /* [0, kept) are the survivors of the window, [i, n) the rest */
        memmove(q->v + kept, q->v + i, (q->n - i) * sizeof(*q->v));
        q->n = kept + (q->n - i);
        if (merged)
                *merged = n_senders > 0 ? n_senders - 1 : 0;
        return true;
}

void txq_done(txqueue *q) {
        free(q->v);
        free(q->senders);
        *q = (txqueue) {};
}
