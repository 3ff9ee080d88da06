/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The SocketCAN port against a scripted fake kernel (this host has no AF_CAN),
 * plus the parts that run for real: interface lookup, and write/recvmsg/poll
 * on a datagram socketpair standing in for the CAN socket. */
#include <check.h>
#include <errno.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/un.h>
#include <unistd.h>

#include "can/socketcan.h"
#include "can/transport.h"
#include "util/time_util.h"

/* ---- fake kernel ---- */

#define FAKE_FD 42
#define MAX_CALLS 256
#define MAX_SCRIPT 128

enum call_kind {
        C_NAMETOINDEX, C_SOCKET, C_SETSOCKOPT, C_BIND, C_WRITE, C_RECVMSG, C_POLL, C_IFFLAGS, C_CLOSE,
};

typedef struct call {
        enum call_kind kind;
        int level, name; /* setsockopt */
        int timeout;     /* poll */
        short events;    /* poll */
        int fd;
} call;

typedef struct rx_item {
        ssize_t ret;            /* bytes, or -errno */
        struct can_frame cf;
        bool has_tv;
        struct timeval tv;
        bool has_ovfl;
        uint32_t ovfl;
        int msg_flags;
} rx_item;

typedef struct fake {
        call calls[MAX_CALLS];
        size_t n_calls;

        int ifindex;            /* if_nametoindex result (or -errno) */
        int socket_ret;
        int setsockopt_fail_at; /* index of the setsockopt call to fail, -1 none */
        int setsockopt_err;
        int bind_ret;
        int if_flags_ret;
        unsigned if_flags;

        ssize_t write_script[MAX_SCRIPT]; /* results; 0 = success; past the end: success */
        size_t n_write_script, write_pos;
        struct can_frame written[MAX_SCRIPT];
        size_t n_written;

        rx_item rx[MAX_SCRIPT];     /* past the end: -EAGAIN */
        size_t n_rx, rx_pos;

        int poll_script[MAX_SCRIPT]; /* results; past the end: 1 (ready) */
        size_t n_poll_script, poll_pos;

        int n_open_fds;
        int next_fd;
        int recv_own;

        uint64_t mono_us, real_us;
        int clock_ret;

        /* setsockopt values seen */
        struct can_filter filters[32];
        size_t n_filters;
        can_err_mask_t err_mask;
        int rxq_ovfl, timestamp;
        struct sockaddr_can bound;
} fake;

static void add_call(fake *f, call c) {
        ck_assert_uint_lt(f->n_calls, MAX_CALLS);
        f->calls[f->n_calls++] = c;
}

static int f_nametoindex(void *ud, const char *name) {
        fake *f = ud;
        add_call(f, (call) { .kind = C_NAMETOINDEX });
        return f->ifindex;
}

static int f_socket(void *ud, int domain, int type, int protocol) {
        fake *f = ud;
        add_call(f, (call) { .kind = C_SOCKET });
        ck_assert_int_eq(domain, PF_CAN);
        ck_assert_int_eq(type, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC);
        ck_assert_int_eq(protocol, CAN_RAW);
        if (f->socket_ret < 0)
                return f->socket_ret;
        f->n_open_fds++;
        return f->next_fd++;
}

static int f_setsockopt(void *ud, int fd, int level, int name, const void *val, socklen_t len) {
        fake *f = ud;
        size_t idx = 0;

        for (size_t i = 0; i < f->n_calls; i++)
                if (f->calls[i].kind == C_SETSOCKOPT)
                        idx++;
        add_call(f, (call) { .kind = C_SETSOCKOPT, .level = level, .name = name, .fd = fd });
        if ((int) idx == f->setsockopt_fail_at)
                return f->setsockopt_err;
        if (level == SOL_CAN_RAW && name == CAN_RAW_FILTER) {
                ck_assert_uint_eq(len % sizeof(struct can_filter), 0);
                f->n_filters = len / sizeof(struct can_filter);
                ck_assert_uint_le(f->n_filters, 32);
                memcpy(f->filters, val, len);
        } else if (level == SOL_CAN_RAW && name == CAN_RAW_ERR_FILTER) {
                ck_assert_uint_eq(len, sizeof(can_err_mask_t));
                memcpy(&f->err_mask, val, len);
        } else if (level == SOL_SOCKET && name == SO_RXQ_OVFL) {
                memcpy(&f->rxq_ovfl, val, sizeof(int));
        } else if (level == SOL_SOCKET && name == SO_TIMESTAMP) {
                memcpy(&f->timestamp, val, sizeof(int));
        } else if (level == SOL_CAN_RAW && name == CAN_RAW_RECV_OWN_MSGS) {
                memcpy(&f->recv_own, val, sizeof(int));
        }
        return 0;
}

static int f_bind(void *ud, int fd, const struct sockaddr *sa, socklen_t len) {
        fake *f = ud;
        add_call(f, (call) { .kind = C_BIND, .fd = fd });
        ck_assert_uint_eq(len, sizeof(struct sockaddr_can));
        memcpy(&f->bound, sa, sizeof(f->bound));
        return f->bind_ret;
}

static ssize_t f_write(void *ud, int fd, const void *buf, size_t len) {
        fake *f = ud;
        ssize_t r = 0;

        add_call(f, (call) { .kind = C_WRITE, .fd = fd });
        ck_assert_uint_eq(len, CAN_MTU);
        if (f->write_pos < f->n_write_script)
                r = f->write_script[f->write_pos++];
        if (r < 0 || r > 0)
                return r;
        ck_assert_uint_lt(f->n_written, MAX_SCRIPT);
        memcpy(&f->written[f->n_written++], buf, sizeof(struct can_frame));
        return (ssize_t) len;
}

static ssize_t f_recvmsg(void *ud, int fd, struct msghdr *msg, int flags) {
        fake *f = ud;
        const rx_item *it;
        size_t clen = 0;

        add_call(f, (call) { .kind = C_RECVMSG, .fd = fd });
        ck_assert(flags & MSG_DONTWAIT);
        if (f->rx_pos >= f->n_rx)
                return -EAGAIN;
        it = &f->rx[f->rx_pos++];
        if (it->ret < 0)
                return it->ret;

        ck_assert_uint_eq(msg->msg_iovlen, 1);
        memcpy(msg->msg_iov[0].iov_base, &it->cf, (size_t) it->ret < sizeof(it->cf) ? (size_t) it->ret : sizeof(it->cf));
        msg->msg_flags = it->msg_flags;

        /* Control messages laid out as the kernel would. */
        char *ctl = msg->msg_control;
        if (it->has_tv) {
                struct cmsghdr *c = (struct cmsghdr *) (ctl + clen);
                ck_assert_uint_le(clen + CMSG_SPACE(sizeof(struct timeval)), msg->msg_controllen);
                c->cmsg_level = SOL_SOCKET;
                c->cmsg_type = SO_TIMESTAMP;
                c->cmsg_len = CMSG_LEN(sizeof(struct timeval));
                memcpy(CMSG_DATA(c), &it->tv, sizeof(it->tv));
                clen += CMSG_SPACE(sizeof(struct timeval));
        }
        if (it->has_ovfl) {
                struct cmsghdr *c = (struct cmsghdr *) (ctl + clen);
                ck_assert_uint_le(clen + CMSG_SPACE(sizeof(uint32_t)), msg->msg_controllen);
                c->cmsg_level = SOL_SOCKET;
                c->cmsg_type = SO_RXQ_OVFL;
                c->cmsg_len = CMSG_LEN(sizeof(uint32_t));
                memcpy(CMSG_DATA(c), &it->ovfl, sizeof(uint32_t));
                clen += CMSG_SPACE(sizeof(uint32_t));
        }
        msg->msg_controllen = clen;
        return it->ret;
}

static int f_poll(void *ud, struct pollfd *fds, nfds_t n, int timeout_ms) {
        fake *f = ud;
        int r = 1;

        add_call(f, (call) { .kind = C_POLL, .timeout = timeout_ms, .events = n ? fds[0].events : 0 });
        if (f->poll_pos < f->n_poll_script)
                r = f->poll_script[f->poll_pos++];
        if (r < 0)
                return r;
        if (r == 0 || n == 0) {
                f->mono_us += (uint64_t) timeout_ms * 1000u; /* slept the whole timeout */
                f->real_us += (uint64_t) timeout_ms * 1000u;
                return 0;
        }
        if (r > 0) {
                fds[0].revents = POLLOUT;
                f->mono_us += 100;
                f->real_us += 100;
        }
        return r;
}

static int f_if_flags(void *ud, int fd, const char *name, unsigned *ret_flags) {
        fake *f = ud;
        add_call(f, (call) { .kind = C_IFFLAGS, .fd = fd });
        if (f->if_flags_ret < 0)
                return f->if_flags_ret;
        *ret_flags = f->if_flags;
        return 0;
}

static int f_close(void *ud, int fd) {
        fake *f = ud;
        add_call(f, (call) { .kind = C_CLOSE, .fd = fd });
        f->n_open_fds--;
        return 0;
}

static int f_clock_gettime(void *ud, clockid_t clock, struct timespec *ts) {
        fake *f = ud;
        uint64_t us = clock == CLOCK_MONOTONIC ? f->mono_us : f->real_us;

        if (f->clock_ret < 0)
                return f->clock_ret;
        ck_assert(clock == CLOCK_MONOTONIC || clock == CLOCK_REALTIME);
        *ts = us_to_timespec(us);
        return 0;
}

static fake F;
static can_sys fake_sys;

static void fake_reset(void) {
        memset(&F, 0, sizeof(F));
        F.ifindex = 7;
        F.setsockopt_fail_at = -1;
        F.if_flags = IFF_UP | IFF_RUNNING;
        F.next_fd = FAKE_FD;
        F.mono_us = 1000000000u;        /* 1000 s after boot */
        F.real_us = 1700000000000000u;  /* some day in 2023 */
        fake_sys = (can_sys) {
                .socket = f_socket,
                .setsockopt = f_setsockopt,
                .bind = f_bind,
                .write = f_write,
                .recvmsg = f_recvmsg,
                .poll = f_poll,
                .if_nametoindex = f_nametoindex,
                .if_flags = f_if_flags,
                .close = f_close,
                .clock_gettime = f_clock_gettime,
                .userdata = &F,
        };
}

static size_t count_calls(enum call_kind k) {
        size_t n = 0;
        for (size_t i = 0; i < F.n_calls; i++)
                if (F.calls[i].kind == k)
                        n++;
        return n;
}

static void push_write(ssize_t r) {
        F.write_script[F.n_write_script++] = r;
}

static rx_item *push_rx(ssize_t ret, canid_t id, uint8_t len) {
        rx_item *it = &F.rx[F.n_rx++];
        memset(it, 0, sizeof(*it));
        it->ret = ret;
        it->cf.can_id = id;
        it->cf.len = len;
        for (unsigned i = 0; i < 8; i++)
                it->cf.data[i] = (uint8_t) (0xA0 + i);
        return it;
}

static rx_item *push_err_frame(canid_t err, uint8_t d1) {
        rx_item *it = push_rx(CAN_MTU, CAN_ERR_FLAG | err, CAN_ERR_DLC);
        memset(it->cf.data, 0, 8);
        it->cf.data[1] = d1;
        return it;
}

typedef struct state_log {
        lss_link_state old_state[16], new_state[16];
        int fd_during[16];
        size_t closes_before[16];
        size_t n;
        socketcan_port *p;
} state_log;

static void on_state(void *userdata, lss_link_state o, lss_link_state n) {
        state_log *l = userdata;
        ck_assert_uint_lt(l->n, 16);
        l->old_state[l->n] = o;
        l->new_state[l->n] = n;
        l->fd_during[l->n] = socketcan_port_fd(l->p);
        l->closes_before[l->n] = count_calls(C_CLOSE);
        l->n++;
}

static socketcan_port *open_fake(state_log *log) {
        socketcan_config cfg = { .sys = &fake_sys, .hooks = { .link_changed = log ? on_state : NULL, .userdata = log } };
        socketcan_port *p = NULL;

        ck_assert_int_eq(socketcan_port_open("can0", &cfg, &p), 0);
        ck_assert_ptr_nonnull(p);
        if (log)
                log->p = p;
        return p;
}

static lss_frame lss_req(void) {
        lss_frame f;
        lss_encode_switch_global(&f, LSS_MODE_CONFIGURATION);
        return f;
}

/* ---- filters ---- */

START_TEST(filter_array_exact) {
        static const struct can_filter want[] = {
                { 0x7E4, CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_SFF_MASK },
                { 0x7E5, CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_SFF_MASK },
                { 0x701, CAN_EFF_FLAG | CAN_RTR_FLAG | 0x7FF },
                { 0x702, CAN_EFF_FLAG | CAN_RTR_FLAG | 0x7FE },
                { 0x704, CAN_EFF_FLAG | CAN_RTR_FLAG | 0x7FC },
                { 0x708, CAN_EFF_FLAG | CAN_RTR_FLAG | 0x7F8 },
                { 0x710, CAN_EFF_FLAG | CAN_RTR_FLAG | 0x7F0 },
                { 0x720, CAN_EFF_FLAG | CAN_RTR_FLAG | 0x7E0 },
                { 0x740, CAN_EFF_FLAG | CAN_RTR_FLAG | 0x7C0 },
                { 0x581, CAN_EFF_FLAG | CAN_RTR_FLAG | 0x7FF },
                { 0x582, CAN_EFF_FLAG | CAN_RTR_FLAG | 0x7FE },
                { 0x584, CAN_EFF_FLAG | CAN_RTR_FLAG | 0x7FC },
                { 0x588, CAN_EFF_FLAG | CAN_RTR_FLAG | 0x7F8 },
                { 0x590, CAN_EFF_FLAG | CAN_RTR_FLAG | 0x7F0 },
                { 0x5A0, CAN_EFF_FLAG | CAN_RTR_FLAG | 0x7E0 },
                { 0x5C0, CAN_EFF_FLAG | CAN_RTR_FLAG | 0x7C0 },
        };
        const struct can_filter *got;
        size_t n = socketcan_filters(&got);

        ck_assert_uint_eq(n, sizeof(want) / sizeof(want[0]));
        ck_assert_mem_eq(got, want, sizeof(want));
}
END_TEST

/* The kernel's rule, (id & mask) == (filter & mask), over every identifier:
 * exactly 0x7E4, 0x7E5 (our echo), 0x701..0x77F and 0x581..0x5FF pass, as standard data frames only. */
START_TEST(filter_semantics_all_ids) {
        const struct can_filter *flt;
        size_t n = socketcan_filters(&flt);

        for (canid_t id = 0; id <= CAN_SFF_MASK; id++) {
                bool want = id == 0x7E4 || id == 0x7E5 || (id >= 0x701 && id <= 0x77F) || (id >= 0x581 && id <= 0x5FF);
                const canid_t variants[] = { id, id | CAN_RTR_FLAG, id | CAN_EFF_FLAG, id | CAN_EFF_FLAG | CAN_RTR_FLAG,
                                             id | 0x10000000u | CAN_EFF_FLAG };

                for (size_t v = 0; v < sizeof(variants) / sizeof(variants[0]); v++) {
                        struct can_frame cf = { .can_id = variants[v] };
                        bool kernel = false;

                        for (size_t i = 0; i < n; i++)
                                kernel |= (cf.can_id & flt[i].can_mask) == (flt[i].can_id & flt[i].can_mask);
                        ck_assert_msg(kernel == (want && v == 0), "id %#x variant %zu", id, v);
                        ck_assert(socketcan_filter_match(&cf) == kernel);
                }
        }
}
END_TEST

START_TEST(err_mask_bits) {
        can_err_mask_t m = socketcan_err_mask();
        ck_assert_uint_eq(m, CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_ACK | CAN_ERR_RESTARTED | CAN_ERR_TX_TIMEOUT);
        ck_assert(!(m & (CAN_ERR_BUSERROR | CAN_ERR_PROT | CAN_ERR_LOSTARB | CAN_ERR_CNT)));
}
END_TEST

/* ---- open ---- */

START_TEST(open_order_and_options) {
        socketcan_port *p;
        const struct can_filter *want;
        size_t n_want = socketcan_filters(&want);
        ssize_t i_filter = -1, i_err = -1, i_ovfl = -1, i_ts = -1, i_own = -1, i_bind = -1, i_socket = -1;

        fake_reset();
        p = open_fake(NULL);
        for (size_t i = 0; i < F.n_calls; i++) {
                const call *c = &F.calls[i];
                if (c->kind == C_SOCKET)
                        i_socket = (ssize_t) i;
                if (c->kind == C_BIND)
                        i_bind = (ssize_t) i;
                if (c->kind != C_SETSOCKOPT)
                        continue;
                ck_assert_int_eq(c->fd, FAKE_FD);
                if (c->level == SOL_CAN_RAW && c->name == CAN_RAW_FILTER)
                        i_filter = (ssize_t) i;
                else if (c->level == SOL_CAN_RAW && c->name == CAN_RAW_ERR_FILTER)
                        i_err = (ssize_t) i;
                else if (c->level == SOL_SOCKET && c->name == SO_RXQ_OVFL)
                        i_ovfl = (ssize_t) i;
                else if (c->level == SOL_SOCKET && c->name == SO_TIMESTAMP)
                        i_ts = (ssize_t) i;
                else if (c->level == SOL_CAN_RAW && c->name == CAN_RAW_RECV_OWN_MSGS)
                        i_own = (ssize_t) i;
                else
                        ck_abort_msg("unexpected setsockopt %d/%d", c->level, c->name); /* e.g. CAN_RAW_FD_FRAMES */
        }
        ck_assert_int_eq(F.calls[0].kind, C_NAMETOINDEX);
        ck_assert_int_gt(i_socket, 0);
        ck_assert_int_gt(i_filter, i_socket);
        ck_assert_int_gt(i_err, i_socket);
        ck_assert_int_gt(i_ovfl, i_socket);
        ck_assert_int_gt(i_ts, i_socket);
        ck_assert_int_gt(i_own, i_socket);
        ck_assert_int_gt(i_bind, i_own);
        /* bind last of all */
        ck_assert_int_eq(i_bind, (ssize_t) F.n_calls - 1);
        ck_assert_int_gt(i_bind, i_filter);
        ck_assert_int_gt(i_bind, i_err);

        ck_assert_uint_eq(F.n_filters, n_want);
        ck_assert_mem_eq(F.filters, want, n_want * sizeof(*want));
        ck_assert_uint_eq(F.err_mask, socketcan_err_mask());
        ck_assert_int_eq(F.rxq_ovfl, 1);
        ck_assert_int_eq(F.timestamp, 1);
        ck_assert_int_eq(F.recv_own, 1);
        ck_assert(socketcan_port_echoes(p));
        ck_assert_int_eq(F.bound.can_family, AF_CAN);
        ck_assert_int_eq(F.bound.can_ifindex, 7);

        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_UP);
        ck_assert_int_eq(socketcan_port_fd(p), FAKE_FD);
        ck_assert_int_eq(socketcan_port_ifindex(p), 7);
        ck_assert_str_eq(socketcan_port_ifname(p), "can0");
        socketcan_port_free(p);
        ck_assert_int_eq(F.n_open_fds, 0);
}
END_TEST

START_TEST(open_missing_interface) {
        socketcan_port *p;
        lss_frame f = lss_req();
        uint64_t t;
        lss_transport_status st;

        fake_reset();
        F.ifindex = -ENODEV;
        p = open_fake(NULL);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_GONE);
        ck_assert_int_eq(socketcan_port_fd(p), -1);
        ck_assert_int_eq(socketcan_port_ifindex(p), 0);
        ck_assert_uint_eq(count_calls(C_SOCKET), 0);
        ck_assert_int_eq(socketcan_port_send(p, &f), -ENODEV);
        ck_assert_int_eq(socketcan_port_recv(p, &f, &t), -ENODEV);
        ck_assert_uint_eq(count_calls(C_WRITE) + count_calls(C_RECVMSG), 0);
        socketcan_port_status(p, &st);
        ck_assert_int_eq(st.link, LSS_LINK_GONE);
        ck_assert_uint_eq(st.events, 0);
        socketcan_port_free(p);

        /* ENXIO from the lookup means the same */
        fake_reset();
        F.ifindex = -ENXIO;
        p = open_fake(NULL);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_GONE);
        socketcan_port_free(p);
}
END_TEST

START_TEST(open_no_af_can) {
        socketcan_port *p = NULL;
        socketcan_config cfg = { .sys = &fake_sys };

        fake_reset();
        F.socket_ret = -EAFNOSUPPORT;
        ck_assert_int_eq(socketcan_port_open("can0", &cfg, &p), -EAFNOSUPPORT);
        ck_assert_ptr_null(p);
        ck_assert(!socketcan_kernel_has_can(&fake_sys));
        fake_reset();
        ck_assert(socketcan_kernel_has_can(&fake_sys));

        fake_reset();
        F.ifindex = -ENOMEM; /* other lookup errors are errors */
        ck_assert_int_eq(socketcan_port_open("can0", &cfg, &p), -ENOMEM);
        ck_assert_ptr_null(p);
}
END_TEST

START_TEST(open_setsockopt_failures) {
        socketcan_config cfg = { .sys = &fake_sys };

        for (int i = 0; i < 4; i++) {
                socketcan_port *p = NULL;

                fake_reset();
                F.setsockopt_fail_at = i;
                F.setsockopt_err = -ENOPROTOOPT;
                ck_assert_int_eq(socketcan_port_open("can0", &cfg, &p), -ENOPROTOOPT);
                ck_assert_ptr_null(p);
                ck_assert_int_eq(F.n_open_fds, 0); /* closed again */
                ck_assert_uint_eq(count_calls(C_BIND), 0);
        }
}
END_TEST

/* Without echo the port works; the engine then drains by estimated wire time. */
START_TEST(open_without_echo) {
        socketcan_config cfg = { .sys = &fake_sys };
        socketcan_port *p = NULL;
        lss_transport_status st;

        fake_reset();
        F.setsockopt_fail_at = 4; /* CAN_RAW_RECV_OWN_MSGS */
        F.setsockopt_err = -ENOPROTOOPT;
        ck_assert_int_eq(socketcan_port_open("can0", &cfg, &p), 0);
        ck_assert_int_eq(F.calls[F.n_calls - 1].kind, C_BIND);
        ck_assert(!socketcan_port_echoes(p));
        socketcan_port_status(p, &st);
        ck_assert(!st.tx_echo);
        socketcan_port_free(p);
}
END_TEST

START_TEST(open_bind_results) {
        socketcan_config cfg = { .sys = &fake_sys };
        socketcan_port *p = NULL;

        /* The interface vanished between lookup and bind: gone, not an error. */
        fake_reset();
        F.bind_ret = -ENODEV;
        ck_assert_int_eq(socketcan_port_open("can0", &cfg, &p), 0);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_GONE);
        ck_assert_int_eq(F.n_open_fds, 0);
        p = socketcan_port_free(p);

        fake_reset();
        F.bind_ret = -EADDRINUSE;
        ck_assert_int_eq(socketcan_port_open("can0", &cfg, &p), -EADDRINUSE);
        ck_assert_ptr_null(p);
        ck_assert_int_eq(F.n_open_fds, 0);

        /* flags lookup says gone too */
        fake_reset();
        F.if_flags_ret = -ENODEV;
        ck_assert_int_eq(socketcan_port_open("can0", &cfg, &p), 0);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_GONE);
        ck_assert_int_eq(F.n_open_fds, 0);
        p = socketcan_port_free(p);

        /* flags lookup failing otherwise: assume up */
        fake_reset();
        F.if_flags_ret = -EPERM;
        ck_assert_int_eq(socketcan_port_open("can0", &cfg, &p), 0);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_UP);
        p = socketcan_port_free(p);
}
END_TEST

START_TEST(open_link_down) {
        socketcan_port *p;

        fake_reset();
        F.if_flags = IFF_UP; /* no carrier */
        p = open_fake(NULL);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_DOWN);
        ck_assert_int_eq(socketcan_port_fd(p), FAKE_FD);
        socketcan_port_free(p);

        fake_reset();
        F.if_flags = 0;
        p = open_fake(NULL);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_DOWN);
        socketcan_port_free(p);
}
END_TEST

START_TEST(open_bad_names) {
        socketcan_port *p = NULL;
        socketcan_config cfg = { .sys = &fake_sys };

        fake_reset();
        ck_assert_int_eq(socketcan_port_open("", &cfg, &p), -EINVAL);
        ck_assert_int_eq(socketcan_port_open("0123456789abcdef", &cfg, &p), -EINVAL); /* 16 > IFNAMSIZ-1 */
        ck_assert_int_eq(socketcan_port_open("a/b", &cfg, &p), -EINVAL);
        ck_assert_int_eq(socketcan_port_open("can:0", &cfg, &p), -EINVAL);
        ck_assert_int_eq(socketcan_port_open("can 0", &cfg, &p), -EINVAL);
        ck_assert_int_eq(socketcan_port_open("can\t0", &cfg, &p), -EINVAL);
        ck_assert_int_eq(socketcan_port_open("..", &cfg, &p), -EINVAL);
        ck_assert_int_eq(socketcan_port_open(".", &cfg, &p), -EINVAL);
        ck_assert_int_eq(socketcan_port_open(NULL, &cfg, &p), -EINVAL);
        ck_assert_int_eq(socketcan_port_open("can0", &cfg, NULL), -EINVAL);
        ck_assert_ptr_null(p);
        ck_assert_uint_eq(F.n_calls, 0);
        ck_assert_int_eq(socketcan_port_open("0123456789abcde", &cfg, &p), 0); /* 15 is fine */
        socketcan_port_free(p);
}
END_TEST

/* ---- send ---- */

START_TEST(send_conversions) {
        socketcan_port *p;
        lss_frame f = lss_req();

        fake_reset();
        p = open_fake(NULL);
        ck_assert_int_eq(socketcan_port_send(p, &f), 0);
        ck_assert_uint_eq(F.n_written, 1);
        ck_assert_uint_eq(F.written[0].can_id, 0x7E5);
        ck_assert_uint_eq(F.written[0].len, 8);
        ck_assert_mem_eq(F.written[0].data, ((const uint8_t[]){ 0x04, 0x01, 0, 0, 0, 0, 0, 0 }), 8);

        nmt_encode(&f, NMT_CS_RESET_NODE, 0);
        ck_assert_int_eq(socketcan_port_send(p, &f), 0);
        ck_assert_uint_eq(F.written[1].can_id, 0);
        ck_assert_uint_eq(F.written[1].len, 2);
        ck_assert_uint_eq(F.written[1].data[0], 0x81);

        f = (lss_frame) { .id = 0x1234567, .flags = LSS_FRAME_EFF, .len = 1, .data = { 9 } };
        ck_assert_int_eq(socketcan_port_send(p, &f), 0);
        ck_assert_uint_eq(F.written[2].can_id, 0x1234567 | CAN_EFF_FLAG);

        f = (lss_frame) { .id = 0x7E4, .flags = LSS_FRAME_RTR, .len = 8, .data = { 1, 2 } };
        ck_assert_int_eq(socketcan_port_send(p, &f), 0);
        ck_assert_uint_eq(F.written[3].can_id, 0x7E4 | CAN_RTR_FLAG);
        ck_assert_uint_eq(F.written[3].len, 8);
        ck_assert_uint_eq(F.written[3].data[0], 0); /* remote frames carry no data */

        /* what classic CAN cannot carry is refused before any syscall */
        const lss_frame bad[] = {
                { .id = 0x7E5, .flags = LSS_FRAME_FD, .len = 8 },
                { .id = 0x7E5, .flags = LSS_FRAME_ERR, .len = 8 },
                { .id = 0x7E5, .flags = 0x80, .len = 8 },
                { .id = 0x7E5, .len = 9 },
                { .id = 0x800, .len = 8 },
                { .id = 0x20000000, .flags = LSS_FRAME_EFF, .len = 8 },
        };
        size_t writes = count_calls(C_WRITE);
        for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++)
                ck_assert_int_eq(socketcan_port_send(p, &bad[i]), -EINVAL);
        ck_assert_uint_eq(count_calls(C_WRITE), writes);
        socketcan_port_free(p);
}
END_TEST

/* A full tx queue never blocks: -EAGAIN at once (no poll, no time passes),
 * nothing written; the same frame goes out on a later send, exactly once,
 * and the next after it. */
START_TEST(send_full_queue_returns_at_once) {
        const ssize_t full[] = { -ENOBUFS, -EAGAIN };
        socketcan_port *p;
        lss_frame f = lss_req();

        fake_reset();
        p = open_fake(NULL);
        for (size_t i = 0; i < 2; i++) {
                uint64_t t0 = F.mono_us;
                push_write(full[i]);
                ck_assert_int_eq(socketcan_port_send(p, &f), -EAGAIN);
                ck_assert_uint_eq(F.mono_us, t0);
                ck_assert_uint_eq(count_calls(C_POLL), 0);
                ck_assert_uint_eq(count_calls(C_WRITE), i + 1);
                ck_assert_uint_eq(F.n_written, 0);
        }
        ck_assert_int_eq(socketcan_port_send(p, &f), 0);
        f.data[1] = 0;
        ck_assert_int_eq(socketcan_port_send(p, &f), 0);
        ck_assert_uint_eq(F.n_written, 2);
        ck_assert_uint_eq(F.written[0].data[1], 1);
        ck_assert_uint_eq(F.written[1].data[1], 0);
        /* a full queue is not a link problem */
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_UP);
        socketcan_port_free(p);
}
END_TEST

START_TEST(send_eintr_and_short) {
        socketcan_port *p;
        lss_frame f = lss_req();

        fake_reset();
        p = open_fake(NULL);
        push_write(-EINTR);
        ck_assert_int_eq(socketcan_port_send(p, &f), 0);
        ck_assert_uint_eq(F.n_written, 1);
        ck_assert_uint_eq(count_calls(C_WRITE), 2);

        push_write(8);
        ck_assert_int_eq(socketcan_port_send(p, &f), -EIO);
        push_write(-EMSGSIZE);
        ck_assert_int_eq(socketcan_port_send(p, &f), -EMSGSIZE);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_UP);
        ck_assert_uint_eq(F.n_written, 1);
        socketcan_port_free(p);
}
END_TEST

START_TEST(send_enetdown_recovers) {
        state_log log = {};
        socketcan_port *p;
        lss_frame f = lss_req();
        lss_transport_status st;

        fake_reset();
        p = open_fake(&log);
        push_write(-ENETDOWN);
        ck_assert_int_eq(socketcan_port_send(p, &f), -ENETDOWN);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_DOWN);
        ck_assert_int_eq(socketcan_port_fd(p), FAKE_FD); /* the socket stays */
        ck_assert_uint_eq(count_calls(C_CLOSE), 0);
        ck_assert_uint_eq(log.n, 1);
        ck_assert_int_eq(log.old_state[0], LSS_LINK_UP);
        ck_assert_int_eq(log.new_state[0], LSS_LINK_DOWN);
        socketcan_port_status(p, &st);
        ck_assert_int_eq(st.link, LSS_LINK_DOWN);
        ck_assert(st.events & LSS_BUS_EVENT_LINK_CHANGED);
        socketcan_port_status(p, &st);
        ck_assert_uint_eq(st.events, 0);

        /* link back: the same socket works */
        ck_assert_int_eq(socketcan_port_send(p, &f), 0);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_UP);
        ck_assert_uint_eq(log.n, 2);
        ck_assert_int_eq(log.new_state[1], LSS_LINK_UP);
        ck_assert_uint_eq(F.n_written, 1);
        socketcan_port_free(p);
}
END_TEST

START_TEST(send_enodev_goes_gone) {
        const int errs[] = { -ENODEV, -ENXIO };

        for (size_t i = 0; i < 2; i++) {
                state_log log = {};
                socketcan_port *p;
                lss_frame f = lss_req();

                fake_reset();
                p = open_fake(&log);
                push_write(errs[i]);
                ck_assert_int_eq(socketcan_port_send(p, &f), -ENODEV);
                ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_GONE);
                ck_assert_int_eq(socketcan_port_fd(p), -1);
                ck_assert_int_eq(socketcan_port_ifindex(p), 0);
                ck_assert_int_eq(F.n_open_fds, 0);
                ck_assert_uint_eq(log.n, 1);
                ck_assert_int_eq(log.new_state[0], LSS_LINK_GONE);
                /* told while the fd was still open, so the loop can drop it */
                ck_assert_int_eq(log.fd_during[0], FAKE_FD);
                ck_assert_uint_eq(log.closes_before[0], 0);
                ck_assert_uint_eq(count_calls(C_CLOSE), 1);

                size_t writes = count_calls(C_WRITE);
                ck_assert_int_eq(socketcan_port_send(p, &f), -ENODEV);
                ck_assert_uint_eq(count_calls(C_WRITE), writes);
                socketcan_port_free(p);
                ck_assert_uint_eq(count_calls(C_CLOSE), 1); /* not twice */
        }
}
END_TEST

/* ---- receive ---- */

START_TEST(recv_frames) {
        socketcan_port *p;
        lss_frame f;
        uint64_t t = 0;

        fake_reset();
        p = open_fake(NULL);
        push_rx(CAN_MTU, 0x7E4, 8);
        push_rx(CAN_MTU, 0x705, 1)->cf.data[0] = 0;
        ck_assert_int_eq(socketcan_port_recv(p, &f, &t), 1);
        ck_assert_uint_eq(f.id, 0x7E4);
        ck_assert_uint_eq(f.flags, 0);
        ck_assert_uint_eq(f.len, 8);
        ck_assert_uint_eq(f.data[7], 0xA7);
        ck_assert_uint_eq(t, F.mono_us); /* no stamp: read time */
        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), 1);
        uint8_t nid, st;
        ck_assert(bootup_decode(&f, &nid, &st));
        ck_assert_uint_eq(nid, 5);
        ck_assert_int_eq(socketcan_port_recv(p, &f, &t), 0);
        socketcan_port_free(p);
}
END_TEST

/* Our own request comes back flagged (MSG_CONFIRM) in its place among the
 * answers; another sender's 0x7E5 comes out unflagged: another master. */
START_TEST(recv_own_echo) {
        socketcan_port *p;
        lss_frame f;
        uint64_t t = 0;
        lss_transport_status st;

        fake_reset();
        p = open_fake(NULL);
        push_rx(CAN_MTU, 0x7E5, 8);                             /* another master's */
        push_rx(CAN_MTU, 0x7E5, 8)->msg_flags = MSG_CONFIRM;    /* ours, on the wire */
        push_rx(CAN_MTU, 0x7E4, 8);
        /* another master's comes out as it is: the daemon must notice it */
        ck_assert_int_eq(socketcan_port_recv(p, &f, &t), 1);
        ck_assert_uint_eq(f.id, 0x7E5);
        ck_assert_uint_eq(f.flags, 0);
        ck_assert(lss_is_foreign_request(&f));
        ck_assert_int_eq(socketcan_port_recv(p, &f, &t), 1);
        ck_assert_uint_eq(f.id, 0x7E5);
        ck_assert_uint_eq(f.flags, LSS_FRAME_ECHO);
        ck_assert_uint_eq(f.len, 8);
        ck_assert(!lss_is_response(&f));
        ck_assert(!lss_is_foreign_request(&f));
        ck_assert_int_eq(socketcan_port_recv(p, &f, &t), 1);
        ck_assert_uint_eq(f.id, 0x7E4);
        ck_assert_uint_eq(f.flags, 0);
        ck_assert_int_eq(socketcan_port_recv(p, &f, &t), 0);
        socketcan_port_status(p, &st);
        ck_assert(st.tx_echo);
        ck_assert_uint_eq(st.rx_invalid, 0);
        socketcan_port_free(p);
}
END_TEST

START_TEST(recv_invalid_reads) {
        socketcan_port *p;
        lss_frame f;
        uint64_t t;
        lss_transport_status st;

        fake_reset();
        p = open_fake(NULL);
        push_rx(8, 0x7E4, 8);                                   /* short read */
        push_rx(CANFD_MTU, 0x7E4, 8);                           /* longer than we asked: cannot be */
        push_rx(CAN_MTU, 0x7E4, 8)->msg_flags = MSG_TRUNC;      /* truncated */
        push_rx(CAN_MTU, 0x7E4, 9);                             /* DLC > 8 */
        push_rx(CAN_MTU, 0x7E4 | CAN_EFF_FLAG, 8);              /* extended look-alike */
        push_rx(CAN_MTU, 0x7E4 | CAN_RTR_FLAG, 8);              /* remote look-alike */
        push_rx(CAN_MTU, 0x123, 8);                             /* not ours */
        push_rx(CAN_MTU, 0x700, 1);                             /* node 0 */
        push_rx(-EINTR, 0, 0);                                  /* interrupted: retried */
        push_rx(CAN_MTU, 0x7E4, 8);
        ck_assert_int_eq(socketcan_port_recv(p, &f, &t), 1);
        ck_assert_uint_eq(f.id, 0x7E4);
        ck_assert_uint_eq(f.flags, 0);
        socketcan_port_status(p, &st);
        ck_assert_uint_eq(st.rx_invalid, 8);
        ck_assert_uint_eq(st.rx_dropped, 0);
        ck_assert_int_eq(socketcan_port_recv(p, &f, &t), 0);
        socketcan_port_free(p);
}
END_TEST

START_TEST(recv_batch_is_bounded) {
        socketcan_port *p;
        lss_frame f;

        fake_reset();
        p = open_fake(NULL);
        for (int i = 0; i < 100; i++)
                push_rx(4, 0x7E4, 8);
        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), 0);
        ck_assert_uint_eq(count_calls(C_RECVMSG), 64);
        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), 0);
        ck_assert_uint_eq(count_calls(C_RECVMSG), 64 + 37); /* 36 left, then EAGAIN */
        socketcan_port_free(p);
}
END_TEST

START_TEST(recv_overflow_counter) {
        socketcan_port *p;
        lss_frame f;
        lss_transport_status st;
        rx_item *it;

        fake_reset();
        p = open_fake(NULL);
        it = push_rx(CAN_MTU, 0x7E4, 8);
        it->has_ovfl = true;
        it->ovfl = 0;
        it = push_rx(CAN_MTU, 0x7E4, 8);
        it->has_ovfl = true;
        it->ovfl = 3;
        it->has_tv = true;
        it->tv = (struct timeval) { .tv_sec = (time_t) (F.real_us / 1000000u) };
        it = push_rx(4, 0x7E4, 8); /* even on a read we throw away */
        it->has_ovfl = true;
        it->ovfl = 5;
        push_rx(CAN_MTU, 0x7E4, 8); /* no cmsg: nothing new */

        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), 1);
        socketcan_port_status(p, &st);
        ck_assert_uint_eq(st.rx_dropped, 0);
        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), 1);
        socketcan_port_status(p, &st);
        ck_assert_uint_eq(st.rx_dropped, 3);
        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), 1);
        socketcan_port_status(p, &st);
        ck_assert_uint_eq(st.rx_dropped, 5);
        ck_assert_uint_eq(st.rx_invalid, 1);
        socketcan_port_free(p);

        /* the kernel counter wraps */
        fake_reset();
        p = open_fake(NULL);
        it = push_rx(CAN_MTU, 0x7E4, 8);
        it->has_ovfl = true;
        it->ovfl = UINT32_MAX - 1;
        it = push_rx(CAN_MTU, 0x7E4, 8);
        it->has_ovfl = true;
        it->ovfl = 2;
        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), 1);
        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), 1);
        socketcan_port_status(p, &st);
        ck_assert_uint_eq(st.rx_dropped, (uint64_t) UINT32_MAX - 1 + 4);
        socketcan_port_free(p);
}
END_TEST

START_TEST(recv_error_frames) {
        socketcan_port *p;
        lss_frame f;
        lss_transport_status st;
        rx_item *it;

        fake_reset();
        p = open_fake(NULL);
        push_err_frame(CAN_ERR_CRTL, CAN_ERR_CRTL_TX_WARNING);
        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), 0); /* consumed, not returned */
        socketcan_port_status(p, &st);
        ck_assert_int_eq(st.bus, LSS_BUS_ERROR_WARNING);
        ck_assert_uint_eq(st.events, LSS_BUS_EVENT_STATE_CHANGED);
        ck_assert_uint_eq(st.error_frames, 1);

        push_err_frame(CAN_ERR_CRTL, CAN_ERR_CRTL_RX_PASSIVE);
        push_err_frame(CAN_ERR_BUSOFF, 0);
        push_rx(CAN_MTU, 0x7E4, 8);
        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), 1); /* frames after error frames still come */
        socketcan_port_status(p, &st);
        ck_assert_int_eq(st.bus, LSS_BUS_OFF);
        ck_assert_uint_eq(st.error_frames, 3);

        push_err_frame(CAN_ERR_RESTARTED, 0);
        push_err_frame(CAN_ERR_ACK, 0);
        it = push_err_frame(CAN_ERR_CRTL | CAN_ERR_CNT, CAN_ERR_CRTL_RX_OVERFLOW);
        it->cf.data[6] = 17;
        it->cf.data[7] = 130;
        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), 0);
        socketcan_port_status(p, &st);
        ck_assert_int_eq(st.bus, LSS_BUS_ERROR_ACTIVE);
        ck_assert_uint_eq(st.events, LSS_BUS_EVENT_STATE_CHANGED | LSS_BUS_EVENT_RESTARTED | LSS_BUS_EVENT_NO_ACK |
                                             LSS_BUS_EVENT_RX_OVERFLOW);
        ck_assert_uint_eq(st.rx_dropped, 1); /* the controller lost at least one frame */
        ck_assert_uint_eq(st.tx_errors, 17);
        ck_assert_uint_eq(st.rx_errors, 130);
        socketcan_port_free(p);
}
END_TEST

START_TEST(decode_error_table) {
        static const struct {
                canid_t id;
                uint8_t d1;
                lss_bus_state from, to;
                uint32_t events;
                uint64_t dropped;
        } cases[] = {
                { CAN_ERR_CRTL, CAN_ERR_CRTL_RX_WARNING, LSS_BUS_ERROR_ACTIVE, LSS_BUS_ERROR_WARNING, LSS_BUS_EVENT_STATE_CHANGED, 0 },
                { CAN_ERR_CRTL, CAN_ERR_CRTL_TX_PASSIVE | CAN_ERR_CRTL_RX_WARNING, LSS_BUS_ERROR_WARNING, LSS_BUS_ERROR_PASSIVE,
                  LSS_BUS_EVENT_STATE_CHANGED, 0 },
                { CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE, LSS_BUS_ERROR_PASSIVE, LSS_BUS_ERROR_ACTIVE, LSS_BUS_EVENT_STATE_CHANGED, 0 },
                { CAN_ERR_CRTL, CAN_ERR_CRTL_UNSPEC, LSS_BUS_ERROR_PASSIVE, LSS_BUS_ERROR_PASSIVE, 0, 0 },
                { CAN_ERR_CRTL, CAN_ERR_CRTL_TX_OVERFLOW, LSS_BUS_ERROR_ACTIVE, LSS_BUS_ERROR_ACTIVE, LSS_BUS_EVENT_TX_OVERFLOW, 0 },
                { CAN_ERR_CRTL, CAN_ERR_CRTL_RX_OVERFLOW, LSS_BUS_ERROR_ACTIVE, LSS_BUS_ERROR_ACTIVE, LSS_BUS_EVENT_RX_OVERFLOW, 1 },
                { CAN_ERR_BUSOFF, 0, LSS_BUS_ERROR_PASSIVE, LSS_BUS_OFF, LSS_BUS_EVENT_STATE_CHANGED, 0 },
                { CAN_ERR_BUSOFF | CAN_ERR_CRTL, CAN_ERR_CRTL_TX_PASSIVE, LSS_BUS_ERROR_ACTIVE, LSS_BUS_OFF, LSS_BUS_EVENT_STATE_CHANGED, 0 },
                { CAN_ERR_RESTARTED, 0, LSS_BUS_OFF, LSS_BUS_ERROR_ACTIVE, LSS_BUS_EVENT_STATE_CHANGED | LSS_BUS_EVENT_RESTARTED, 0 },
                { CAN_ERR_ACK, 0, LSS_BUS_ERROR_ACTIVE, LSS_BUS_ERROR_ACTIVE, LSS_BUS_EVENT_NO_ACK, 0 },
                { CAN_ERR_TX_TIMEOUT, 0, LSS_BUS_ERROR_ACTIVE, LSS_BUS_ERROR_ACTIVE, LSS_BUS_EVENT_TX_TIMEOUT, 0 },
                { CAN_ERR_PROT | CAN_ERR_BUSERROR, 0, LSS_BUS_ERROR_ACTIVE, LSS_BUS_ERROR_ACTIVE, LSS_BUS_EVENT_PROTOCOL, 0 },
                { CAN_ERR_LOSTARB, 0, LSS_BUS_ERROR_WARNING, LSS_BUS_ERROR_WARNING, 0, 0 },
        };

        for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
                struct can_frame cf = { .can_id = CAN_ERR_FLAG | cases[i].id, .len = CAN_ERR_DLC };
                lss_bus_state s = cases[i].from;
                uint32_t ev = 0;
                uint64_t dropped = 0;
                uint8_t tx = 1, rx = 2;

                cf.data[1] = cases[i].d1;
                cf.data[6] = 99;
                socketcan_decode_error(&cf, &s, &ev, &dropped, &tx, &rx);
                ck_assert_msg(s == cases[i].to, "case %zu: state %d", i, s);
                ck_assert_msg(ev == cases[i].events, "case %zu: events %#x", i, ev);
                ck_assert_uint_eq(dropped, cases[i].dropped);
                ck_assert_uint_eq(tx, 1); /* no CAN_ERR_CNT: counters untouched */
                ck_assert_uint_eq(rx, 2);
        }
}
END_TEST

START_TEST(frame_from_can_checks) {
        struct can_frame cf = { .can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF, .len = 8 };
        lss_frame f;

        ck_assert_int_eq(socketcan_frame_from_can(&cf, &f), -EINVAL);
        cf = (struct can_frame) { .can_id = 0x7E4, .len = 9 };
        ck_assert_int_eq(socketcan_frame_from_can(&cf, &f), -EINVAL);
        cf = (struct can_frame) { .can_id = 0x1ABCDEF0 | CAN_EFF_FLAG | CAN_RTR_FLAG, .len = 4, .data = { 1, 2, 3, 4 } };
        ck_assert_int_eq(socketcan_frame_from_can(&cf, &f), 0);
        ck_assert_uint_eq(f.id, 0x1ABCDEF0);
        ck_assert_uint_eq(f.flags, LSS_FRAME_EFF | LSS_FRAME_RTR);
        ck_assert_uint_eq(f.len, 4);
        ck_assert_uint_eq(f.data[0], 0);

        /* round trip */
        lss_frame in, out;
        struct can_frame c2;
        lss_encode_fastscan(&in, 0x12345678, 31, 0, 0);
        ck_assert_int_eq(socketcan_frame_to_can(&in, &c2), 0);
        ck_assert_int_eq(socketcan_frame_from_can(&c2, &out), 0);
        ck_assert_mem_eq(&in, &out, sizeof(in));
}
END_TEST

START_TEST(recv_link_errors) {
        state_log log = {};
        socketcan_port *p;
        lss_frame f;

        fake_reset();
        p = open_fake(&log);
        push_rx(-ENETDOWN, 0, 0);
        push_rx(CAN_MTU, 0x7E4, 8);
        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), -ENETDOWN);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_DOWN);
        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), 1); /* queued frames still readable */
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_DOWN); /* only a send proves it is up */

        push_rx(-EBADF, 0, 0);
        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), -EBADF);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_DOWN);

        push_rx(-ENODEV, 0, 0);
        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), -ENODEV);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_GONE);
        ck_assert_int_eq(socketcan_port_fd(p), -1);
        ck_assert_int_eq(F.n_open_fds, 0);
        ck_assert_uint_eq(log.n, 2);
        ck_assert_int_eq(log.new_state[1], LSS_LINK_GONE);
        socketcan_port_free(p);
}
END_TEST

/* ---- receive time ---- */

START_TEST(rx_time_conversion) {
        socketcan_port *p;
        lss_frame f = lss_req();
        uint64_t t, off;
        lss_frame req = lss_req();
        rx_item *it;

        fake_reset();
        p = open_fake(NULL);
        off = F.real_us - F.mono_us;

        /* arrived 10 ms before we read it */
        it = push_rx(CAN_MTU, 0x7E4, 8);
        it->has_tv = true;
        it->tv = us_to_timeval(F.real_us - 10000);
        ck_assert_int_eq(socketcan_port_recv(p, &f, &t), 1);
        ck_assert_uint_eq(t, F.mono_us - 10000);
        ck_assert_uint_eq(socketcan_port_now(p), F.mono_us);

        /* a stamp after the read is impossible: clamp to the read time */
        it = push_rx(CAN_MTU, 0x7E4, 8);
        it->has_tv = true;
        it->tv = us_to_timeval(F.real_us + 5000);
        ck_assert_int_eq(socketcan_port_recv(p, &f, &t), 1);
        ck_assert_uint_eq(t, F.mono_us);

        /* Request sent at S; a stale answer arrived 2 ms before S; then the
         * realtime clock is stepped back 1 s before we read it. The new
         * offset alone would put the frame 998 ms after S: it must stay before S. */
        uint64_t s;
        F.mono_us += 50000;
        F.real_us += 50000;
        ck_assert_int_eq(socketcan_port_send(p, &req), 0);
        s = F.mono_us;
        it = push_rx(CAN_MTU, 0x7E4, 8);
        it->has_tv = true;
        it->tv = us_to_timeval(s + off - 2000);
        F.mono_us += 3000;
        F.real_us += 3000 - 1000000;
        ck_assert_int_eq(socketcan_port_recv(p, &f, &t), 1);
        ck_assert_uint_lt(t, s);
        ck_assert_uint_eq(t, s - 2000);

        /* Step forward by 1 s after a fresh answer arrived: it may look
         * earlier (safe: the engine retries), never later. */
        off = F.real_us - F.mono_us;
        F.mono_us += 1000;
        F.real_us += 1000;
        ck_assert_int_eq(socketcan_port_send(p, &req), 0);
        s = F.mono_us;
        it = push_rx(CAN_MTU, 0x7E4, 8);
        it->has_tv = true;
        it->tv = us_to_timeval(s + off + 500);
        F.mono_us += 1000;
        F.real_us += 1000 + 1000000;
        ck_assert_int_eq(socketcan_port_recv(p, &f, &t), 1);
        ck_assert_uint_le(t, s + 500);

        /* an old offset sample (> 1 s) is not used */
        off = F.real_us - F.mono_us;
        F.mono_us += 5000000;
        F.real_us += 5000000 + 3000; /* 3 ms of slew meanwhile */
        it = push_rx(CAN_MTU, 0x7E4, 8);
        it->has_tv = true;
        it->tv = us_to_timeval(F.real_us - 1000);
        ck_assert_int_eq(socketcan_port_recv(p, &f, &t), 1);
        ck_assert_uint_eq(t, F.mono_us - 1000);

        /* a broken clock gives 0: "long ago", never "fresh" */
        it = push_rx(CAN_MTU, 0x7E4, 8);
        F.clock_ret = -EINVAL;
        ck_assert_int_eq(socketcan_port_recv(p, &f, &t), 1);
        ck_assert_uint_eq(t, 0);
        ck_assert_uint_eq(socketcan_port_now(p), 0);
        socketcan_port_free(p);
}
END_TEST

/* ---- rtnetlink-driven state ---- */

START_TEST(link_events) {
        state_log log = {};
        socketcan_port *p;
        const unsigned up = IFF_UP | IFF_RUNNING;

        fake_reset();
        F.ifindex = -ENODEV;
        p = open_fake(&log);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_GONE);

        /* other interfaces do not matter */
        ck_assert_int_eq(socketcan_port_link_event(p, 3, "eth0", true, up), 0);
        ck_assert_int_eq(socketcan_port_link_event(p, 3, "eth0", false, 0), 0);
        ck_assert_int_eq(socketcan_port_link_event(p, 3, "", true, up), 0);
        ck_assert_int_eq(socketcan_port_link_event(p, 7, "can0", false, 0), 0); /* deleted while gone */
        ck_assert_uint_eq(count_calls(C_SOCKET), 0);

        /* can0 appears: re-opened by name */
        F.ifindex = 7;
        ck_assert_int_eq(socketcan_port_link_event(p, 7, "can0", true, up), 1);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_UP);
        ck_assert_int_eq(socketcan_port_fd(p), FAKE_FD);
        ck_assert_int_eq(socketcan_port_ifindex(p), 7);
        ck_assert_int_eq(F.bound.can_ifindex, 7);
        ck_assert_uint_eq(log.n, 1);
        ck_assert_int_eq(log.old_state[0], LSS_LINK_GONE);
        ck_assert_int_eq(log.new_state[0], LSS_LINK_UP);
        ck_assert_int_eq(log.fd_during[0], FAKE_FD); /* the new fd is there to add */

        /* repeats change nothing */
        ck_assert_int_eq(socketcan_port_link_event(p, 7, "can0", true, up), 0);
        ck_assert_uint_eq(count_calls(C_SOCKET), 1);

        /* down and up: a fresh socket (the old one holds a pending ENETDOWN) */
        ck_assert_int_eq(socketcan_port_link_event(p, 7, "can0", true, IFF_UP), 1);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_DOWN);
        ck_assert_uint_eq(count_calls(C_SOCKET), 1);
        ck_assert_int_eq(socketcan_port_link_event(p, 7, "", true, up), 1); /* nameless but our ifindex */
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_UP);
        ck_assert_uint_eq(count_calls(C_SOCKET), 2);

        /* deleted */
        ck_assert_int_eq(socketcan_port_link_event(p, 7, "can0", false, 0), 1);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_GONE);
        ck_assert_int_eq(F.n_open_fds, 0);

        /* back with a new ifindex, link down */
        F.ifindex = 9;
        F.if_flags = 0;
        ck_assert_int_eq(socketcan_port_link_event(p, 9, "can0", true, 0), 1);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_DOWN);
        ck_assert_int_eq(socketcan_port_ifindex(p), 9);
        ck_assert_int_eq(F.n_open_fds, 1);

        /* a new netdev took the name while we are bound to the old one: rebind */
        F.ifindex = 11;
        F.if_flags = up;
        ck_assert_int_eq(socketcan_port_link_event(p, 11, "can0", true, up), 1);
        ck_assert_int_eq(socketcan_port_ifindex(p), 11);
        ck_assert_int_eq(F.n_open_fds, 1);

        /* renamed away */
        ck_assert_int_eq(socketcan_port_link_event(p, 11, "old-can0", true, up), 1);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_GONE);
        ck_assert_int_eq(F.n_open_fds, 0);

        /* event races with deletion: lookup fails, still gone */
        F.ifindex = -ENODEV;
        ck_assert_int_eq(socketcan_port_link_event(p, 12, "can0", true, up), 0);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_GONE);

        /* re-open fails for another reason */
        F.ifindex = 12;
        F.socket_ret = -EMFILE;
        ck_assert_int_eq(socketcan_port_link_event(p, 12, "can0", true, up), -EMFILE);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_GONE);

        /* explicit reopen */
        F.socket_ret = 0;
        ck_assert_int_eq(socketcan_port_reopen(p), 0);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_UP);
        F.ifindex = -ENODEV;
        ck_assert_int_eq(socketcan_port_reopen(p), -ENODEV);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_GONE);
        ck_assert_int_eq(F.n_open_fds, 0);
        socketcan_port_free(p);
}
END_TEST

START_TEST(bus_state_resets_when_link_comes_up) {
        socketcan_port *p;
        lss_frame f;
        lss_transport_status st;

        fake_reset();
        p = open_fake(NULL);
        push_err_frame(CAN_ERR_BUSOFF, 0);
        ck_assert_int_eq(socketcan_port_recv(p, &f, NULL), 0);
        ck_assert_int_eq(socketcan_port_link_event(p, 7, "can0", true, IFF_UP), 1);
        socketcan_port_status(p, &st);
        ck_assert_int_eq(st.bus, LSS_BUS_OFF);
        ck_assert_int_eq(socketcan_port_link_event(p, 7, "can0", true, IFF_UP | IFF_RUNNING), 1);
        socketcan_port_status(p, &st);
        ck_assert_int_eq(st.bus, LSS_BUS_ERROR_ACTIVE);
        ck_assert(st.events & LSS_BUS_EVENT_STATE_CHANGED);
        ck_assert(st.events & LSS_BUS_EVENT_LINK_CHANGED);
        socketcan_port_free(p);
}
END_TEST

/* ---- the seam ---- */

START_TEST(as_transport) {
        socketcan_port *p;
        lss_transport t;
        lss_frame f = lss_req();
        uint64_t rx;
        lss_transport_status st;

        fake_reset();
        p = open_fake(NULL);
        ck_assert_int_eq(socketcan_port_transport(p, &t), 0);
        ck_assert_int_eq(lss_transport_get_fd(&t), FAKE_FD);
        ck_assert_uint_eq(lss_transport_now(&t), F.mono_us);
        ck_assert_int_eq(lss_transport_send(&t, &f), 0);
        ck_assert_uint_eq(F.n_written, 1);
        push_rx(CAN_MTU, 0x7E4, 8);
        ck_assert_int_eq(lss_transport_recv(&t, &f, &rx), 1);
        ck_assert_uint_eq(f.id, 0x7E4);
        ck_assert_int_eq(lss_transport_recv(&t, &f, &rx), 0);
        push_err_frame(CAN_ERR_ACK, 0);
        ck_assert_int_eq(lss_transport_recv(&t, &f, &rx), 0);
        ck_assert_int_eq(lss_transport_status_get(&t, &st), 0);
        ck_assert_uint_eq(st.events, LSS_BUS_EVENT_NO_ACK);
        /* link state, echo and link events through the seam */
        ck_assert_str_eq(t.ops->kind, "SocketCAN");
        ck_assert_int_eq(lss_transport_link(&t), LSS_LINK_UP);
        ck_assert(lss_transport_echoes(&t));
        ck_assert_uint_eq(lss_transport_next_event(&t), UINT64_MAX);
        ck_assert(!lss_transport_retune_caused(&t, LSS_LINK_DOWN)); /* it never retuned */
        lss_link_event ev = { .ifindex = 99, .ifname = "can5", .present = true, .flags = IFF_UP | IFF_RUNNING };
        ck_assert_int_eq(lss_transport_link_event(&t, &ev), 0); /* another interface */
        ev = (lss_link_event) { .ifindex = 7, .ifname = "can0", .present = true, .flags = IFF_UP };
        ck_assert_int_eq(lss_transport_link_event(&t, &ev), 1); /* not running: down */
        ck_assert_int_eq(lss_transport_link(&t), LSS_LINK_DOWN);
        ev.present = false;
        ck_assert_int_eq(lss_transport_link_event(&t, &ev), 1);
        ck_assert_int_eq(lss_transport_link(&t), LSS_LINK_GONE);
        ck_assert(!lss_transport_echoes(&t));
        ck_assert_int_eq(lss_transport_get_fd(&t), -1);
        lss_transport_close(&t); /* frees the port: valgrind checks */
        ck_assert_ptr_null(t.ops);
        ck_assert_int_eq(F.n_open_fds, 0);
        lss_transport_close(&t); /* twice is harmless */
}
END_TEST

static int dummy_send(void *impl, const lss_frame *f) {
        (*(int *) impl)++;
        return 0;
}

static uint64_t dummy_now(void *impl) {
        return 42;
}

START_TEST(transport_defaults_and_names) {
        static const lss_transport_ops ops = { .send = dummy_send, .now = dummy_now };
        int sent = 0;
        lss_transport t = { .ops = &ops, .impl = &sent };
        lss_transport_status st;
        lss_frame f = lss_req();

        memset(&st, 0xFF, sizeof(st));
        ck_assert_int_eq(lss_transport_status_get(&t, &st), 0);
        ck_assert_int_eq(st.link, LSS_LINK_UP);
        ck_assert_int_eq(st.bus, LSS_BUS_ERROR_ACTIVE);
        ck_assert_uint_eq(st.rx_dropped, 0);
        ck_assert_int_eq(lss_transport_get_fd(&t), -1);
        ck_assert_int_eq(lss_transport_send(&t, &f), 0);
        ck_assert_int_eq(sent, 1);
        ck_assert_uint_eq(lss_transport_now(&t), 42);
        /* optional ops: always up, no echo, no wake-up, no links, nothing to retune */
        ck_assert_int_eq(lss_transport_link(&t), LSS_LINK_UP);
        ck_assert(!lss_transport_echoes(&t));
        ck_assert_uint_eq(lss_transport_next_event(&t), UINT64_MAX);
        lss_link_event ev = { .ifindex = 1, .ifname = "can0", .present = true };
        ck_assert_int_eq(lss_transport_link_event(&t, &ev), -EOPNOTSUPP);
        lss_retune_wait w;
        ck_assert_int_eq(lss_transport_retune_start(&t, 250000, &w), -EOPNOTSUPP);
        ck_assert(!lss_transport_retune_caused(&t, LSS_LINK_DOWN));
        lss_transport_close(&t);
        ck_assert_ptr_null(t.impl);

        ck_assert_str_eq(lss_link_state_to_string(LSS_LINK_UP), "up");
        ck_assert_str_eq(lss_link_state_to_string(LSS_LINK_DOWN), "down");
        ck_assert_str_eq(lss_link_state_to_string(LSS_LINK_GONE), "gone");
        ck_assert_ptr_null(lss_link_state_to_string(_LSS_LINK_STATE_MAX));
        ck_assert_str_eq(lss_bus_state_to_string(LSS_BUS_ERROR_ACTIVE), "error-active");
        ck_assert_str_eq(lss_bus_state_to_string(LSS_BUS_ERROR_WARNING), "error-warning");
        ck_assert_str_eq(lss_bus_state_to_string(LSS_BUS_ERROR_PASSIVE), "error-passive");
        ck_assert_str_eq(lss_bus_state_to_string(LSS_BUS_OFF), "bus-off");
        ck_assert_ptr_null(lss_bus_state_to_string((lss_bus_state) -1));
}
END_TEST

/* ---- real system calls ---- */

/* On this host socket(AF_CAN) fails; on a kernel with CAN, binding a CAN
 * socket to lo fails with ENODEV (not a CAN device): gone. Either is right. */
START_TEST(real_host_open) {
        socketcan_port *p = NULL;
        int r;

        ck_assert_int_eq(socketcan_port_open("lssnosuch0", NULL, &p), 0);
        ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_GONE);
        ck_assert_int_eq(socketcan_port_reopen(p), -ENODEV);
        p = socketcan_port_free(p);

        r = socketcan_port_open("lo", NULL, &p);
        if (r == 0) {
                ck_assert_int_eq(socketcan_port_state(p), LSS_LINK_GONE);
                socketcan_port_free(p);
        } else
                ck_assert_int_eq(r, -EAFNOSUPPORT);
        ck_assert_ptr_null(socketcan_port_free(NULL));
}
END_TEST

/* A datagram socketpair stands in for the CAN socket: real write(),
 * recvmsg(), poll() and close() with the port's own buffers. */
typedef struct pair_ctx {
        int fds[2];
} pair_ctx;

static int pair_socket(void *ud, int domain, int type, int protocol) {
        return ((pair_ctx *) ud)->fds[0];
}

static int pair_ok(void *ud, int fd, int level, int name, const void *val, socklen_t len) {
        return 0;
}

static int pair_bind(void *ud, int fd, const struct sockaddr *sa, socklen_t len) {
        return 0;
}

static int pair_index(void *ud, const char *name) {
        return 5;
}

static int pair_flags(void *ud, int fd, const char *name, unsigned *ret_flags) {
        *ret_flags = IFF_UP | IFF_RUNNING;
        return 0;
}

START_TEST(real_io_on_socketpair) {
        const can_sys *d = can_sys_default();
        pair_ctx ctx;
        can_sys sys;
        socketcan_config cfg = { 0 };
        socketcan_port *p = NULL;
        lss_frame f = lss_req(), g;
        struct can_frame cf;
        uint64_t t0, t, rx;
        int sent = 0, r;

        ck_assert_int_eq(socketpair(AF_UNIX, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, ctx.fds), 0);
        sys = *d;
        sys.socket = pair_socket;
        sys.setsockopt = pair_ok;
        sys.bind = pair_bind;
        sys.if_nametoindex = pair_index;
        sys.if_flags = pair_flags;
        sys.userdata = &ctx;
        cfg.sys = &sys;
        ck_assert_int_eq(socketcan_port_open("can9", &cfg, &p), 0);
        ck_assert_int_eq(socketcan_port_fd(p), ctx.fds[0]);

        /* out */
        ck_assert_int_eq(socketcan_port_send(p, &f), 0);
        ck_assert_int_eq(read(ctx.fds[1], &cf, sizeof(cf)), CAN_MTU);
        ck_assert_uint_eq(cf.can_id, 0x7E5);
        ck_assert_uint_eq(cf.data[0], 0x04);

        /* in */
        ck_assert_int_eq(socketcan_port_recv(p, &g, &rx), 0);
        cf = (struct can_frame) { .can_id = 0x7E4, .len = 8, .data = { 0x44 } };
        ck_assert_int_eq(write(ctx.fds[1], &cf, 8), 8); /* short */
        ck_assert_int_eq(write(ctx.fds[1], &cf, sizeof(cf)), CAN_MTU);
        t0 = socketcan_port_now(p);
        ck_assert_int_eq(socketcan_port_recv(p, &g, &rx), 1);
        ck_assert_uint_eq(g.data[0], 0x44);
        ck_assert_uint_ge(rx, t0);
        ck_assert_uint_le(rx, socketcan_port_now(p));

        /* fill the peer's queue: EAGAIN at once, no waiting */
        for (;;) {
                r = socketcan_port_send(p, &f);
                if (r < 0)
                        break;
                sent++;
                ck_assert_int_lt(sent, 100000);
        }
        t0 = socketcan_port_now(p);
        ck_assert_int_eq(socketcan_port_send(p, &f), -EAGAIN);
        t = socketcan_port_now(p);
        ck_assert_int_eq(r, -EAGAIN);
        ck_assert_int_gt(sent, 0);
        ck_assert_uint_lt(t - t0, 20000);

        /* drain one: room again, and nothing was duplicated */
        ck_assert_int_eq(read(ctx.fds[1], &cf, sizeof(cf)), CAN_MTU);
        ck_assert_int_eq(socketcan_port_send(p, &f), 0);
        int n = 0;
        while (read(ctx.fds[1], &cf, sizeof(cf)) == CAN_MTU)
                n++;
        ck_assert_int_eq(n, sent); /* sent-1 left + the new one */

        socketcan_port_free(p); /* closes fds[0] */
        close(ctx.fds[1]);
}
END_TEST

/* The real wrappers keep the negative-errno convention. */
START_TEST(real_sys_wrappers) {
        const can_sys *d = can_sys_default();
        const int one = 1;
        struct sockaddr_un bad = { .sun_family = AF_UNIX, .sun_path = "/nonexistent-dir/x" };
        struct timespec ts;
        unsigned flags = 0;
        int fd;

        fd = d->socket(NULL, AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
        ck_assert_int_ge(fd, 0);
        ck_assert_int_eq(d->setsockopt(NULL, fd, SOL_SOCKET, SO_PASSCRED, &one, sizeof(one)), 0);
        ck_assert_int_lt(d->setsockopt(NULL, fd, SOL_CAN_RAW, CAN_RAW_FILTER, &one, sizeof(one)), 0); /* EOPNOTSUPP here */
        ck_assert_int_eq(d->bind(NULL, fd, (const struct sockaddr *) &bad, sizeof(bad)), -ENOENT);
        /* SIOCGIFFLAGS works on any socket */
        ck_assert_int_eq(d->if_flags(NULL, fd, "lo", &flags), 0);
        ck_assert(flags & IFF_LOOPBACK);
        ck_assert_int_eq(d->if_flags(NULL, fd, "lssnosuch0", &flags), -ENODEV);
        ck_assert_int_eq(d->if_flags(NULL, fd, "0123456789abcdef", &flags), -EINVAL);
        ck_assert_int_eq(d->if_nametoindex(NULL, "lo"), 1);
        ck_assert_int_eq(d->if_nametoindex(NULL, "lssnosuch0"), -ENODEV);
        ck_assert_int_eq(d->clock_gettime(NULL, CLOCK_MONOTONIC, &ts), 0);
        ck_assert_int_eq(d->clock_gettime(NULL, (clockid_t) 12345, &ts), -EINVAL);
        ck_assert_int_eq(d->close(NULL, fd), 0);
        ck_assert_int_eq(d->close(NULL, fd), -EBADF);
        ck_assert_int_eq(d->socket(NULL, 12345, SOCK_DGRAM, 0), -EAFNOSUPPORT);
        ck_assert_int_eq(d->write(NULL, -1, "x", 1), -EBADF);
}
END_TEST

int main(void) {
        Suite *s = suite_create("socketcan");
        TCase *tc = tcase_create("core");

        tcase_add_test(tc, filter_array_exact);
        tcase_add_test(tc, filter_semantics_all_ids);
        tcase_add_test(tc, err_mask_bits);
        tcase_add_test(tc, open_order_and_options);
        tcase_add_test(tc, open_missing_interface);
        tcase_add_test(tc, open_no_af_can);
        tcase_add_test(tc, open_setsockopt_failures);
        tcase_add_test(tc, open_without_echo);
        tcase_add_test(tc, open_bind_results);
        tcase_add_test(tc, open_link_down);
        tcase_add_test(tc, open_bad_names);
        tcase_add_test(tc, send_conversions);
        tcase_add_test(tc, send_full_queue_returns_at_once);
        tcase_add_test(tc, send_eintr_and_short);
        tcase_add_test(tc, send_enetdown_recovers);
        tcase_add_test(tc, send_enodev_goes_gone);
        tcase_add_test(tc, recv_frames);
        tcase_add_test(tc, recv_own_echo);
        tcase_add_test(tc, recv_invalid_reads);
        tcase_add_test(tc, recv_batch_is_bounded);
        tcase_add_test(tc, recv_overflow_counter);
        tcase_add_test(tc, recv_error_frames);
        tcase_add_test(tc, decode_error_table);
        tcase_add_test(tc, frame_from_can_checks);
        tcase_add_test(tc, recv_link_errors);
        tcase_add_test(tc, rx_time_conversion);
        tcase_add_test(tc, link_events);
        tcase_add_test(tc, bus_state_resets_when_link_comes_up);
        tcase_add_test(tc, as_transport);
        tcase_add_test(tc, transport_defaults_and_names);
        tcase_add_test(tc, real_host_open);
        tcase_add_test(tc, real_io_on_socketpair);
        tcase_add_test(tc, real_sys_wrappers);
        suite_add_tcase(s, tc);

        SRunner *sr = srunner_create(s);
        srunner_run_all(sr, CK_NORMAL);
        int failed = srunner_ntests_failed(sr);
        srunner_free(sr);
        return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
