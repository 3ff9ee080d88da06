/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* A scripted fake kernel for the rtnetlink code (test-rtnl.c,
 * test-rtnl-retune.c): kernel-like messages built with libmnl, and a can_sys
 * whose NETLINK_ROUTE sockets answer our requests by a few rules of the real
 * kernel. With NF.later set, replies are held back until nf_release(): a
 * kernel that answers only later. */
#pragma once

#include <check.h>
#include <errno.h>
#include <libmnl/libmnl.h>
#include <linux/can/netlink.h>
#include <linux/if_link.h>
#include <linux/rtnetlink.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "can/rtnl_watch.h"
#include "util/time_util.h"

/* ---- building kernel-like messages with libmnl ---- */

typedef struct link_spec {
        uint16_t type;          /* RTM_NEWLINK / RTM_DELLINK */
        int ifindex;
        unsigned flags;
        const char *name;       /* NULL: no IFLA_IFNAME */
        const char *kind;       /* NULL: no IFLA_LINKINFO */
        uint32_t bitrate;       /* with kind: IFLA_INFO_DATA/IFLA_CAN_BITTIMING if non-zero */
        bool data_first;        /* IFLA_INFO_DATA before IFLA_INFO_KIND */
} link_spec;

static inline size_t put_link(void *buf, size_t size, const link_spec *ls, uint32_t seq, uint16_t nlflags) {
        struct nlmsghdr *nlh = mnl_nlmsg_put_header(buf);
        struct ifinfomsg *ifi;

        nlh->nlmsg_type = ls->type;
        nlh->nlmsg_flags = nlflags;
        nlh->nlmsg_seq = seq;
        ifi = mnl_nlmsg_put_extra_header(nlh, sizeof(*ifi));
        ifi->ifi_family = AF_UNSPEC;
        ifi->ifi_index = ls->ifindex;
        ifi->ifi_flags = ls->flags;
        mnl_attr_put_u32(nlh, IFLA_MTU, 16);
        if (ls->name)
                mnl_attr_put_strz(nlh, IFLA_IFNAME, ls->name);
        if (ls->kind) {
                struct nlattr *info = mnl_attr_nest_start(nlh, IFLA_LINKINFO);
                if (!ls->data_first)
                        mnl_attr_put_strz(nlh, IFLA_INFO_KIND, ls->kind);
                if (ls->bitrate) {
                        struct nlattr *data = mnl_attr_nest_start(nlh, IFLA_INFO_DATA);
                        struct can_bittiming bt = { .bitrate = ls->bitrate, .sample_point = 875, .brp = 4 };
                        mnl_attr_put_u32(nlh, IFLA_CAN_RESTART_MS, 100);
                        mnl_attr_put(nlh, IFLA_CAN_BITTIMING, sizeof(bt), &bt);
                        mnl_attr_nest_end(nlh, data);
                }
                if (ls->data_first)
                        mnl_attr_put_strz(nlh, IFLA_INFO_KIND, ls->kind);
                mnl_attr_nest_end(nlh, info);
        }
        mnl_attr_put_u32(nlh, IFLA_TXQLEN, 10);
        ck_assert_uint_le(nlh->nlmsg_len, size);
        return nlh->nlmsg_len;
}

static inline size_t put_done(void *buf, uint32_t seq, int err) {
        struct nlmsghdr *nlh = mnl_nlmsg_put_header(buf);
        int *e;

        nlh->nlmsg_type = NLMSG_DONE;
        nlh->nlmsg_flags = NLM_F_MULTI;
        nlh->nlmsg_seq = seq;
        e = mnl_nlmsg_put_extra_header(nlh, sizeof(int));
        *e = err;
        return nlh->nlmsg_len;
}

static inline size_t put_error(void *buf, uint32_t seq, int err) {
        struct nlmsghdr *nlh = mnl_nlmsg_put_header(buf);
        struct nlmsgerr *e;

        nlh->nlmsg_type = NLMSG_ERROR;
        nlh->nlmsg_seq = seq;
        e = mnl_nlmsg_put_extra_header(nlh, sizeof(*e));
        e->error = err;
        e->msg.nlmsg_seq = seq;
        return nlh->nlmsg_len;
}


typedef struct req_attrs {
        const struct nlattr *tb[IFLA_MAX + 1];
} req_attrs;

static inline int req_attr_cb(const struct nlattr *a, void *data) {
        req_attrs *ra = data;
        if (mnl_attr_get_type(a) <= IFLA_MAX)
                ra->tb[mnl_attr_get_type(a)] = a;
        return MNL_CB_OK;
}

static inline int nest_cb(const struct nlattr *a, void *data) {
        const struct nlattr **tb = data;
        if (mnl_attr_get_type(a) < 16)
                tb[mnl_attr_get_type(a)] = a;
        return MNL_CB_OK;
}

/* ---- fake kernel ---- */

#define MAX_Q 400
#define MAX_FDS 4
#define FD_BASE 100

typedef struct dgram {
        ssize_t err;            /* <0: recvmsg returns this instead */
        uint32_t pid;           /* sender port id, 0 = kernel */
        size_t len;
        char *data;
} dgram;

typedef struct fake_link {
        int ifindex;
        char name[IFNAMSIZ];
        const char *kind;
        uint32_t bitrate;
        unsigned flags;
} fake_link;

typedef struct nlfake {
        struct {
                bool open;
                unsigned groups;
                dgram q[MAX_Q];
                size_t head, tail;
                size_t shown;   /* with `later`: replies before this are readable */
        } fds[MAX_FDS];
        fake_link links[8];
        size_t n_links;
        int socket_err, bind_err, write_err, poll_err;
        unsigned socket_fail_after; /* sockets allowed before -EMFILE; 0 = any number */
        ssize_t write_short;
        bool mute;              /* never answer */
        int fail_newlink_with;  /* error for every RTM_NEWLINK */
        char ops[512];          /* what the requests did, in order */
        uint64_t mono_us;
        bool later;             /* hold replies back until nf_release() */
        unsigned n_sockets, n_closes, n_requests, n_polls;
} nlfake;

static nlfake NF;

static inline void nf_push(int fd, ssize_t err, uint32_t pid, const void *data, size_t len) {
        int i = fd - FD_BASE;
        ck_assert(i >= 0 && i < MAX_FDS && NF.fds[i].open);
        ck_assert_uint_lt(NF.fds[i].tail, MAX_Q);
        dgram *d = &NF.fds[i].q[NF.fds[i].tail++];
        d->err = err;
        d->pid = pid;
        d->len = len;
        d->data = NULL;
        if (len) {
                d->data = malloc(len);
                memcpy(d->data, data, len);
        }
}

static inline void nf_drop_queue(int i) {
        while (NF.fds[i].head < NF.fds[i].tail)
                free(NF.fds[i].q[NF.fds[i].head++].data);
        NF.fds[i].head = NF.fds[i].tail = NF.fds[i].shown = 0;
}

static inline void nf_reset(void) {
        for (int i = 0; i < MAX_FDS; i++)
                nf_drop_queue(i);
        memset(&NF, 0, sizeof(NF));
        NF.mono_us = 5000000;
}

static inline void nf_add_link(int ifindex, const char *name, const char *kind, uint32_t bitrate, unsigned flags) {
        fake_link *l = &NF.links[NF.n_links++];
        l->ifindex = ifindex;
        snprintf(l->name, sizeof(l->name), "%s", name);
        l->kind = kind;
        l->bitrate = bitrate;
        l->flags = flags;
}

static inline size_t put_fake_link(char *buf, size_t size, const fake_link *l, uint32_t seq, uint16_t flags) {
        link_spec ls = { RTM_NEWLINK, l->ifindex, l->flags, l->name, l->kind,
                         l->kind && strcmp(l->kind, "can") == 0 ? l->bitrate : 0, false };
        return put_link(buf, size, &ls, seq, flags);
}

static inline int nf_socket(void *ud, int domain, int type, int protocol) {
        ck_assert_int_eq(domain, AF_NETLINK);
        ck_assert_int_eq(protocol, NETLINK_ROUTE);
        ck_assert(type & SOCK_CLOEXEC);
        if (NF.socket_err)
                return NF.socket_err;
        if (NF.socket_fail_after && NF.n_sockets >= NF.socket_fail_after)
                return -EMFILE;
        for (int i = 0; i < MAX_FDS; i++)
                if (!NF.fds[i].open) {
                        NF.fds[i].open = true;
                        NF.fds[i].groups = 0;
                        NF.n_sockets++;
                        return FD_BASE + i;
                }
        ck_abort_msg("too many fake sockets");
        return -EMFILE;
}

static inline int nf_setsockopt(void *ud, int fd, int level, int name, const void *val, socklen_t len) {
        return 0;
}

static inline int nf_bind(void *ud, int fd, const struct sockaddr *sa, socklen_t len) {
        const struct sockaddr_nl *nl = (const struct sockaddr_nl *) sa;
        ck_assert_uint_eq(len, sizeof(*nl));
        ck_assert_int_eq(nl->nl_family, AF_NETLINK);
        ck_assert_uint_eq(nl->nl_pid, 0);
        if (NF.bind_err)
                return NF.bind_err;
        NF.fds[fd - FD_BASE].groups = nl->nl_groups;
        return 0;
}

static inline fake_link *nf_find(int ifindex, const char *name) {
        for (size_t i = 0; i < NF.n_links; i++)
                if ((ifindex > 0 && NF.links[i].ifindex == ifindex) || (ifindex <= 0 && name && strcmp(NF.links[i].name, name) == 0))
                        return &NF.links[i];
        return NULL;
}

static inline void nf_ack(int fd, uint32_t seq, int err) {
        char b[128];
        size_t n = put_error(b, seq, err);
        nf_push(fd, 0, 0, b, n);
}

static inline void nf_op(const char *what, unsigned rate) {
        size_t l = strlen(NF.ops);
        if (rate)
                snprintf(NF.ops + l, sizeof(NF.ops) - l, "%s=%u ", what, rate);
        else
                snprintf(NF.ops + l, sizeof(NF.ops) - l, "%s ", what);
}

/* A few rtnetlink rules of the real kernel, enough for our requests. */
static inline ssize_t nf_write(void *ud, int fd, const void *buf, size_t len) {
        const struct nlmsghdr *nlh = buf;
        const struct ifinfomsg *ifi = mnl_nlmsg_get_payload(nlh);
        req_attrs ra = {};
        char out[4096];
        fake_link *l;

        if (NF.write_err)
                return NF.write_err;
        if (NF.write_short)
                return NF.write_short;
        NF.n_requests++;
        ck_assert(mnl_nlmsg_ok(nlh, (int) len));
        ck_assert_uint_eq(nlh->nlmsg_len, len);
        ck_assert(nlh->nlmsg_flags & NLM_F_REQUEST);
        if (NF.mute)
                return (ssize_t) len;
        ck_assert_int_ge(mnl_attr_parse(nlh, sizeof(*ifi), req_attr_cb, &ra), 0);

        if (nlh->nlmsg_type == RTM_GETLINK && (nlh->nlmsg_flags & NLM_F_DUMP) == NLM_F_DUMP) {
                /* two links per datagram, then DONE on its own */
                for (size_t i = 0; i < NF.n_links; i += 2) {
                        size_t n = put_fake_link(out, sizeof(out), &NF.links[i], nlh->nlmsg_seq, NLM_F_MULTI);
                        if (i + 1 < NF.n_links)
                                n += put_fake_link(out + n, sizeof(out) - n, &NF.links[i + 1], nlh->nlmsg_seq, NLM_F_MULTI);
                        nf_push(fd, 0, 0, out, n);
                }
                nf_push(fd, 0, 0, out, put_done(out, nlh->nlmsg_seq, 0));
                return (ssize_t) len;
        }
        l = nf_find(ifi->ifi_index, ra.tb[IFLA_IFNAME] ? mnl_attr_get_str(ra.tb[IFLA_IFNAME]) : NULL);
        if (!l) {
                nf_ack(fd, nlh->nlmsg_seq, -ENODEV);
                return (ssize_t) len;
        }
        if (nlh->nlmsg_type == RTM_GETLINK) {
                nf_push(fd, 0, 0, out, put_fake_link(out, sizeof(out), l, nlh->nlmsg_seq, 0));
                if (nlh->nlmsg_flags & NLM_F_ACK)
                        nf_ack(fd, nlh->nlmsg_seq, 0);
                return (ssize_t) len;
        }
        ck_assert_uint_eq(nlh->nlmsg_type, RTM_NEWLINK);
        ck_assert(nlh->nlmsg_flags & NLM_F_ACK);
        if (NF.fail_newlink_with) {
                nf_ack(fd, nlh->nlmsg_seq, NF.fail_newlink_with);
                return (ssize_t) len;
        }
        if (ra.tb[IFLA_LINKINFO]) {
                const struct nlattr *info[16] = {}, *data[16] = {};
                struct can_bittiming bt;

                ck_assert_int_ge(mnl_attr_parse_nested(ra.tb[IFLA_LINKINFO], nest_cb, info), 0);
                ck_assert_str_eq(mnl_attr_get_str(info[IFLA_INFO_KIND]), l->kind);
                ck_assert_int_ge(mnl_attr_parse_nested(info[IFLA_INFO_DATA], nest_cb, data), 0);
                memcpy(&bt, mnl_attr_get_payload(data[IFLA_CAN_BITTIMING]), sizeof(bt));
                if (l->flags & IFF_UP) {
                        nf_ack(fd, nlh->nlmsg_seq, -EBUSY);
                        nf_op("busy", 0);
                        return (ssize_t) len;
                }
                if (bt.bitrate == 12345) { /* no such rate on this controller */
                        nf_ack(fd, nlh->nlmsg_seq, -EINVAL);
                        nf_op("refused", 0);
                        return (ssize_t) len;
                }
                l->bitrate = bt.bitrate;
                nf_op("rate", bt.bitrate);
        }
        if (ifi->ifi_change & IFF_UP) {
                l->flags = (l->flags & ~IFF_UP) | (ifi->ifi_flags & IFF_UP);
                nf_op(ifi->ifi_flags & IFF_UP ? "up" : "down", 0);
        }
        nf_ack(fd, nlh->nlmsg_seq, 0);
        return (ssize_t) len;
}

static inline ssize_t nf_recvmsg(void *ud, int fd, struct msghdr *msg, int flags) {
        int i = fd - FD_BASE;
        dgram *d;
        size_t n;

        ck_assert(flags & MSG_DONTWAIT);
        if (NF.fds[i].head == (NF.later ? NF.fds[i].shown : NF.fds[i].tail))
                return -EAGAIN;
        d = &NF.fds[i].q[NF.fds[i].head++];
        if (d->err < 0) {
                free(d->data);
                return d->err;
        }
        n = d->len < msg->msg_iov[0].iov_len ? d->len : msg->msg_iov[0].iov_len;
        memcpy(msg->msg_iov[0].iov_base, d->data, n);
        msg->msg_flags = n < d->len ? MSG_TRUNC : 0;
        ck_assert_uint_ge(msg->msg_namelen, sizeof(struct sockaddr_nl));
        *(struct sockaddr_nl *) msg->msg_name = (struct sockaddr_nl) { .nl_family = AF_NETLINK, .nl_pid = d->pid };
        msg->msg_namelen = sizeof(struct sockaddr_nl);
        free(d->data);
        return (ssize_t) n;
}

static inline int nf_poll(void *ud, struct pollfd *fds, nfds_t n, int timeout_ms) {
        NF.n_polls++;
        if (NF.poll_err)
                return NF.poll_err;
        NF.mono_us += (uint64_t) timeout_ms * 1000u; /* nothing came */
        return 0;
}

static inline int nf_close(void *ud, int fd) {
        int i = fd - FD_BASE;
        ck_assert(NF.fds[i].open);
        nf_drop_queue(i);
        NF.fds[i].open = false;
        NF.n_closes++;
        return 0;
}

static inline int nf_clock(void *ud, clockid_t clock, struct timespec *ts) {
        *ts = us_to_timespec(NF.mono_us);
        return 0;
}

static const can_sys nf_sys = {
        .socket = nf_socket,
        .setsockopt = nf_setsockopt,
        .bind = nf_bind,
        .write = nf_write,
        .recvmsg = nf_recvmsg,
        .poll = nf_poll,
        .close = nf_close,
        .clock_gettime = nf_clock,
};

/* The replies held back so far become readable. */
static inline void nf_release(void) {
        for (int i = 0; i < MAX_FDS; i++)
                NF.fds[i].shown = NF.fds[i].tail;
}

static inline void nf_standard_links(void) {
        nf_add_link(1, "lo", NULL, 0, IFF_UP | IFF_RUNNING | IFF_LOOPBACK);
        nf_add_link(4, "can0", "can", 125000, IFF_UP | IFF_RUNNING);
        nf_add_link(5, "vcan0", "vcan", 0, IFF_UP | IFF_RUNNING);
        nf_add_link(6, "can1", "can", 0, 0);
        nf_add_link(7, "eth0", "veth", 0, IFF_UP);
}
