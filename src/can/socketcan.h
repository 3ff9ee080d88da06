/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* A SocketCAN CAN_RAW port on one interface, opened by name.
 *
 * The port survives its interface: if the interface is missing at start or
 * disappears later (ENODEV/ENXIO), the port is "gone" (no fd) and is re-opened
 * by name when rtnetlink reports the interface again (socketcan_port_link_event);
 * if the link is down, sends fail with -ENETDOWN and the same socket works
 * again once the link is up. It receives only LSS responses (0x7E4) and
 * boot-up/heartbeat frames (0x701..0x77F), as classic standard data frames,
 * plus the error frames that tell the controller's state. */
#pragma once

#include <linux/can.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "can/can_sys.h"
#include "can/transport.h"
#include "lss/lss_proto.h"

typedef struct socketcan_port socketcan_port;

typedef struct socketcan_config {
        /* link_changed: on every link state change. When the new state is
         * "gone" the old fd is still open during the call (remove it from the
         * event loop here), and is closed right after. Must not call back
         * into the port except for getters. */
        lss_transport_hooks hooks;
        /* System calls; NULL = the real ones. */
        const can_sys *sys;
} socketcan_config;

/* Opens a port on interface `ifname` (1..15 characters). A missing interface
 * is not an error: the port starts "gone". Errors: -EINVAL (bad name),
 * -ENOMEM, -EAFNOSUPPORT (kernel without CAN), and other socket errors. */
int socketcan_port_open(const char *ifname, const socketcan_config *cfg, socketcan_port **ret);
/* Closes the socket and frees; returns NULL. NULL is fine. */
socketcan_port *socketcan_port_free(socketcan_port *p);
/* Whether the kernel has CAN (a CAN_RAW socket opens; the kernel loads
 * can-raw on demand): a missing interface on a kernel without it never
 * appears. `sys` NULL = the real system calls. */
bool socketcan_kernel_has_can(const can_sys *sys);

/* Closes the socket (if any) and opens a new one by name. 0 when open now,
 * -ENODEV when the interface is (still) missing, other errors as open. */
int socketcan_port_reopen(socketcan_port *p);

/* Feed every rtnetlink link event here (any interface: the port picks its own).
 * `present` false for RTM_DELLINK. Re-opens the port when its interface
 * (re)appears under its name with a new ifindex, closes it when it is deleted
 * or renamed away, and takes up/down from IFF_UP|IFF_RUNNING.
 * Returns 1 if the port's state or socket changed, 0 if not, <0 if a re-open failed. */
int socketcan_port_link_event(socketcan_port *p, int ifindex, const char *ifname, bool present, unsigned flags);

/* One classic CAN frame, never blocking. 0, or -EAGAIN (tx queue full:
 * nothing sent, write it again later) / -ENETDOWN / -ENODEV / -EINVAL
 * (frame not classic CAN) / other. */
int socketcan_port_send(socketcan_port *p, const lss_frame *f);
/* 1: a frame and its CLOCK_MONOTONIC receive time in µs; 0: nothing pending;
 * <0: -ENETDOWN, -ENODEV, or another socket error. Error frames and invalid
 * reads are consumed here and show in the status. */
int socketcan_port_recv(socketcan_port *p, lss_frame *f, uint64_t *rx_us);
/* Current fd (for POLLIN), -1 when gone. */
int socketcan_port_fd(const socketcan_port *p);
/* CLOCK_MONOTONIC in µs. */
uint64_t socketcan_port_now(socketcan_port *p);
/* Fills `st` and clears its events. */
void socketcan_port_status(socketcan_port *p, lss_transport_status *st);
lss_link_state socketcan_port_state(const socketcan_port *p);
/* recv() hands back our own sent frames (LSS_FRAME_ECHO): tx confirmation. */
bool socketcan_port_echoes(const socketcan_port *p);
const char *socketcan_port_ifname(const socketcan_port *p);
int socketcan_port_ifindex(const socketcan_port *p); /* 0 when gone */

/* The port as a transport (socketcan_transport.c); the transport's close()
 * frees the port. Its retune sets the bit rate over rtnetlink (rtnl_retune.h,
 * through the port's can_sys) and re-opens the socket. -ENOMEM: the port
 * is still the caller's. */
int socketcan_port_transport(socketcan_port *p, lss_transport *ret);
/* The system calls the port was opened with. */
const can_sys *socketcan_port_sys(const socketcan_port *p);

/* ---- pure helpers, exported for tests ---- */

/* The receive filter list installed on every socket. */
size_t socketcan_filters(const struct can_filter **ret);
/* The error classes we opt in to (CAN_RAW_ERR_FILTER). */
can_err_mask_t socketcan_err_mask(void);
/* lss_frame <-> struct can_frame; -EINVAL for what classic CAN cannot carry. */
int socketcan_frame_to_can(const lss_frame *f, struct can_frame *cf);
int socketcan_frame_from_can(const struct can_frame *cf, lss_frame *f);
/* Whether the filter list lets this (non-error) frame through. */
bool socketcan_filter_match(const struct can_frame *cf);
/* Applies an error frame to a bus state: updates *state, ORs LSS_BUS_EVENT_*
 * into *events, adds frames the controller lost to *dropped, stores error
 * counters when the frame has them. */
void socketcan_decode_error(const struct can_frame *cf, lss_bus_state *state, uint32_t *events,
                            uint64_t *dropped, uint8_t *tx_errors, uint8_t *rx_errors);
