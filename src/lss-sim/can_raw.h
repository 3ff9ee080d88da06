/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The simulator's own CAN_RAW socket. Unlike the master's transport it
 * listens to the master's side of the protocol: LSS requests (0x7E5) and NMT
 * commands (0x000). */
#pragma once

#include <stdbool.h>
#include <stdint.h>

#include <linux/can.h>

#include "lss/lss_proto.h"

/* Socket on `ifname`, non-blocking, filters set before bind (standard
 * 0x7E5 and 0x000 only, no RTR, no error frames), own frames not received,
 * SO_RXQ_OVFL on. Returns the fd or -errno (-ENODEV: no such interface). */
int can_raw_open(const char *ifname);
/* 1: a frame; 0: nothing to read; -EBADMSG: a read of the wrong size or a
 * frame socketcan_frame_from_can() refuses (the frame is skipped); other -errno (-ENETDOWN, -ENODEV ...). *drops gets the
 * kernel's count of frames dropped for a full receive queue when known. */
int can_raw_recv(int fd, lss_frame *f, uint32_t *drops);
/* 0, or -ENOBUFS/-EAGAIN when the transmit queue is full, -EINVAL for a frame
 * classic CAN cannot carry (socketcan_frame_to_can()), or -errno. */
int can_raw_send(int fd, const lss_frame *f);
