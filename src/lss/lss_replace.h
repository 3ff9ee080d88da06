/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The replacement of a broken device (lss_autoassign_plan.replace): the rule
 * alone; the pass (lss_autoassign.c) carries it out. Not a public header.
 *
 * A device the map does not know, found non-configured by the pass's
 * enumeration, is a candidate while a map entry of its vendor and product
 * has not been found: it is kept aside (not pooled, not reported) until the
 * pass knows what is missing. So is one that 1018h read by SDO shows at a
 * missing entry's node-ID, of that entry's vendor and product
 * (lss_autoassign_sdo.c); it keeps the node-ID it has, nothing is sent to
 * it. Then, per vendor/product pair: exactly one
 * entry missing and exactly one candidate: the candidate gets that entry's
 * node-ID. More of either: nobody is replaced and the outcomes say why (a
 * guess could give a node-ID, and the stored configuration behind it, to the
 * wrong device). No entry missing: the candidate is an unknown device like
 * any other (ignored or pooled). */
#pragma once

#include <stdbool.h>
#include <stddef.h>

#include "lss/lss_autoassign.h"

typedef struct lss_replace_verdict {
        int entry;      /* >= 0: the missing map entry whose node-ID the candidate gets */
        bool ambiguous; /* its pair has several candidates or several entries missing: left alone */
        char why[160];  /* ambiguous: the outcome's message */
} lss_replace_verdict;

/* Whether the pass keeps this device (found by a scan, not in the map) for
 * the rule; handled: per map entry, found on the bus so far. */
bool lss_replace_candidate(const lss_autoassign_plan *p, const bool *handled, const lss_device *d);

/* The verdict for each of the candidates, from the pass's outcomes (an entry
 * is missing when its outcome is); the missing outcomes of an ambiguous pair
 * get the verdict's message too when they have none. */
void lss_replace_decide(const lss_autoassign_plan *p, lss_outcome *out, size_t n_out, const lss_device *cand,
                        size_t n_cand, lss_replace_verdict *v);

/* The candidate's outcome after its assignment to entry e: what it replaced,
 * and on the missing entry's outcome who replaced it. */
void lss_replace_note(const lss_autoassign_plan *p, int e, lss_outcome *o, lss_outcome *out, size_t n_out);
