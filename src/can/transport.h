/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The transport seam: how the daemon drives one CAN bus, whatever is behind it
 * (a SocketCAN port in production, the in-memory bus in tests).
 *
 * Contract every implementation keeps:
 *  - send() puts one frame on the bus, or returns an error having sent nothing:
 *    never drops, reorders or duplicates, and never blocks. Errors: -EAGAIN
 *    (tx queue full: send the same frame again later; how long to keep
 *    trying is the caller's choice), -ENETDOWN (link down: fail the
 *    transaction, the transport works again once the link is up), -ENODEV
 *    (interface gone: the transport re-opens it by name later), -EINVAL
 *    (frame not sendable).
 *  - recv() returns 1 with one frame and its receive time, 0 when nothing is
 *    pending, <0 on error (same codes as send). Frames arrive in bus order.
 *    Error frames never come out of recv(): they update the status.
 *    When status() says tx_echo, recv() also returns each frame we sent,
 *    flagged LSS_FRAME_ECHO, in its place among the received frames once
  *    the controller has put it on the wire (tx confirmation). LSS requests
 *    (0x7E5) of other senders come out too, unflagged: another master on
 *    the bus, which the caller must notice (lss_is_foreign_request()).
 *  - rx times and now() are the same clock (CLOCK_MONOTONIC µs, or the
 *    virtual clock of a simulated bus). An rx time is never later than the
 *    moment the frame was really received, so the engine's drain rule
 *    ("ignore frames received before my request was sent") never takes a
 *    stale frame for an answer.
 *  - get_fd() is a pollable fd (POLLIN: call recv() until it returns 0), or
 *    -1 when there is none (simulated bus, or a port whose interface is gone).
 *    The fd changes when a port is re-opened: callers re-query it after any
 *    -ENODEV and after the link comes back.
 *  - status() fills a snapshot and clears its `events`. A step of the engine
 *    that saw rx_dropped change lost frames: its result is invalid.
 *    status may be NULL in an implementation that never loses frames.
 *  - link() is the link state now (NULL: always up); an implementation
 *    whose link can change tells its user through the hooks it was opened
 *    with, the fd still open during the call when the new state is "gone".
 *  - echoes(): recv() hands back our sent frames (NULL: never).
 *  - next_event(): an implementation without an fd says when recv() has
 *    something next (same clock as now(); UINT64_MAX: nothing; NULL: never).
 *  - link_event() takes every rtnetlink link event (any interface: the
 *    implementation picks its own): 1 when its state or fd changed, 0 when
 *    not, <0 when a re-open failed; NULL: the links of the host do not
 *    matter to it.
 *  - retune_start() begins putting the host's controller on another bit
 *    rate (SetBitrate) and never blocks: 1 done already, 0 running, -EOPNOTSUPP
 *    nothing to retune, other <0 failed. While running, the caller calls
 *    retune_step() when wait->fd is readable (POLLIN) or at wait->deadline
 *    (same clock as now()), which answers the same way (wait refilled on
 *    0). After the end the fd of the bus may have changed. NULL: none.
 *  - retune_caused(): whether the retune made this change of link() (it
 *    took the link down and up: those changes are its own, each once,
 *    whenever they are reported). NULL: never.
 *  - close() frees the implementation.
 */
#pragma once

#include <errno.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "lss/lss_proto.h"

typedef enum lss_link_state {
        LSS_LINK_UP = 0,   /* interface up and running: frames go out */
        LSS_LINK_DOWN,     /* interface exists but is down (or has no carrier) */
        LSS_LINK_GONE,     /* no such interface (yet, or any more) */
        _LSS_LINK_STATE_MAX,
} lss_link_state;

/* Controller fault confinement state, from error frames. */
typedef enum lss_bus_state {
        LSS_BUS_ERROR_ACTIVE = 0,
        LSS_BUS_ERROR_WARNING,  /* an error counter passed 96: still works */
        LSS_BUS_ERROR_PASSIVE,  /* an error counter passed 127 */
        LSS_BUS_OFF,            /* tx error counter passed 255: controller silent */
        _LSS_BUS_STATE_MAX,
} lss_bus_state;

/* Things error frames reported since the previous status() call. */
#define LSS_BUS_EVENT_NO_ACK        (1u << 0) /* our frame got no ACK: nobody else on the bus (or wrong rate) */
#define LSS_BUS_EVENT_RESTARTED     (1u << 1) /* controller restarted after bus-off */
#define LSS_BUS_EVENT_TX_TIMEOUT    (1u << 2) /* driver could not send within its timeout */
#define LSS_BUS_EVENT_PROTOCOL      (1u << 3) /* bit/stuff/form errors: wiring or bit-rate mismatch */
#define LSS_BUS_EVENT_RX_OVERFLOW   (1u << 4) /* controller lost received frames (also counted in rx_dropped) */
#define LSS_BUS_EVENT_TX_OVERFLOW   (1u << 5) /* controller lost frames we sent */
#define LSS_BUS_EVENT_STATE_CHANGED (1u << 6) /* `bus` changed */
#define LSS_BUS_EVENT_LINK_CHANGED  (1u << 7) /* `link` changed */

typedef struct lss_transport_status {
        lss_link_state link;
        lss_bus_state bus;
        uint32_t events;        /* LSS_BUS_EVENT_*, cleared by each status() */
        uint64_t rx_dropped;    /* frames lost before we read them (socket queue or controller), cumulative */
        uint64_t rx_invalid;    /* reads ignored: bad length, DLC > 8, frames the filter should have kept out */
        uint64_t error_frames;  /* error frames received, cumulative */
        uint8_t tx_errors;      /* controller error counters, when the driver reports them */
        uint8_t rx_errors;
        bool tx_echo;           /* recv() returns our sent frames flagged LSS_FRAME_ECHO */
} lss_transport_status;

/* One rtnetlink link event, as link_event() takes it. */
typedef struct lss_link_event {
        int ifindex;
        const char *ifname;     /* "" if the message had none */
        bool present;           /* false for RTM_DELLINK */
        unsigned flags;         /* IFF_* */
} lss_link_event;

/* What a running retune waits for. */
typedef struct lss_retune_wait {
        int fd;                 /* POLLIN, or -1: the deadline only */
        uint64_t deadline;      /* same clock as now() */
} lss_retune_wait;

/* What an implementation tells its user. */
typedef struct lss_transport_hooks {
        void (*link_changed)(void *userdata, lss_link_state old_state, lss_link_state new_state);
        void *userdata;
} lss_transport_hooks;

typedef struct lss_transport_ops {
        const char *kind;       /* for people: "SocketCAN", "simulated" */
        int (*send)(void *impl, const lss_frame *f);
        int (*recv)(void *impl, lss_frame *f, uint64_t *rx_us);
        int (*get_fd)(void *impl);
        uint64_t (*now)(void *impl);
        int (*status)(void *impl, lss_transport_status *st); /* optional */
        lss_link_state (*link)(void *impl);                    /* optional */
        bool (*echoes)(void *impl);                            /* optional */
        uint64_t (*next_event)(void *impl);                    /* optional */
        int (*link_event)(void *impl, const lss_link_event *ev); /* optional */
        int (*retune_start)(void *impl, uint32_t bitrate, lss_retune_wait *wait); /* optional */
        int (*retune_step)(void *impl, lss_retune_wait *wait);  /* with retune_start */
        bool (*retune_caused)(void *impl, lss_link_state new_state); /* optional */
        void (*close)(void *impl);
} lss_transport_ops;

typedef struct lss_transport {
        const lss_transport_ops *ops;
        void *impl;
} lss_transport;

static inline int lss_transport_send(lss_transport *t, const lss_frame *f) {
        return t->ops->send(t->impl, f);
}

static inline int lss_transport_recv(lss_transport *t, lss_frame *f, uint64_t *rx_us) {
        return t->ops->recv(t->impl, f, rx_us);
}

static inline int lss_transport_get_fd(lss_transport *t) {
        return t->ops->get_fd ? t->ops->get_fd(t->impl) : -1;
}

static inline uint64_t lss_transport_now(lss_transport *t) {
        return t->ops->now(t->impl);
}

/* Implementations without status() are always up, error-active and lossless. */
static inline int lss_transport_status_get(lss_transport *t, lss_transport_status *st) {
        if (t->ops->status)
                return t->ops->status(t->impl, st);
        memset(st, 0, sizeof(*st));
        return 0;
}

static inline lss_link_state lss_transport_link(lss_transport *t) {
        return t->ops->link ? t->ops->link(t->impl) : LSS_LINK_UP;
}

static inline bool lss_transport_echoes(lss_transport *t) {
        return t->ops->echoes && t->ops->echoes(t->impl);
}

static inline uint64_t lss_transport_next_event(lss_transport *t) {
        return t->ops->next_event ? t->ops->next_event(t->impl) : UINT64_MAX;
}

/* -EOPNOTSUPP when link events do not matter to the implementation. */
static inline int lss_transport_link_event(lss_transport *t, const lss_link_event *ev) {
        return t->ops->link_event ? t->ops->link_event(t->impl, ev) : -EOPNOTSUPP;
}

static inline int lss_transport_retune_start(lss_transport *t, uint32_t bitrate, lss_retune_wait *wait) {
        return t->ops->retune_start ? t->ops->retune_start(t->impl, bitrate, wait) : -EOPNOTSUPP;
}

static inline int lss_transport_retune_step(lss_transport *t, lss_retune_wait *wait) {
        return t->ops->retune_step(t->impl, wait);
}

static inline bool lss_transport_retune_caused(lss_transport *t, lss_link_state new_state) {
        return t->ops->retune_caused && t->ops->retune_caused(t->impl, new_state);
}

/* Frees the implementation; safe on a closed (zeroed) transport. */
static inline void lss_transport_close(lss_transport *t) {
        if (t->ops && t->ops->close)
                t->ops->close(t->impl);
        t->ops = NULL;
        t->impl = NULL;
}

/* "up", "down", "gone"; NULL if out of range. */
const char *lss_link_state_to_string(lss_link_state s);
/* "error-active", "error-warning", "error-passive", "bus-off"; NULL if out of range. */
const char *lss_bus_state_to_string(lss_bus_state s);
