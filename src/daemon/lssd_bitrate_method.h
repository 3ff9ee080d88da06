/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The SetBitrate() method of a bus: options, checks, the job queued. What the
 * job does is lssd_bitrate.c's. */
#pragma once

#include <stdint.h>
#include <systemd/sd-bus.h>

#include "daemon/lssd_bus.h"

/* SetBitrate(u bitrate, q switch_delay_ms, a{sv} options) after the
 * arguments were read and validated: reads the options (`store` b, default
 * the bus's `store`; `skip_missing` b, default false), refuses buses whose
 * configuration does not enable bit-rate changes (NotSupported), authorizes
 * and queues the job. */
int lssd_bitrate_method(lssd_bus *b, sd_bus_message *m, uint32_t bitrate, uint16_t switch_delay_ms,
                        sd_bus_error *error);
