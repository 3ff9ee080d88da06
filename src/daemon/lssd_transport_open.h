/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* What is behind a bus's transport seam in lssd: a SocketCAN port, or with
 * --simulate the simulated bus (src/simbus) with its --sim-slave devices. */
#pragma once

#include <stdint.h>

#include "can/transport.h"
#include "daemon/lssd_args.h"

/* A missing interface is no error (link "gone"). 1: gone, and the log
 * says why already (this kernel has no CAN at all). */
int lssd_transport_open(const lssd_args *args, const char *ifname, uint32_t bitrate,
                        const lss_transport_hooks *hooks, lss_transport *ret);
