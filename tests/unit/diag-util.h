/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Checking what a loader said: the messages of a lssconf_diag (tests of
 * the config loader and the DCF reader). */
#pragma once

#include <check.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "config/lssconf_diag.h"

/* A message of that severity containing every one of the NULL-terminated substrings. */
static inline bool has_message(const lssconf_diag *d, lssconf_diag_severity sev, ...) {
        for (size_t i = 0; i < d->n_messages; i++) {
                if (d->messages[i].severity != sev)
                        continue;
                bool all = true;
                va_list ap;
                va_start(ap, sev);
                for (const char *s; (s = va_arg(ap, const char *)); )
                        if (!strstr(d->messages[i].text, s))
                                all = false;
                va_end(ap);
                if (all)
                        return true;
        }
        return false;
}

static inline void dump(const lssconf_diag *d) {
        for (size_t i = 0; i < d->n_messages; i++)
                fprintf(stderr, "  %s: %s\n", lssconf_diag_severity_to_string(d->messages[i].severity),
                        d->messages[i].text);
}

#define expect_message(d, sev, ...) \
        do { \
                if (!has_message(d, sev, __VA_ARGS__, (const char *) NULL)) { \
                        dump(d); \
                        ck_abort_msg("no %s with: %s", lssconf_diag_severity_to_string(sev), #__VA_ARGS__); \
                } \
        } while (0)
