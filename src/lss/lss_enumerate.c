/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Enumeration: every non-configured slave by fastscan, nothing assigned.
 *
 * CiA 305 has a slave found by fastscan wait in configuration state, where
 * it takes no further part. The LSS slave of CANopenNode v4, the most used
 * open-source stack, answers every Fastscan request in configuration state:
 * a pass that relies on the rule finds the same slave, or a phantom
 * 0:0:0:0, forever. So each round
 *   1. fastscan finds identity F;
 *   2. F is confirmed: read back by Inquire Identity from the one slave in
 *      configuration (while a configured slave that took part is kept in
 *      configuration: all back to waiting and a selective switch to F);
 *   3. a non-configured slave is set aside: it gets a volatile pending
 *      node-ID T nobody answers to (SDO probe, a few candidates at once,
 *      each used within a few finds), goes back to waiting, takes
 *      T and stops answering Fastscan; a configured one stays in
 *      configuration (it should not have answered at all). A caller that
 *      assigns (s->direct: AutoAssign's pool) may give the slave its
 *      node-ID instead, stored and verified: configured, it takes no part
 *      either, and is no candidate of the give-back.
 * At the end, also on failure or cancel, every slave set aside gets 255
 * back and NMT Reset Communication on T, and every one is verified by
 * selective switch and Inquire Node-ID.
 * Bounds: rounds that find nobody new at most as many as the finds plus a
 * margin (rounds_exhausted), cfg.retries failed rounds in a row, a deadline; a slave found again after it was set aside, one that confirms
 * an identity other than the one found, or a phantom found twice ends the
 * pass with LSS_E_CONFLICT naming it (result.id). */
#include <errno.h>
#include <inttypes.h>
#include <string.h>

#include "lss/lss_internal.h"

#define SEND(m, pc, frame_expr) STEP_REQUEST(m, pc, frame_expr, -1)
#define ID_FMT "%08x:%08x:%08x:%08x"
#define ID_ARGS(id) (id).vendor, (id).product, (id).revision, (id).serial
/* what a device is given after NMT Reset Communication before it is asked */
#define RESET_SETTLE_US 50000u
/* a fastscan: 1 ping + 4 x (32 bits + a confirmation) */
#define FASTSCAN_STEPS 133u

uint64_t lss_enumerate_deadline_us(const lss_timing_config *c) {
        /* every step of every possible find waiting twice the full timeout */
        uint64_t round = (uint64_t) FASTSCAN_STEPS * 2u * ((uint64_t) c->timeout_us + c->guard_floor_us);
        return (LSS_ENUMERATE_MAX_FINDS + 1u) * round;
}

/* The shares of an enumeration's time, as measured on 16 slaves (lssd
 * --simulate and a VM): the finds 80 %, the looks for anybody left 10 %
 * (the last one patient), the give-back 10 %. */
#define PROGRESS_FINDS 0.8
#define PROGRESS_LOOKS 0.1

/* How far k finds are, 0..1: k of the finds expected; with nothing (more)
 * expected k / (k + 4), which slows down as finds go on but never stops or
 * nears the end before the pass is over (at 16 slaves 0.8 of the way:
 * the looks after the last find make up the rest). */
#define PROGRESS_UNKNOWN_FINDS 4.0
static double finds_done(const lss_master *m, size_t k) {
        if (m->expected_finds >= k && m->expected_finds > 0)
                return (double) k / m->expected_finds;
        return (double) k / ((double) k + PROGRESS_UNKNOWN_FINDS);
}

/* Slaves this pass found: candidates and those that took a node-ID at once. */
static size_t finds_of(const lss_scan_state *s) {
        return s->n_cand + s->n_direct;
}

static lss_device *found_before(lss_scan_state *s, const lss_identity *id) {
        for (size_t i = 0; i < s->n_cand; i++)
                if (lss_identity_equal(&s->cand[i].id, id))
                        return &s->cand[i];
        return NULL;
}

/* While the pass runs a candidate's node_id is 0 when it was set aside, else
 * the node-ID it answered with: it is kept in configuration (a configured
 * slave that took part, or one that refused a temporary node-ID) until the
 * give-back reads the real one. */
static bool kept(const lss_device *d) {
        return d->node_id != 0;
}

/* A slave set aside that answers with the temporary node-ID it was given:
 * it is one of the pass's own, given 255 back at the end, no configured
 * device. */
static bool at_its_temporary(const lss_device *d, uint8_t node) {
        return d->aside_node_id != 0 && node == d->aside_node_id;
}

static void add_nmt(lss_master *m, enum nmt_cs cs, uint8_t node) {
        lss_frame f;
        nmt_encode(&f, cs, node);
        step_add_tx(m, &f);
}

/* Inquire Identity of the slave in configuration, against s->found. When a
 * selective switch for F follows anyway (`serial_first`), it singles F out
 * by its whole identity: the serial, the field finds differ in, is asked
 * first, and the other fields only when it is not F's, to name the slave
 * that answered. */
int proc_confirm_found(lss_master *m, lss_scan_state *s, bool serial_first) {
        PT_BEGIN(&s->cpc);
        s->confirm = CONFIRM_OK;
        s->other = s->found;
        if (serial_first) {
                REQUEST_RETRIED(m, &s->cpc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_SERIAL),
                                LSS_CS_INQUIRE_VENDOR + LSS_FIELD_SERIAL);
                if (!step_answered(m) || step_conflict(m)) {
                        s->confirm = !step_answered(m) ? CONFIRM_NOBODY : CONFIRM_UNCLEAR;
                        goto out;
                }
                if (lss_get_u32(m->step.answer.data + 1) == s->found.serial)
                        goto out;
        }
        for (s->field = 0; s->field < LSS_FIELD_COUNT; s->field++) {
                REQUEST_RETRIED(m, &s->cpc, s->attempt, lss_encode_inquire(&f__, s->field),
                                LSS_CS_INQUIRE_VENDOR + (int) s->field);
                if (!step_answered(m) || step_conflict(m)) {
                        s->confirm = !step_answered(m) && s->field == 0 ? CONFIRM_NOBODY : CONFIRM_UNCLEAR;
                        break;
                }
                lss_identity_set_field(&s->other, s->field, lss_get_u32(m->step.answer.data + 1));
        }
        if (s->confirm == CONFIRM_OK && !lss_identity_equal(&s->other, &s->found))
                s->confirm = CONFIRM_OTHER;
out:;
        PT_END(&s->cpc);
}

/* With configured slaves kept in configuration an inquiry would have them
 * answer too: all back to waiting, and only F answers a selective switch. */
int proc_confirm_by_selection(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->cpc);
        s->selected = true;
        /* twice: a slave that loses it stays in configuration with F, with no
         * answer to tell, and would take F's temporary node-ID too */
        SEND(m, &s->cpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        SEND(m, &s->cpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        SELECT_RETRIED(m, &s->cpc, s->attempt, &s->found);
        s->confirm = !step_answered(m) ? CONFIRM_NOBODY : step_conflict(m) ? CONFIRM_UNCLEAR : CONFIRM_OK;
        PT_END(&s->cpc);
}

#define N_ADRIFT (sizeof(((lss_scan_state *) 0)->adrift) / sizeof(bool))

static bool is_adrift(const lss_scan_state *s, const lss_device *d) {
        size_t i = (size_t) (d - s->cand);
        return i < N_ADRIFT && s->adrift[i];
}

static void set_adrift(lss_scan_state *s, size_t i, bool adrift) {
        if (i < N_ADRIFT)
                s->adrift[i] = adrift;
}

/* The kept slaves back into configuration after a switch to waiting. One
 * whose selection stays unanswered (its frames lost) is adrift: in waiting
 * it takes part in Fastscan, and found again it is kept again (handle_found);
 * the give-back's verification reaches any other. */
static int reselect_kept(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->rpc);
        for (s->i = 0; s->i < s->n_cand; s->i++)
                if (kept(&s->cand[s->i]) && s->i != s->kept_now) {
                        SELECT_RETRIED(m, &s->rpc, s->attempt, &s->cand[s->i].id);
                        set_adrift(s, s->i, !step_answered(m));
                }
        PT_END(&s->rpc);
}

/* A configured slave that answers Fastscan in configuration: a device of
 * the result at once (it answered a selection and Inquire Node-ID), no
 * candidate: in waiting it takes no part in Fastscan, and kept in
 * configuration it would answer every request of the rounds after. */
static int let_go(lss_master *m, const lss_identity *id, uint8_t node) {
        if (master_add_device(m, id, node) < 0) {
                master_fail(m, LSS_E_INCOMPLETE, "out of memory");
                return -ENOMEM;
        }
        return 0;
}

/* One request only F could match, in configuration state: F's serial as
 * the field expected after it. */
static int ask_fastscan_in_configuration(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->qpc);
        lss_frame f;
        lss_encode_fastscan(&f, s->found.serial, 0, LSS_FIELD_SERIAL, LSS_FIELD_SERIAL);
        step_lss(m, LSS_CS_IDENTIFY_SLAVE);
        step_add_tx(m, &f);
        m->step.silence_answers = true;
        step_start(m);
        PT_YIELD(&s->qpc);
        PT_END(&s->qpc);
}

/* Does F, which the last confirmation put in configuration state, answer
 * Fastscan there? One request only F could match (its serial, with the
 * serial as the field expected: a slave in waiting is at that field only
 * if it matched F's vendor, product and revision, and then its serial is
 * another), asked again while silent: a CANopenNode slave answers any
 * Fastscan in configuration state, and a lost answer would keep it there
 * to answer every request that follows. s->bends. */
static int answers_in_configuration(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->kpc);
        s->bends = false;
        for (s->k = 0; s->k < m->timing.cfg.retries && s->k < 2 && !s->bends; s->k++) {
                PT_CALL(&s->kpc, ask_fastscan_in_configuration(m, s));
                s->bends = step_answered(m);
        }
        if (!s->bends)
                goto out;
        /* A stalled host's answers to the fastscan just done (a slave's
         * answers queue: they come in a burst) look the same: asked again
         * once they could all have come, it still answers. */
        m->step = (lss_step) { .kind = STEP_DELAY, .wait_us = lss_timing_patient_wait(&m->timing, 0) };
        step_start(m);
        PT_YIELD(&s->kpc);
        s->bends = false;
        for (s->k = 0; s->k < m->timing.cfg.retries && s->k < 2 && !s->bends; s->k++) {
                PT_CALL(&s->kpc, ask_fastscan_in_configuration(m, s));
                s->bends = step_answered(m);
        }
out:;
        PT_END(&s->kpc);
}

/* Identify Remote Slave of F's identity alone: the confirmation of a slave
 * that is kept in configuration beside others, who would all answer an
 * inquiry. An identify answer says nothing of which request it answers (a
 * late one of the step before looks the same): the give-back verifies every
 * candidate by selective switch at the end. */
static void step_identify_found(lss_master *m, const lss_scan_state *s) {
        const lss_identify_range r = { s->found.vendor, s->found.product, s->found.revision, s->found.revision,
                                       s->found.serial, s->found.serial };
        step_identify(m, &r);
        /* only F matches, and any answer is the same frame (cs 0x4F): no
         * other answer to wait for, as after a selective switch */
        m->step.ends_at_answer = true;
        step_start(m);
}

/* F stays in configuration state, where a CiA 305 slave takes no part in
 * Fastscan: nothing is configured into it (its node-ID is read at the end). */
static int keep_found(lss_scan_state *s, uint8_t node) {
        if (cand_add(s, &s->found) < 0)
                return -ENOMEM;
        if (lss_node_id_valid(node))
                s->held[node] = true;
        s->cand[s->n_cand - 1].node_id = node;
        s->kept_now = s->n_cand - 1;
        s->n_kept++;
        s->n_kept_bent += s->bends; /* a dry run keeps one that answered the check */
        return 0;
}

/* A volatile pending node-ID for the confirmed slave in configuration, from
 * the top of the range down, that nobody answers to; back to waiting, where
 * it takes that ID (CiA 305) and stops taking part. */
static int set_aside(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->apc);
        for (;;) {
                while (s->next_temp >= LSS_NODE_ID_MIN &&
                       ((s->avoid && s->avoid[s->next_temp]) || s->temp_taken[s->next_temp]))
                        s->next_temp--;
                if (s->next_temp < LSS_NODE_ID_MIN) {
                        master_fail(m, LSS_E_INCOMPLETE, "no free node-ID left to set slave " ID_FMT " aside",
                                    ID_ARGS(s->found));
                        goto out;
                }
                if (s->temp_free[s->next_temp])
                        break;
                /* the next few candidates from the top down, probed together */
                s->probe = (lss_probe_state) { .taken = s->temp_taken, .free = s->temp_free };
                for (int id = s->next_temp; id >= (int) LSS_NODE_ID_MIN && s->probe.n_ids < LSS_FEW_TX; id--)
                        if (!(s->avoid && s->avoid[id]) && !s->temp_taken[id])
                                s->probe.ids[s->probe.n_ids++] = (uint8_t) id;
                PT_CALL(&s->apc, proc_probe(m, &s->probe));
        }
        s->temp = s->next_temp--;
        s->temp_free[s->temp] = false;
        REQUEST_RETRIED(m, &s->apc, s->attempt, lss_encode_configure_node_id(&f__, s->temp),
                        LSS_CS_CONFIGURE_NODE_ID);
        AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->apc, s->attempt,
                                                     lss_encode_configure_node_id(&f__, s->temp),
                                                     LSS_CS_CONFIGURE_NODE_ID));
        if (cand_add(s, &s->found) < 0) {
                master_fail(m, LSS_E_INCOMPLETE, "out of memory");
                goto out;
        }
        if (!step_answered(m) || step_conflict(m)) {
                /* it may have taken T: given back with the others at the end */
                s->cand[s->n_cand - 1].node_id = 0;
                s->cand[s->n_cand - 1].aside_node_id = s->temp;
                s->back_due[s->temp] = true;
                s->n_aside++;
                master_fail(m, LSS_E_INCOMPLETE, "slave " ID_FMT " did not take a temporary node-ID (%s)",
                            ID_ARGS(s->found), !step_answered(m) ? "no answer" : "several answers");
                goto out;
        }
        if (m->step.answer.data[1] != 0) {
                /* refused (a device with a narrower node-ID range): it stays
                 * in configuration, where a CiA 305 slave takes no part */
                s->n_kept++;
                s->n_kept_bent++;
                goto out;
        }
        s->cand[s->n_cand - 1].node_id = 0;
        s->cand[s->n_cand - 1].aside_node_id = s->temp;
        s->back_due[s->temp] = true;
        s->n_aside++;
        SEND(m, &s->apc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        if (s->keep_stopped) {
                /* taking T reset it into pre-operational */
                SEND(m, &s->apc, nmt_encode(&f__, NMT_CS_STOP, s->temp));
        }
out:;
        PT_END(&s->apc);
}

/* A slave set aside that has not been seen back at 255 yet. */
static bool back_due(const lss_scan_state *s, const lss_device *d) {
        return d->aside_node_id && s->back_due[d->aside_node_id];
}

/* The give-back's share after the finds and looks: half for giving 255
 * back, half for the verification. */
static void progress_back(lss_master *m, const lss_scan_state *s, unsigned half) {
        double done = ((double) half + (double) (s->i + 1) / (double) s->n_cand) / 2.0;
        master_progress(m, PROGRESS_FINDS + PROGRESS_LOOKS + (1.0 - PROGRESS_FINDS - PROGRESS_LOOKS) * done);
}

/* 255 and a reset for every slave set aside (asked again for one still at
 * its temporary node-ID: a frame lost on the way costs a retry, not a
 * device left at a node-ID it was never given), then every one verified by
 * selective switch and Inquire Node-ID; the verified become result devices. */
static int give_back(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->vpc);
        for (s->i = 0; s->i < s->n_cand; s->i++)
                s->cand[s->i].node_id = 0; /* not verified */
        for (s->gb_try = 0;; s->gb_try++) {
                SEND(m, &s->vpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                for (s->i = 0; s->i < s->n_cand; s->i++) {
                        if (!back_due(s, &s->cand[s->i]))
                                continue;
                        SELECT_RETRIED(m, &s->vpc, s->attempt, &s->cand[s->i].id);
                        if (!step_answered(m))
                                continue; /* still reset below; the verification says the rest */
                        REQUEST_RETRIED(m, &s->vpc, s->attempt,
                                        lss_encode_configure_node_id(&f__, LSS_NODE_ID_UNCONFIGURED),
                                        LSS_CS_CONFIGURE_NODE_ID);
                        SEND(m, &s->vpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                        progress_back(m, s, 0);
                }
                /* the resets, a few frames a step (the transmit queue is short) */
                for (s->i = 0; s->n_aside > 0 && s->i < s->n_cand;) {
                        m->step = (lss_step) { .kind = STEP_DELAY };
                        for (; s->i < s->n_cand && m->step.n_tx < LSS_FEW_TX - 1; s->i++)
                                if (back_due(s, &s->cand[s->i]))
                                        add_nmt(m, NMT_CS_RESET_COMMUNICATION, s->cand[s->i].aside_node_id);
                        if (s->i == s->n_cand) {
                                /* devices that take LSS only when stopped were reset into pre-operational */
                                if (s->keep_stopped)
                                        add_nmt(m, NMT_CS_STOP, 0);
                                m->step.wait_us = RESET_SETTLE_US;
                        }
                        step_start(m);
                        PT_YIELD(&s->vpc);
                }
                s->stuck = 0;
                for (s->i = 0; s->i < s->n_cand; s->i++) {
                        if (s->gb_try > 0 && !back_due(s, &s->cand[s->i]))
                                continue;
                        SELECT_RETRIED(m, &s->vpc, s->attempt, &s->cand[s->i].id);
                        /* A slave confirmed in this pass: silence is a stall,
                         * likely (unverified, the whole pass is asked again).
                         * One whose answer was lost, or came unseen while the
                         * switch was asked again, is in configuration, deaf to
                         * it: the patient asks start from waiting (nobody else
                         * is in configuration here). */
                        if (!step_answered(m))
                                SEND(m, &s->vpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                        AGAIN_PATIENTLY_IF_SILENT(m, SELECT_RETRIED(m, &s->vpc, s->attempt, &s->cand[s->i].id));
                        if (!step_answered(m))
                                continue;
                        REQUEST_RETRIED(m, &s->vpc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                                        LSS_CS_INQUIRE_NODE_ID);
                        AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->vpc, s->attempt,
                                                                     lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                                                                     LSS_CS_INQUIRE_NODE_ID));
                        if (step_answered(m) && !step_conflict(m)) {
                                s->cand[s->i].node_id = m->step.answer.data[1];
                                if (s->cand[s->i].aside_node_id &&
                                    s->cand[s->i].node_id == LSS_NODE_ID_UNCONFIGURED)
                                        s->back_due[s->cand[s->i].aside_node_id] = false;
                        }
                        SEND(m, &s->vpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                        progress_back(m, s, 1);
                }
                for (s->i = 0; s->i < s->n_cand; s->i++)
                        s->stuck += back_due(s, &s->cand[s->i]);
                if (s->stuck == 0 || s->gb_try >= m->timing.cfg.retries)
                        break;
                m->stats.retries++;
        }
        /* A switch to waiting has no answer: one lost by the last slave
         * verified would leave it in configuration. Whoever answers an
         * inquiry (asked again while silent: a lost one costs a retry) is
         * still there and is switched again. */
        for (s->gb_try = 0; s->n_cand > 0; s->gb_try++) {
                REQUEST_RETRIED(m, &s->vpc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                                LSS_CS_INQUIRE_NODE_ID);
                if (!step_answered(m) || s->gb_try >= m->timing.cfg.retries)
                        break;
                m->stats.retries++;
                SEND(m, &s->vpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        }
        s->dropped = 0;
        for (s->i = 0; s->i < s->n_cand; s->i++) {
                const lss_device *d = &s->cand[s->i];
                if (d->node_id == 0)
                        s->dropped++;
                else if (master_add_device(m, &d->id, d->node_id) < 0)
                        master_fail(m, LSS_E_INCOMPLETE, "out of memory");
                else {
                        m->devices[m->n_devices - 1].aside_node_id = d->aside_node_id;
                        /* verified: announced, if it was not (once per identity) */
                        master_found(m, &d->id, d->node_id, d->aside_node_id);
                }
        }
        s->restore = false;
        PT_END(&s->vpc);
}

/* The confirmed non-configured slave F, alone in configuration (selected,
 * its node-ID just inquired), takes the node-ID s->direct gives it, stored
 * and verified as by an assignment: it takes no further part, as one set
 * aside. s->took: it did (or failed to after Configure Node-ID), its
 * outcome is the caller's; else it is still in configuration, untouched:
 * set it aside. */
static int assign_direct(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->dpc);
        s->took = false;
        for (;;) {
                s->dprobe = NULL;
                for (unsigned n = 0; n < 128; n++)
                        s->not_free[n] = s->back_due[n] || s->held[n];
                if (!s->direct->choose(m, s->direct->ud, &s->found, s->not_free, &s->dprobe)) {
                        if (!s->dprobe)
                                goto out;
                        PT_CALL(&s->dpc, proc_probe(m, s->dprobe));
                        continue;
                }
                m->as.old = s->node;
                m->as.old_known = true;
                m->as.lone = s->node_lone;
                m->as.pc = 0;
                PT_CALL(&s->dpc, proc_assign_selected(m, &m->as));
                if (!m->result.in_use)
                        break;
                s->direct->done(m, s->direct->ud); /* somebody answers at it: another one */
        }
        s->took = true;
        if (m->result.status != LSS_OK) {
                /* it may have taken the node-ID, or not: back to waiting, as any assignment that failed */
                SEND(m, &s->dpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        } else if (s->keep_stopped && m->result.changed) {
                /* its boot-up with the node-ID put it in pre-operational */
                SEND(m, &s->dpc, nmt_encode(&f__, NMT_CS_STOP, m->as.node_id));
        }
        s->direct->done(m, s->direct->ud);
        s->n_direct++;
out:;
        PT_END(&s->dpc);
}

/* A verdict that ends the pass on slaves that did not answer as CiA 305
 * says is given only when a round with patient waits shows it again: a
 * stalled host (answers 100-200 ms late, taken for those of later steps)
 * makes compliant slaves look like that. True: ask again, patiently. */
static bool recheck_first(lss_scan_state *s) {
        if (s->patient_round)
                return false;
        s->recheck = true;
        return true;
}

/* s->found is confirmed: its vendor, product and revision are the next
 * fastscan's guess. Fastscan finds the least identity first, so devices of
 * one revision come in a run; a field that changed from find to find twice
 * in a row is not guessed until two finds share it again: its guess would
 * be a silent confirmation every find, ~8 ms in the VM (1 s of a blind
 * Scan of 127 whose revisions differ). */
static void set_last_found(lss_scan_state *s) {
        for (unsigned f = 0; f < LSS_FIELD_COUNT - 1; f++) {
                bool same = lss_identity_field(&s->found, f) == lss_identity_field(&s->last_found, f);
                s->unlike[f] = same ? 0 : s->unlike[f] < UINT8_MAX ? s->unlike[f] + 1 : UINT8_MAX;
        }
        s->last_found = s->found;
}

/* The leading fields guessed: a guess is confirmed in order, the fields
 * after one nobody has are scanned. */
static unsigned fields_to_guess(const lss_scan_state *s) {
        unsigned n = 0;
        while (n < LSS_FIELD_COUNT - 1 && s->unlike[n] < 2)
                n++;
        return n;
}

static void misbehaving(lss_master *m, lss_scan_state *s, const lss_identity *id, const char *what) {
        m->result.id = *id;
        s->misbehaving = true;
        master_fail(m, LSS_E_CONFLICT, "slave " ID_FMT " %s: it does not follow CiA 305, the enumeration stopped",
                    ID_ARGS(*id), what);
}

/* One round after fastscan found s->found: confirm it, then keep it in
 * configuration or set it aside. Ends the pass (status) when a slave
 * misbehaves; s->confirm tells the caller how the round went. */
static int handle_found(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->hpc);
        s->cpc = 0;
        s->selected = s->took = s->switched = s->let_go = false;
        s->kept_now = SIZE_MAX;
        /* Only a slave that answers Fastscan in configuration state needs
         * setting aside with a node-ID; any other stays there, untouched */
        s->kpc = 0;
        PT_CALL(&s->hpc, answers_in_configuration(m, s));
        if (!s->bends && !s->direct && s->n_kept > 0 && !found_before(s, &s->found)) {
                /* the slaves kept would answer an inquiry too: F's own identify */
                STEP_RETRIED(m, &s->hpc, s->attempt, step_identify_found(m, s));
                /* An identify answer only to an ask again, or late, may be a
                 * late one of another step (it says nothing of which request
                 * it answers): F is then asked by selection, whose answer is
                 * F's alone, before it is announced */
                if (step_answered(m) && s->attempt == 0 && !m->step.late) {
                        if (keep_found(s, LSS_NODE_ID_UNCONFIGURED) < 0) {
                                master_fail(m, LSS_E_INCOMPLETE, "out of memory");
                                goto out;
                        }
                        s->confirm = CONFIRM_OK;
                        set_last_found(s);
                        /* it answered Fastscan: non-configured, as far as CiA 305 goes */
                        master_found(m, &s->found, LSS_NODE_ID_UNCONFIGURED, 0);
                        goto out;
                }
                /* a slave without identify services, or nobody: by selection */
        }
        if (s->n_kept == 0)
                PT_CALL(&s->hpc, proc_confirm_found(m, s, !s->no_set_aside && (s->bends || s->direct)));
        if (s->confirm == CONFIRM_OTHER) {
                /* Another identity answered. Two compliant slaves in
                 * configuration do that when one went there on a confirmation
                 * answered after its step ended and their answers interleave;
                 * so does a slave that enters configuration on a Fastscan for
                 * another identity. Answers were missed: wait longer, send
                 * everybody back to waiting and ask for F by selection (if
                 * nobody answers, F was made up). Only a slave that does it
                 * again is named. */
                if (s->n_other++ > 0 && lss_identity_equal(&s->other, &s->other_before)) {
                        if (recheck_first(s))
                                goto out;
                        misbehaving(m, s, &s->other, "entered configuration state on a Fastscan for another "
                                    "identity, twice");
                        goto out;
                }
                s->other_before = s->other;
                lss_timing_on_stray(&m->timing);
                s->confirm = CONFIRM_UNCLEAR;
        }
        if (s->n_kept > 0 || s->confirm == CONFIRM_UNCLEAR ||
            (s->confirm == CONFIRM_OK && !s->no_set_aside && (s->bends || s->direct))) {
                /* another slave in configuration too (one that went there
                 * early, or kept): the selective switch singles F out. Also
                 * before F may be set aside: a second slave in configuration
                 * whose answers to the inquiry came after their steps ended
                 * would take the temporary node-ID with F, and keep it. */
                s->cpc = 0;
                PT_CALL(&s->hpc, proc_confirm_by_selection(m, s));
                s->switched = true;
        }
        if (s->confirm == CONFIRM_OK) {
                REQUEST_RETRIED(m, &s->hpc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                                LSS_CS_INQUIRE_NODE_ID);
                if (step_answered(m) && !step_conflict(m)) {
                        s->node = m->step.answer.data[1];
                        s->node_lone = m->step.n_frames == 1 && !m->step.void_;
                } else {
                        s->confirm = CONFIRM_UNCLEAR;
                }
        }
        if (s->confirm == CONFIRM_OK && (s->again = found_before(s, &s->found)) != NULL &&
            at_its_temporary(s->again, s->node)) {
                /* Set aside, and at the node-ID it was given there: it took
                 * part no more, others' late answers made up its identity
                 * (it answers a selection in any state). It stays set aside. */
                s->confirm = CONFIRM_UNCLEAR;
        }
        if (s->confirm == CONFIRM_OK && s->again != NULL && kept(s->again) && is_adrift(s, s->again) && !s->bends) {
                /* Kept, but its reselection went unanswered: it was in
                 * waiting, took part as a compliant slave does there, and
                 * is in configuration again now, silent to Fastscan there
                 * (the check above). Kept again, no verdict: with frames
                 * lost at 3 %, 7 in 1000 blind Scans of 16 (loss-bench)
                 * named a compliant slave "answered Fastscan again in
                 * configuration state". */
                s->kept_now = (size_t) (s->again - s->cand);
                set_adrift(s, s->kept_now, false);
                s->again->node_id = s->node;
                goto reselect;
        }
        if (s->confirm == CONFIRM_OK && s->again != NULL) {
                /* Set aside, it still took part (a slave that answers
                 * Fastscan with a node-ID): keep it in configuration. Found
                 * there too, it answers in every state. */
                if (kept(s->again) || s->node == LSS_NODE_ID_UNCONFIGURED) {
                        if (recheck_first(s))
                                goto out;
                        misbehaving(m, s, &s->found, s->no_set_aside
                                    ? "answers Fastscan in configuration state (a dry run sets nobody aside "
                                      "with a temporary node-ID, which such a slave needs)"
                                    : kept(s->again) ? "answered Fastscan again in configuration state, where it "
                                                       "was silent to it before"
                                                     : "answered Fastscan again after it was set aside");
                        goto out;
                }
                s->again->node_id = s->node;
                s->kept_now = (size_t) (s->again - s->cand);
                s->n_kept++;
                s->n_kept_bent++;
                goto reselect;
        }
        if (s->confirm == CONFIRM_NOBODY) {
                /* nobody in configuration: the identity was made of answers
                 * to requests that matched nobody */
                if (s->phantoms++ > 0 && s->no_set_aside && s->n_kept > 0) {
                        if (recheck_first(s))
                                goto out;
                        /* slaves kept in configuration answered too: name a
                         * confirmed one, never the made-up identity */
                        m->result.id = s->cand[s->n_cand - 1].id;
                        s->misbehaving = true;
                        master_fail(m, LSS_E_CONFLICT, "slaves answer Fastscan in configuration state (like "
                                    "CANopenNode): a dry run sets nobody aside with a temporary node-ID, which "
                                    "such slaves need, so it stopped after %zu found", s->n_cand);
                        goto out;
                }
                if (s->phantoms > 1 && (lss_identity_equal(&s->found, &s->phantom) ||
                                        s->phantoms > m->timing.cfg.retries)) {
                        if (recheck_first(s))
                                goto out;
                        m->result.id = s->found;
                        s->misbehaving = true;
                        master_fail(m, LSS_E_CONFLICT,
                                    "Fastscan found " ID_FMT " %u times but no slave confirmed it: a slave answers "
                                    "Fastscan requests that do not match it, the enumeration stopped",
                                    ID_ARGS(s->found), s->phantoms);
                        goto out;
                }
                s->phantom = s->found;
        } else if (s->confirm == CONFIRM_UNCLEAR) {
                SEND(m, &s->hpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                s->switched = true;
        } else if (s->bends && s->node != LSS_NODE_ID_UNCONFIGURED) {
                /* configured, and it answers every Fastscan in configuration
                 * (CANopenNode; found on late answers of others): back to
                 * waiting, where it takes no part, a device found */
                s->let_go = true;
                if (let_go(m, &s->found, s->node) < 0)
                        goto out;
                SEND(m, &s->hpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                s->switched = true;
        } else if (s->node != LSS_NODE_ID_UNCONFIGURED || s->no_set_aside) {
                /* configured, yet it took part; or a dry run, which configures
                 * nothing, not even a temporary node-ID: leave it in configuration */
                if (keep_found(s, s->node) < 0) {
                        master_fail(m, LSS_E_INCOMPLETE, "out of memory");
                        goto out;
                }
        } else {
                if (s->direct) {
                        s->dpc = 0;
                        PT_CALL(&s->hpc, assign_direct(m, s));
                        s->switched = s->switched || s->took;
                }
                if (!s->took && !s->bends) {
                        if (keep_found(s, LSS_NODE_ID_UNCONFIGURED) < 0) {
                                master_fail(m, LSS_E_INCOMPLETE, "out of memory");
                                goto out;
                        }
                } else if (!s->took) {
                        s->apc = 0;
                        s->restore = true;
                        PT_CALL(&s->hpc, set_aside(m, s));
                        s->switched = true;
                        if (m->result.status != LSS_OK)
                                goto out;
                }
        }
        if (s->confirm == CONFIRM_OK) {
                set_last_found(s);
                /* confirmed by its own answers and now a candidate: tell the
                 * caller at once (a slave set aside gets 255 back at the end) */
                master_found(m, &s->found, s->node,
                             s->took || s->let_go ? 0 : s->cand[s->n_cand - 1].aside_node_id);
                s->switched = s->switched || s->took;
        }
reselect:
        /* Kept ones were let go by a switch to waiting in this round: the
         * selection, an unclear round, or setting a slave aside or giving it
         * its node-ID (the one kept this round is in configuration). */
        if (s->n_kept > 0 && s->switched) {
                s->rpc = 0;
                PT_CALL(&s->hpc, reselect_kept(m, s));
        }
out:
        s->kept_now = SIZE_MAX; /* a later switch to waiting lets this one go too */
        PT_END(&s->hpc);
}

/* A round finds one slave or nobody new (a stall, a lost frame, an unclear
 * confirmation: a retry). A full bus on a host that stalls now and then
 * loses more rounds than a fixed margin over 127 finds, so the bound is on
 * the rounds that found nobody: no more of them than finds, plus a margin
 * (cfg.retries failed in a row end the pass earlier); and twice the finds a
 * bus can hold in all. */
static bool rounds_exhausted(const lss_master *m, const lss_scan_state *s) {
        unsigned margin = 2u * (m->timing.cfg.retries + 1u);
        unsigned finds = (unsigned) finds_of(s);
        return s->rounds - finds >= finds + margin || s->rounds >= 2u * LSS_ENUMERATE_MAX_FINDS + margin;
}

/* Each slave kept in configuration, alone there, asked patiently whether
 * it answers Fastscan in configuration state: one that does is set aside
 * now (non-configured) or let go. The kept are all back in waiting after it. */
static int reexamine_kept(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->xpc);
        for (s->x = 0; s->x < s->n_cand; s->x++) {
                if (!kept(&s->cand[s->x]))
                        continue;
                SEND(m, &s->xpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                SELECT_RETRIED(m, &s->xpc, s->attempt, &s->cand[s->x].id);
                if (!step_answered(m) || step_conflict(m))
                        continue;
                s->found = s->cand[s->x].id;
                s->kpc = 0;
                PT_CALL(&s->xpc, answers_in_configuration(m, s));
                if (!s->bends)
                        continue;
                /* Kept beside others, it was confirmed by identify, and its
                 * node-ID taken for 255 (it answered Fastscan): one that
                 * answers it in configuration may be a configured CANopenNode
                 * slave, whose node-ID a temporary one would replace. Alone
                 * in configuration now: asked. */
                REQUEST_RETRIED(m, &s->xpc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                                LSS_CS_INQUIRE_NODE_ID);
                if (!step_answered(m) || step_conflict(m)) {
                        s->n_kept_bent++; /* still kept: the verdicts decide */
                        continue;
                }
                s->node = m->step.answer.data[1];
                if (at_its_temporary(&s->cand[s->x], s->node)) {
                        /* set aside before, at its temporary node-ID: set aside again */
                        s->cand[s->x].node_id = 0;
                        s->n_kept--;
                        continue;
                }
                /* no longer kept: set aside as a new candidate, or let go (configured) */
                for (size_t i = s->x; i + 1 < s->n_cand; i++) {
                        s->cand[i] = s->cand[i + 1];
                        set_adrift(s, i, is_adrift(s, &s->cand[i + 1]));
                }
                s->n_cand--;
                s->n_kept--;
                s->x--;
                if (s->node != LSS_NODE_ID_UNCONFIGURED) {
                        if (let_go(m, &s->found, s->node) < 0)
                                goto out;
                        continue;
                }
                s->apc = 0;
                s->restore = true;
                PT_CALL(&s->xpc, set_aside(m, s));
                if (m->result.status != LSS_OK)
                        goto out;
        }
        SEND(m, &s->xpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
out:;
        PT_END(&s->xpc);
}

/* The round after one that ended on a verdict (recheck_first()): every
 * slave back to waiting (the kept ones selected again), and waits as long
 * as for a device that fell silent. */
static int begin_patient_round(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->bpc);
        s->recheck = false;
        s->patient_round = true;
        /* the patient rounds get the margins again, and show a verdict anew */
        s->rounds = (unsigned) finds_of(s);
        s->failed_scans = s->phantoms = s->n_other = 0;
        m->stats.rechecks++;
        master_patient_begin(m, lss_timing_patient_wait(&m->timing, LSS_VERDICT_WAIT_FLOOR_US));
        SEND(m, &s->bpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        s->rpc = 0;
        PT_CALL(&s->bpc, reselect_kept(m, s));
        if (s->n_kept == 0 || s->no_set_aside)
                goto out;
        /* A kept one may answer every request: its answers to the set-aside
         * check were held back. One Fastscan request for a kept slave's
         * serial, with all kept in configuration, is answered by such a
         * slave alone (the kept CiA 305 slaves take no part; one in waiting
         * at that field would have that slave's identity): asked patiently,
         * it clears them all; answered, each is asked alone. */
        for (s->x = 0; !kept(&s->cand[s->x]); s->x++)
                ;
        s->found = s->cand[s->x].id;
        s->kpc = 0;
        PT_CALL(&s->bpc, answers_in_configuration(m, s));
        if (!s->bends)
                goto out;
        s->xpc = 0;
        PT_CALL(&s->bpc, reexamine_kept(m, s));
        if (m->result.status != LSS_OK)
                goto out;
        s->rpc = 0;
        PT_CALL(&s->bpc, reselect_kept(m, s));
out:;
        PT_END(&s->bpc);
}

/* Answers came later than the timeout allows on this bus, once at least:
 * its host or the bus stalls now and then. (Answers a little after the
 * adaptive waits, which a VM sees in every pass, are no stall.) */
static bool stalls_seen(const lss_master *m) {
        return m->timing.stalled;
}

/* A Scan about to say the bus is empty: a verdict nothing checks later. */
static bool empty_scan(const lss_scan_state *s) {
        return s->listen && finds_of(s) == 0 && !s->pinged;
}

/* The looks for anybody left after a silent ping: one on a bus where
 * nobody answered yet (an empty bus costs), two patient ones for a Scan's
 * "nobody here" (as every verdict: a host stalled past one patient wait
 * made it say "OK, 0 devices" on a bus of 8), else cfg.retries more; more
 * when the operation lost frames, so that a slave whose ping or answer is
 * lost each time is improbable (lss_loss.h). */
static unsigned last_look(const lss_master *m, const lss_scan_state *s) {
        unsigned base = finds_of(s) > 0 || s->pinged ? m->timing.cfg.retries + 1u : empty_scan(s) ? 2u : 1u;
        unsigned all = lss_loss_asks(&m->loss, 1, base), pings = lss_loss_asks(&s->ping_loss, 1, base);
        return (all > pings ? all : pings) - 1u;
}

int proc_enumerate(lss_master *m, lss_scan_state *s) {
        PT_BEGIN(&s->pc);
        s->deadline = m->now + lss_enumerate_deadline_us(&m->timing.cfg);
        s->misbehaving = s->nobody = s->pinged = false;
        s->ping_loss = (lss_loss) { 0 };
        for (s->pass = 0; s->pass <= m->timing.cfg.retries; s->pass++) {
                s->n_cand = s->n_direct = s->n_aside = s->n_kept = s->n_kept_bent = 0;
                s->rounds = s->phantoms = s->failed_scans = s->n_other = s->looks = 0;
                memset(s->unlike, 0, sizeof(s->unlike));
                memset(s->adrift, 0, sizeof(s->adrift));
                s->recheck = s->patient_round = false;
                s->next_temp = LSS_NODE_ID_MAX;
                s->hint = (lss_fastscan_known) { 0 };
                s->floored = false;
                memset(s->back_due, 0, sizeof(s->back_due));
                memset(s->held, 0, sizeof(s->held));
                memset(s->temp_taken, 0, sizeof(s->temp_taken));
                memset(s->temp_free, 0, sizeof(s->temp_free));
                s->prog_base0 = m->prog_base;
                s->prog_span0 = m->prog_span;
                m->n_devices = 0;
                /* nobody left in configuration from before */
                SEND(m, &s->pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                while (!m->cancelling) {
                        if (rounds_exhausted(m, s) && recheck_first(s)) {
                                s->bpc = 0;
                                PT_CALL(&s->pc, begin_patient_round(m, s));
                                if (m->result.status != LSS_OK)
                                        break;
                        }
                        if (rounds_exhausted(m, s)) {
                                master_fail(m, LSS_E_INCOMPLETE, "the enumeration stopped: %u of its %u fastscan "
                                            "rounds found nobody new (%zu slaves found)",
                                            s->rounds - (unsigned) finds_of(s), s->rounds, finds_of(s));
                                break;
                        }
                        s->rounds++;
                        if (m->now >= s->deadline) {
                                master_fail(m, LSS_E_INCOMPLETE, "the enumeration stopped at its deadline of %" PRIu64
                                            " s (%zu slaves found)", lss_enumerate_deadline_us(&m->timing.cfg) / 1000000u,
                                            finds_of(s));
                                break;
                        }
                        /* A look again after a silent ping is for a slave that
                         * lost it, or one that sat in configuration uncounted:
                         * not slow ones, whose answers the first look, waiting
                         * the timeout, took in (or made the waits patient). */
                        /* A slave kept in configuration that answered Fastscan
                         * there answers every request: no step of the fastscan
                         * ends at its answer. The others were asked and were
                         * silent; one whose answers to that were lost or
                         * stalled shows as a second frame or a stray answer,
                         * which turn that off too (lss_fastscan.c, judge_lone). */
                        s->fs = (lss_fastscan_state) { .known = s->known, .hint = s->hint,
                                                       .floored = s->floored && s->n_kept_bent == 0,
                                                       .others_answer = s->n_kept_bent > 0,
                                                       .ping_again = s->looks > 0 };
                        /* A Scan that finds nobody says the bus is empty, and
                         * nothing checks that later: its ping may be answered by
                         * slaves slower than the timeout, after the step. */
                        if (s->listen && finds_of(s) == 0)
                                s->fs.ping_late_us = lss_timing_listen_guard(&m->timing);
                        /* The last look ends the pass when silent: an answer a
                         * stalled host holds back must still reach it (a slave's
                         * answers queue, so it holds back all of them), where
                         * nothing looks again for what it misses or this bus has
                         * stalled before. Each look of an empty Scan is a last one. */
                        if ((s->looks >= last_look(m, s) || empty_scan(s)) && (s->patient_end || stalls_seen(m)))
                                s->fs.ping_late_us = lss_timing_patient_wait(&m->timing, LSS_VERDICT_WAIT_FLOOR_US);
                        if (finds_of(s) > 0) {
                                /* vendor, product and revision of the last find: likely those of the next */
                                s->fs.guess = s->last_found;
                                s->fs.n_guess = fields_to_guess(s);
                        }
                        /* this find's share of the finds' */
                        m->prog_base = s->prog_base0 + s->prog_span0 * PROGRESS_FINDS * finds_done(m, finds_of(s));
                        m->prog_span = s->prog_span0 * PROGRESS_FINDS * (finds_done(m, finds_of(s) + 1) -
                                                                         finds_done(m, finds_of(s)));
                        PT_CALL(&s->pc, proc_fastscan(m, &s->fs));
                        m->prog_base = s->prog_base0;
                        m->prog_span = s->prog_span0;
                        if (m->cancelling)
                                break;
                        s->pinged = s->pinged || s->fs.heard;
                        /* a floor holds from one find to the next: anything else
                         * (a look, a fastscan that found nobody, a find not
                         * confirmed, a patient round) may bring a slave below it */
                        s->floored = false;
                        if (s->fs.none) {
                                /* a ping answered, a later one silent: a slave went
                                 * into configuration on an answer that came late,
                                 * uncounted; the looks for nobody begin again */
                                if (s->fs.heard && s->fs.silent) {
                                        s->looks = 0;
                                        /* with no confirmation of the last field out, no
                                         * slave went into configuration: a ping was lost */
                                        if (!s->fs.sent_last)
                                                lss_loss_answered(&s->ping_loss, 1, 1);
                                }
                                /* A silent look is no round that found nobody new:
                                 * the looks have their own bound, last_look(), which
                                 * frame loss raises beyond the rounds' margin */
                                if (s->fs.silent && !s->fs.heard)
                                        s->rounds--;
                                /* (a pass that found nobody, e.g. the map's devices
                                 * all handled, asks once, as an empty bus costs;
                                 * not when a ping was answered: a slave is there) */
                                if (s->looks++ >= last_look(m, s)) {
                                        /* set nobody aside: nobody gets 255 back */
                                        s->nobody = s->n_cand == 0 && s->fs.silent;
                                        break;
                                }
                                /* likely all found: the looks' share, look by look */
                                master_progress(m, PROGRESS_FINDS + PROGRESS_LOOKS * (double) s->looks /
                                                                    (double) (last_look(m, s) + 1));
                                /* Silence may be a slave that lost the ping (a frame lost
                                 * costs a retry, not a slave) or one whose fastscan
                                 * confirmation was answered after its step ended, now in
                                 * configuration, uncounted, taking no part: back to
                                 * waiting, and ping again. The switch has no answer:
                                 * twice (a slave that loses it stays in configuration).
                                 * It lets the kept slaves go, each selected back after
                                 * it (0.75 s for 126 at 125 kbit/s): so only the first
                                 * look of a run switches, as nobody goes into
                                 * configuration while the pings are silent, and every
                                 * look once the operation lost frames. */
                                if (s->looks == 1 || m->loss.lost > 0) {
                                        SEND(m, &s->pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                                        SEND(m, &s->pc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                                        s->rpc = 0;
                                        PT_CALL(&s->pc, reselect_kept(m, s));
                                }
                                continue;
                        }
                        if (s->looks > 0) { /* a silent ping was wrong: lost, or somebody uncounted */
                                lss_loss_answered(&m->loss, s->looks, 1);
                                lss_loss_answered(&s->ping_loss, s->looks, 1);
                        } else {
                                lss_loss_answered(&s->ping_loss, 0, 1);
                        }
                        s->looks = 0;
                        if (!s->fs.found) {
                                /* somebody answered the ping and was not found:
                                 * frames of it were lost (or came late), so the
                                 * looks for anybody left ask more often */
                                lss_loss_answered(&m->loss, 1, 1);
                                if (++s->failed_scans <= m->timing.cfg.retries)
                                        continue;
                                if (recheck_first(s)) {
                                        s->bpc = 0;
                                        PT_CALL(&s->pc, begin_patient_round(m, s));
                                        if (m->result.status != LSS_OK)
                                                break;
                                        continue;
                                }
                                master_fail(m, LSS_E_INCOMPLETE, "fastscan did not converge after %zu slaves",
                                            finds_of(s));
                                break;
                        }
                        for (unsigned i = 0; i < LSS_FIELD_COUNT; i++)
                                lss_identity_set_field(&s->found, i, s->fs.value[i]);
                        /* those that answered beside it are searched for below their shared bits */
                        s->hint.value = s->found;
                        memcpy(s->hint.known_bits, s->fs.crowd_bits, sizeof(s->hint.known_bits));
                        s->hpc = 0;
                        PT_CALL(&s->pc, handle_found(m, s));
                        if (m->result.status != LSS_OK)
                                break;
                        s->floored = s->confirm == CONFIRM_OK && !s->recheck;
                        if (s->confirm == CONFIRM_UNCLEAR && s->failed_scans + 1 > m->timing.cfg.retries)
                                recheck_first(s);
                        if (s->recheck) {
                                s->bpc = 0;
                                PT_CALL(&s->pc, begin_patient_round(m, s));
                                if (m->result.status != LSS_OK)
                                        break;
                                continue;
                        }
                        if (s->confirm == CONFIRM_OK && s->patient_round) {
                                /* shown right after all: back to the waits of the bus */
                                master_patient_end(m);
                                s->patient_round = false;
                        }
                        if (s->confirm == CONFIRM_UNCLEAR && ++s->failed_scans > m->timing.cfg.retries) {
                                master_fail(m, LSS_E_CONFLICT, "the slave found by fastscan (" ID_FMT ") could not "
                                            "be confirmed: several slaves answered", ID_ARGS(s->found));
                                break;
                        }
                        if (s->confirm == CONFIRM_OK)
                                s->failed_scans = 0;
                }
                if (s->patient_round) {
                        master_patient_end(m);
                        s->patient_round = false;
                }
                /* also after a failure or a cancel: nobody keeps a temporary node-ID */
                s->vpc = 0;
                PT_CALL(&s->pc, give_back(m, s));
                if (m->cancelling) {
                        master_fail(m, LSS_E_CANCELLED, "cancelled (the slaves set aside were given node-ID 255 "
                                    "back first)");
                        goto out;
                }
                if (m->result.status != LSS_OK)
                        goto out;
                if (s->stuck > 0) {
                        for (s->i = 0; !back_due(s, &s->cand[s->i]); s->i++)
                                ;
                        m->result.id = s->cand[s->i].id;
                        master_fail(m, LSS_E_INCOMPLETE, "%u slaves kept the temporary node-ID they were set aside "
                                    "with, " ID_FMT " node-ID %u first (reset them or power them off and on)",
                                    s->stuck, ID_ARGS(s->cand[s->i].id), s->cand[s->i].aside_node_id);
                        goto out;
                }
                if (s->dropped == 0)
                        goto out;
                m->stats.retries++;
        }
        master_fail(m, LSS_E_INCOMPLETE, "%u slaves found by fastscan could not be verified", s->dropped);
out:;
        PT_END(&s->pc);
}

/* lss_master_give_back(): what an enumeration broken off by another master
 * did not give back, as at its end. */
static int proc_give_back_top(lss_master *m) {
        lss_scan_state *s = &m->sc;
        PT_BEGIN(&m->pc);
        s->vpc = 0;
        PT_CALL(&m->pc, give_back(m, s));
        if (m->result.status == LSS_OK && s->stuck > 0) {
                for (s->i = 0; !back_due(s, &s->cand[s->i]); s->i++)
                        ;
                m->result.id = s->cand[s->i].id;
                master_fail(m, LSS_E_INCOMPLETE, "%u slaves kept the temporary node-ID they were set aside "
                            "with, " ID_FMT " node-ID %u first (reset them or power them off and on)",
                            s->stuck, ID_ARGS(s->cand[s->i].id), s->cand[s->i].aside_node_id);
        }
        PT_END(&m->pc);
}

int lss_master_give_back(lss_master *m, const lss_device *d, size_t n, uint64_t now) {
        lss_scan_state *s = &m->sc;
        if (n > 0 && !d)
                return -EINVAL;
        for (size_t i = 0; i < n; i++)
                if (!lss_node_id_valid(d[i].aside_node_id))
                        return -EINVAL;
        if (m->running)
                return -EBUSY;
        s->n_cand = s->n_aside = s->n_kept = 0;
        s->keep_stopped = false;
        memset(s->back_due, 0, sizeof(s->back_due));
        for (size_t i = 0; i < n; i++) {
                if (cand_add(s, &d[i].id) < 0)
                        return -ENOMEM;
                s->cand[s->n_cand - 1].aside_node_id = d[i].aside_node_id;
                s->back_due[d[i].aside_node_id] = true;
                s->n_aside++;
        }
        int r = master_start_procedure(m, proc_give_back_top, now);
        /* start_op cleared it: a cancel waits for the give-back, as an enumeration's */
        if (r >= 0 && m->running)
                s->restore = true;
        return r;
}
