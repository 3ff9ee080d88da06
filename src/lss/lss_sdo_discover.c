/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* SDO identity discovery: who is at which node-ID, of any vendor, whether
 * or not it answers LSS. Every CANopen device has an SDO server on
 * 0x600 + node-ID / 0x580 + node-ID and object 1018h (identity). For each
 * node-ID of the range the pass reads 1018h:1..4 by expedited upload:
 *
 *   - Many node-IDs at once. Each node-ID has its COB-IDs of its own, so up
 *     to `window` of them have a request out together; one request per
 *     node-ID (an SDO server serves one transfer at a time): the next
 *     sub-index goes out when the last one was answered.
 *   - An answer names what it answers (index and sub-index), so no drain by
 *     time and no late guard is needed: an answer for 1018h:k at node n
 *     counts whenever it comes after the first request for it, also after
 *     a retry or after the pass gave the sub-index up (a late answer reopens
 *     the node-ID).
 *   - A request nobody answers at first contact (sub-index 1) is sent once
 *     more, then the node-ID is silent (nobody there, or a device in NMT
 *     Stopped); a device that answered is asked 1 + cfg.retries times for
 *     each further field before it stays unknown. When the pass lost
 *     frames, the silent node-IDs are asked again at the end, as often as
 *     that loss calls for (lss_loss.h).
 *   - Identical answers count once; a second, different answer to one
 *     request is two devices at one node-ID: a conflict, never one device.
 *   - An abort means a device is there without that field; 0x06020000
 *     (no object 1018h) ends the node-ID.
 *   - Boot-ups, heartbeats and SDO answers to other clients are recorded as
 *     heard, at any node-ID.
 * It writes no object and sends no NMT command. Waits: the engine's timing
 * rules (lss_timing.h) on latencies measured on SDO answers. First contact
 * (sub-index 1) needs no full wait of its own, since an answer names what it
 * answers and a late one reopens its node-ID: it waits like any step once
 * an SDO answer (or, before, an LSS answer of this host) was timed, else a
 * quarter of the limit; the pass ends with one full wait for the late. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "lss/lss_internal.h"

#define SDO_TX_BASE 0x580u                /* server -> client */
#define SDO_RX_BASE 0x600u                /* client -> server */
#define SDO_UPLOAD_REQUEST 0x40u
#define SDO_ABORT 0x80u
#define SDO_ABORT_NO_OBJECT 0x06020000u   /* object does not exist */
#define IDENTITY_INDEX 0x1018u
#define SUBS LSS_FIELD_COUNT              /* 1018h sub-indexes 1..4 */
#define FIRST_TRIES 2u                    /* first contact: a silent request is sent once more */
#define NO_TIME UINT64_MAX

enum answer_kind { ANSWER_NONE = 0, ANSWER_VALUE, ANSWER_ABORT, ANSWER_OTHER };

typedef struct sdo_answer {
        uint8_t kind;                     /* enum answer_kind */
        uint32_t v;                       /* the value (masked to its size) or abort code */
} sdo_answer;

enum slot_state { SLOT_IDLE = 0, SLOT_WANT, SLOT_BUSY, SLOT_DONE };

typedef struct sdo_slot {
        uint8_t state;                    /* enum slot_state */
        uint8_t sub;                      /* 1018h sub-index asked now, 1..SUBS */
        uint8_t tries;                    /* requests for it so far */
        uint8_t contacts;                 /* requests for sub-index 1 in all */
        bool queued;                      /* handed out in this round: its write time comes with on_sent */
        bool silent;                      /* sub-index 1 was given up: nobody answered */
        uint64_t sent_at, wire_at, deadline;
        uint64_t asked_at[SUBS + 1];      /* first request of each sub-index; NO_TIME: never asked */
        uint8_t asked_twice;              /* bit k: sub-index k was asked again */
        sdo_answer got[SUBS + 1];
        uint8_t differ;                   /* bit k: a second, different answer to sub-index k */
        bool heard;
        uint8_t nmt_state;
} sdo_slot;

typedef struct lss_sdo_state {
        int pc;
        uint8_t first, last;
        unsigned window, in_flight, done, total;
        uint8_t next;                     /* next node-ID to admit */
        uint64_t last_wire_at;            /* our last request is on the wire by then (estimate) */
        uint64_t guard_end;
        lss_timing timing;                /* SDO answer latencies, apart from LSS ones */
        sdo_slot slot[LSS_NODE_ID_MAX + 1];
        lss_sdo_node nodes[LSS_NODE_ID_MAX];
} lss_sdo_state;

void lss_sdo_discover_free_state(lss_master *m) {
        free(m->sdo);
        m->sdo = NULL;
}

static bool in_range(const lss_sdo_state *s, unsigned node) {
        return node >= s->first && node <= s->last;
}

/* The write time of the requests handed out before the last wait: the
 * wire time and deadline estimated when they were queued move with it
 * (asked_at stays the queue time: no answer comes before that). */
static void note_written(lss_master *m, lss_sdo_state *s) {
        uint64_t written = m->step.written ? m->step.sent_at : 0;
        for (unsigned n = s->first; n <= s->last; n++) {
                sdo_slot *sl = &s->slot[n];
                if (!sl->queued)
                        continue;
                sl->queued = false;
                if (written <= sl->sent_at)
                        continue;
                uint64_t d = written - sl->sent_at;
                sl->sent_at += d;
                sl->wire_at += d;
                sl->deadline += d;
        }
        if (written > 0 && s->last_wire_at < written)
                s->last_wire_at = written;
}

/* How long a first-contact request waits (see the top of the file). */
static uint32_t first_contact_wait(const lss_master *m, const lss_sdo_state *s) {
        if (s->timing.n_samples > 0)
                return lss_timing_wait(&s->timing, LSS_WAIT_ANSWER);
        if (m->timing.n_samples > 0)
                return lss_timing_wait(&m->timing, LSS_WAIT_ANSWER);
        return lss_timing_limit(&s->timing) / 4;
}

static bool send_request(lss_master *m, lss_sdo_state *s, uint8_t node) {
        sdo_slot *sl = &s->slot[node];
        lss_frame f = { .id = SDO_RX_BASE + node, .len = 8,
                        .data = { SDO_UPLOAD_REQUEST, (uint8_t) IDENTITY_INDEX, IDENTITY_INDEX >> 8, sl->sub } };
        if (!step_queue_tx(m, &f))
                return false;
        /* our requests go on the wire one after the other, and the answers
         * to those before it (lower identifiers) win the arbitration: each
         * request counts with an answer frame */
        uint64_t start = s->last_wire_at > m->now ? s->last_wire_at : m->now;
        uint32_t frame_us = lss_timing_frame_us(&s->timing, &f);
        sl->sent_at = m->now;
        sl->wire_at = start + frame_us;
        s->last_wire_at = sl->wire_at + frame_us;
        sl->deadline = sl->wire_at +
                       (sl->sub == 1 ? first_contact_wait(m, s) : lss_timing_wait(&s->timing, LSS_WAIT_ANSWER));
        if (sl->asked_at[sl->sub] == NO_TIME)
                sl->asked_at[sl->sub] = m->now;
        else
                sl->asked_twice |= (uint8_t) (1u << sl->sub);
        sl->tries++;
        sl->contacts += sl->sub == 1;
        sl->queued = true;
        sl->state = SLOT_BUSY;
        m->stats.steps++;
        return true;
}

static void slot_done(lss_master *m, lss_sdo_state *s, sdo_slot *sl) {
        sl->state = SLOT_DONE;
        s->in_flight--;
        s->done++;
        master_progress(m, (double) s->done / s->total);
}

/* On to the next sub-index not answered yet, or done: after the last one,
 * or when the device has no object 1018h at all. */
static void slot_next(lss_master *m, lss_sdo_state *s, sdo_slot *sl) {
        for (unsigned k = 1; k <= SUBS; k++)
                if (sl->got[k].kind == ANSWER_ABORT && sl->got[k].v == SDO_ABORT_NO_OBJECT) {
                        slot_done(m, s, sl);
                        return;
                }
        while (sl->sub <= SUBS && sl->got[sl->sub].kind != ANSWER_NONE)
                sl->sub++;
        if (sl->sub > SUBS) {
                slot_done(m, s, sl);
                return;
        }
        sl->tries = 0;
        sl->state = SLOT_WANT;
}

static sdo_answer decode(const lss_frame *f) {
        uint8_t cs = f->data[0];
        uint32_t v = lss_get_u32(f->data + 4);
        if (cs == SDO_ABORT)
                return (sdo_answer) { ANSWER_ABORT, v };
        /* initiate upload response, expedited: 4 bytes, or 4 - n with the size indicated */
        if ((cs & 0xE2u) == 0x42u) {
                unsigned size = cs & 0x01u ? 4u - ((cs >> 2) & 0x03u) : 4u;
                return (sdo_answer) { ANSWER_VALUE, size == 4 ? v : v & ((UINT32_C(1) << (8 * size)) - 1) };
        }
        return (sdo_answer) { ANSWER_OTHER, 0 }; /* segmented or not an upload answer: no value */
}

/* An answer of node `node` for 1018h sub-index `sub`, received at `rx`. */
static void take_answer(lss_master *m, lss_sdo_state *s, uint8_t node, uint8_t sub, const lss_frame *f,
                        uint64_t rx) {
        sdo_slot *sl = &s->slot[node];
        sdo_answer a = decode(f);

        if (sl->got[sub].kind != ANSWER_NONE) {
                if (sl->got[sub].kind == a.kind && sl->got[sub].v == a.v) {
                        /* the same once more: the answer to a request sent again
                         * came too, so the first one was later than the wait */
                        if (sl->asked_twice & (1u << sub)) {
                                m->stats.stray_answers++;
                                lss_timing_on_stray(&s->timing);
                        }
                        return;
                }
                if (!(sl->differ & (1u << sub)))
                        m->stats.conflicts++;
                sl->differ |= (uint8_t) (1u << sub);
                return;
        }
        sl->got[sub] = a;
        if ((sl->state == SLOT_BUSY || sl->state == SLOT_WANT) && sl->sub == sub) {
                uint32_t latency = rx > sl->wire_at ? (uint32_t) (rx - sl->wire_at) : 0;
                lss_timing_add_sample(&s->timing, latency);
                lss_timing_on_answer(&s->timing, latency, false);
                lss_loss_answered(&m->loss, sl->tries - 1u, 1);
                slot_next(m, s, sl);
                return;
        }
        /* later than both requests: the node-ID (or its next field) is asked
         * again, and the waits grow to this latency */
        m->stats.late_answers++;
        uint64_t lat = rx - sl->asked_at[sub];
        lss_timing_on_answer(&s->timing, lat > UINT32_MAX ? UINT32_MAX : (uint32_t) lat, true);
        if (sl->state == SLOT_DONE && sl->silent) {
                sl->silent = false;
                sl->state = SLOT_IDLE;
                s->done--;
                s->in_flight++;
                slot_next(m, s, sl);
        }
}

static void on_frame(lss_master *m, lss_sdo_state *s, const lss_frame *f, uint64_t rx) {
        uint8_t node, state;

        if (bootup_decode(f, &node, &state)) {
                s->slot[node].heard = true;
                s->slot[node].nmt_state = state & 0x7F; /* a node guarding answer's toggle bit off */
                return;
        }
        if (f->flags == 0 && f->len == 8 && f->id > SDO_TX_BASE && f->id <= SDO_TX_BASE + LSS_NODE_ID_MAX) {
                node = (uint8_t) (f->id - SDO_TX_BASE);
                uint8_t sub = f->data[3];
                if (in_range(s, node) && lss_get_u16(f->data + 1) == IDENTITY_INDEX && sub >= 1 && sub <= SUBS &&
                    s->slot[node].asked_at[sub] != NO_TIME && rx >= s->slot[node].asked_at[sub])
                        take_answer(m, s, node, sub, f, rx);
                else
                        s->slot[node].heard = true; /* another client's transfer, or before we asked */
                return;
        }
        m->stats.ignored_frames++;
        step_on_stray(m, f);
}

/* Requests whose wait ran out: sent once more, then given up. */
static void on_time(lss_master *m, lss_sdo_state *s) {
        for (unsigned n = s->first; n <= s->last; n++) {
                sdo_slot *sl = &s->slot[n];
                if (sl->state != SLOT_BUSY || sl->deadline > m->now)
                        continue;
                m->stats.timeouts++;
                /* a device that answered is asked as often as any LSS step */
                if (sl->tries < (sl->sub == 1 ? FIRST_TRIES : 1 + m->timing.cfg.retries)) {
                        m->stats.retries++;
                        sl->state = SLOT_WANT;
                } else if (sl->sub == 1) {
                        sl->silent = true;
                        slot_done(m, s, sl);
                } else {
                        sl->sub++;
                        sl->state = SLOT_IDLE;
                        slot_next(m, s, sl);
                }
        }
}

/* Requests for the node-IDs in flight, then new node-IDs up to the window. */
static void fill_window(lss_master *m, lss_sdo_state *s) {
        for (unsigned n = s->first; n <= s->last; n++)
                if (s->slot[n].state == SLOT_WANT && !send_request(m, s, (uint8_t) n))
                        return;
        while (s->in_flight < s->window && s->next <= s->last && s->next >= s->first) {
                sdo_slot *sl = &s->slot[s->next];
                if (sl->state == SLOT_DONE) {
                        s->next++; /* not asked (sdo_discover_setup's `only`) */
                        continue;
                }
                sl->sub = 1;
                sl->tries = 0;
                s->in_flight++;
                if (!send_request(m, s, s->next)) {
                        sl->state = SLOT_WANT;
                        return;
                }
                s->next++;
        }
}

/* A request that found the transmit queue full is tried again soon. */
#define QUEUE_FULL_RETRY_US 1000u

static uint64_t next_deadline(const lss_sdo_state *s, uint64_t now) {
        uint64_t d = NO_TIME;
        for (unsigned n = s->first; n <= s->last; n++) {
                const sdo_slot *sl = &s->slot[n];
                uint64_t t = sl->state == SLOT_BUSY ? sl->deadline :
                        sl->state == SLOT_WANT ? now + QUEUE_FULL_RETRY_US : NO_TIME;
                if (t < d)
                        d = t;
        }
        return d;
}

static void build_result(lss_master *m, lss_sdo_state *s) {
        size_t k = 0;
        for (unsigned n = LSS_NODE_ID_MIN; n <= LSS_NODE_ID_MAX; n++) {
                const sdo_slot *sl = &s->slot[n];
                lss_sdo_node d = { .node_id = (uint8_t) n, .nmt_state = sl->heard ? sl->nmt_state : 0xFF };
                for (unsigned sub = 1; sub <= SUBS; sub++) {
                        const sdo_answer *a = &sl->got[sub];
                        uint8_t bit = (uint8_t) (1u << (sub - 1));
                        if (a->kind != ANSWER_NONE)
                                d.source |= LSS_SDO_FROM_SDO;
                        if (sl->differ & (1u << sub))
                                d.conflict = true;
                        else if (a->kind == ANSWER_VALUE) {
                                d.known |= bit;
                                lss_identity_set_field(&d.id, sub - 1, a->v);
                        }
                        if (a->kind == ANSWER_ABORT) {
                                if (!d.aborted)
                                        d.abort_code = a->v;
                                d.aborted |= bit;
                        }
                }
                if (sl->heard)
                        d.source |= LSS_SDO_FROM_HEARD;
                if (d.source)
                        s->nodes[k++] = d;
        }
        m->result.sdo_nodes = s->nodes;
        m->result.n_sdo_nodes = k;
}

/* Node-IDs given up as silent while the pass lost frames are asked again,
 * until each was asked as often as the loss calls for (lss_loss.h): the
 * answers of a device at one may have been lost every time. Through the
 * window, as at first. Whether any was. */
static bool reopen_silent(lss_master *m, lss_sdo_state *s) {
        unsigned asks = lss_loss_asks(&m->loss, 1, FIRST_TRIES);
        bool any = false;
        for (unsigned n = s->first; n <= s->last; n++) {
                sdo_slot *sl = &s->slot[n];
                if (sl->state != SLOT_DONE || !sl->silent || sl->contacts >= asks)
                        continue;
                sl->silent = false;
                sl->state = SLOT_IDLE;
                s->done--;
                any = true;
        }
        if (any) {
                s->next = s->first;
                m->stats.retries++;
        }
        return any;
}

int proc_sdo_discover(lss_master *m) {
        lss_sdo_state *s = m->sdo;

        PT_BEGIN(&s->pc);
        for (;;) {
                /* asking: until every node-ID of the range is done */
                while (s->done < s->total) {
                        fill_window(m, s);
                        step_event(m, next_deadline(s, m->now));
                        PT_YIELD(&s->pc);
                        note_written(m, s);
                        /* frames the transport lost (a void step) cost a retry, nothing else */
                        if (m->step.n_answers > 0)
                                on_frame(m, s, &m->step.answer, m->step.first_at);
                        else
                                on_time(m, s);
                }
                if (reopen_silent(m, s))
                        continue;
                /* a second, slower device's answer to the last requests, and
                 * late ones, may still come: the full wait */
                s->guard_end = m->now + lss_timing_wait(&s->timing, LSS_WAIT_DISCOVERY) +
                               lss_timing_answer_guard(&s->timing);
                while (s->done == s->total && m->now < s->guard_end) {
                        step_event(m, s->guard_end);
                        PT_YIELD(&s->pc);
                        if (m->step.n_answers > 0)
                                on_frame(m, s, &m->step.answer, m->step.first_at);
                }
                if (s->done == s->total)
                        break;
        }
        build_result(m, s);
        if (s->timing.patience_us > m->stats.patience_us)
                m->stats.patience_us = s->timing.patience_us;
        PT_END(&s->pc);
}

static bool params_ok(const lss_sdo_discover_params *p) {
        return lss_node_id_valid(p->first) && lss_node_id_valid(p->last) && p->first <= p->last &&
               p->window <= LSS_SDO_WINDOW_MAX;
}

int sdo_discover_setup(lss_master *m, const lss_sdo_discover_params *p, const bool *only) {
        if (!params_ok(p))
                return -EINVAL;
        if (!m->sdo) {
                m->sdo = malloc(sizeof(*m->sdo));
                if (!m->sdo)
                        return -ENOMEM;
        }
        lss_sdo_state *s = m->sdo;
        memset(s, 0, sizeof(*s));
        s->first = s->next = p->first;
        s->last = p->last;
        s->window = p->window ? p->window : LSS_SDO_WINDOW_DEFAULT;
        s->total = (unsigned) p->last - p->first + 1;
        lss_timing_init(&s->timing, &m->timing.cfg);
        for (unsigned n = 0; n <= LSS_NODE_ID_MAX; n++)
                for (unsigned k = 0; k <= SUBS; k++)
                        s->slot[n].asked_at[k] = NO_TIME;
        for (unsigned n = s->first; only && n <= s->last; n++)
                if (!only[n]) {
                        s->slot[n].state = SLOT_DONE;
                        s->done++;
                }
        return 0;
}

int lss_master_sdo_discover(lss_master *m, const lss_sdo_discover_params *p, uint64_t now) {
        if (!params_ok(p))
                return -EINVAL;
        if (m->running)
                return -EBUSY;
        int r = sdo_discover_setup(m, p, NULL);
        return r < 0 ? r : master_start_procedure(m, proc_sdo_discover, now);
}
