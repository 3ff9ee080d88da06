/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The one sequence of stages that finds the devices of a bus, for Scan and
 * SetBitrate alike: stage 0 the fastscan enumeration (every non-configured
 * device), stages 1..n_pairs a slowscan per vendor/product pair (configured
 * devices the map or earlier scans name), then, with j->scan_sdo, the SDO
 * discovery of 1018h at node-IDs 1..127 (configured devices of any vendor)
 * and the confirmation through LSS of what only SDO found. */
#include "daemon/lssd_run.h"
#include "daemon/lssd_log.h"

unsigned lssd_discover_sdo_stage(const lssd_job *j) {
        return (unsigned) j->n_pairs + 1;
}

unsigned lssd_discover_confirm_stage(const lssd_job *j) {
        return (unsigned) j->n_pairs + 2;
}

unsigned lssd_discover_n_stages(const lssd_job *j) {
        return (unsigned) j->n_pairs + 1 + (j->scan_sdo ? 2 : 0);
}

unsigned lssd_discover_part(const lssd_job *j) {
        unsigned sdo = lssd_discover_sdo_stage(j);
        return j->stage < sdo ? LSSD_SCAN_PART_LSS : j->stage == sdo ? LSSD_SCAN_PART_SDO : LSSD_SCAN_PART_CONFIRM;
}

/* What an enumeration will likely find: the non-configured devices seen
 * before (the first scan of a bus cannot know). */
unsigned lssd_run_expected_finds(const lssd_job_env *e) {
        unsigned n = 0;
        for (const lssd_device *d = e->devices->head; d; d = d->next)
                n += !d->missing && d->node_id == LSS_NODE_ID_UNCONFIGURED;
        return n;
}

void lssd_run_expect_finds(lssd_job_env *e) {
        lss_master_set_expected_finds(e->engine, lssd_run_expected_finds(e));
}

int lssd_discover_start(lssd_job_env *e, const lssd_job *j) {
        uint64_t now = lssd_job_env_now(e);
        if (j->scan_sdo && j->stage == lssd_discover_sdo_stage(j)) {
                lss_sdo_discover_params p = { .first = LSS_NODE_ID_MIN, .last = LSS_NODE_ID_MAX };
                return lss_master_sdo_discover(e->engine, &p, now);
        }
        if (j->scan_sdo && j->stage == lssd_discover_confirm_stage(j))
                return lss_master_confirm(e->engine, j->sdo_cand, j->n_sdo_cand, now);
        if (j->stage == 0) {
                lssd_run_expect_finds(e);
                return lss_master_enumerate(e->engine, NULL, now);
        }
        const lssd_vendor_product *p = &j->pairs[j->stage - 1];
        lss_identify_range range = {
                .vendor = p->vendor, .product = p->product,
                .rev_lo = 0, .rev_hi = UINT32_MAX,
                .serial_lo = 0, .serial_hi = UINT32_MAX,
        };
        return lss_master_slowscan(e->engine, &range, now);
}

int lssd_discover_take(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        for (size_t i = 0; i < r->n_devices; i++) {
                int k = lssd_job_add_found(j, &r->devices[i]);
                if (k < 0)
                        return k;
        }
        if (j->scan_sdo && j->stage == lssd_discover_sdo_stage(j) && r->status == LSS_OK)
                return lssd_scan_take_sdo(e, j, r);
        return 0;
}

bool lssd_discover_more(const lssd_job *j) {
        if (j->stage < (unsigned) j->n_pairs)
                return true;
        if (!j->scan_sdo)
                return false;
        return j->stage < lssd_discover_sdo_stage(j) || (j->stage == lssd_discover_sdo_stage(j) && j->n_sdo_cand > 0);
}
