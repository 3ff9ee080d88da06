/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include "can/socketcan.h"

#include <ctype.h>
#include <errno.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <stdlib.h>
#include <string.h>
#include <sys/time.h>

#include "util/time_util.h"

/* Reads that return nothing to the caller (error frames, junk) before recv()
 * yields with 0, so that a flood cannot starve the event loop. The fd stays
 * readable, so a level-triggered poll calls us again. */
#define RECV_BATCH_MAX 64

/* A clock offset sample older than this is not used to bound rx times:
 * slewing (≤ 500 ppm) may have moved the clocks apart by up to 0.5 ms. */
#define OFFSET_SAMPLE_MAX_AGE_US 1000000u

struct socketcan_port {
        char ifname[IFNAMSIZ];
        int fd;                 /* -1 when gone */
        int ifindex;            /* 0 when gone */
        lss_link_state state;
        const can_sys *sys;
        lss_transport_hooks hooks;

        lss_bus_state bus;
        uint32_t events;
        uint64_t rx_dropped, rx_invalid, error_frames;
        uint8_t tx_errors, rx_errors;
        uint32_t ovfl_seen;     /* last SO_RXQ_OVFL count of this socket */
        bool echo;              /* CAN_RAW_RECV_OWN_MSGS is on: our frames come back once sent */

        /* CLOCK_REALTIME - CLOCK_MONOTONIC at the last send/recv, see rx_time() */
        bool have_offset;
        int64_t offset_us;
        uint64_t offset_at_us;
};

/* LSS responses and NMT error control (boot-up/heartbeat) only, and our own
 * LSS requests when the kernel echoes them (tx confirmation). CAN_EFF_FLAG
 * and CAN_RTR_FLAG are part of every mask (and clear in every id), so an
 * extended-ID or remote frame that merely looks like 0x7E4 never matches.
 * 0x701..0x77F is split into aligned power-of-two blocks to match it
 * exactly (0x700, "node 0", is no node). */
#define SFF_DATA(mask) (CAN_EFF_FLAG | CAN_RTR_FLAG | (mask))
static const struct can_filter rx_filters[] = {
        { LSS_COB_SLAVE, SFF_DATA(CAN_SFF_MASK) },
        /* 0x7E5: our own requests back (MSG_CONFIRM), and another master's */
        { LSS_COB_MASTER, SFF_DATA(CAN_SFF_MASK) },
        { 0x701, SFF_DATA(0x7FF) },     /* 0x701 */
        { 0x702, SFF_DATA(0x7FE) },     /* 0x702..0x703 */
        { 0x704, SFF_DATA(0x7FC) },     /* 0x704..0x707 */
        { 0x708, SFF_DATA(0x7F8) },     /* 0x708..0x70F */
        { 0x710, SFF_DATA(0x7F0) },     /* 0x710..0x71F */
        { 0x720, SFF_DATA(0x7E0) },     /* 0x720..0x73F */
        { 0x740, SFF_DATA(0x7C0) },     /* 0x740..0x77F */
        /* SDO responses 0x581..0x5FF: auto-assignment asks whether a node-ID
         * is taken by an SDO upload and listens for the answer */
        { 0x581, SFF_DATA(0x7FF) },
        { 0x582, SFF_DATA(0x7FE) },
        { 0x584, SFF_DATA(0x7FC) },
        { 0x588, SFF_DATA(0x7F8) },
        { 0x590, SFF_DATA(0x7F0) },
        { 0x5A0, SFF_DATA(0x7E0) },
        { 0x5C0, SFF_DATA(0x7C0) },
};

size_t socketcan_filters(const struct can_filter **ret) {
        *ret = rx_filters;
        return sizeof(rx_filters) / sizeof(rx_filters[0]);
}

/* Error classes that change what the daemon may do: bus-off, controller
 * state (warning/passive/active, rx/tx overflow), missing ACK (no other
 * node, or wrong bit rate), restart after bus-off, driver tx timeout.
 * Not CAN_ERR_PROT/BUSERROR: with berr-reporting on they come for every bad
 * bit and can flood the receive queue until real frames are dropped; their
 * effect on fault confinement arrives as CAN_ERR_CRTL anyway. Not LOSTARB:
 * normal on a shared bus. Not CAN_ERR_CNT: drivers tag bus-error frames with it. */
can_err_mask_t socketcan_err_mask(void) {
        return CAN_ERR_TX_TIMEOUT | CAN_ERR_CRTL | CAN_ERR_ACK | CAN_ERR_BUSOFF | CAN_ERR_RESTARTED;
}

bool socketcan_filter_match(const struct can_frame *cf) {
        for (size_t i = 0; i < sizeof(rx_filters) / sizeof(rx_filters[0]); i++)
                if ((cf->can_id & rx_filters[i].can_mask) == (rx_filters[i].can_id & rx_filters[i].can_mask))
                        return true;
        return false;
}

int socketcan_frame_to_can(const lss_frame *f, struct can_frame *cf) {
        if (f->flags & ~(LSS_FRAME_EFF | LSS_FRAME_RTR))
                return -EINVAL; /* FD is never enabled; error frames are the controller's */
        if (f->len > CAN_MAX_DLEN)
                return -EINVAL;
        if (f->id > ((f->flags & LSS_FRAME_EFF) ? CAN_EFF_MASK : CAN_SFF_MASK))
                return -EINVAL;

        memset(cf, 0, sizeof(*cf));
        cf->can_id = f->id;
        if (f->flags & LSS_FRAME_EFF)
                cf->can_id |= CAN_EFF_FLAG;
        cf->len = f->len;
        if (f->flags & LSS_FRAME_RTR)
                cf->can_id |= CAN_RTR_FLAG; /* a remote frame carries no data, only a DLC */
        else
                memcpy(cf->data, f->data, f->len);
        return 0;
}

int socketcan_frame_from_can(const struct can_frame *cf, lss_frame *f) {
        if (cf->can_id & CAN_ERR_FLAG)
                return -EINVAL;
        if (cf->len > CAN_MAX_DLEN)
                return -EINVAL;

        memset(f, 0, sizeof(*f));
        if (cf->can_id & CAN_EFF_FLAG) {
                f->id = cf->can_id & CAN_EFF_MASK;
                f->flags |= LSS_FRAME_EFF;
        } else
                f->id = cf->can_id & CAN_SFF_MASK;
        f->len = cf->len;
        if (cf->can_id & CAN_RTR_FLAG)
                f->flags |= LSS_FRAME_RTR;
        else
                memcpy(f->data, cf->data, cf->len);
        return 0;
}

void socketcan_decode_error(const struct can_frame *cf, lss_bus_state *state, uint32_t *events,
                            uint64_t *dropped, uint8_t *tx_errors, uint8_t *rx_errors) {
        canid_t id = cf->can_id;
        lss_bus_state s = *state;

        /* Error frames always carry CAN_ERR_DLC bytes; data[] is 8 bytes anyway. */
        if (id & CAN_ERR_CRTL) {
                uint8_t d = cf->data[1];

                /* The frame tells the worse of the rx and tx states. */
                if (d & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE))
                        s = LSS_BUS_ERROR_PASSIVE;
                else if (d & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING))
                        s = LSS_BUS_ERROR_WARNING;
                else if (d & CAN_ERR_CRTL_ACTIVE)
                        s = LSS_BUS_ERROR_ACTIVE;
                if (d & CAN_ERR_CRTL_RX_OVERFLOW) {
                        /* The controller does not say how many: at least one. */
                        *events |= LSS_BUS_EVENT_RX_OVERFLOW;
                        (*dropped)++;
                }
                if (d & CAN_ERR_CRTL_TX_OVERFLOW)
                        *events |= LSS_BUS_EVENT_TX_OVERFLOW;
        }
        if (id & CAN_ERR_RESTARTED) {
                s = LSS_BUS_ERROR_ACTIVE;
                *events |= LSS_BUS_EVENT_RESTARTED;
        }
        if (id & CAN_ERR_BUSOFF)
                s = LSS_BUS_OFF;
        if (id & CAN_ERR_ACK)
                *events |= LSS_BUS_EVENT_NO_ACK;
        if (id & CAN_ERR_TX_TIMEOUT)
                *events |= LSS_BUS_EVENT_TX_TIMEOUT;
        if (id & (CAN_ERR_PROT | CAN_ERR_BUSERROR))
                *events |= LSS_BUS_EVENT_PROTOCOL;
        if (id & CAN_ERR_CNT) {
                *tx_errors = cf->data[6];
                *rx_errors = cf->data[7];
        }
        if (s != *state) {
                *state = s;
                *events |= LSS_BUS_EVENT_STATE_CHANGED;
        }
}

/* ---- clock ---- */

static uint64_t clock_us(socketcan_port *p, clockid_t clock) {
        struct timespec ts;

        /* Cannot fail for these clocks; 0 is the safe answer ("long ago")
         * should it ever: frames then look stale, never fresh. */
        if (p->sys->clock_gettime(p->sys->userdata, clock, &ts) < 0)
                return 0;
        return timespec_to_us(&ts);
}

uint64_t socketcan_port_now(socketcan_port *p) {
        return clock_us(p, CLOCK_MONOTONIC);
}

/* Receive time of a frame on CLOCK_MONOTONIC.
 *
 * The kernel stamps a frame when it arrives (SO_TIMESTAMP), but only on
 * CLOCK_REALTIME. We convert with the REALTIME-MONOTONIC offset sampled right
 * now. What the engine needs is that a frame that arrived before its request
 * went out is never stamped after it (the drain rule), so an error may only
 * make a frame look earlier. A realtime step between arrival and now would
 * shift the converted time by the step, so we also convert with the offset
 * sampled at the previous send/recv (recent: every send samples it) and take
 * the earlier of the two: whichever side of the arrival the step fell on, one
 * of them is right and the other is only earlier. Finally nothing can arrive
 * after we read it: clamp to the read time. Without a timestamp the read time
 * is the best upper bound we have. */
/* CLOCK_REALTIME - CLOCK_MONOTONIC, read between two monotonic reads so
 * that a preemption cannot skew it: the narrowest of a few tries wins, and
 * the error is at most half its gap (a wrong offset would make an answer
 * look older than it is, and the engine would drop it as stale). */
static int64_t clock_offset(socketcan_port *p, uint64_t *mono) {
        int64_t best = 0;
        uint64_t best_gap = UINT64_MAX;
        *mono = 0;
        for (int i = 0; i < 4; i++) {
                uint64_t m1 = clock_us(p, CLOCK_MONOTONIC);
                uint64_t r = clock_us(p, CLOCK_REALTIME);
                uint64_t m2 = clock_us(p, CLOCK_MONOTONIC);
                uint64_t gap = m2 >= m1 ? m2 - m1 : 0;
                if (gap < best_gap) {
                        best_gap = gap;
                        best = (int64_t) r - (int64_t) (m1 + gap / 2);
                        *mono = m2;
                }
                if (gap <= 20)
                        break;
        }
        return best;
}

static uint64_t rx_time(socketcan_port *p, const struct timeval *tv) {
        uint64_t mono = 0;
        int64_t offset = clock_offset(p, &mono);
        int64_t t = (int64_t) mono;

        if (tv) {
                int64_t stamp = timeval_to_us(tv);
                t = stamp - offset;
                /* A realtime step between arrival and now would shift the frame;
                 * the sample from the last send/recv (< 1 s old) bounds it: take
                 * the earlier, so a stale frame never looks fresh. */
                if (p->have_offset && mono - p->offset_at_us <= OFFSET_SAMPLE_MAX_AGE_US && stamp - p->offset_us < t)
                        t = stamp - p->offset_us;
                /* never in the future, whatever the clocks did */
                if (t > (int64_t) mono)
                        t = (int64_t) mono;
                if (t < 0)
                        t = 0;
        }
        p->have_offset = true;
        p->offset_us = offset;
        p->offset_at_us = mono;
        return (uint64_t) t;
}

static void sample_offset(socketcan_port *p) {
        (void) rx_time(p, NULL);
}

/* ---- state ---- */

static void set_state(socketcan_port *p, lss_link_state s) {
        lss_link_state old = p->state;

        if (s == old)
                return;
        p->state = s;
        p->events |= LSS_BUS_EVENT_LINK_CHANGED;
        /* A controller that (re)starts is error-active. */
        if (s == LSS_LINK_UP && p->bus != LSS_BUS_ERROR_ACTIVE) {
                p->bus = LSS_BUS_ERROR_ACTIVE;
                p->events |= LSS_BUS_EVENT_STATE_CHANGED;
        }
        if (p->hooks.link_changed)
                p->hooks.link_changed(p->hooks.userdata, old, s);
}

static void go_gone(socketcan_port *p) {
        /* Tell first, with the fd still open, so the caller can drop it from its loop. */
        set_state(p, LSS_LINK_GONE);
        if (p->fd >= 0)
                (void) p->sys->close(p->sys->userdata, p->fd);
        p->fd = -1;
        p->ifindex = 0;
}

/* Maps socket errors to port state. */
static int port_fail(socketcan_port *p, int r) {
        switch (r) {
        case -ENETDOWN:
                set_state(p, LSS_LINK_DOWN);
                return -ENETDOWN;
        case -ENODEV:
        case -ENXIO:
                /* The interface was unregistered: the kernel unbound the socket. */
                go_gone(p);
                return -ENODEV;
        default:
                return r;
        }
}

static int set_opt(socketcan_port *p, int fd, int level, int name, const void *val, socklen_t len) {
        return p->sys->setsockopt(p->sys->userdata, fd, level, name, val, len);
}

/* Opens and binds a socket by name. -ENODEV when there is no such interface. */
static int open_socket(socketcan_port *p) {
        const can_sys *sys = p->sys;
        const struct can_filter *filters;
        size_t n_filters = socketcan_filters(&filters);
        can_err_mask_t err_mask = socketcan_err_mask();
        const int one = 1;
        unsigned flags = IFF_UP | IFF_RUNNING;
        int idx, fd, r;

        idx = sys->if_nametoindex(sys->userdata, p->ifname);
        if (idx == -ENXIO)
                idx = -ENODEV;
        if (idx < 0)
                return idx;
        if (idx == 0)
                return -ENODEV;

        /* Non-blocking: the daemon's event loop must never sleep in read()
         * or write(); a full tx queue is the caller's to wait out. */
        fd = sys->socket(sys->userdata, PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
        if (fd < 0)
                return fd;

        /* Filters before bind: a bound socket with the default filter
         * (everything) would queue unwanted frames until the filter is set. */
        r = set_opt(p, fd, SOL_CAN_RAW, CAN_RAW_FILTER, filters, (socklen_t) (n_filters * sizeof(*filters)));
        if (r < 0)
                goto fail;
        /* Error frames are opt-in; without them bus-off and missing ACKs are invisible. */
        r = set_opt(p, fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof(err_mask));
        if (r < 0)
                goto fail;
        /* Every received message then carries the socket's drop counter: a
         * full receive queue loses frames silently otherwise. */
        r = set_opt(p, fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof(one));
        if (r < 0)
                goto fail;
        /* Arrival time stamped by the kernel, not when we got round to reading. */
        r = set_opt(p, fd, SOL_SOCKET, SO_TIMESTAMP, &one, sizeof(one));
        if (r < 0)
                goto fail;
        /* Our own frames come back (flagged MSG_CONFIRM) when the controller
         * has sent them: the one sure sign that a request is on the wire, in
         * the same queue as the answers. Without it (never seen) the engine
         * falls back to the estimated wire time. */
        p->echo = set_opt(p, fd, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &one, sizeof(one)) >= 0;
        /* CAN_RAW_FD_FRAMES stays off: only classic 16-byte frames can arrive.
         * CAN_RAW_LOOPBACK stays on: on vcan, other local sockets (lss-sim,
         * candump) only see our frames through it, and the echo needs it. */

        r = sys->if_flags(sys->userdata, fd, p->ifname, &flags);
        if (r == -ENODEV || r == -ENXIO)
                goto fail_gone;
        /* Any other failure: assume up, the first send tells. */

        {
                struct sockaddr_can addr = { .can_family = AF_CAN, .can_ifindex = idx };

                /* Bind last: from here on frames are queued, filtered. */
                r = sys->bind(sys->userdata, fd, (const struct sockaddr *) &addr, sizeof(addr));
                if (r == -ENODEV || r == -ENXIO)
                        goto fail_gone;
                if (r < 0)
                        goto fail;
        }

        p->fd = fd;
        p->ifindex = idx;
        p->ovfl_seen = 0;
        set_state(p, (flags & IFF_UP) && (flags & IFF_RUNNING) ? LSS_LINK_UP : LSS_LINK_DOWN);
        return 0;

fail_gone:
        r = -ENODEV;
fail:
        (void) sys->close(sys->userdata, fd);
        return r;
}

int socketcan_port_reopen(socketcan_port *p) {
        go_gone(p);
        return open_socket(p);
}

/* The kernel's rules for netdev names (dev_valid_name). */
static bool ifname_valid(const char *name, size_t len) {
        if (len == 0 || len >= IFNAMSIZ || strcmp(name, ".") == 0 || strcmp(name, "..") == 0)
                return false;
        for (size_t i = 0; i < len; i++)
                if (name[i] == '/' || name[i] == ':' || isspace((unsigned char) name[i]))
                        return false;
        return true;
}

int socketcan_port_open(const char *ifname, const socketcan_config *cfg, socketcan_port **ret) {
        socketcan_port *p;
        size_t len;
        int r;

        if (!ifname || !ret)
                return -EINVAL;
        len = strlen(ifname);
        if (!ifname_valid(ifname, len))
                return -EINVAL;

        p = calloc(1, sizeof(*p));
        if (!p)
                return -ENOMEM;
        memcpy(p->ifname, ifname, len + 1);
        p->fd = -1;
        p->state = LSS_LINK_GONE;
        p->sys = cfg && cfg->sys ? cfg->sys : can_sys_default();

        r = open_socket(p);
        if (r < 0 && r != -ENODEV) {
                free(p);
                return r;
        }
        p->events = 0; /* the caller reads the initial state; nothing happened yet */
        /* Set only now: nobody is listening to the initial open. */
        if (cfg) {
                p->hooks = cfg->hooks;
        }
        *ret = p;
        return 0;
}

bool socketcan_kernel_has_can(const can_sys *sys) {
        if (!sys)
                sys = can_sys_default();
        int fd = sys->socket(sys->userdata, PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
        if (fd >= 0)
                (void) sys->close(sys->userdata, fd);
        /* only a missing address family says "no CAN"; anything else (fd limits) is not our business here */
        return fd != -EAFNOSUPPORT && fd != -EPROTONOSUPPORT;
}

socketcan_port *socketcan_port_free(socketcan_port *p) {
        if (!p)
                return NULL;
        if (p->fd >= 0)
                (void) p->sys->close(p->sys->userdata, p->fd);
        free(p);
        return NULL;
}

int socketcan_port_link_event(socketcan_port *p, int ifindex, const char *ifname, bool present, unsigned flags) {
        bool has_name = ifname && *ifname;
        bool by_name = has_name && strcmp(ifname, p->ifname) == 0;
        bool by_index = p->fd >= 0 && ifindex > 0 && ifindex == p->ifindex;
        lss_link_state before = p->state;
        int before_fd = p->fd, r;

        if (!present || (has_name && !by_name)) {
                /* Deleted, or renamed away: that netdev is no longer ours. */
                if (!by_index)
                        return 0;
                go_gone(p);
                return 1;
        }
        if (!by_name && !by_index)
                return 0; /* nameless event about another netdev */
        if (by_name && (p->fd < 0 || ifindex != p->ifindex)) {
                /* Appeared, or a new netdev took our name: bind to it. */
                r = socketcan_port_reopen(p);
                if (r == -ENODEV) /* gone again already */
                        return p->state != before || before_fd >= 0;
                if (r < 0)
                        return r;
        }
        bool up = (flags & IFF_UP) && (flags & IFF_RUNNING);
        if (up && before != LSS_LINK_UP && p->fd >= 0 && p->fd == before_fd) {
                /* A CAN_RAW socket bound (or left) while its interface was down
                 * carries a pending ENETDOWN that the next send or recv would
                 * report although the link is up now: start with a fresh one. */
                r = socketcan_port_reopen(p);
                if (r == -ENODEV)
                        return 1;
                if (r < 0)
                        return r;
        }
        set_state(p, up ? LSS_LINK_UP : LSS_LINK_DOWN);
        return p->state != before || p->fd != before_fd;
}

/* ---- send ---- */

/* Never waits: a full tx queue (ENOBUFS from the device queue, EAGAIN from
 * the socket buffer) is -EAGAIN with nothing sent, and the caller writes the
 * same frame again later from its event loop. */
int socketcan_port_send(socketcan_port *p, const lss_frame *f) {
        struct can_frame cf;
        int r;

        r = socketcan_frame_to_can(f, &cf);
        if (r < 0)
                return r;
        if (p->fd < 0)
                return -ENODEV;

        for (;;) {
                ssize_t n = p->sys->write(p->sys->userdata, p->fd, &cf, CAN_MTU);

                if (n == CAN_MTU) {
                        /* It went out, so the link is up whatever we heard last. */
                        if (p->state == LSS_LINK_DOWN)
                                set_state(p, LSS_LINK_UP);
                        sample_offset(p);
                        return 0;
                }
                if (n >= 0)
                        return -EIO; /* CAN_RAW takes a frame whole or not at all */
                if (n == -EINTR)
                        continue; /* nothing was queued */
                if (n == -ENOBUFS || n == -EAGAIN)
                        return -EAGAIN;
                return port_fail(p, (int) n);
        }
}

/* ---- receive ---- */

static void account_drops(socketcan_port *p, uint32_t count) {
        /* The kernel counter is cumulative per socket and wraps. */
        uint32_t delta = count - p->ovfl_seen;

        p->ovfl_seen = count;
        p->rx_dropped += delta;
}

int socketcan_port_recv(socketcan_port *p, lss_frame *f, uint64_t *rx_us) {
        if (p->fd < 0)
                return -ENODEV;

        for (unsigned i = 0; i < RECV_BATCH_MAX; i++) {
                struct can_frame cf;
                struct iovec iov = { .iov_base = &cf, .iov_len = sizeof(cf) };
                union {
                        char buf[CMSG_SPACE(sizeof(struct timeval)) + CMSG_SPACE(sizeof(uint32_t))];
                        struct cmsghdr align;
                } control;
                struct msghdr msg = {
                        .msg_iov = &iov,
                        .msg_iovlen = 1,
                        .msg_control = control.buf,
                        .msg_controllen = sizeof(control.buf),
                };
                struct timeval tv;
                bool have_tv = false;
                ssize_t n;

                memset(&control, 0, sizeof(control));
                n = p->sys->recvmsg(p->sys->userdata, p->fd, &msg, MSG_DONTWAIT);
                if (n == -EAGAIN || n == -EWOULDBLOCK)
                        return 0;
                if (n == -EINTR)
                        continue;
                if (n < 0)
                        return port_fail(p, (int) n);

                for (struct cmsghdr *c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c)) {
                        if (c->cmsg_level != SOL_SOCKET)
                                continue;
                        if (c->cmsg_type == SO_TIMESTAMP && c->cmsg_len >= CMSG_LEN(sizeof(tv))) {
                                memcpy(&tv, CMSG_DATA(c), sizeof(tv));
                                have_tv = true;
                        } else if (c->cmsg_type == SO_RXQ_OVFL && c->cmsg_len >= CMSG_LEN(sizeof(uint32_t))) {
                                uint32_t count;

                                memcpy(&count, CMSG_DATA(c), sizeof(count));
                                account_drops(p, count);
                        }
                }

                /* Only whole classic frames: never trust a length we did not ask for. */
                if (n != CAN_MTU || (msg.msg_flags & MSG_TRUNC)) {
                        p->rx_invalid++;
                        continue;
                }
                if (cf.can_id & CAN_ERR_FLAG) {
                        p->error_frames++;
                        socketcan_decode_error(&cf, &p->bus, &p->events, &p->rx_dropped, &p->tx_errors, &p->rx_errors);
                        continue;
                }
                /* The kernel filter keeps these out; a second check costs nothing. */
                if (!socketcan_filter_match(&cf) || socketcan_frame_from_can(&cf, f) < 0) {
                        p->rx_invalid++;
                        continue;
                }
                /* Our own request back from the controller carries MSG_CONFIRM;
                 * one without it is another sender's (a second master, a
                 * tool): it comes out as it is, for the caller to notice
                 * (lss_is_foreign_request()). */
                if (f->id == LSS_COB_MASTER && !(f->flags & LSS_FRAME_EFF) && (msg.msg_flags & MSG_CONFIRM))
                        f->flags |= LSS_FRAME_ECHO;
                if (rx_us)
                        *rx_us = rx_time(p, have_tv ? &tv : NULL);
                return 1;
        }
        return 0;
}

int socketcan_port_fd(const socketcan_port *p) {
        return p->fd;
}

void socketcan_port_status(socketcan_port *p, lss_transport_status *st) {
        *st = (lss_transport_status) {
                .link = p->state,
                .bus = p->bus,
                .events = p->events,
                .rx_dropped = p->rx_dropped,
                .rx_invalid = p->rx_invalid,
                .error_frames = p->error_frames,
                .tx_errors = p->tx_errors,
                .rx_errors = p->rx_errors,
                .tx_echo = socketcan_port_echoes(p),
        };
        p->events = 0;
}

bool socketcan_port_echoes(const socketcan_port *p) {
        return p->echo && p->fd >= 0;
}

lss_link_state socketcan_port_state(const socketcan_port *p) {
        return p->state;
}

const char *socketcan_port_ifname(const socketcan_port *p) {
        return p->ifname;
}

int socketcan_port_ifindex(const socketcan_port *p) {
        return p->ifindex;
}

const can_sys *socketcan_port_sys(const socketcan_port *p) {
        return p->sys;
}
