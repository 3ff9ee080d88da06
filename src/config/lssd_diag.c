/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <stdio.h>
#include <stdlib.h>

#include "config/lssd_diag.h"

void lssd_diag_init(lssd_diag *d) {
        *d = (lssd_diag) LSSD_DIAG_INIT;
}

void lssd_diag_clear(lssd_diag *d) {
        for (size_t i = 0; i < d->n_messages; i++)
                free(d->messages[i].text);
        free(d->messages);
        lssd_diag_init(d);
}

static __attribute__((format(printf, 3, 0))) void lssd_diag_addv(lssd_diag *d, lssd_diag_severity severity,
                                                                 const char *format, va_list ap) {
        if (severity == LSSD_DIAG_ERROR)
                d->n_errors++;
        else
                d->n_warnings++;

        if (d->n_messages >= LSSD_DIAG_MAX) {
                d->n_dropped++;
                return;
        }

        /* Grow by doubling; the cap keeps this bounded. */
        if (d->n_messages == d->n_allocated) {
                size_t n = d->n_allocated ? d->n_allocated * 2 : 8;
                lssd_diag_message *m = realloc(d->messages, n * sizeof(*m));
                if (!m)
                        goto oom;
                d->messages = m;
                d->n_allocated = n;
        }

        char *text;
        if (vasprintf(&text, format, ap) < 0)
                goto oom;

        d->messages[d->n_messages++] = (lssd_diag_message) { .severity = severity, .text = text };
        return;

oom:
        d->oom = true;
        d->n_dropped++;
}

void lssd_diag_add(lssd_diag *d, lssd_diag_severity severity, const char *format, ...) {
        va_list ap;
        va_start(ap, format);
        lssd_diag_addv(d, severity, format, ap);
        va_end(ap);
}

const char *lssd_diag_severity_to_string(lssd_diag_severity severity) {
        return severity == LSSD_DIAG_ERROR ? "error" : "warning";
}
