/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "can/rtnl_watch.h"
#include "daemon/lssd_bitrate_host.h"
#include "daemon/lssd_errors.h"

static int refuse(lssd_bitrate_refusal *ret, const char *error, const char *result, const char *fmt, ...)
        __attribute__((format(printf, 4, 5)));

static int refuse(lssd_bitrate_refusal *ret, const char *error, const char *result, const char *fmt, ...) {
        va_list ap;

        ret->error = error;
        ret->result = result;
        va_start(ap, fmt);
        vsnprintf(ret->text, sizeof(ret->text), fmt, ap);
        va_end(ap);
        return -1;
}

const char *lssd_bitrate_retune_error(int err) {
        switch (err) {
        case EPERM:
        case EACCES:
                return LSSD_ERROR_PERMISSION_DENIED;
        case EOPNOTSUPP:
        case EINVAL:
        case ERANGE:
                return LSSD_ERROR_NOT_SUPPORTED;
        case ENETDOWN:
        case ENODEV:
                return LSSD_ERROR_BUS_DOWN;
        default:
                return SD_BUS_ERROR_FAILED;
        }
}

int lssd_bitrate_check_host(const lssd_host_link *h, uint32_t bitrate, lssd_bitrate_refusal *ret) {
        rtnl_link link = { .kind = "" };
        int r;

        if (h->link != LSS_LINK_UP)
                return refuse(ret, LSSD_ERROR_BUS_DOWN, "bus-down", "%s is %s: nothing sent", h->ifname,
                              h->link == LSS_LINK_GONE ? "not there" : "down");
        if (h->bus_state == LSS_BUS_OFF)
                return refuse(ret, LSSD_ERROR_BUS_OFF, "bus-off", "%s: the controller is bus-off: nothing sent",
                              h->ifname);
        /* the simulated controller follows; a virtual interface has no rate */
        if (h->simulated || h->virtual_link)
                return 0;

        r = rtnl_check_can_bitrate(NULL, h->ifname, &link);
        if (r == -EOPNOTSUPP && (strcmp(link.kind, "vcan") == 0 || strcmp(link.kind, "vxcan") == 0))
                return 0;
        switch (r) {
        case 0:
                return 0;
        case -EPERM:
        case -EACCES:
                return refuse(ret, LSSD_ERROR_PERMISSION_DENIED, "permission-denied",
                              "lssd may not retune %s to %u bit/s (the kernel refused a bit-timing change: %s): "
                              "it needs CAP_NET_ADMIN, which lssd.service has only with the lssd-bitrate.conf "
                              "drop-in; nothing sent, every device stays at %u bit/s", h->ifname, bitrate,
                              strerror(-r), h->bitrate);
        case -EOPNOTSUPP:
                return refuse(ret, LSSD_ERROR_NOT_SUPPORTED, "not-supported",
                              "%s (kind \"%s\") has no bit timing lssd can set over rtnetlink, so it could not "
                              "follow the devices to %u bit/s; nothing sent", h->ifname,
                              link.kind[0] ? link.kind : "none", bitrate);
        case -ENETDOWN:
        case -ENODEV:
                return refuse(ret, LSSD_ERROR_BUS_DOWN, "bus-down", "%s is %s: nothing sent", h->ifname,
                              r == -ENODEV ? "not there" : "down");
        default:
                return refuse(ret, SD_BUS_ERROR_FAILED, "failed",
                              "could not find out whether lssd may retune %s (%s): nothing sent", h->ifname,
                              strerror(-r));
        }
}
