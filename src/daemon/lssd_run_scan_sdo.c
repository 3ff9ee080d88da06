/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Scan's SDO stages: what the SDO identity discovery found becomes finds
 * (complete identities, one device per node-ID), those the LSS stages did
 * not find are confirmed through LSS next; every node-ID that answered or
 * was heard but is no device gets one journal line and one note of the
 * Scan reply saying what was seen and how to find it. */
#include <stdio.h>
#include <stdlib.h>

#include "daemon/lssd_run.h"
#include "daemon/lssd_log.h"

#define IDENTITY_FIELDS_ALL 0xFu

static bool node_id_found(const lssd_job *j, uint8_t node_id) {
        for (size_t i = 0; i < j->n_found; i++)
                if (j->found[i].dev.node_id == node_id)
                        return true;
        return false;
}

static const char *nmt_state_name(uint8_t state) {
        switch (state) {
        case 0x00: return "a boot-up";
        case 0x04: return "heartbeats in NMT Stopped";
        case 0x05: return "heartbeats in NMT Operational";
        case 0x7F: return "heartbeats in NMT Pre-operational";
        case 0xFF: return "SDO answers to another client";
        default: return "heartbeats";
        }
}

/* "1018h:3 aborted (06090011), 1018h:4 no answer" for the fields not known */
static void missing_fields(const lss_sdo_node *n, char *buf, size_t size) {
        size_t len = 0;
        buf[0] = 0;
        for (unsigned k = 0; k < LSS_FIELD_COUNT && len < size; k++) {
                if (n->known & (1u << k))
                        continue;
                if (n->aborted & (1u << k))
                        len += (size_t) snprintf(buf + len, size - len, "%s1018h:%u aborted", len ? ", " : "",
                                                 k + 1);
                else
                        len += (size_t) snprintf(buf + len, size - len, "%s1018h:%u no answer", len ? ", " : "",
                                                 k + 1);
        }
}

/* One journal line and one note of the reply for a node-ID that answered
 * or was heard but is no device of the Scan. */
static void not_a_device(const lssd_job_env *e, lssd_job *j, const lss_sdo_node *n) {
        char text[320], what[96];
        bool warn = false;
        if (n->conflict) {
                warn = true;
                snprintf(text, sizeof(text), "node-ID %u: two devices answered SDO with different identities "
                         "(1018h): they share the node-ID; give one of them another (lssctl assign), Scan with "
                         "their vendor/product finds each by LSS", n->node_id);
        } else if (n->source & LSS_SDO_FROM_SDO) {
                missing_fields(n, what, sizeof(what));
                snprintf(text, sizeof(text), "node %u answers SDO but its identity is incomplete (%s%s%08x): not "
                         "reported; Scan with its vendor/product finds it if it answers LSS", n->node_id, what,
                         n->aborted ? ", first abort code " : "", n->aborted ? n->abort_code : 0);
        } else if (!node_id_found(j, n->node_id)) {
                if (n->nmt_state == 0x04)
                        snprintf(text, sizeof(text), "node %u sends heartbeats in NMT Stopped: it does not answer "
                                 "SDO; AutoAssign with nmt_stop, or Scan with its vendor/product, finds it",
                                 n->node_id);
                else
                        snprintf(text, sizeof(text), "node %u was heard (%s) but did not answer SDO: not reported; "
                                 "Scan with its vendor/product finds it if it answers LSS", n->node_id,
                                 nmt_state_name(n->nmt_state));
        } else
                return;
        if (warn)
                log_warning("%s: %s: %s", e->ifname, lssd_job_name(j), text);
        else
                log_notice("%s: %s: %s", e->ifname, lssd_job_name(j), text);
        (void) lssd_job_add_note(j, text); /* out of memory: the journal has it */
}

int lssd_scan_take_sdo(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        for (size_t i = 0; i < r->n_sdo_nodes; i++) {
                const lss_sdo_node *n = &r->sdo_nodes[i];
                if (!(n->source & LSS_SDO_FROM_SDO) || n->conflict || n->known != IDENTITY_FIELDS_ALL) {
                        not_a_device(e, j, n);
                        continue;
                }
                lss_device d = { .id = n->id, .node_id = n->node_id };
                int k = lssd_job_add_found_by(j, &d, LSSD_FOUND_SDO);
                if (k <= 0) {
                        if (k < 0)
                                return k;
                        continue; /* found by LSS already */
                }
                lss_identity *a = realloc(j->sdo_cand, (j->n_sdo_cand + 1) * sizeof(*a));
                if (!a)
                        return -ENOMEM;
                j->sdo_cand = a;
                j->sdo_cand[j->n_sdo_cand++] = n->id;
        }
        if (j->n_sdo_cand > 0)
                log_debug("%s: %s: %zu device%s found by SDO only: confirming through LSS", e->ifname, lssd_job_name(j),
                          j->n_sdo_cand, j->n_sdo_cand == 1 ? "" : "s");
        return 0;
}
