/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Frame loss on the in-memory bus (issue 38, point 4): blind Scan and blind
 * AutoAssign from a pool of N non-configured slaves, every slave losing each
 * frame it receives and each it sends with probability P, over many seeds.
 * Prints per case the runs that reported success, that found every slave,
 * and that reported success while a slave was missing (which must be 0);
 * the seeds of the last are listed.
 *   loss-bench [SEEDS [N [FIRST_SEED]]]   (default 1000 16 1)
 * Exits 1 when any run reported success with a slave missing. */
#include <stdio.h>
#include <stdlib.h>

#include "sim/loss_trial.h"

static const uint32_t drops_ppm[] = { 10000, 20000, 30000 };
static const char *const names[] = { "blind Scan", "blind AutoAssign, pool", "Scan of vendor+product",
                                     "SDO discovery" };

int main(int argc, char **argv) {
        unsigned seeds = argc > 1 ? (unsigned) strtoul(argv[1], NULL, 10) : 1000;
        size_t n = argc > 2 ? (size_t) strtoul(argv[2], NULL, 10) : 16;
        uint64_t first = argc > 3 ? strtoull(argv[3], NULL, 10) : 1;
        int bad = 0;

        printf("# %u seeds from %llu, %zu non-configured slaves, each frame lost with P each way\n", seeds,
               (unsigned long long) first, n);
        printf("%-22s %5s %6s %8s %10s %12s %14s\n", "case", "P", "runs", "success", "all found", "silent miss",
               "mean virtual s");
        for (int kind = LOSS_TRIAL_SCAN; kind < _LOSS_TRIAL_MAX; kind++)
                for (size_t d = 0; d < sizeof(drops_ppm) / sizeof(drops_ppm[0]); d++) {
                        unsigned success = 0, all = 0, miss = 0;
                        double secs = 0;
                        char missed[512] = "";
                        size_t used = 0;
                        for (unsigned k = 0; k < seeds; k++) {
                                loss_trial t;
                                if (loss_trial_run((enum loss_trial_kind) kind, n, drops_ppm[d], first + k, &t) < 0) {
                                        fprintf(stderr, "out of memory\n");
                                        return 2;
                                }
                                success += t.success;
                                all += t.found == t.n;
                                secs += (double) t.virtual_us / 1e6;
                                if (!loss_trial_silent_miss(&t))
                                        continue;
                                miss++;
                                if (used < sizeof(missed) - 24)
                                        used += (size_t) snprintf(missed + used, sizeof(missed) - used, " %llu (%zu)",
                                                                  (unsigned long long) (first + k), t.found);
                        }
                        printf("%-22s %4.1f%% %6u %8u %10u %12u %14.2f\n",
                               names[kind],
                               drops_ppm[d] / 1e4, seeds, success, all, miss, seeds ? secs / seeds : 0.0);
                        if (miss) {
                                printf("#   success with a slave missing, seed (found):%s\n", missed);
                                bad = 1;
                        }
                        fflush(stdout);
                }
        return bad;
}
