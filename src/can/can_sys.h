/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Every system call the SocketCAN port and the rtnetlink code make goes
 * through this table, so that unit tests can replay what a kernel with CAN
 * would do (EAFNOSUPPORT, ENOBUFS runs, ENETDOWN, ENODEV, short reads,
 * overflow counters, netlink replies) on a host that has no AF_CAN at all.
 *
 * Unlike libc, every entry returns a negative errno on failure and never
 * touches errno. */
#pragma once

#include <net/if.h>
#include <poll.h>
#include <stddef.h>
#include <sys/socket.h>
#include <sys/types.h>
#include <time.h>

typedef struct can_sys {
        int (*socket)(void *ud, int domain, int type, int protocol);
        int (*setsockopt)(void *ud, int fd, int level, int name, const void *val, socklen_t len);
        int (*bind)(void *ud, int fd, const struct sockaddr *sa, socklen_t len);
        ssize_t (*write)(void *ud, int fd, const void *buf, size_t len);
        ssize_t (*recvmsg)(void *ud, int fd, struct msghdr *msg, int flags);
        int (*poll)(void *ud, struct pollfd *fds, nfds_t n, int timeout_ms);
        /* ifindex (> 0) of a network interface, -ENODEV if there is none */
        int (*if_nametoindex)(void *ud, const char *name);
        /* IFF_* flags of an interface (SIOCGIFFLAGS through socket fd) */
        int (*if_flags)(void *ud, int fd, const char *name, unsigned *ret_flags);
        int (*close)(void *ud, int fd);
        int (*clock_gettime)(void *ud, clockid_t clock, struct timespec *ts);
        void *userdata;
} can_sys;

/* The real system calls. */
const can_sys *can_sys_default(void);
