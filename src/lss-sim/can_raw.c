/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <net/if.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

#include <linux/can/raw.h>

#include "can/socketcan.h"
#include "lss-sim/can_raw.h"

#ifndef SO_RXQ_OVFL
#define SO_RXQ_OVFL 40
#endif

static int set_int(int fd, int level, int name, int value) {
        return setsockopt(fd, level, name, &value, sizeof(value)) < 0 ? -errno : 0;
}

int can_raw_open(const char *ifname) {
        /* EFF and RTR in the mask: extended or remote frames that merely
         * look like LSS or NMT never arrive */
        const struct can_filter filters[] = {
                { .can_id = LSS_COB_MASTER, .can_mask = CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_SFF_MASK },
                { .can_id = NMT_COB, .can_mask = CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_SFF_MASK },
                /* SDO requests 0x600..0x67F: the master's "is this node-ID taken" probe */
                { .can_id = 0x600, .can_mask = CAN_EFF_FLAG | CAN_RTR_FLAG | 0x780 },
        };
        const can_err_mask_t no_errors = 0;
        struct sockaddr_can addr = { .can_family = AF_CAN };
        unsigned ifindex;
        int fd, r;

        if (strlen(ifname) >= IFNAMSIZ)
                return -EINVAL;
        fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
        if (fd < 0)
                return -errno;

        /* every option before bind, so no unfiltered frame slips in */
        if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, filters, sizeof(filters)) < 0 ||
            setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &no_errors, sizeof(no_errors)) < 0) {
                r = -errno;
                goto fail;
        }
        /* the default, said out loud: the slaves never hear themselves */
        r = set_int(fd, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, 0);
        if (r < 0)
                goto fail;
        r = set_int(fd, SOL_SOCKET, SO_RXQ_OVFL, 1);
        if (r < 0)
                goto fail;

        ifindex = if_nametoindex(ifname);
        if (ifindex == 0) {
                r = errno == ENXIO || errno == 0 ? -ENODEV : -errno;
                goto fail;
        }
        addr.can_ifindex = (int) ifindex;
        if (bind(fd, (struct sockaddr *) &addr, sizeof(addr)) < 0) {
                r = -errno;
                goto fail;
        }
        return fd;

fail:
        close(fd);
        return r;
}

int can_raw_recv(int fd, lss_frame *f, uint32_t *drops) {
        struct can_frame cf;
        struct iovec iov = { .iov_base = &cf, .iov_len = sizeof(cf) };
        union {
                struct cmsghdr align;
                char buf[CMSG_SPACE(sizeof(uint32_t))];
        } control;
        struct msghdr msg = {
                .msg_iov = &iov,
                .msg_iovlen = 1,
                .msg_control = &control,
                .msg_controllen = sizeof(control),
        };
        ssize_t n;

        n = recvmsg(fd, &msg, MSG_DONTWAIT);
        if (n < 0) {
                if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)
                        return 0;
                return -errno;
        }
        for (struct cmsghdr *c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c))
                if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL && drops)
                        memcpy(drops, CMSG_DATA(c), sizeof(*drops));
        /* only classic frames are expected (CAN FD is not enabled) */
        if (n != (ssize_t) CAN_MTU || (msg.msg_flags & MSG_TRUNC))
                return -EBADMSG;
        if (socketcan_frame_from_can(&cf, f) < 0)
                return -EBADMSG;
        return 1;
}

int can_raw_send(int fd, const lss_frame *f) {
        struct can_frame cf;
        ssize_t n;
        int r;

        r = socketcan_frame_to_can(f, &cf);
        if (r < 0)
                return r;
        n = write(fd, &cf, CAN_MTU);
        if (n < 0)
                return errno == EWOULDBLOCK ? -EAGAIN : -errno;
        if (n != (ssize_t) CAN_MTU)
                return -EIO;
        return 0;
}
