/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#define SD_JOURNAL_SUPPRESS_LOCATION
#include <systemd/sd-journal.h>

#include "daemon/lssd_log.h"

static bool under_journal(void) {
        return getenv("JOURNAL_STREAM") != NULL;
}

/* LSSD_LOG_LEVEL=debug|info|notice|warning|err|0..7 (default info). Read on
 * every call: logging is rare, and it keeps the logger free of state. */
static int max_level(void) {
        static const char *const names[] = { "emerg", "alert", "crit", "err", "warning", "notice", "info", "debug" };
        const char *e = getenv("LSSD_LOG_LEVEL");
        if (!e || !*e)
                return LOG_INFO;
        if (e[0] >= '0' && e[0] <= '7' && e[1] == '\0')
                return e[0] - '0';
        for (int i = 0; i < 8; i++)
                if (strcmp(e, names[i]) == 0)
                        return i;
        return LOG_INFO;
}

static void emit(int priority, const char *text) {
        /* one write per line so concurrent writers do not interleave */
        if (under_journal())
                fprintf(stderr, "<%d>%s\n", priority & LOG_PRIMASK, text);
        else
                fprintf(stderr, "%s\n", text);
        fflush(stderr);
}

void lssd_log(int priority, const char *format, ...) {
        char buf[1024];
        va_list ap;
        if ((priority & LOG_PRIMASK) > max_level())
                return;
        va_start(ap, format);
        vsnprintf(buf, sizeof(buf), format, ap);
        va_end(ap);
        emit(priority, buf);
}

int lssd_log_errno(int priority, int error, const char *format, ...) {
        char buf[1024];
        va_list ap;
        va_start(ap, format);
        vsnprintf(buf, sizeof(buf), format, ap);
        va_end(ap);
        lssd_log(priority, "%s: %s", buf, strerror(error < 0 ? -error : error));
        return error < 0 ? error : -error;
}

void lssd_log_device(int priority, const char *ifname, const lss_identity *id, unsigned node_id, const char *format,
                     ...) {
        char buf[1024];
        va_list ap;
        if ((priority & LOG_PRIMASK) > max_level())
                return;
        va_start(ap, format);
        vsnprintf(buf, sizeof(buf), format, ap);
        va_end(ap);

        if (under_journal() &&
            sd_journal_send("MESSAGE=%s", buf, "PRIORITY=%d", priority & LOG_PRIMASK, "LSS_INTERFACE=%s", ifname,
                            "LSS_VENDOR=0x%08x", id->vendor, "LSS_PRODUCT=0x%08x", id->product,
                            "LSS_REVISION=0x%08x", id->revision, "LSS_SERIAL=0x%08x", id->serial,
                            "LSS_NODE_ID=%u", node_id, NULL) >= 0)
                return;
        emit(priority, buf);
}

const char *lssd_clock_text(uint64_t realtime_us, char *buf, size_t size) {
        time_t t = (time_t) (realtime_us / 1000000u);
        struct tm tm;
        char hms[16];
        if (!localtime_r(&t, &tm) || strftime(hms, sizeof(hms), "%H:%M:%S", &tm) == 0)
                snprintf(hms, sizeof(hms), "?");
        snprintf(buf, size, "%s.%03u", hms, (unsigned) (realtime_us % 1000000u / 1000u));
        return buf;
}
