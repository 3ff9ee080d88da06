/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include "can/can_sys.h"

#include <errno.h>
#include <stdint.h>
#include <string.h>
#include <sys/ioctl.h>
#include <unistd.h>

static int neg_errno(void) {
        return errno > 0 ? -errno : -EIO;
}

static int sys_socket(void *ud, int domain, int type, int protocol) {
        int fd = socket(domain, type, protocol);
        return fd < 0 ? neg_errno() : fd;
}

static int sys_setsockopt(void *ud, int fd, int level, int name, const void *val, socklen_t len) {
        return setsockopt(fd, level, name, val, len) < 0 ? neg_errno() : 0;
}

static int sys_bind(void *ud, int fd, const struct sockaddr *sa, socklen_t len) {
        return bind(fd, sa, len) < 0 ? neg_errno() : 0;
}

static ssize_t sys_write(void *ud, int fd, const void *buf, size_t len) {
        ssize_t n = write(fd, buf, len);
        return n < 0 ? neg_errno() : n;
}

static ssize_t sys_recvmsg(void *ud, int fd, struct msghdr *msg, int flags) {
        ssize_t n = recvmsg(fd, msg, flags);
        return n < 0 ? neg_errno() : n;
}

static int sys_poll(void *ud, struct pollfd *fds, nfds_t n, int timeout_ms) {
        int r = poll(fds, n, timeout_ms);
        return r < 0 ? neg_errno() : r;
}

static int sys_if_nametoindex(void *ud, const char *name) {
        unsigned idx = if_nametoindex(name);
        if (idx == 0)
                return neg_errno();
        return idx > INT32_MAX ? -ERANGE : (int) idx;
}

static int sys_if_flags(void *ud, int fd, const char *name, unsigned *ret_flags) {
        struct ifreq ifr = {};

        if (strlen(name) >= sizeof(ifr.ifr_name))
                return -EINVAL;
        strncpy(ifr.ifr_name, name, sizeof(ifr.ifr_name) - 1);
        if (ioctl(fd, SIOCGIFFLAGS, &ifr) < 0)
                return neg_errno();
        *ret_flags = (unsigned short) ifr.ifr_flags;
        return 0;
}

static int sys_close(void *ud, int fd) {
        /* Linux releases the fd even when close() fails: never retry. */
        return close(fd) < 0 ? neg_errno() : 0;
}

static int sys_clock_gettime(void *ud, clockid_t clock, struct timespec *ts) {
        return clock_gettime(clock, ts) < 0 ? neg_errno() : 0;
}

static const can_sys default_sys = {
        .socket = sys_socket,
        .setsockopt = sys_setsockopt,
        .bind = sys_bind,
        .write = sys_write,
        .recvmsg = sys_recvmsg,
        .poll = sys_poll,
        .if_nametoindex = sys_if_nametoindex,
        .if_flags = sys_if_flags,
        .close = sys_close,
        .clock_gettime = sys_clock_gettime,
};

const can_sys *can_sys_default(void) {
        return &default_sys;
}
