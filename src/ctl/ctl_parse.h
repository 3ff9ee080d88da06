/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Command-line values: numbers are decimal, or hexadecimal with "0x"
 * (leading zeros never mean octal, so 000000ec is refused rather than
 * misread). */
#pragma once

#include <stdbool.h>
#include <stdint.h>

int ctl_parse_u32(const char *s, uint32_t *ret);
/* 1..127 */
int ctl_parse_node_id(const char *s, uint8_t *ret);
/* VENDOR:PRODUCT:REVISION:SERIAL; returns 0 and fills id[4], -EINVAL on
 * a malformed identity, -ENOENT when s has no ':' at all (a bare serial). */
int ctl_parse_identity(const char *s, uint32_t id[4]);
/* A bit rate of the CiA 301 table: "250000", "250k", "1M". */
int ctl_parse_bitrate(const char *s, uint32_t *ret);
