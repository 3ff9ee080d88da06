/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* SetBitrate(): the whole network, the master's own interface included, to a
 * new bit rate (its runner: lssd_run_bitrate.c). A job of two parts: a fresh scan (fastscan + slowscan of the
 * map's and the known devices' vendor/product pairs), then the engine's
 * bit-rate procedure (lss_master_set_bitrate) over every device found, mapped
 * or known. Between the activation and the verification the engine asks for
 * the host interface to be retuned; the bus does that (lssd_bus.c). */
#pragma once

#include <stdbool.h>
#include <stdint.h>
#include <systemd/sd-bus.h>


/* Switch delays lssd accepts (ms): long enough to retune the host inside
 * the first period, short enough not to hold the bus for long. */
#define LSSD_SWITCH_DELAY_MIN_MS 10u
#define LSSD_SWITCH_DELAY_MAX_MS 10000u
