/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The pass's reading of 1018h by SDO (the engine's SDO identity discovery,
 * lss_sdo_discover.c, as a child procedure of the pass), for two things LSS
 * alone cannot find:
 *
 *  - A map entry without revision that identify-remote did not resolve: a
 *    configured device without identify services (CANopenNode) is found by
 *    nothing else. Its vendor, product and serial read at some node-ID name
 *    it; with the revision 1018h gives, it is handled by its full identity
 *    (selective switch, Inquire Node-ID, ...) like an entry with revision.
 *    The device could be at any node-ID: 1..127 are read.
 *  - With `replace`: a missing entry's node-ID answered by one device of its
 *    vendor and product that the map does not know, a spare configured at
 *    that node-ID (lss_replace.h). Only the node-IDs of such entries that
 *    answered the pass's probe are read.
 *
 * Devices in NMT Stopped answer no SDO: with NMT Stop the reading comes
 * before the Stop, where the pass cannot know yet whether it will need it
 * (so whenever the map could: an entry without revision, or `replace` and a
 * mapped node-ID that answers); without, it comes after the enumeration and
 * only for what is still unresolved. A map of full identities with nothing
 * missing reads nothing. The reading writes nothing (upload requests only). */
#include <string.h>

#include "lss/lss_autoassign_state.h"

/* An identity read whole, from one device. */
static bool whole(const lss_sdo_node *d) {
        return (d->source & LSS_SDO_FROM_SDO) && d->known == 0xF && !d->conflict;
}

bool aa_sdo_wanted(lss_aa_state *s) {
        bool all = false, some = false;
        memset(s->sdo_only, 0, sizeof(s->sdo_only));
        for (size_t i = 0; i < s->plan->n_map; i++) {
                const lss_map_entry *e = &s->plan->map[i];
                if (s->handled[i])
                        continue; /* (nothing is handled before the Stop) */
                if (!e->revision_known)
                        all = true;
                else if (s->plan->replace && s->taken[e->node_id])
                        some = s->sdo_only[e->node_id] = true;
        }
        if (all)
                memset(s->sdo_only, 1, sizeof(s->sdo_only));
        return all || some;
}

int aa_proc_sdo(lss_master *m, lss_aa_state *s) {
        PT_BEGIN(&s->s_pc);
        if (sdo_discover_setup(m, &(lss_sdo_discover_params) { .first = LSS_NODE_ID_MIN, .last = LSS_NODE_ID_MAX },
                               s->sdo_only) < 0)
                goto out; /* no memory: the pass goes on with what LSS finds */
        PT_CALL(&s->s_pc, proc_sdo_discover(m));
        s->sdo_nodes = m->result.sdo_nodes;
        s->n_sdo_nodes = m->result.n_sdo_nodes;
        /* the pass's result is its outcomes */
        m->result.sdo_nodes = NULL;
        m->result.n_sdo_nodes = 0;
out:;
        PT_END(&s->s_pc);
}

size_t aa_sdo_resolve(lss_aa_state *s) {
        lss_device found[LSS_NODE_ID_MAX];
        size_t n = 0;
        for (size_t k = 0; k < s->n_sdo_nodes; k++) {
                const lss_sdo_node *d = &s->sdo_nodes[k];
                int e = whole(d) ? aa_lookup(s->plan, &d->id) : -1;
                if (e >= 0 && !s->handled[e] && !s->plan->map[e].revision_known)
                        found[n++] = (lss_device) { .id = d->id, .node_id = d->node_id };
        }
        return n > 0 && aa_todo_take(s, found, n) == 0 ? n : 0;
}

void aa_sdo_replacements(lss_aa_state *s) {
        if (!s->plan->replace)
                return;
        for (size_t k = 0; k < s->n_sdo_nodes; k++) {
                const lss_sdo_node *d = &s->sdo_nodes[k];
                if (!whole(d) || aa_lookup(s->plan, &d->id) >= 0 || aa_already_handled(s, &d->id))
                        continue;
                for (size_t i = 0; i < s->plan->n_map; i++) {
                        const lss_map_entry *e = &s->plan->map[i];
                        if (!s->handled[i] && e->node_id == d->node_id && e->id.vendor == d->id.vendor &&
                            e->id.product == d->id.product)
                                aa_cand_keep(s, &(lss_device) { .id = d->id, .node_id = d->node_id });
                }
        }
}

bool aa_in_place(lss_master *m, lss_aa_state *s, const bool *unstored) {
        const lss_device *d = &s->todo[s->t];
        if (s->replacing < 0 || d->node_id != s->target || (s->plan->store && unstored[s->target]))
                return false;
        m->result.status = LSS_OK;
        m->result.id = d->id;
        m->result.node_id = s->target;
        m->result.changed = m->result.in_use = m->result.not_stored = m->result.dry = false;
        m->result.err = 0;
        return true;
}
