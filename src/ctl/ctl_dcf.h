/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* CiA 306 device configuration files (DCF), both ways: import-dcf reads an
 * integrator's DCFs into the buses of lssd.conf(5) (config/dcf.h, the
 * reader lssd uses too); scan --as-dcf writes one DCF fragment per device
 * found, for the integrator's tool to take back. */
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "ctl/ctl.h"

/* One device for scan --as-dcf: configured, found by LSS, alone at its node-ID. */
typedef struct ctl_dcf_device {
        const char *ifname;
        uint32_t id[4];          /* vendor, product, revision, serial */
        uint8_t node_id;
        uint32_t bitrate;        /* of its bus in bit/s, 0: not known */
} ctl_dcf_device;

/* Writes DIR/<ifname>-node<NNN>.dcf for each (DIR is made when missing; a
 * file there of that name is replaced) and says what it wrote. Failures
 * are reported (ctl_fail) and returned. */
int ctl_write_dcfs(ctl_context *c, const char *dir, const ctl_dcf_device *v, size_t n);
