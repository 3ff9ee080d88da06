/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include "sim/loss_trial.h"

#include <errno.h>
#include <stdio.h>

#include "lss/lss_autoassign.h"
#include "lss/lss_master.h"
#include "sim/lss_drive.h"
#include "sim/membus.h"
#include "sim/sim_random.h"

#define HOUR_US (3600ull * 1000000ull)

static size_t scan_found(membus *b, const lss_result *r) {
        size_t found = 0;
        for (size_t i = 0; i < r->n_devices; i++) {
                const lss_slave *s = membus_find(b, &r->devices[i].id);
                found += s && s->st.active_node_id == r->devices[i].node_id;
        }
        return found;
}

/* "done" is the daemon's verdict (lssd_run_autoassign.c): the pass ended OK
 * and no outcome says something is wrong; else what does goes to `why` */
static bool pool_done(const lss_outcome *o, size_t n_out, const lss_result *r, loss_trial *why) {
        if (r->status != LSS_OK)
                return false;
        for (size_t k = 0; k < n_out; k++)
                if (o[k].kind == LSS_OUTCOME_MISSING || o[k].kind == LSS_OUTCOME_CONFLICT ||
                    o[k].kind == LSS_OUTCOME_FAILED) {
                        snprintf(why->message, sizeof(why->message), "%08x %s: %s", o[k].id.serial,
                                 lss_outcome_name(o[k].kind), o[k].message);
                        return false;
                }
        return true;
}

static size_t pool_found(membus *b, const lss_outcome *o, size_t n_out) {
        size_t found = 0;
        for (size_t k = 0; k < n_out; k++) {
                const lss_slave *s = membus_find(b, &o[k].id);
                found += s && o[k].kind == LSS_OUTCOME_POOL && s->st.active_node_id == o[k].new_node_id;
        }
        return found;
}

/* a node-ID that answered SDO; its identity may be incomplete (fields
 * lost), which the result says */
static size_t sdo_found(const lss_result *r) {
        size_t found = 0;
        for (size_t i = 0; i < r->n_sdo_nodes; i++)
                found += (r->sdo_nodes[i].source & LSS_SDO_FROM_SDO) && !r->sdo_nodes[i].conflict;
        return found;
}

static void start(lss_master *m, membus *b, enum loss_trial_kind kind) {
        static const lss_autoassign_plan plan = { .unknown = LSS_UNKNOWN_POOL, .pool_lo = 1, .pool_hi = 64,
                                                  .store = true };
        static const lss_identify_range range = { 0xEC, 0x1234, 0, UINT32_MAX, 0, UINT32_MAX };
        static const lss_sdo_discover_params sdo = { .first = LSS_NODE_ID_MIN, .last = LSS_NODE_ID_MAX };
        switch (kind) {
        case LOSS_TRIAL_SCAN: lss_master_enumerate(m, NULL, membus_now(b)); break;
        case LOSS_TRIAL_POOL: lss_master_autoassign(m, &plan, membus_now(b)); break;
        case LOSS_TRIAL_SLOWSCAN: lss_master_slowscan(m, &range, membus_now(b)); break;
        case LOSS_TRIAL_SDO: lss_master_sdo_discover(m, &sdo, membus_now(b)); break;
        case _LOSS_TRIAL_MAX: break;
        }
}

int loss_trial_run(enum loss_trial_kind kind, size_t n, uint32_t drop_ppm, uint64_t seed, loss_trial *out) {
        membus *b = membus_new(125000);
        lss_master *m = lss_master_new(NULL);
        if (!b || !m) {
                lss_master_free(m);
                membus_free(b);
                return -ENOMEM;
        }
        /* identical answers that wait for the wire together merge, as on CAN */
        membus_set_merge_identical(b, true);
        membus_set_seed(b, seed);
        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.latency_us = 1000;
        f.jitter_us = 300;
        f.rx_loss_ppm = f.tx_loss_ppm = drop_ppm;
        uint64_t ids = seed;
        for (size_t i = 0; i < n; i++) {
                lss_identity id = { 0xEC, 0x1234, (uint32_t) sim_random_next(&ids), (uint32_t) sim_random_next(&ids) };
                membus_add_slave(b, &id, kind == LOSS_TRIAL_SDO ? (uint8_t) (i + 1) : LSS_NODE_ID_UNCONFIGURED, &f);
        }
        if (kind == LOSS_TRIAL_SDO)
                membus_set_master_fifo(b, true); /* the requests leave in order, as from a socket */
        start(m, b, kind);
        const lss_result *r = lss_drive(m, b, HOUR_US, NULL, NULL);
        /* boot-ups and the last switch to waiting reach the slaves */
        lss_drive_idle(b, 100000);

        *out = (loss_trial) { .n = n, .virtual_us = membus_now(b) };
        snprintf(out->message, sizeof(out->message), "%s", r->message);
        if (kind == LOSS_TRIAL_SDO) {
                out->success = r->status == LSS_OK;
                out->found = sdo_found(r);
        } else if (kind != LOSS_TRIAL_POOL) {
                out->success = r->status == LSS_OK;
                out->found = scan_found(b, r);
        } else {
                size_t n_out;
                const lss_outcome *o = lss_master_outcomes(m, &n_out);
                out->success = pool_done(o, n_out, r, out);
                out->found = pool_found(b, o, n_out);
        }
        lss_master_free(m);
        membus_free(b);
        return 0;
}
