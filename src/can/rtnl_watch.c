/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* rtnetlink sockets: the link watcher and one-shot requests. */
#include "can/rtnl_watch.h"

#include <errno.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <stdlib.h>
#include <string.h>

#include "can/rtnl_sock.h"
#include "util/time_util.h"

/* Datagrams read per rtnl_watch_process() call; the fd stays readable after. */
#define WATCH_BATCH_MAX 256u

struct rtnl_watch {
        const can_sys *sys;
        int fd;
        rtnl_link_cb cb;
        void *userdata;
        void *buf;
};

typedef struct count_ctx {
        rtnl_link_cb cb;
        void *userdata;
        int count;
} count_ctx;

static void count_cb(const rtnl_link *link, void *userdata) {
        count_ctx *c = userdata;

        c->count++;
        if (c->cb)
                c->cb(link, c->userdata);
}

uint64_t rtnl_sock_now(const can_sys *sys) {
        struct timespec ts;

        if (sys->clock_gettime(sys->userdata, CLOCK_MONOTONIC, &ts) < 0)
                return 0;
        return timespec_to_us(&ts);
}

int rtnl_sock_open(const can_sys *sys, unsigned groups) {
        struct sockaddr_nl sa = { .nl_family = AF_NETLINK, .nl_groups = groups };
        int fd, r;

        fd = sys->socket(sys->userdata, AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC | SOCK_NONBLOCK, NETLINK_ROUTE);
        if (fd < 0)
                return fd;
        /* nl_pid 0: the kernel picks our port id. */
        r = sys->bind(sys->userdata, fd, (const struct sockaddr *) &sa, sizeof(sa));
        if (r < 0) {
                (void) sys->close(sys->userdata, fd);
                return r;
        }
        return fd;
}

/* Only the kernel (port id 0) is believed: any local process may send to
 * our port id. */
ssize_t rtnl_sock_recv(const can_sys *sys, int fd, void *buf, size_t size) {
        for (;;) {
                struct sockaddr_nl sa = {};
                struct iovec iov = { .iov_base = buf, .iov_len = size };
                struct msghdr msg = {
                        .msg_name = &sa,
                        .msg_namelen = sizeof(sa),
                        .msg_iov = &iov,
                        .msg_iovlen = 1,
                };
                ssize_t n;

                n = sys->recvmsg(sys->userdata, fd, &msg, MSG_DONTWAIT);
                if (n == -EINTR)
                        continue;
                if (n == -EWOULDBLOCK)
                        return -EAGAIN;
                if (n < 0)
                        return n;
                if (msg.msg_namelen != sizeof(sa) || sa.nl_family != AF_NETLINK || sa.nl_pid != 0)
                        continue;
                if (msg.msg_flags & MSG_TRUNC)
                        return -EMSGSIZE;
                return n;
        }
}

/* Sends one request on fd and reads until its DONE/ACK/error. */
static int nl_transact(const can_sys *sys, int fd, void *buf, size_t len, rtnl_link_cb cb, void *userdata) {
        const struct nlmsghdr *req = buf;
        uint32_t want_seq = req->nlmsg_seq;
        uint64_t deadline;
        ssize_t n;

        n = sys->write(sys->userdata, fd, buf, len);
        if (n < 0)
                return (int) n;
        if ((size_t) n != len)
                return -EIO;

        deadline = rtnl_sock_now(sys) + RTNL_REQUEST_TIMEOUT_US;
        for (;;) {
                uint32_t seq = want_seq; /* a malformed reply has none: it ends the request */
                int r;

                n = rtnl_sock_recv(sys, fd, buf, RTNL_BUFFER_SIZE);
                if (n == -EAGAIN) {
                        struct pollfd pfd = { .fd = fd, .events = POLLIN };
                        uint64_t now = rtnl_sock_now(sys);

                        if (now >= deadline)
                                return -ETIMEDOUT;
                        r = sys->poll(sys->userdata, &pfd, 1, (int) us_to_ms_up(deadline - now));
                        if (r < 0 && r != -EINTR)
                                return r;
                        continue;
                }
                if (n < 0)
                        return (int) n;
                r = rtnl_parse(buf, (size_t) n, cb, userdata, &seq);
                if (r == 0)
                        continue; /* more parts of a dump, or the reply before its ACK */
                if (seq != want_seq)
                        continue; /* the end of something else */
                return r < 0 ? r : 0;
        }
}

/* Opens a socket, runs one request built by the caller in buf, closes. */
static int nl_request(const can_sys *sys, void *buf, size_t len, rtnl_link_cb cb, void *userdata) {
        int fd, r;

        fd = rtnl_sock_open(sys, 0);
        if (fd < 0)
                return fd;
        r = nl_transact(sys, fd, buf, len, cb, userdata);
        (void) sys->close(sys->userdata, fd);
        return r;
}

int rtnl_dump_links(const can_sys *sys, rtnl_link_cb cb, void *userdata) {
        count_ctx c = { .cb = cb, .userdata = userdata };
        void *buf;
        int r;

        if (!sys)
                sys = can_sys_default();
        buf = malloc(RTNL_BUFFER_SIZE);
        if (!buf)
                return -ENOMEM;
        r = rtnl_build_getlink(buf, RTNL_BUFFER_SIZE, 1, 0, NULL);
        if (r >= 0)
                r = nl_request(sys, buf, (size_t) r, count_cb, &c);
        free(buf);
        return r < 0 ? r : c.count;
}

static void copy_first_cb(const rtnl_link *link, void *userdata) {
        count_ctx *c = userdata;

        if (c->count++ == 0)
                *(rtnl_link *) c->userdata = *link;
}

int rtnl_get_link(const can_sys *sys, const char *ifname, rtnl_link *ret) {
        count_ctx c = { .userdata = ret };
        void *buf;
        int r;

        if (!ifname || !*ifname || strlen(ifname) >= IFNAMSIZ)
                return -EINVAL;
        if (!sys)
                sys = can_sys_default();
        buf = malloc(RTNL_BUFFER_SIZE);
        if (!buf)
                return -ENOMEM;
        r = rtnl_build_getlink(buf, RTNL_BUFFER_SIZE, 1, 0, ifname);
        if (r >= 0)
                r = nl_request(sys, buf, (size_t) r, copy_first_cb, &c);
        free(buf);
        if (r < 0)
                return r;
        return c.count > 0 ? 0 : -ENODEV;
}

int rtnl_check_can_bitrate(const can_sys *sys, const char *ifname, rtnl_link *ret) {
        rtnl_link link;
        void *buf;
        int r;

        if (!sys)
                sys = can_sys_default();
        r = rtnl_get_link(sys, ifname, &link);
        if (r < 0)
                return r;
        if (ret)
                *ret = link;
        if (strcmp(link.kind, "can") != 0)
                return -EOPNOTSUPP;
        if (!(link.flags & IFF_UP) || link.bitrate == 0)
                return -ENETDOWN;

        buf = malloc(RTNL_BUFFER_SIZE);
        if (!buf)
                return -ENOMEM;
        /* The rate it runs at: the kernel checks CAP_NET_ADMIN first (EPERM),
         * then refuses bit timing on a running controller (EBUSY) — a
         * change that is allowed and leaves the controller untouched. */
        r = rtnl_build_set_can_bitrate(buf, RTNL_BUFFER_SIZE, 1, link.ifindex, link.bitrate);
        if (r >= 0)
                r = nl_request(sys, buf, (size_t) r, NULL, NULL);
        free(buf);
        return r == -EBUSY ? 0 : r;
}

int rtnl_watch_new(const can_sys *sys, rtnl_link_cb cb, void *userdata, rtnl_watch **ret) {
        rtnl_watch *w;

        if (!cb || !ret)
                return -EINVAL;
        w = calloc(1, sizeof(*w));
        if (!w)
                return -ENOMEM;
        w->sys = sys ? sys : can_sys_default();
        w->cb = cb;
        w->userdata = userdata;
        w->buf = malloc(RTNL_BUFFER_SIZE);
        if (!w->buf) {
                free(w);
                return -ENOMEM;
        }
        /* RTMGRP_LINK: every RTM_NEWLINK/RTM_DELLINK, up/down and carrier changes included. */
        w->fd = rtnl_sock_open(w->sys, RTMGRP_LINK);
        if (w->fd < 0) {
                int r = w->fd;

                free(w->buf);
                free(w);
                return r;
        }
        *ret = w;
        return 0;
}

rtnl_watch *rtnl_watch_free(rtnl_watch *w) {
        if (!w)
                return NULL;
        (void) w->sys->close(w->sys->userdata, w->fd);
        free(w->buf);
        free(w);
        return NULL;
}

int rtnl_watch_fd(const rtnl_watch *w) {
        return w->fd;
}

int rtnl_watch_process(rtnl_watch *w) {
        count_ctx c = { .cb = w->cb, .userdata = w->userdata };
        bool resync = false;

        for (unsigned i = 0; i < WATCH_BATCH_MAX; i++) {
                ssize_t n = rtnl_sock_recv(w->sys, w->fd, w->buf, RTNL_BUFFER_SIZE);

                if (n == -EAGAIN)
                        break;
                if (n == -ENOBUFS || n == -EMSGSIZE) {
                        /* Events were lost. Read what is still queued (older
                         * than the loss) first, then ask for the whole truth. */
                        resync = true;
                        continue;
                }
                if (n < 0)
                        return (int) n;
                /* A malformed event is skipped; what parsed before it was delivered. */
                (void) rtnl_parse(w->buf, (size_t) n, count_cb, &c, NULL);
        }
        if (resync) {
                int r = rtnl_dump_links(w->sys, count_cb, &c);

                if (r < 0)
                        return r;
        }
        return c.count;
}
