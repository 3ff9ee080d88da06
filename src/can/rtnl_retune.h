/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* SetBitrate's retune of a real CAN controller over rtnetlink, without
 * blocking: look the link up, link down (the kernel refuses bit timing on a
 * running controller), IFLA_CAN_BITTIMING, link up. Each request is written
 * to a non-blocking socket and its answer taken when the socket is
 * readable, so the caller's event loop serves everything else meanwhile:
 * poll rtnl_retune_fd() and call rtnl_retune_step() when it is readable or
 * at rtnl_retune_deadline().
 *
 * The retune also knows which link changes it made: it set the link down
 * and up, so the link events that say so are its own (rtnl_retune_claim()),
 * whenever the watcher delivers them, and no others. */
#pragma once

#include <stdbool.h>
#include <stdint.h>

#include "can/can_sys.h"

typedef struct rtnl_retune rtnl_retune;

/* Starts retuning `ifname` to `bitrate` (sys NULL = the real system
 * calls): 0 running, <0 could not start (nothing changed). */
int rtnl_retune_start(const can_sys *sys, const char *ifname, uint32_t bitrate, rtnl_retune **ret);
/* Reads what the kernel answered and sends the next request:
 *   0 still running (wait for the fd or the deadline again),
 *   1 done: the link runs at the new rate (or did already: nothing touched),
 *   <0 failed: -EOPNOTSUPP the link's kind is not "can" (vcan: no bit
 *      timing), -ENODEV no such link, -EPERM without CAP_NET_ADMIN, -EINVAL a
 *      rate the controller refuses, -ETIMEDOUT the kernel did not answer
 *      within RTNL_REQUEST_TIMEOUT_US. Once the link was taken down it is
 *      set up again even if the rate was refused.
 * After the end further calls return the same. */
int rtnl_retune_step(rtnl_retune *r);
/* The socket to poll (POLLIN) while running; -1 once ended. */
int rtnl_retune_fd(const rtnl_retune *r);
/* When to call rtnl_retune_step() at the latest (CLOCK_MONOTONIC µs of
 * `sys`); UINT64_MAX once ended. */
uint64_t rtnl_retune_deadline(const rtnl_retune *r);
/* The link of this retune went up (`up`) or down: whether this retune made
 * it so. Each change it made is claimed once; seeing it up again claims
 * the way down too (events come in order). Valid after the end as well:
 * the watcher may deliver the events later than the answers. */
bool rtnl_retune_claim(rtnl_retune *r, bool up);
/* Closes the socket and frees; returns NULL. NULL is fine. */
rtnl_retune *rtnl_retune_free(rtnl_retune *r);
