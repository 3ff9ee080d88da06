/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Logging. Lines go to stderr; under systemd (JOURNAL_STREAM set) each gets
 * the "<N>" priority prefix journald reads. Job results carry the device
 * identity as journal fields when the journal is there (LSS_INTERFACE=,
 * LSS_VENDOR=, LSS_PRODUCT=, LSS_REVISION=, LSS_SERIAL=, LSS_NODE_ID=). */
#pragma once

#include <stddef.h>
#include <stdint.h>
#include <syslog.h>

#include "lss/lss_proto.h"

void lssd_log(int priority, const char *format, ...) __attribute__((format(printf, 2, 3)));
/* Logs "<message>: <strerror(-error)>" and returns error (negative errno). */
int lssd_log_errno(int priority, int error, const char *format, ...) __attribute__((format(printf, 3, 4)));
/* A line about one device; node_id 0 = not known. */
void lssd_log_device(int priority, const char *ifname, const lss_identity *id, unsigned node_id, const char *format,
                     ...) __attribute__((format(printf, 5, 6)));

/* A moment (CLOCK_REALTIME µs) as local time of day: "12:03:04.512". Returns buf. */
const char *lssd_clock_text(uint64_t realtime_us, char *buf, size_t size);

#define log_debug(...)   lssd_log(LOG_DEBUG, __VA_ARGS__)
#define log_info(...)    lssd_log(LOG_INFO, __VA_ARGS__)
#define log_notice(...)  lssd_log(LOG_NOTICE, __VA_ARGS__)
#define log_warning(...) lssd_log(LOG_WARNING, __VA_ARGS__)
#define log_error(...)   lssd_log(LOG_ERR, __VA_ARGS__)
#define log_error_errno(e, ...)   lssd_log_errno(LOG_ERR, (e), __VA_ARGS__)
#define log_warning_errno(e, ...) lssd_log_errno(LOG_WARNING, (e), __VA_ARGS__)
