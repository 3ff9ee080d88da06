/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The auto-assignment pass (the plan is in lss_autoassign.h). Built from the
 * engine's own procedures: assignment by selective switch, slowscan,
 * enumeration. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lss/lss_autoassign_state.h"
#include "lss/lss_replace.h"


void lss_autoassign_free_state(lss_master *m) {
        if (!m->aa)
                return;
        free(m->aa->handled);
        free(m->aa->first);
        free(m->aa->failed_at);
        free(m->aa->todo);
        free(m->aa->out);
        free(m->aa->cand);
        free(m->aa->verdict);
        free(m->aa);
        m->aa = NULL;
}

int aa_todo_take(lss_aa_state *s, const lss_device *d, size_t n) {
        s->n_todo = 0;
        if (aa_outcome_reserve(s, n) < 0)
                return -ENOMEM;
        if (n > s->cap_todo) {
                lss_device *t = realloc(s->todo, n * sizeof(*t));
                if (!t) {
                        s->oom = true;
                        return -ENOMEM;
                }
                s->todo = t;
                s->cap_todo = n;
        }
        if (n)
                memcpy(s->todo, d, n * sizeof(*d));
        s->n_todo = n;
        return 0;
}

/* Lowest pool node-ID not given by the map and not seen taken. */
static uint8_t pool_next(const lss_aa_state *s) {
        for (unsigned id = s->plan->pool_lo; id <= s->plan->pool_hi && id <= LSS_NODE_ID_MAX; id++)
                if (!s->used[id])
                        return (uint8_t) id;
        return 0;
}

static unsigned assign_flags(const lss_aa_state *s) {
        return LSS_ASSIGN_VERIFY | LSS_ASSIGN_CHECK_FREE | (s->plan->store ? LSS_ASSIGN_STORE : 0) |
               (s->plan->dry_run ? LSS_ASSIGN_DRY_RUN : 0);
}

/* The node-IDs that may not be stored: the caller's table is live (lssd adds
 * the node-IDs it hears boot up during the pass), the second look adds its own. */
static const bool *unstored_now(lss_aa_state *s) {
        for (unsigned i = 0; i < 128; i++)
                s->unstored[i] = s->restore[i] || (s->plan->unstored && s->plan->unstored[i]);
        return s->unstored;
}

/* After an assignment: what the probe at the start said no longer holds for
 * the node-ID the device left (probed again when needed) or took. */
static void moved(lss_aa_state *s, const lss_master *m) {
        if (!m->result.changed)
                return;
        if (lss_node_id_valid(m->result.node_id)) {
                s->taken[m->result.node_id] = false;
                s->free[m->result.node_id] = false;
        }
        s->free[s->target] = false;
}

/* NMT Stop is sent (nmt_stop, and not a dry run) */
static bool stops(const lss_aa_state *s) {
        return s->plan->nmt_stop && !s->plan->dry_run;
}

/* A candidate of the replacement rule waits for the end of the pass. */
int aa_cand_keep(lss_aa_state *s, const lss_device *d) {
        for (size_t i = 0; i < s->n_cand; i++)
                if (lss_identity_equal(&s->cand[i].id, &d->id))
                        return 0; /* found again by a later scan */
        if (s->n_cand == s->cap_cand) {
                size_t cap = s->cap_cand ? s->cap_cand * 2 : 4;
                lss_device *c = realloc(s->cand, cap * sizeof(*c));
                if (c)
                        s->cand = c;
                lss_replace_verdict *v = c ? realloc(s->verdict, cap * sizeof(*v)) : NULL;
                if (!v)
                        return -ENOMEM;
                s->verdict = v;
                s->cap_cand = cap;
        }
        s->cand[s->n_cand++] = *d;
        return 0;
}

/* Which node-ID the found device todo[t] gets (s->target, s->entry,
 * s->replacing); false: none, its outcome is recorded or it is kept for the
 * replacement rule. */
static bool choose_target(lss_aa_state *s) {
        const lss_device *d = &s->todo[s->t];
        const lss_replace_verdict *v = s->deciding ? &s->verdict[s->t] : NULL;
        s->replacing = -1;
        s->entry = aa_lookup(s->plan, &d->id);
        if (s->entry >= 0) {
                s->handled[s->entry] = true;
                s->target = s->plan->map[s->entry].node_id;
                return true;
        }
        if (v && v->entry >= 0) {
                s->replacing = v->entry;
                s->target = s->plan->map[v->entry].node_id;
                return true;
        }
        if (v && v->ambiguous) {
                aa_leave_alone(s, d, LSS_OUTCOME_UNKNOWN, LSS_OK, v->why);
                return false;
        }
        /* decided before the pool could take it */
        if (!v && lss_replace_candidate(s->plan, s->handled, d) && aa_cand_keep(s, d) == 0)
                return false;
        if (s->plan->unknown == LSS_UNKNOWN_POOL && d->node_id == LSS_NODE_ID_UNCONFIGURED) {
                s->target = pool_next(s);
                if (s->target != 0)
                        return true;
                aa_leave_alone(s, d, LSS_OUTCOME_FAILED, LSS_E_INVALID, "the pool is exhausted");
                return false;
        }
        aa_leave_alone(s, d, LSS_OUTCOME_UNKNOWN, LSS_OK, "");
        return false;
}

/* The pool node-IDs the non-configured unknown devices in `todo` may take,
 * to be asked together before they are given out (a batch per wait, as the
 * mapped ones at the start): asked one at a time, each cost a full timeout
 * per device, 5 % of a blind pass of 32. */
static void pool_probe_plan(lss_aa_state *s) {
        size_t want = 0;
        s->probe = (lss_probe_state) { .taken = s->taken, .free = s->free };
        if (s->plan->unknown != LSS_UNKNOWN_POOL)
                return;
        for (size_t t = 0; t < s->n_todo; t++)
                if (s->todo[t].node_id == LSS_NODE_ID_UNCONFIGURED && aa_lookup(s->plan, &s->todo[t].id) < 0 &&
                    !aa_already_handled(s, &s->todo[t].id))
                        want++;
        for (unsigned id = s->plan->pool_lo; want > 0 && id <= s->plan->pool_hi && id <= LSS_NODE_ID_MAX; id++)
                if (!s->used[id] && !s->taken[id]) {
                        if (!s->free[id])
                                s->probe.ids[s->probe.n_ids++] = (uint8_t) id;
                        want--;
                }
}

/* Handle the devices in `todo` (full identities, found by a scan). */
static int handle_found(lss_master *m, lss_aa_state *s) {
        PT_BEGIN(&s->i_pc);
        /* again while one answered: the next of the pool takes its place */
        for (pool_probe_plan(s); s->probe.n_ids > 0; pool_probe_plan(s))
                PT_CALL(&s->i_pc, proc_probe(m, &s->probe));
        for (s->t = 0; s->t < s->n_todo; s->t++) {
                if (aa_already_handled(s, &s->todo[s->t].id) || !choose_target(s))
                        continue;
                for (;;) {
                        if (aa_in_place(m, s, unstored_now(s)))
                                break; /* a replacement configured at its node-ID: nothing to send */
                        memset(&m->as, 0, sizeof(m->as));
                        m->as.id = s->todo[s->t].id;
                        m->as.node_id = s->target;
                        m->as.flags = assign_flags(s);
                        m->as.taken = s->taken;
                        m->as.free = s->free;
                        m->as.unstored = unstored_now(s);
                        PT_CALL(&s->i_pc, proc_assign(m, &m->as));
                        /* a pool ID somebody already answers to: take the next one */
                        if (s->entry < 0 && s->replacing < 0 && m->result.in_use) {
                                s->used[s->target] = true;
                                aa_result_reset(m);
                                s->target = pool_next(s);
                                if (s->target != 0)
                                        continue;
                                master_fail(m, LSS_E_CONFLICT, "every node-ID of the pool answers on the bus");
                        }
                        break;
                }
                s->changed = m->result.changed;
                moved(s, m);
                aa_record(m, s, &s->todo[s->t].id, s->replacing >= 0 ? LSS_OUTCOME_REPLACED :
                                                    s->entry < 0 ? LSS_OUTCOME_POOL : LSS_OUTCOME_ASSIGNED);
                if (s->replacing >= 0) {
                        lss_outcome *o = aa_outcome_add(s, &s->todo[s->t].id);
                        if (o)
                                lss_replace_note(s->plan, s->replacing, o, s->out, s->n_out);
                }
                if (s->changed && stops(s)) {
                        /* the verifying reset took them out of Stopped */
                        STEP_REQUEST(m, &s->i_pc, nmt_encode(&f__, NMT_CS_STOP, 0), -1);
                }
        }
        PT_END(&s->i_pc);
}

/* Steps 1 and 2 for every map entry not seen yet: a full identity straight
 * by selective switch, an entry without revision by bisecting the revision
 * for its serial (finds configured devices too). */
static int proc_map_direct(lss_master *m, lss_aa_state *s) {
        PT_BEGIN(&s->d_pc);
        /* 1. full identities: straight to them by selective switch */
        for (s->i = 0; s->i < s->plan->n_map; s->i++) {
                if (!s->plan->map[s->i].revision_known || s->handled[s->i])
                        continue;
                s->target = s->plan->map[s->i].node_id;
                memset(&m->as, 0, sizeof(m->as));
                m->as.id = s->plan->map[s->i].id;
                m->as.node_id = s->target;
                m->as.flags = assign_flags(s);
                m->as.taken = s->taken;
                m->as.free = s->free;
                m->as.unstored = unstored_now(s);
                m->as.first_look = !s->patient;
                PT_CALL(&s->d_pc, proc_assign(m, &m->as));
                if (m->result.status != LSS_E_NOT_FOUND) {
                        s->handled[s->i] = true;
                        s->changed = m->result.changed;
                        moved(s, m);
                        aa_record(m, s, &s->plan->map[s->i].id, LSS_OUTCOME_ASSIGNED);
                        if (s->changed && stops(s)) {
                                /* the verifying reset took them out of Stopped */
                                STEP_REQUEST(m, &s->d_pc, nmt_encode(&f__, NMT_CS_STOP, 0), -1);
                        }
                } else
                        aa_result_reset(m);
        }

        /* 2. no revision in the map: bisect the revision for that serial */
        for (s->i = 0; s->i < s->plan->n_map; s->i++) {
                if (s->plan->map[s->i].revision_known || s->handled[s->i])
                        continue;
                m->sc.range = (lss_identify_range) { s->plan->map[s->i].id.vendor, s->plan->map[s->i].id.product, 0,
                                                     UINT32_MAX, s->plan->map[s->i].id.serial,
                                                     s->plan->map[s->i].id.serial };
                m->sc.pc = m->sc.vpc = 0;
                PT_CALL(&s->d_pc, proc_slowscan(m, &m->sc));
                aa_result_reset(m);
                if (aa_todo_take(s, m->devices, m->n_devices) < 0)
                        continue;
                s->i_pc = 0;
                PT_CALL(&s->d_pc, handle_found(m, s));
        }

        PT_END(&s->d_pc);
}

/* The lowest pool node-ID not given, not taken and nobody is set aside
 * with (0: none). */
static uint8_t pool_next_direct(const lss_aa_state *s, const bool *aside) {
        for (unsigned id = s->plan->pool_lo; id <= s->plan->pool_hi && id <= LSS_NODE_ID_MAX; id++)
                if (!s->used[id] && !s->taken[id] && !aside[id])
                        return (uint8_t) id;
        return 0;
}

/* The enumeration's direct assignment (lss_enum_direct): a device for the
 * pool gets its node-ID the moment it is confirmed, alone in configuration,
 * as handle_found() would give it after the give-back, which saves it
 * three selective switches, two Configure Node-ID and an inquiry. A map
 * entry's device, a replacement candidate and one left alone are set aside
 * and handled after the enumeration, as in a dry run. */
static bool direct_choose(lss_master *m, void *ud, const lss_identity *id, const bool *aside,
                          lss_probe_state **probe) {
        lss_aa_state *s = ud;
        lss_device d = { .id = *id, .node_id = LSS_NODE_ID_UNCONFIGURED };
        if (aa_already_handled(s, id) || aa_lookup(s->plan, id) >= 0 || lss_replace_candidate(s->plan, s->handled, &d))
                return false;
        /* no node-ID given without room for its outcome (s->oom: the pass fails) */
        if (aa_outcome_reserve(s, 1) < 0)
                return false;
        s->target = pool_next_direct(s, aside);
        if (s->target == 0)
                return false; /* the pool is exhausted: handle_found() says so */
        if (!s->free[s->target]) {
                /* the next few of the pool, probed together */
                s->probe = (lss_probe_state) { .taken = s->taken, .free = s->free };
                for (unsigned n = s->target; n <= s->plan->pool_hi && n <= LSS_NODE_ID_MAX &&
                                             s->probe.n_ids < LSS_MAX_TX; n++)
                        if (!s->used[n] && !s->taken[n] && !aside[n] && !s->free[n])
                                s->probe.ids[s->probe.n_ids++] = (uint8_t) n;
                *probe = &s->probe;
                return false;
        }
        s->entry = s->replacing = -1;
        memset(&m->as, 0, sizeof(m->as));
        m->as.id = *id;
        m->as.node_id = s->target;
        m->as.flags = assign_flags(s);
        m->as.taken = s->taken;
        m->as.free = s->free;
        m->as.unstored = unstored_now(s);
        return true;
}

static void direct_done(lss_master *m, void *ud) {
        lss_aa_state *s = ud;
        s->avoid[s->target] = true; /* never a temporary node-ID of the enumeration */
        if (m->result.in_use) {
                s->used[s->target] = true;
                aa_result_reset(m);
                return;
        }
        moved(s, m);
        aa_record(m, s, &m->as.id, LSS_OUTCOME_POOL);
}

/* 3. non-configured devices left: fastscan with the map's vendor and
 * product bits first, then blind while somebody still answers */
static int enumerate_all(lss_master *m, lss_aa_state *s) {
        PT_BEGIN(&s->e_pc);
        for (s->pair = 0; s->pair <= s->plan->n_map; s->pair++) {
                memset(&m->sc.known, 0, sizeof(m->sc.known));
                if (s->pair < s->plan->n_map) {
                        const lss_identity *id = &s->plan->map[s->pair].id;
                        bool seen = false;
                        for (size_t j = 0; j < s->pair; j++)
                                seen |= s->plan->map[j].id.vendor == id->vendor &&
                                        s->plan->map[j].id.product == id->product;
                        if (seen)
                                continue;
                        m->sc.known.value = *id;
                        m->sc.known.known_bits[LSS_FIELD_VENDOR] = 32;
                        m->sc.known.known_bits[LSS_FIELD_PRODUCT] = 32;
                }
                for (unsigned id = 0; id < 128; id++)
                        s->avoid[id] = s->used[id] || s->taken[id];
                m->sc.avoid = s->avoid;
                m->sc.keep_stopped = stops(s);
                m->sc.no_set_aside = s->plan->dry_run;
                s->direct = (lss_enum_direct) { .choose = direct_choose, .done = direct_done, .ud = s };
                m->sc.direct = s->plan->unknown == LSS_UNKNOWN_POOL && !s->plan->dry_run ? &s->direct : NULL;
                m->sc.listen = false; /* the second look asks patiently for what the map has */
                m->sc.patient_end = s->plan->unknown == LSS_UNKNOWN_POOL || s->plan->replace;
                m->sc.pc = m->sc.vpc = 0;
                s->given_before = aa_count_given(s);
                PT_CALL(&s->e_pc, proc_enumerate(m, &m->sc));
                if (m->cancelling)
                        break;
                /* Every non-configured slave answers the ping, whatever its
                 * identity: when nobody did at the end, after a switch to
                 * waiting, and nobody was set aside (to get 255 back), the
                 * enumerations left (other vendors, blind) would only ask it
                 * again, a full wait each. */
                if (m->sc.nobody && m->result.status == LSS_OK) {
                        s->failed = LSS_OK; /* nobody left unfound: an earlier verdict is answered */
                        break;
                }
                if (m->sc.misbehaving) {
                        /* nothing more can be found by fastscan: report it, assign nothing of this scan */
                        aa_enumeration_failed(s, m);
                        break;
                }
                /* Any other verdict (did not converge, its deadline, a find not
                 * confirmed or verified, no free node-ID) leaves slaves it may
                 * not have reached: what it verified is assigned, but the
                 * verdict is the pass's unless a blind enumeration after it
                 * completes. Dropped, the pass said "done" with a slave never
                 * reached (issue 38). */
                if (m->result.status != LSS_OK) {
                        s->failed = m->result.status;
                        snprintf(s->failed_msg, sizeof(s->failed_msg), "%s", m->result.message);
                } else if (s->pair == s->plan->n_map)
                        s->failed = LSS_OK;
                aa_result_reset(m);
                if (aa_todo_take(s, m->devices, m->n_devices) < 0)
                        continue;
                s->i_pc = 0;
                PT_CALL(&s->e_pc, handle_found(m, s));
                /* A slave whose fastscan confirmation (or ping) answer came
                 * after the wait entered configuration state uncounted and
                 * sat out the rest of that enumeration; the switch to waiting
                 * at its end freed it. So scan blind again while a blind
                 * enumeration still gave somebody a node-ID (and did not end
                 * on silent pings after a switch to waiting: `nobody` above). */
                if (s->pair == s->plan->n_map && aa_count_given(s) > s->given_before &&
                    ++s->blind_passes < LSS_NODE_ID_MAX)
                        s->pair--; /* the loop's ++ comes back to the blind enumeration */
        }
        PT_END(&s->e_pc);
}


/* 4. a present device must not be called missing because an answer
 * came late (a loaded host, a slow device): what the map has and the
 * pass did not find is looked for again with every step waiting
 * several times longer, after another NMT Stop where asked. Each step is
 * asked twice: the first look asked retries + 1 times already, the second
 * is for a slow answer (and a frame lost on the way, once). */
static int second_look(lss_master *m, lss_aa_state *s) {
        PT_BEGIN(&s->l_pc);
        /* the bus or the host was slower than the configured timeout allowed
         * for, so well beyond it */
        m->stats.patient_wait_us = lss_timing_patient_wait(&m->timing, 0);
        master_patient_begin(m, m->stats.patient_wait_us);
        s->patient = true;
        if (stops(s)) {
                STEP_REQUEST(m, &s->l_pc, nmt_encode(&f__, NMT_CS_STOP, 0), -1);
                m->step = (lss_step) { .kind = STEP_DELAY, .wait_us = 20000 };
                step_start(m);
                PT_YIELD(&s->l_pc);
        }
        s->d_pc = 0;
        PT_CALL(&s->l_pc, proc_map_direct(m, s));
        master_patient_end(m);
        s->patient = false;
        PT_END(&s->l_pc);
}

/* 6. the replacement candidates take the place of the found ones */
static void take_candidates(lss_aa_state *s) {
        lss_device *t = s->todo;
        size_t cap = s->cap_todo;
        s->todo = s->cand;
        s->n_todo = s->n_cand;
        s->cap_todo = s->cap_cand;
        s->cand = t;
        s->cap_cand = cap;
        s->n_cand = 0;
        lss_replace_decide(s->plan, s->out, s->n_out, s->todo, s->n_todo, s->verdict);
}

static int proc_autoassign(lss_master *m) {
        lss_aa_state *s = m->aa;
        PT_BEGIN(&s->pc);
        for (size_t i = 0; i < s->plan->n_map; i++)
                s->used[s->plan->map[i].node_id] = true;

        /* Which mapped node-IDs somebody answers to, all at the start, a
         * batch of them per wait (one wait each cost a full timeout per
         * device); stopped devices do not answer SDO, so before NMT Stop. */
        s->probe = (lss_probe_state) { .taken = s->taken, .free = s->free };
        for (size_t i = 0; i < s->plan->n_map; i++)
                if (!s->taken[s->plan->map[i].node_id])
                        s->probe.ids[s->probe.n_ids++] = s->plan->map[i].node_id;
        PT_CALL(&s->pc, proc_probe(m, &s->probe));
        /* 1018h by SDO (lss_autoassign_sdo.c): before the Stop, or later
         * when the pass knows it needs it */
        if (stops(s) && aa_sdo_wanted(s)) {
                s->sdo_read = true;
                s->s_pc = 0;
                PT_CALL(&s->pc, aa_proc_sdo(m, s));
        }
        if (stops(s)) {
                STEP_REQUEST(m, &s->pc, nmt_encode(&f__, NMT_CS_STOP, 0), -1);
                /* give the devices time to act on it before LSS starts */
                m->step = (lss_step) { .kind = STEP_DELAY, .wait_us = 20000 };
                step_start(m);
                PT_YIELD(&s->pc);
        }

        PT_CALL(&s->pc, proc_map_direct(m, s));

        s->e_pc = 0;
        PT_CALL(&s->pc, enumerate_all(m, s));
        if (m->cancelling)
                goto out;

        if (!s->sdo_read && aa_sdo_wanted(s)) {
                s->sdo_read = true;
                s->s_pc = 0;
                PT_CALL(&s->pc, aa_proc_sdo(m, s));
        }
        if (aa_sdo_resolve(s) > 0) {
                /* entries without revision that SDO named: by their full identity */
                s->i_pc = 0;
                PT_CALL(&s->pc, handle_found(m, s));
        }

        /* 4. a present device must not be called missing because an answer
         * came late: what the map has and the pass did not find is looked
         * for again, patiently */
        if (aa_second_look_entries(s) > 0) {
                s->l_pc = 0;
                PT_CALL(&s->pc, second_look(m, s));
        }

        /* 5. what the map has and the bus has not */
        aa_report_missing(m, s);
        aa_sdo_replacements(s);

        /* 6. the replacement rule (lss_replace.h), now that the pass knows
         * what is missing: the candidates take the place of the found ones */
        if (s->n_cand > 0) {
                take_candidates(s);
                s->deciding = true;
                s->i_pc = 0;
                PT_CALL(&s->pc, handle_found(m, s));
                s->deciding = false;
        }
        STEP_REQUEST(m, &s->pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING), -1);
        if (s->plan->reset_after_pass && !s->plan->dry_run) {
                s->r_pc = 0;
                PT_CALL(&s->pc, aa_proc_reset_pending(m, s));
        }
        m->result.status = LSS_OK;
        if (s->oom)
                master_fail(m, LSS_E_INCOMPLETE, "out of memory: devices found were left as they were");
        else if (s->failed != LSS_OK)
                master_fail(m, s->failed, "%s", s->failed_msg);
out:
        m->n_devices = 0; /* the outcomes are the result */
        PT_END(&s->pc);
}

void aa_on_foreign(lss_master *m) {
        lss_aa_state *s = m->aa;
        if (!s || m->proc != proc_autoassign || !m->as.configuring)
                return;
        /* the device whose assignment was under way: its Configure Node-ID
         * went out, nothing confirmed it, nothing gave it back */
        lss_outcome *o = aa_outcome_add(s, &m->as.id);
        if (!o)
                return;
        o->kind = LSS_OUTCOME_FAILED;
        o->status = LSS_E_FOREIGN_MASTER;
        o->old_node_id = o->new_node_id = m->as.old;
        o->kept_node_id = m->as.node_id;
        o->pending_reset = false;
        snprintf(o->message, sizeof(o->message), "broken off after Configure Node-ID %u (%.200s): the device may "
                 "hold node-ID %u, which is kept for it", m->as.node_id, m->result.message, m->as.node_id);
        s->used[m->as.node_id] = true;
}

int lss_master_autoassign(lss_master *m, const lss_autoassign_plan *plan, uint64_t now) {
        if (!plan || (plan->n_map && !plan->map))
                return -EINVAL;
        for (size_t i = 0; i < plan->n_map; i++)
                if (!lss_node_id_valid(plan->map[i].node_id))
                        return -EINVAL;
        if (plan->unknown == LSS_UNKNOWN_POOL &&
            (!lss_node_id_valid(plan->pool_lo) || !lss_node_id_valid(plan->pool_hi) || plan->pool_lo > plan->pool_hi))
                return -EINVAL;
        if (lss_master_busy(m))
                return -EBUSY;
        lss_autoassign_free_state(m);
        m->aa = calloc(1, sizeof(*m->aa));
        if (!m->aa)
                return -ENOMEM;
        m->aa->plan = plan;
        m->stats.patient_wait_us = 0;
        m->aa->handled = calloc(plan->n_map + 1, sizeof(bool));
        m->aa->first = calloc(plan->n_map + 1, sizeof(lss_outcome));
        m->aa->failed_at = calloc(plan->n_map + 1, sizeof(*m->aa->failed_at));
        if (!m->aa->handled || !m->aa->first || !m->aa->failed_at) {
                lss_autoassign_free_state(m);
                return -ENOMEM;
        }
        return master_start_procedure(m, proc_autoassign, now);
}
