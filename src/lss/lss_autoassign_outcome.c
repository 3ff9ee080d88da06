/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The auto-assignment pass's outcomes, one per device it dealt with: how a
 * found device's assignment, the second look and the entries the bus has
 * not become outcomes (the pass is in lss_autoassign.c). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lss/lss_autoassign_state.h"

const char *lss_outcome_name(enum lss_outcome_kind k) {
        static const char *const names[] = {
                [LSS_OUTCOME_UNCHANGED] = "unchanged", [LSS_OUTCOME_ASSIGNED] = "assigned",
                [LSS_OUTCOME_POOL] = "pool",           [LSS_OUTCOME_REPLACED] = "replaced",
                [LSS_OUTCOME_UNKNOWN] = "unknown",     [LSS_OUTCOME_MISSING] = "missing",
                [LSS_OUTCOME_CONFLICT] = "conflict",   [LSS_OUTCOME_FAILED] = "failed",
        };
        return (unsigned) k < sizeof(names) / sizeof(names[0]) ? names[k] : "unknown";
}

/* How many devices this pass gave a node-ID. */
size_t aa_count_given(const lss_aa_state *s) {
        size_t n = 0;
        for (size_t i = 0; i < s->n_out; i++)
                n += s->out[i].kind == LSS_OUTCOME_ASSIGNED || s->out[i].kind == LSS_OUTCOME_POOL ||
                     s->out[i].kind == LSS_OUTCOME_REPLACED;
        return n;
}

int aa_outcome_reserve(lss_aa_state *s, size_t n) {
        if (s->n_out + n <= s->cap_out)
                return 0;
        size_t cap = s->cap_out ? s->cap_out * 2 : 16;
        while (cap < s->n_out + n)
                cap *= 2;
        lss_outcome *o = realloc(s->out, cap * sizeof(*o));
        if (!o) {
                s->oom = true;
                return -ENOMEM;
        }
        s->out = o;
        s->cap_out = cap;
        return 0;
}

lss_outcome *aa_outcome_add(lss_aa_state *s, const lss_identity *id) {
        for (size_t i = 0; i < s->n_out; i++)
                if (lss_identity_equal(&s->out[i].id, id))
                        return &s->out[i]; /* found twice (e.g. by two scans): one outcome */
        if (aa_outcome_reserve(s, 1) < 0)
                return NULL;
        lss_outcome *o = &s->out[s->n_out++];
        memset(o, 0, sizeof(*o));
        o->id = *id;
        return o;
}

bool aa_already_handled(const lss_aa_state *s, const lss_identity *id) {
        for (size_t i = 0; i < s->n_out; i++)
                if (lss_identity_equal(&s->out[i].id, id) && s->out[i].kind != LSS_OUTCOME_MISSING)
                        return true;
        return false;
}

bool lss_map_entry_matches(const lss_map_entry *e, const lss_identity *id) {
        return lss_identity_matches(&e->id, e->revision_known, id);
}

int aa_lookup(const lss_autoassign_plan *p, const lss_identity *id) {
        for (size_t i = 0; i < p->n_map; i++)
                if (lss_map_entry_matches(&p->map[i], id))
                        return (int) i;
        return -1;
}

/* Turn the result of an assignment into the device's outcome; `given`: its
 * kind when the device got a node-ID (assigned, pool, replaced). */
void aa_record(lss_master *m, lss_aa_state *s, const lss_identity *id, enum lss_outcome_kind given) {
        const lss_result *r = &m->result;
        int e = aa_lookup(s->plan, id);
        if (e >= 0 && r->status != LSS_OK && !s->patient)
                s->failed_at[e] = r->failed_service;
        lss_outcome *o = aa_outcome_add(s, id);
        if (!o)
                return;
        o->old_node_id = r->node_id;
        o->status = r->status;
        o->pending_reset = false;
        o->kept_node_id = 0;
        /* only a failure's message is this device's: one of an earlier
         * step of the pass (set aside as its own outcome) may still be there;
         * a success clears what a first look wrote here */
        snprintf(o->message, sizeof(o->message), "%s", r->status != LSS_OK ? r->message : "");
        if (r->status == LSS_OK) {
                o->kind = !r->changed && given != LSS_OUTCOME_REPLACED ? LSS_OUTCOME_UNCHANGED : given;
                o->new_node_id = s->target;
                o->not_stored = r->not_stored;
                o->pending_reset = r->pending_reset && r->changed;
                o->err = r->err;
                o->dry = r->dry && r->changed;
                s->used[s->target] = true;
        } else if (r->status == LSS_E_NOT_FOUND) {
                o->kind = LSS_OUTCOME_MISSING;
                o->old_node_id = o->new_node_id = 0;
        } else {
                o->kind = r->status == LSS_E_CONFLICT ? LSS_OUTCOME_CONFLICT : LSS_OUTCOME_FAILED;
                o->new_node_id = r->node_id;
                o->kept_node_id = r->may_hold ? s->target : 0;
                if (r->in_use || r->may_hold)
                        s->used[s->target] = true;
        }
        if (lss_node_id_valid(r->node_id))
                s->used[r->node_id] = true;
        if (s->patient && r->status == LSS_OK && e >= 0 && s->first[e].kind != LSS_OUTCOME_MISSING &&
            s->first[e].old_node_id != 0 && s->first[e].old_node_id != s->target) {
                /* the first look changed it before it fell silent: this pass assigned it */
                o->kind = given;
                o->old_node_id = s->first[e].old_node_id;
        }
        if (s->patient && r->status != LSS_E_NOT_FOUND && !o->message[0])
                snprintf(o->message, sizeof(o->message), "found on a second look, with waits of %u ms",
                         m->timing.cfg.timeout_us / 1000);
        /* the pass goes on: one device's trouble is its own outcome */
        aa_result_reset(m);
}

void aa_result_reset(lss_master *m) {
        m->result.status = LSS_OK;
        m->result.failed_service = LSS_SERVICE_NONE;
        m->result.reason = LSS_REASON_NONE;
        m->result.message[0] = 0;
        m->result.in_use = false;
}

/* The misbehaving slave is the pass's error and a failed outcome of its own. */
void aa_enumeration_failed(lss_aa_state *s, lss_master *m) {
        s->failed = m->result.status;
        snprintf(s->failed_msg, sizeof(s->failed_msg), "%s", m->result.message);
        lss_outcome *o = aa_outcome_add(s, &m->result.id);
        if (o) {
                o->kind = LSS_OUTCOME_FAILED;
                o->status = m->result.status;
                o->old_node_id = o->new_node_id = 0;
                snprintf(o->message, sizeof(o->message), "%s", m->result.message);
        }
        aa_result_reset(m);
}

/* The outcome of a found device that gets no node-ID. */
void aa_leave_alone(lss_aa_state *s, const lss_device *d, enum lss_outcome_kind kind, enum lss_status st,
                    const char *why) {
        lss_outcome *o = aa_outcome_add(s, &d->id);
        if (!o)
                return;
        o->kind = kind;
        o->status = st;
        o->old_node_id = o->new_node_id = d->node_id;
        /* it answered with that node-ID (pending, for a slave such as Lely's) */
        if (lss_node_id_valid(d->node_id))
                s->used[d->node_id] = true;
        snprintf(o->message, sizeof(o->message), "%s", why);
}

/* Map entries for the second look: not found, found by a scan but silent
 * to the selective switch after it, or silent halfway through their
 * assignment (their outcome is kept in s->first until they answer). */
size_t aa_second_look_entries(lss_aa_state *s) {
        size_t n = 0;
        for (size_t i = 0; i < s->plan->n_map; i++) {
                s->first[i].kind = LSS_OUTCOME_MISSING;
                for (size_t k = 0; s->handled[i] && k < s->n_out;) {
                        lss_outcome *o = &s->out[k];
                        if (aa_lookup(s->plan, &o->id) != (int) i) {
                                k++;
                        } else if (o->kind == LSS_OUTCOME_FAILED && o->status == LSS_E_NO_RESPONSE) {
                                s->first[i] = *o;
                                o->kind = LSS_OUTCOME_MISSING; /* looked for again */
                                s->handled[i] = false;
                                /* silent after Configure Node-ID or at Store: it may
                                 * have the node-ID and not have stored it */
                                if (s->failed_at[i] == LSS_SERVICE_CONFIGURE_NODE_ID ||
                                    s->failed_at[i] == LSS_SERVICE_STORE)
                                        s->restore[s->plan->map[i].node_id] = true;
                                k++;
                        } else if (o->kind == LSS_OUTCOME_MISSING && o->status == LSS_E_NOT_FOUND) {
                                /* the second look says what became of it */
                                memmove(o, o + 1, (s->n_out - k - 1) * sizeof(*o));
                                s->n_out--;
                                s->handled[i] = false;
                        } else
                                k++;
                }
                n += !s->handled[i];
        }
        return n;
}

/* Step 5 of the pass: an outcome for each map entry the bus has not. */
void aa_report_missing(const lss_master *m, lss_aa_state *s) {
        for (size_t i = 0; i < s->plan->n_map; i++)
                if (!s->handled[i]) {
                        lss_outcome *o = s->first[i].kind != LSS_OUTCOME_MISSING ?
                                aa_outcome_add(s, &s->first[i].id) : NULL;
                        if (o) {
                                /* silent again: the first look's failure stands */
                                *o = s->first[i];
                                continue;
                        }
                        o = aa_outcome_add(s, &s->plan->map[i].id);
                        if (o) {
                                o->kind = LSS_OUTCOME_MISSING;
                                o->status = LSS_E_NOT_FOUND;
                                if (m->stats.patient_wait_us)
                                        snprintf(o->message, sizeof(o->message), "not found, also not when "
                                                 "asked again with waits of %u ms", m->stats.patient_wait_us / 1000);
                        }
                }
}

const lss_outcome *lss_master_outcomes(const lss_master *m, size_t *n) {
        *n = m->aa ? m->aa->n_out : 0;
        return m->aa ? m->aa->out : NULL;
}
