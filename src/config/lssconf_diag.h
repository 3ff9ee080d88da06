/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* A list of diagnostics (errors and warnings) collected while loading a
 * configuration. The loader never prints: the daemon logs these, and
 * `lssd --check-config` prints them. */
#pragma once

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>

typedef enum lssconf_diag_severity {
        LSSCONF_DIAG_WARNING,
        LSSCONF_DIAG_ERROR,
} lssconf_diag_severity;

typedef struct lssconf_diag_message {
        lssconf_diag_severity severity;
        char *text; /* "file:line: what: problem", no trailing newline, printable */
} lssconf_diag_message;

/* At most this many messages are stored; the rest are only counted, so a
 * file of junk cannot make the list grow without bound. */
#define LSSCONF_DIAG_MAX 200u

typedef struct lssconf_diag {
        lssconf_diag_message *messages;
        size_t n_messages;
        size_t n_allocated; /* capacity of messages[] */
        size_t n_errors;   /* all errors reported, stored or not */
        size_t n_warnings; /* all warnings reported, stored or not */
        size_t n_dropped;  /* reported but not stored (over the cap or out of memory) */
        bool oom;          /* an allocation failed while recording a message */
} lssconf_diag;

#define LSSCONF_DIAG_INIT { .messages = NULL }

void lssconf_diag_init(lssconf_diag *d);
/* Frees every message and leaves *d empty and ready for reuse. */
void lssconf_diag_clear(lssconf_diag *d);

/* Records one message. Never fails from the caller's point of view: when out
 * of memory the message is counted and d->oom is set. */
void lssconf_diag_add(lssconf_diag *d, lssconf_diag_severity severity, const char *format, ...)
        __attribute__((format(printf, 3, 4)));

static inline bool lssconf_diag_has_errors(const lssconf_diag *d) {
        return d->n_errors > 0;
}

/* "error" or "warning" */
const char *lssconf_diag_severity_to_string(lssconf_diag_severity severity);
