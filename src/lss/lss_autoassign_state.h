/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The state of the auto-assignment pass, shared by lss_autoassign.c (the
 * pass) and lss_autoassign_outcome.c (its outcomes). Not a public header. */
#pragma once

#include "lss/lss_autoassign.h"
#include "lss/lss_internal.h"
#include "lss/lss_replace.h"

typedef struct lss_aa_state {
        /* the pass, and its children: handle_found, map direct,
         * enumeration, second look */
        int pc, i_pc, d_pc, e_pc, l_pc;
        bool patient;              /* the second look runs */
        lss_outcome *first;        /* per map entry: its outcome before the second look (kind MISSING: none) */
        const lss_autoassign_plan *plan;
        bool *handled;          /* per map entry: seen on the bus */
        bool used[128];         /* node-IDs known to be taken */
        lss_device *todo;       /* devices found by a scan, still to handle */
        size_t n_todo, cap_todo, t, i;
        uint32_t vp[2];         /* vendor/product pair being enumerated */
        size_t pair;
        int entry;              /* map entry of the device being handled, -1 none */
        int replacing;          /* missing map entry whose node-ID it gets, -1 none */
        lss_device *cand;       /* kept for the replacement rule (lss_replace.h) */
        size_t n_cand, cap_cand;
        lss_replace_verdict *verdict; /* per candidate, while `deciding` */
        bool deciding;          /* handle_found() is given the candidates, with their verdicts */
        bool changed;
        uint8_t target;
        enum lss_service *failed_at; /* per map entry: the service its first look failed at */
        bool restore[128];      /* node-IDs the second look must store again (a first look
                                 * silent after Configure Node-ID or at Store) */
        bool unstored[128];     /* those and the caller's, as they are now */
        bool taken[128];        /* answered the SDO probe at the start (before an NMT Stop) */
        bool free[128];         /* silent to it, and nobody assigned there since */
        lss_probe_state probe;
        lss_outcome *out;
        size_t n_out, cap_out;
        size_t given_before;    /* node-IDs given before the current blind enumeration */
        unsigned blind_passes;
        bool avoid[128];        /* node-IDs an enumeration may not set a slave aside with */
        lss_enum_direct direct; /* the enumeration gives pool node-IDs as it finds (lss_autoassign.c) */
        enum lss_status failed; /* an enumeration's verdict: a slave that does not follow CiA 305,
                                 * or one not answered by a complete enumeration after it */
        char failed_msg[400];
        bool oom;               /* an outcome or the devices found could not be kept: the
                                 * pass fails "out of memory", never "done" without them */
        /* reset_after_pass (lss_autoassign_reset.c) */
        int r_pc;
        size_t k;
        uint64_t until;
        /* 1018h read by SDO (lss_autoassign_sdo.c) */
        int s_pc;
        bool sdo_read;          /* done in this pass (once at most) */
        bool sdo_only[128];     /* the node-IDs it reads */
        const lss_sdo_node *sdo_nodes; /* what it read (the engine's SDO state keeps them) */
        size_t n_sdo_nodes;
} lss_aa_state;

/* The found devices to handle next: a copy of d[0, n). */
int aa_todo_take(lss_aa_state *s, const lss_device *d, size_t n);
/* Keep a device for the replacement rule (candidates). */
int aa_cand_keep(lss_aa_state *s, const lss_device *d);

/* lss_autoassign_sdo.c: whether the pass reads 1018h by SDO now, and
 * where (sdo_only): entries without revision not found (all node-IDs),
 * with `replace` the node-IDs of entries not found that answer. */
bool aa_sdo_wanted(lss_aa_state *s);
/* The reading, a child procedure (s_pc zeroed first). */
int aa_proc_sdo(lss_master *m, lss_aa_state *s);
/* Devices it named for entries without revision not found yet, into todo
 * (their count). */
size_t aa_sdo_resolve(lss_aa_state *s);
/* With `replace`: a device the map does not know at a missing entry's
 * node-ID, of that entry's vendor and product, is a candidate. */
void aa_sdo_replacements(lss_aa_state *s);
/* The replacement todo[t] already has its node-ID (and need not store it):
 * the result of an assignment that sent nothing is set, true. */
bool aa_in_place(lss_master *m, lss_aa_state *s, const bool *unstored);

/* How many devices this pass gave a node-ID. */
size_t aa_count_given(const lss_aa_state *s);
/* The outcome of this identity, added when there is none yet (NULL: no
 * memory, and s->oom set). */
lss_outcome *aa_outcome_add(lss_aa_state *s, const lss_identity *id);
/* Room for n more outcomes, so that a device's assignment is never done
 * without room to report it; -ENOMEM (s->oom set). */
int aa_outcome_reserve(lss_aa_state *s, size_t n);
/* The identity has an outcome other than missing. */
bool aa_already_handled(const lss_aa_state *s, const lss_identity *id);
/* The map entry that names this device, -1 none. */
int aa_lookup(const lss_autoassign_plan *p, const lss_identity *id);
/* The result of an assignment as the device's outcome; `given`: its kind
 * when the device got a node-ID (assigned, pool, replaced). */
void aa_record(lss_master *m, lss_aa_state *s, const lss_identity *id, enum lss_outcome_kind given);
/* The pass goes on after a step whose failure it dealt with: nothing of
 * that failure (status, codes, message) is left for the next step's outcome. */
void aa_result_reset(lss_master *m);
/* The misbehaving slave of an enumeration: the pass's error and its outcome. */
void aa_enumeration_failed(lss_aa_state *s, lss_master *m);
/* The outcome of a found device that gets no node-ID. */
void aa_leave_alone(lss_aa_state *s, const lss_device *d, enum lss_outcome_kind kind, enum lss_status st,
                    const char *why);
/* The map entries the second look asks for again (their count). */
size_t aa_second_look_entries(lss_aa_state *s);
/* reset_after_pass: the devices that hold their node-ID for their next
 * reset are reset and verified, or given their old node-ID back (a child
 * procedure, r_pc zeroed first; nothing to do without such devices). */
int aa_proc_reset_pending(lss_master *m, lss_aa_state *s);
/* Step 5: an outcome for each map entry the bus has not. */
void aa_report_missing(const lss_master *m, lss_aa_state *s);
