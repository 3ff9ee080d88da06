/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <stdio.h>
#include <stdlib.h>

#include "config/lssconf_diag.h"

void lssconf_diag_init(lssconf_diag *d) {
        *d = (lssconf_diag) LSSCONF_DIAG_INIT;
}

void lssconf_diag_clear(lssconf_diag *d) {
        for (size_t i = 0; i < d->n_messages; i++)
                free(d->messages[i].text);
        free(d->messages);
        lssconf_diag_init(d);
}

static __attribute__((format(printf, 3, 0))) void lssconf_diag_addv(lssconf_diag *d, lssconf_diag_severity severity,
                                                                 const char *format, va_list ap) {
        if (severity == LSSCONF_DIAG_ERROR)
                d->n_errors++;
        else
                d->n_warnings++;

        if (d->n_messages >= LSSCONF_DIAG_MAX) {
                d->n_dropped++;
                return;
        }

        /* Grow by doubling; the cap keeps this bounded. */
        if (d->n_messages == d->n_allocated) {
                size_t n = d->n_allocated ? d->n_allocated * 2 : 8;
                lssconf_diag_message *m = realloc(d->messages, n * sizeof(*m));
                if (!m)
                        goto oom;
                d->messages = m;
                d->n_allocated = n;
        }

        char *text;
        if (vasprintf(&text, format, ap) < 0)
                goto oom;

        d->messages[d->n_messages++] = (lssconf_diag_message) { .severity = severity, .text = text };
        return;

oom:
        d->oom = true;
        d->n_dropped++;
}

void lssconf_diag_add(lssconf_diag *d, lssconf_diag_severity severity, const char *format, ...) {
        va_list ap;
        va_start(ap, format);
        lssconf_diag_addv(d, severity, format, ap);
        va_end(ap);
}

const char *lssconf_diag_severity_to_string(lssconf_diag_severity severity) {
        return severity == LSSCONF_DIAG_ERROR ? "error" : "warning";
}
