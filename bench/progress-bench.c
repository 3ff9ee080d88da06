/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* How well an enumeration's progress follows its time (issue 39), on the
 * in-memory bus (virtual time, 125 kbit/s, slaves of one vendor and product
 * with 1 ms latency + up to 0.3 ms jitter, serials in a row): for N
 * non-configured slaves, with the identical answers of several slaves on
 * the wire one frame each (vcan) or merged into one (CAN, when they start
 * together), nothing expected (a bus's first Scan) or N finds expected (the
 * Scans after it), the largest distance of a reported progress from the
 * share of the enumeration's time gone, and where it was; and the longest
 * share of its time the progress stood still, counted as lssd publishes it
 * (whole percents: a report 0.01 or more above the last published).
 * Not a test: prints a table. Every slave must be found, or it fails. */
#include <stdio.h>
#include <stdlib.h>

#include "lss/lss_master.h"
#include "sim/lss_drive.h"
#include "sim/membus.h"

#define MAX_REPORTS 100000

typedef struct reports {
        membus *bus;
        uint64_t t0;
        size_t n;
        double at_us[MAX_REPORTS], p[MAX_REPORTS];
} reports;

static void on_progress(void *ud, double p) {
        reports *r = ud;
        if (r->n < MAX_REPORTS) {
                r->at_us[r->n] = (double) (membus_now(r->bus) - r->t0);
                r->p[r->n++] = p;
        }
}

static int one(unsigned n, bool merge, bool expected) {
        static reports rep;
        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.latency_us = 1000;
        f.jitter_us = 300;
        membus *b = membus_new(125000);
        membus_set_merge_identical(b, merge);
        for (unsigned i = 0; i < n; i++) {
                lss_identity id = { 0xEC, 0x1234, 1, 0x100 + i };
                membus_add_slave(b, &id, LSS_NODE_ID_UNCONFIGURED, &f);
        }
        lss_timing_config c;
        lss_timing_config_default(&c);
        lss_master *m = lss_master_new(&c);
        rep.bus = b;
        rep.n = 0;
        rep.t0 = membus_now(b);
        lss_master_set_progress(m, on_progress, &rep);
        if (expected)
                lss_master_set_expected_finds(m, n);
        lss_master_enumerate(m, NULL, rep.t0);
        const lss_result *r = lss_drive(m, b, 3600ull * 1000000, NULL, NULL);
        double total = (double) (membus_now(b) - rep.t0), off = 0, at = 0, still = 0, shown = 0, since = 0;
        for (size_t i = 0; i < rep.n; i++) {
                if (rep.p[i] >= shown + 0.01) {
                        still = rep.at_us[i] - since > still ? rep.at_us[i] - since : still;
                        shown = rep.p[i];
                        since = rep.at_us[i];
                }
                double d = rep.p[i] - rep.at_us[i] / total;
                if (d < 0)
                        d = -d;
                if (d > off) {
                        off = d;
                        at = rep.at_us[i] / total;
                }
        }
        still = total - since > still ? total - since : still;
        int bad = r->status != LSS_OK || r->n_devices != n;
        printf("%-4u %-7s %-9s %9.2f %9.3f %9.2f %9.3f%s\n", n, merge ? "merged" : "one-each",
               expected ? "N" : "nothing", total / 1e6, off, at, still / total, bad ? "  FAILED" : "");
        lss_master_free(m);
        membus_free(b);
        return bad;
}

int main(void) {
        static const unsigned ns[] = { 2, 4, 8, 16, 32, 64 };
        int bad = 0;
        printf("# enumeration: progress against the share of its time gone\n");
        printf("%-4s %-7s %-9s %9s %9s %9s %9s\n", "N", "answers", "expected", "time s", "max off", "at", "still");
        for (int expected = 0; expected < 2; expected++)
                for (int merge = 0; merge < 2; merge++)
                        for (size_t i = 0; i < sizeof(ns) / sizeof(ns[0]); i++)
                                bad |= one(ns[i], merge, expected);
        return bad;
}
