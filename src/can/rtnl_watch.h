/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* rtnetlink: watch network links appear, disappear and go up/down (to
 * re-open CAN ports by name), learn their current state, and set the bit rate
 * of a real CAN controller (rtnl_retune.h).
 *
 * Start-up order, so no change is missed: rtnl_watch_new() (subscribes),
 * then rtnl_dump_links() (current state), then poll rtnl_watch_fd() and call
 * rtnl_watch_process(). Events that happen during the dump arrive twice;
 * that is harmless because every event carries the whole link state. */
#pragma once

#include <net/if.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "can/can_sys.h"

typedef struct rtnl_link {
        int ifindex;
        char ifname[IFNAMSIZ];  /* "" if the message had none */
        unsigned flags;         /* IFF_* (IFF_UP, IFF_RUNNING, ...) */
        char kind[16];          /* IFLA_INFO_KIND: "can", "vcan", ... or "" */
        uint32_t bitrate;       /* kind "can" with IFLA_CAN_BITTIMING: bit/s; else 0 */
        bool removed;           /* RTM_DELLINK */
} rtnl_link;

typedef void (*rtnl_link_cb)(const rtnl_link *link, void *userdata);

/* ---- messages (pure, no I/O) ---- */

/* Parses a buffer of netlink messages as read from a NETLINK_ROUTE socket and
 * calls `cb` for each RTM_NEWLINK/RTM_DELLINK. Other message types are
 * skipped. Returns:
 *   0        all messages parsed, no NLMSG_DONE/NLMSG_ERROR seen
 *   1        NLMSG_DONE, or NLMSG_ERROR with error 0 (an ACK)
 *   -errno   NLMSG_ERROR carrying that error
 *   -EBADMSG malformed or truncated data (messages before it were delivered)
 * `seq`, if non-NULL, receives the sequence number of the DONE/ERROR message. */
int rtnl_parse(const void *buf, size_t len, rtnl_link_cb cb, void *userdata, uint32_t *seq);

/* Builders write one request into buf and return its length, or -ENOBUFS if
 * size is too small. All but the dump ask for an ACK (NLM_F_ACK).
 * rtnl_build_getlink: by ifindex (> 0), else by ifname (non-NULL), else a dump. */
int rtnl_build_getlink(void *buf, size_t size, uint32_t seq, int ifindex, const char *ifname);
int rtnl_build_set_link_up(void *buf, size_t size, uint32_t seq, int ifindex, bool up);
/* IFLA_LINKINFO { KIND "can", DATA { IFLA_CAN_BITTIMING { bitrate, rest 0 } } }:
 * the kernel computes the sample point and segments itself. */
int rtnl_build_set_can_bitrate(void *buf, size_t size, uint32_t seq, int ifindex, uint32_t bitrate);

/* ---- link watcher ---- */

typedef struct rtnl_watch rtnl_watch;

/* Subscribes to RTMGRP_LINK. sys NULL = real system calls. */
int rtnl_watch_new(const can_sys *sys, rtnl_link_cb cb, void *userdata, rtnl_watch **ret);
rtnl_watch *rtnl_watch_free(rtnl_watch *w);
/* Pollable (POLLIN) fd. */
int rtnl_watch_fd(const rtnl_watch *w);
/* Reads every pending event and calls the callback; returns the number of
 * links reported, or -errno. When the kernel dropped events (ENOBUFS: our
 * receive queue overflowed) it re-dumps all links, so the callback sees the
 * current state again. */
int rtnl_watch_process(rtnl_watch *w);

/* ---- one-shot requests (own socket, synchronous, ≤ 1 s) ---- */

/* Calls cb for every link the kernel has now. Returns the count or -errno. */
int rtnl_dump_links(const can_sys *sys, rtnl_link_cb cb, void *userdata);
/* One link by name; -ENODEV if there is none. */
int rtnl_get_link(const can_sys *sys, const char *ifname, rtnl_link *ret);
/* Whether a retune (rtnl_retune.h) would be allowed on this running
 * controller, found out without changing anything: a bit-timing change to
 * the rate it runs at, which the kernel checks for CAP_NET_ADMIN and then
 * refuses because the controller runs. 0: allowed; -EPERM (or -EACCES)
 * without CAP_NET_ADMIN; -EOPNOTSUPP unless the link's kind is "can";
 * -ENETDOWN when it is not up; -ENODEV when there is no such link. `ret`
 * (may be NULL) gets the link as the kernel reported it. */
int rtnl_check_can_bitrate(const can_sys *sys, const char *ifname, rtnl_link *ret);
