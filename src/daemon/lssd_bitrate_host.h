/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Whether the host interface can follow a bit-rate change, found out before
 * SetBitrate sends anything: devices switched to a rate the host cannot
 * take are cut off from it until somebody retunes it by hand. */
#pragma once

#include <stdint.h>

#include "daemon/lssd_job_env.h"

typedef struct lssd_bitrate_refusal {
        const char *error;      /* D-Bus error name */
        const char *result;     /* JobFinished result */
        char text[512];         /* the cause, for the reply and the journal */
} lssd_bitrate_refusal;

/* 0 when the host interface `h` can be retuned to `bitrate` (a real
 * controller that lssd may retune over rtnetlink, a virtual one with no bit
 * timing, the simulated one); -1 with `ret` filled in otherwise: the
 * interface is down or bus-off, lssd lacks CAP_NET_ADMIN
 * (PermissionDenied), the interface has no bit timing lssd can set
 * (NotSupported). Changes nothing on the interface. */
int lssd_bitrate_check_host(const lssd_host_link *h, uint32_t bitrate, lssd_bitrate_refusal *ret);

/* The D-Bus error for a host retune that failed with `err` (an errno). */
const char *lssd_bitrate_retune_error(int err);
