/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* In-memory CAN bus on virtual time. Internally time is kept in
 * nanoseconds, so that frame times at every table-0 bit rate (800 kbit/s is
 * 1.25 µs a bit) add up exactly; the API speaks microseconds, rounding event
 * times up. */
#include "sim/membus.h"
#include "sim/sim_random.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#define NO_TIME UINT64_MAX

enum src_kind { SRC_MASTER, SRC_SLAVE, SRC_INJECTED };

typedef struct pending {
        lss_frame f;
        uint64_t ready_ns;
        uint64_t seq;     /* order of queueing: FIFO among equals */
        uint64_t arb;     /* arbitration key, lower wins */
        size_t slave;     /* sender index for SRC_SLAVE */
        uint8_t kind;
} pending;

typedef struct heap {
        pending *v;
        size_t n, cap;
        bool (*less)(const pending *a, const pending *b);
} heap;

typedef struct membus_node {
        lss_slave s;
        membus *bus;
        size_t index;
        uint64_t deadline_us;
        uint64_t sent_serial;   /* wire frame this slave (also) transmitted */
} membus_node;

typedef struct rx_entry {
        lss_frame f;
        uint64_t t_us;
} rx_entry;

struct membus {
        uint32_t bitrate;
        uint8_t bus_index;
        uint64_t now_ns;
        uint64_t seed;
        bool merge;
        bool master_fifo;       /* the master's frames leave in the order it sent them */

        membus_node **slaves;
        size_t n_slaves, cap_slaves;
        uint64_t min_deadline_us;
        bool deadline_dirty;    /* a caller got a slave pointer and may have poked it */

        heap future;            /* not ready yet, by ready time */
        heap ready;             /* waiting for the wire, by arbitration */
        pending *mq;            /* master_fifo: the master's frames, oldest first */
        size_t mq_head, mq_len, mq_cap;
        pending *aside;         /* scratch for merging */
        size_t n_aside, cap_aside;
        uint64_t seq;

        bool busy;
        pending wire;
        uint64_t wire_end_ns, wire_free_ns, wire_serial;
        bool wire_from_master;

        rx_entry *rx;
        size_t rx_head, rx_len, rx_cap;

        membus_stats stats;
        uint64_t busy_ns;

        void (*trace)(void *ud, const lss_frame *f, uint64_t t_us);
        void *trace_ud;
};

static uint64_t ns_to_us_up(uint64_t ns) {
        return ns == NO_TIME ? NO_TIME : ns / 1000 + (ns % 1000 != 0);
}

static uint64_t us_to_ns(uint64_t us) {
        return us >= NO_TIME / 1000 ? NO_TIME : us * 1000;
}

/* The bits a controller sends during arbitration, as one number: base ID,
 * RTR (SRR for extended), IDE, extended ID, RTR. Dominant 0 wins, so the
 * lower key wins, and a standard frame beats an extended one with the same
 * base ID. */
static uint64_t arbitration_key(const lss_frame *f) {
        bool rtr = f->flags & LSS_FRAME_RTR;
        if (f->flags & LSS_FRAME_EFF) {
                uint32_t id = f->id & 0x1FFFFFFFu;
                return (uint64_t) (id >> 18) << 21 | 1u << 20 | 1u << 19 | (uint64_t) (id & 0x3FFFFu) << 1 | rtr;
        }
        return (uint64_t) (f->id & 0x7FFu) << 21 | (uint64_t) rtr << 20;
}

static bool by_ready(const pending *a, const pending *b) {
        if (a->ready_ns != b->ready_ns)
                return a->ready_ns < b->ready_ns;
        if (a->arb != b->arb)
                return a->arb < b->arb;
        return a->seq < b->seq;
}

static bool by_arbitration(const pending *a, const pending *b) {
        if (a->arb != b->arb)
                return a->arb < b->arb;
        return a->seq < b->seq;
}

static int grow(void **v, size_t *cap, size_t need, size_t elem) {
        if (need <= *cap)
                return 0;
        size_t c = *cap ? *cap * 2 : 16;
        while (c < need)
                c *= 2;
        void *p = realloc(*v, c * elem);
        if (!p)
                return -ENOMEM;
        *v = p;
        *cap = c;
        return 0;
}

static int heap_push(heap *h, const pending *p) {
        int r = grow((void **) &h->v, &h->cap, h->n + 1, sizeof(pending));
        if (r < 0)
                return r;
        size_t i = h->n++;
        while (i > 0) {
                size_t parent = (i - 1) / 2;
                if (!h->less(p, &h->v[parent]))
                        break;
                h->v[i] = h->v[parent];
                i = parent;
        }
        h->v[i] = *p;
        return 0;
}

static void heap_pop(heap *h, pending *out) {
        *out = h->v[0];
        pending last = h->v[--h->n];
        size_t i = 0;
        for (;;) {
                size_t c = 2 * i + 1;
                if (c >= h->n)
                        break;
                if (c + 1 < h->n && h->less(&h->v[c + 1], &h->v[c]))
                        c++;
                if (!h->less(&h->v[c], &last))
                        break;
                h->v[i] = h->v[c];
                i = c;
        }
        if (h->n > 0)
                h->v[i] = last;
}

static uint8_t rate_index(uint32_t bitrate) {
        int i = lss_bit_timing_index(bitrate);
        /* a rate outside table 0: no slave runs at it unless told so */
        return i < 0 ? 0xFF : (uint8_t) i;
}

membus *membus_new(uint32_t bitrate) {
        if (bitrate == 0)
                return NULL;
        membus *b = calloc(1, sizeof(*b));
        if (!b)
                return NULL;
        b->bitrate = bitrate;
        b->bus_index = rate_index(bitrate);
        b->future.less = by_ready;
        b->ready.less = by_arbitration;
        b->min_deadline_us = NO_TIME;
        return b;
}

void membus_free(membus *b) {
        if (!b)
                return;
        for (size_t i = 0; i < b->n_slaves; i++)
                free(b->slaves[i]);
        free(b->slaves);
        free(b->future.v);
        free(b->ready.v);
        free(b->aside);
        free(b->mq);
        free(b->rx);
        free(b);
}

static void queue_frame(membus *b, const lss_frame *f, uint64_t ready_ns, enum src_kind kind, size_t slave) {
        pending p = {
                .f = *f,
                .ready_ns = ready_ns < b->now_ns ? b->now_ns : ready_ns,
                .seq = b->seq++,
                .arb = arbitration_key(f),
                .slave = slave,
                .kind = (uint8_t) kind,
        };
        /* out of memory in a test harness: the frame is lost, like a full tx queue */
        if (kind == SRC_MASTER && b->master_fifo) {
                if (b->mq_head > 0 && b->mq_head == b->mq_len)
                        b->mq_head = b->mq_len = 0;
                if (grow((void **) &b->mq, &b->mq_cap, b->mq_len + 1, sizeof(pending)) == 0)
                        b->mq[b->mq_len++] = p;
                return;
        }
        (void) heap_push(&b->future, &p);
}

static void slave_emit(void *userdata, const lss_frame *f, uint64_t delay_us) {
        membus_node *n = userdata;
        uint64_t at = n->s.now_us + delay_us;
        queue_frame(n->bus, f, at < n->s.now_us ? NO_TIME : us_to_ns(at), SRC_SLAVE, n->index);
}

size_t membus_add_slave(membus *b, const lss_identity *id, uint8_t node_id, const lss_slave_faults *faults) {
        if (grow((void **) &b->slaves, &b->cap_slaves, b->n_slaves + 1, sizeof(*b->slaves)) < 0)
                return SIZE_MAX;
        membus_node *n = calloc(1, sizeof(*n));
        if (!n)
                return SIZE_MAX;
        n->bus = b;
        n->index = b->n_slaves;
        lss_slave_init(&n->s, id, node_id, b->bus_index, faults, sim_random_slave_seed(b->seed, n->index), slave_emit, n);
        /* power-on is the caller's choice, but the slave lives on bus time */
        n->s.now_us = n->s.tx_ready_us = b->now_ns / 1000;
        lss_slave_set_heartbeat(&n->s, n->s.faults.heartbeat_ms);
        n->deadline_us = lss_slave_deadline(&n->s);
        b->slaves[b->n_slaves++] = n;
        b->deadline_dirty = true;
        return n->index;
}

size_t membus_slave_count(const membus *b) {
        return b->n_slaves;
}

lss_slave *membus_slave(membus *b, size_t i) {
        if (i >= b->n_slaves)
                return NULL;
        b->deadline_dirty = true;
        return &b->slaves[i]->s;
}

lss_slave *membus_find(membus *b, const lss_identity *id) {
        for (size_t i = 0; i < b->n_slaves; i++)
                if (lss_identity_equal(&b->slaves[i]->s.id, id)) {
                        b->deadline_dirty = true;
                        return &b->slaves[i]->s;
                }
        return NULL;
}

uint64_t membus_now(const membus *b) {
        return b->now_ns / 1000;
}

void membus_master_send(membus *b, const lss_frame *f) {
        queue_frame(b, f, b->now_ns, SRC_MASTER, 0);
}

void membus_inject(membus *b, const lss_frame *f, uint64_t at_us) {
        queue_frame(b, f, us_to_ns(at_us), SRC_INJECTED, 0);
}

bool membus_master_recv(membus *b, lss_frame *f, uint64_t *rx_us) {
        if (b->rx_head == b->rx_len)
                return false;
        const rx_entry *e = &b->rx[b->rx_head++];
        if (f)
                *f = e->f;
        if (rx_us)
                *rx_us = e->t_us;
        if (b->rx_head == b->rx_len)
                b->rx_head = b->rx_len = 0;
        return true;
}

static uint64_t scan_deadlines(const membus *b) {
        uint64_t m = NO_TIME;
        for (size_t i = 0; i < b->n_slaves; i++) {
                uint64_t d = lss_slave_deadline(&b->slaves[i]->s);
                if (d < m)
                        m = d;
        }
        return m;
}

static void refresh_deadlines(membus *b) {
        if (!b->deadline_dirty)
                return;
        b->min_deadline_us = NO_TIME;
        for (size_t i = 0; i < b->n_slaves; i++) {
                membus_node *n = b->slaves[i];
                n->deadline_us = lss_slave_deadline(&n->s);
                if (n->deadline_us < b->min_deadline_us)
                        b->min_deadline_us = n->deadline_us;
        }
        b->deadline_dirty = false;
}

/* When the next frame can start: when the wire is free and one is ready. */
static uint64_t next_start_ns(const membus *b) {
        if (b->busy)
                return NO_TIME;
        uint64_t t = NO_TIME;
        if (b->ready.n > 0)
                t = 0;
        else if (b->future.n > 0)
                t = b->future.v[0].ready_ns;
        if (b->mq_head < b->mq_len && b->mq[b->mq_head].ready_ns < t)
                t = b->mq[b->mq_head].ready_ns;
        if (t == NO_TIME)
                return NO_TIME;
        if (t < b->wire_free_ns)
                t = b->wire_free_ns;
        return t < b->now_ns ? b->now_ns : t;
}

uint64_t membus_next_event(const membus *b) {
        uint64_t t = b->busy ? b->wire_end_ns : next_start_ns(b);
        uint64_t d = b->deadline_dirty ? scan_deadlines(b) : b->min_deadline_us;
        d = us_to_ns(d);
        return ns_to_us_up(d < t ? d : t);
}

static bool same_frame(const lss_frame *a, const lss_frame *b) {
        return a->id == b->id && a->flags == b->flags && a->len == b->len &&
                memcmp(a->data, b->data, a->len > 8 ? 8 : a->len) == 0;
}

static bool may_send(const membus *b, const pending *p, uint64_t t_us) {
        return p->kind != SRC_SLAVE || lss_slave_on_bus(&b->slaves[p->slave]->s, b->bus_index, t_us);
}

/* Mark the sender of a copy that goes out in this wire frame. */
static void mark_sender(membus *b, const pending *p) {
        if (p->kind == SRC_MASTER)
                b->wire_from_master = true;
        else if (p->kind == SRC_SLAVE)
                b->slaves[p->slave]->sent_serial = b->wire_serial;
}

static bool already_sending(const membus *b, const pending *p) {
        if (p->kind == SRC_MASTER)
                return b->wire_from_master;
        if (p->kind == SRC_SLAVE)
                return b->slaves[p->slave]->sent_serial == b->wire_serial;
        return false; /* every injected frame comes from a stranger of its own */
}

/* Identical frames from other nodes waiting for this same start go out
 * together with it; a node's second copy stays queued. */
static void merge_identical(membus *b, uint64_t t_ns, uint64_t t_us) {
        pending p;
        b->n_aside = 0;
        if (b->mq_head < b->mq_len && b->mq[b->mq_head].ready_ns <= t_ns &&
            same_frame(&b->mq[b->mq_head].f, &b->wire.f) && !already_sending(b, &b->mq[b->mq_head])) {
                mark_sender(b, &b->mq[b->mq_head++]);
                b->stats.merged_frames++;
        }
        while (b->ready.n > 0 && b->ready.v[0].arb == b->wire.arb) {
                heap_pop(&b->ready, &p);
                if (!may_send(b, &p, t_us)) {
                        b->stats.dropped_frames++;
                        continue;
                }
                if (same_frame(&p.f, &b->wire.f) && !already_sending(b, &p)) {
                        mark_sender(b, &p);
                        b->stats.merged_frames++;
                        continue;
                }
                if (grow((void **) &b->aside, &b->cap_aside, b->n_aside + 1, sizeof(pending)) < 0) {
                        (void) heap_push(&b->ready, &p);
                        break;
                }
                b->aside[b->n_aside++] = p;
        }
        for (size_t i = 0; i < b->n_aside; i++)
                (void) heap_push(&b->ready, &b->aside[i]);
}

static void start_frame(membus *b, uint64_t t_ns) {
        uint64_t t_us = ns_to_us_up(t_ns);
        pending p;

        while (b->future.n > 0 && b->future.v[0].ready_ns <= t_ns) {
                heap_pop(&b->future, &p);
                (void) heap_push(&b->ready, &p);
        }
        /* the master's oldest frame takes part in the arbitration */
        if (b->mq_head < b->mq_len && b->mq[b->mq_head].ready_ns <= t_ns &&
            (b->ready.n == 0 || by_arbitration(&b->mq[b->mq_head], &b->ready.v[0])))
                p = b->mq[b->mq_head++];
        else if (b->ready.n == 0)
                return;
        else
                heap_pop(&b->ready, &p);
        if (!may_send(b, &p, t_us)) {
                /* a node at another bit rate (or retuning) never gets a frame through */
                b->stats.dropped_frames++;
                return;
        }
        b->busy = true;
        b->wire = p;
        b->wire_serial++;
        b->wire_from_master = false;
        mark_sender(b, &p);
        uint64_t bits = can_frame_bits(&p.f);
        uint64_t dur = (bits * UINT64_C(1000000000) + b->bitrate - 1) / b->bitrate;
        b->wire_end_ns = t_ns + dur;
        b->busy_ns += dur;
        if (b->merge)
                merge_identical(b, t_ns, t_us);
}

static void count_frame(membus *b, const pending *p) {
        b->stats.frames++;
        if (p->kind == SRC_MASTER)
                b->stats.master_frames++;
        else if (p->kind == SRC_SLAVE)
                b->stats.slave_frames++;
        else
                b->stats.injected_frames++;
        b->stats.busy_us = b->busy_ns / 1000;
        if (!(p->f.flags & LSS_FRAME_EFF)) {
                if (p->f.id == LSS_COB_MASTER)
                        b->stats.lss_requests++;
                else if (p->f.id == LSS_COB_SLAVE)
                        b->stats.lss_responses++;
        }
}

/* The last bit is on the wire: every other node that can hear it gets it. */
static void finish_frame(membus *b) {
        const pending *p = &b->wire;
        uint64_t t_us = ns_to_us_up(b->wire_end_ns);

        b->busy = false;
        b->wire_free_ns = b->wire_end_ns;
        count_frame(b, p);
        if (b->trace)
                b->trace(b->trace_ud, &p->f, t_us);
        if (!b->wire_from_master &&
            grow((void **) &b->rx, &b->rx_cap, b->rx_len + 1, sizeof(rx_entry)) == 0)
                b->rx[b->rx_len++] = (rx_entry) { .f = p->f, .t_us = t_us };

        b->min_deadline_us = NO_TIME;
        for (size_t i = 0; i < b->n_slaves; i++) {
                membus_node *n = b->slaves[i];
                if (n->sent_serial != b->wire_serial && lss_slave_on_bus(&n->s, b->bus_index, t_us)) {
                        lss_slave_on_frame(&n->s, &p->f, t_us);
                        n->deadline_us = lss_slave_deadline(&n->s);
                }
                if (n->deadline_us < b->min_deadline_us)
                        b->min_deadline_us = n->deadline_us;
        }
}

static void run_deadlines(membus *b, uint64_t t_us) {
        b->min_deadline_us = NO_TIME;
        for (size_t i = 0; i < b->n_slaves; i++) {
                membus_node *n = b->slaves[i];
                if (n->deadline_us <= t_us) {
                        lss_slave_on_time(&n->s, t_us);
                        n->deadline_us = lss_slave_deadline(&n->s);
                }
                if (n->deadline_us < b->min_deadline_us)
                        b->min_deadline_us = n->deadline_us;
        }
}

void membus_advance(membus *b, uint64_t t_us) {
        uint64_t limit = us_to_ns(t_us);

        for (;;) {
                refresh_deadlines(b);
                uint64_t end = b->busy ? b->wire_end_ns : NO_TIME;
                uint64_t dl = us_to_ns(b->min_deadline_us);
                uint64_t start = next_start_ns(b);
                uint64_t e = end < dl ? end : dl;
                if (start < e)
                        e = start;
                if (e == NO_TIME || e > limit)
                        break;
                if (e > b->now_ns)
                        b->now_ns = e;
                /* at one instant: deliveries, then timers, then the next start,
                 * so that frames queued by the first two take part in arbitration */
                if (end == e)
                        finish_frame(b);
                else if (dl == e)
                        run_deadlines(b, b->min_deadline_us);
                else
                        start_frame(b, e);
        }
        if (limit != NO_TIME && limit > b->now_ns)
                b->now_ns = limit;
}

const membus_stats *membus_get_stats(const membus *b) {
        return &b->stats;
}

void membus_reset_stats(membus *b) {
        memset(&b->stats, 0, sizeof(b->stats));
        b->busy_ns = 0;
}

void membus_set_bitrate(membus *b, uint32_t bitrate) {
        if (bitrate == 0)
                return;
        b->bitrate = bitrate;
        b->bus_index = rate_index(bitrate);
}

uint32_t membus_bitrate(const membus *b) {
        return b->bitrate;
}

void membus_set_trace(membus *b, void (*trace)(void *ud, const lss_frame *f, uint64_t t_us), void *ud) {
        b->trace = trace;
        b->trace_ud = ud;
}

void membus_set_seed(membus *b, uint64_t seed) {
        b->seed = seed;
}

void membus_set_merge_identical(membus *b, bool merge) {
        b->merge = merge;
}

void membus_set_master_fifo(membus *b, bool fifo) {
        b->master_fifo = fifo;
}
