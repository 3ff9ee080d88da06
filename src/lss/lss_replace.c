/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The replacement rule (lss_replace.h). */
#include <inttypes.h>
#include <stdio.h>
#include <string.h>

#include "lss/lss_replace.h"

static bool same_pair(const lss_identity *a, const lss_identity *b) {
        return a->vendor == b->vendor && a->product == b->product;
}

bool lss_replace_candidate(const lss_autoassign_plan *p, const bool *handled, const lss_device *d) {
        /* a configured device may serve another node-ID on purpose: only a
         * fresh one, as a spare comes out of its box */
        if (!p->replace || d->node_id != LSS_NODE_ID_UNCONFIGURED)
                return false;
        for (size_t i = 0; i < p->n_map; i++)
                if (!handled[i] && same_pair(&p->map[i].id, &d->id))
                        return true;
        return false;
}

/* The message of an outcome, after what it says already. */
static void message_add(lss_outcome *o, const char *text) {
        size_t n = strlen(o->message);
        snprintf(o->message + n, sizeof(o->message) - n, "%s%s", n ? "; " : "", text);
}

/* The map entry's outcome when it is missing, else NULL. */
static lss_outcome *missing_outcome(const lss_map_entry *e, lss_outcome *out, size_t n_out) {
        for (size_t k = 0; k < n_out; k++)
                if (out[k].kind == LSS_OUTCOME_MISSING && lss_map_entry_matches(e, &out[k].id))
                        return &out[k];
        return NULL;
}

void lss_replace_decide(const lss_autoassign_plan *p, lss_outcome *out, size_t n_out, const lss_device *cand,
                        size_t n_cand, lss_replace_verdict *v) {
        for (size_t c = 0; c < n_cand; c++) {
                size_t n_missing = 0, n_same = 0;
                int entry = -1;
                v[c] = (lss_replace_verdict) { .entry = -1 };
                for (size_t i = 0; i < p->n_map; i++)
                        if (same_pair(&p->map[i].id, &cand[c].id) && missing_outcome(&p->map[i], out, n_out)) {
                                n_missing++;
                                entry = (int) i;
                        }
                for (size_t k = 0; k < n_cand; k++)
                        n_same += same_pair(&cand[k].id, &cand[c].id);
                if (n_missing == 0)
                        continue; /* found after all (the second look): an unknown device like others */
                if (n_missing == 1 && n_same == 1) {
                        v[c].entry = entry;
                        continue;
                }
                v[c].ambiguous = true;
                snprintf(v[c].why, sizeof(v[c].why), "%zu unknown device%s of 0x%" PRIX32 ":0x%" PRIX32
                         " and %zu missing: not replaced, ambiguous", n_same, n_same == 1 ? "" : "s",
                         cand[c].id.vendor, cand[c].id.product, n_missing);
                for (size_t i = 0; i < p->n_map; i++) {
                        lss_outcome *o = same_pair(&p->map[i].id, &cand[c].id) ?
                                missing_outcome(&p->map[i], out, n_out) : NULL;
                        if (o && !strstr(o->message, v[c].why))
                                message_add(o, v[c].why);
                }
        }
}

void lss_replace_note(const lss_autoassign_plan *p, int e, lss_outcome *o, lss_outcome *out, size_t n_out) {
        const lss_map_entry *m = &p->map[e];
        o->replacing = true;
        o->replaced = m->id;
        o->replaced_revision_known = m->revision_known;
        if (o->kind != LSS_OUTCOME_REPLACED) {
                /* its failure, said to be one of a replacement */
                static const char pre[] = "not replaced: ";
                size_t n = sizeof(pre) - 1, len = strnlen(o->message, sizeof(o->message) - 1);
                if (len > sizeof(o->message) - 1 - n)
                        len = sizeof(o->message) - 1 - n;
                memmove(o->message + n, o->message, len);
                memcpy(o->message, pre, n);
                o->message[n + len] = '\0';
                return;
        }
        lss_outcome *gone = missing_outcome(m, out, n_out);
        char by[100];
        snprintf(by, sizeof(by), "%s by %08" PRIx32 ":%08" PRIx32 ":%08" PRIx32 ":%08" PRIx32 " at node-ID %u",
                 o->dry ? "would be replaced" : "replaced", o->id.vendor, o->id.product, o->id.revision,
                 o->id.serial, m->node_id);
        if (gone)
                message_add(gone, by);
}
