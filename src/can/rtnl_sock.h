/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* NETLINK_ROUTE sockets as rtnl_watch.c and rtnl_retune.c use them: inside
 * src/can only. */
#pragma once

#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

#include "can/can_sys.h"

/* The kernel sizes dump messages to the largest buffer we ever read with,
 * up to 32 KiB: with this size nothing is ever truncated. */
#define RTNL_BUFFER_SIZE 32768u
/* How long one request may wait for its answer. */
#define RTNL_REQUEST_TIMEOUT_US 1000000u

/* A non-blocking socket subscribed to `groups` (0: requests only). */
int rtnl_sock_open(const can_sys *sys, unsigned groups);
/* One datagram from the kernel; -EAGAIN when none is pending, -EMSGSIZE
 * when it was truncated. */
ssize_t rtnl_sock_recv(const can_sys *sys, int fd, void *buf, size_t size);
/* CLOCK_MONOTONIC µs through `sys` (0 if it fails). */
uint64_t rtnl_sock_now(const can_sys *sys);
