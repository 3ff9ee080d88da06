/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Argument checks of the D-Bus API. Each sets
 * org.freedesktop.DBus.Error.InvalidArgs naming the argument and quoting the
 * value, and returns its negative errno, or returns 0. */
#pragma once

#include <stdint.h>
#include <systemd/sd-bus.h>

/* A node-ID to assign: 1..127. */
int lssd_validate_node_id(const char *argument, uint8_t node_id, sd_bus_error *error);
/* Raw Configure Node-ID: 1..127, or 0xFF (unconfigure). */
int lssd_validate_raw_node_id(const char *argument, uint8_t node_id, sd_bus_error *error);
/* Switch state global: 0 (waiting) or 1 (configuration). */
int lssd_validate_mode(const char *argument, uint8_t mode, sd_bus_error *error);
/* Configure bit timing: table 0 with index 0..9, or a manufacturer table 128..255. */
int lssd_validate_bit_timing(uint8_t table, uint8_t index, sd_bus_error *error);
/* A bus bit rate of the CiA 301 table 0. */
int lssd_validate_bitrate(const char *argument, uint32_t bitrate, sd_bus_error *error);
/* Inclusive range: lo <= hi. */
int lssd_validate_range(const char *lo_argument, uint32_t lo, const char *hi_argument, uint32_t hi,
                        sd_bus_error *error);
/* A network interface name (1..15 bytes, no '/', ':' or white space, not "." or ".."). */
int lssd_validate_ifname(const char *argument, const char *ifname, sd_bus_error *error);
