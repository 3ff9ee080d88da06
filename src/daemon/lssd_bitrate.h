/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* SetBitrate(): the whole network, the master's own interface included, to a
 * new bit rate. A job of two parts: a fresh scan (fastscan + slowscan of the
 * map's and the known devices' vendor/product pairs), then the engine's
 * bit-rate procedure (lss_master_set_bitrate) over every device found, mapped
 * or known. Between the activation and the verification the engine asks for
 * the host interface to be retuned; lssd_bus.c hands that request here. */
#pragma once

#include <stdbool.h>
#include <stdint.h>
#include <systemd/sd-bus.h>

#include "daemon/lssd_bus.h"
#include "daemon/lssd_job.h"

/* SetBitrate(u bitrate, q switch_delay_ms, a{sv} options) after the
 * arguments were read and validated: reads the options (`store` b, default
 * the bus's `store`; `skip_missing` b, default false), refuses buses whose
 * configuration does not enable bit-rate changes (NotSupported), authorizes
 * and queues the job. */
int lssd_bitrate_method(lssd_bus *b, sd_bus_message *m, uint32_t bitrate, uint16_t switch_delay_ms,
                        sd_bus_error *error);

/* Switch delays lssd accepts (ms): long enough to retune the host inside
 * the first period, short enough not to hold the bus for long. */
#define LSSD_SWITCH_DELAY_MIN_MS 10u
#define LSSD_SWITCH_DELAY_MAX_MS 10000u

/* Begins or continues a SET_BITRATE job (see lssd_job_run()). */
int lssd_bitrate_run(lssd_bus *b, lssd_job *j, const lss_result *r);

/* The engine waits for the host interface to be retuned: do it (rtnetlink
 * on a real controller, the simulated bus with --simulate; skipped on
 * vcan) and tell the engine. Returns true when the socket changed. */
bool lssd_bitrate_retune(lssd_bus *b);

/* The bit-rate procedure itself runs (the scan before it is over): it is
 * not cancelled (Cancel, stop), as cut off it could leave devices with a
 * pending rate or the bus split; it ends within seconds. */
bool lssd_bitrate_uncancellable(lssd_bus *b);

/* Link down/up events now are our own retune: not a failure. */
bool lssd_bitrate_retuning(lssd_bus *b);
