/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* A Scan's Progress: its stages weighted by the time they take, so that it
 * moves with the time gone (issue 39). The parts' times of the last whole
 * Scan with SDO where there was one; before, what the stages cost in
 * fastscan finds (about 130 LSS steps each), as measured with lssd
 * --simulate and in a VM on 16 slaves: the enumeration 1.1 a slave (its
 * give-back included) and 2.5 for the looks for anybody left (the last one
 * patient), the SDO discovery of 127 node-IDs 2-3, a slowscan about one
 * (an identify when nobody matches, a bisection a slave when some do), the
 * confirmation of what SDO alone found little. */
#include "daemon/lssd_run.h"

/* what the first Scan of a bus assumes it holds: a small machine's worth */
#define UNKNOWN_FINDS 16.0
#define COST_FIND 1.1
#define COST_LOOKS 2.5
#define COST_PAIR 1.0
#define COST_SDO 3.0
#define COST_CONFIRM 0.5

/* The cost of the LSS stages before `stage` (0: the enumeration, then one
 * slowscan a pair). */
static double lss_cost_before(const lssd_job *j, unsigned stage) {
        double finds = j->expected_finds > 0 ? (double) j->expected_finds : UNKNOWN_FINDS;
        return stage == 0 ? 0 : finds * COST_FIND + COST_LOOKS + (double) (stage - 1) * COST_PAIR;
}

double lssd_scan_progress(const lssd_job_env *e, const lssd_job *j, double p) {
        unsigned n_lss = (unsigned) j->n_pairs + 1;
        double lss = lss_cost_before(j, n_lss);
        double w[_LSSD_SCAN_PARTS] = { lss, j->scan_sdo ? COST_SDO : 0, j->scan_sdo ? COST_CONFIRM : 0 };
        const uint64_t *measured = e->scan_part_us;
        if (j->scan_sdo && measured[LSSD_SCAN_PART_LSS] > 0)
                for (unsigned k = 0; k < _LSSD_SCAN_PARTS; k++)
                        w[k] = (double) measured[k];

        unsigned part = lssd_discover_part(j);
        double within = p;
        if (part == LSSD_SCAN_PART_LSS) {
                double before = lss_cost_before(j, j->stage);
                within = (before + p * (lss_cost_before(j, j->stage + 1) - before)) / lss;
        }
        double before = 0, total = 0;
        for (unsigned k = 0; k < _LSSD_SCAN_PARTS; k++) {
                before += k < part ? w[k] : 0;
                total += w[k];
        }
        return (before + within * w[part]) / total;
}
