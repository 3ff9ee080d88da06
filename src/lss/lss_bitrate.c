/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Changing the bit rate of the whole network. Activate Bit Timing is
 * unconfirmed and irreversible: a device that takes the new rate while
 * another does not splits the bus. So nothing is activated until every
 * device was reached and accepted the new timing; a refusal (or silence,
 * which is never taken for a yes) configures the devices that had accepted
 * back to the old rate, so that a later Store Configuration cannot persist a
 * rate nobody activated. After the activation the master stays silent for
 * the whole window (2 x delay), asking its caller to retune the host
 * interface inside the first delay period, then checks every device at the
 * new rate. The global procedure (all devices at once) is
 * lss_bitrate_global.c. */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "lss/lss_internal.h"

#define SEND(m, pc, frame_expr) STEP_REQUEST(m, pc, frame_expr, -1)

/* The caller has this long to answer a retune request before the engine
 * gives up waiting (and verifies anyway: the devices have switched). */
#define RETUNE_WAIT_MAX_US (5u * 1000000u)

const char *lss_bitrate_outcome_name(enum lss_bitrate_outcome o) {
        static const char *const names[] = {
                [LSS_BITRATE_PENDING] = "not-tried",
                [LSS_BITRATE_REACHED] = "reached",
                [LSS_BITRATE_UNREACHABLE] = "unreachable",
                [LSS_BITRATE_REFUSED] = "refused",
                [LSS_BITRATE_SILENT] = "silent",
                [LSS_BITRATE_CONFIGURED] = "configured",
                [LSS_BITRATE_REVERTED] = "reverted",
                [LSS_BITRATE_SWITCHED] = "switched",
                [LSS_BITRATE_STORED] = "stored",
                [LSS_BITRATE_STORE_FAILED] = "store-failed",
                [LSS_BITRATE_LOST] = "lost",
        };
        return (unsigned) o < sizeof(names) / sizeof(names[0]) && names[o] ? names[o] : "unknown";
}

const char *lss_retune_name(enum lss_retune r) {
        static const char *const names[] = {
                [LSS_RETUNE_NONE] = "none",
                [LSS_RETUNE_WANTED] = "wanted",
                [LSS_RETUNE_DONE] = "done",
                [LSS_RETUNE_SKIPPED] = "skipped",
                [LSS_RETUNE_FAILED] = "failed",
                [LSS_RETUNE_TIMEOUT] = "timeout",
        };
        return (unsigned) r < sizeof(names) / sizeof(names[0]) && names[r] ? names[r] : "unknown";
}

/* "vvvvvvvv:pppppppp:rrrrrrrr:ssssssss, ..." of the devices with this outcome,
 * cut short (with "...") when the message has no room. */
static void list_devices(const lss_bitrate_state *s, enum lss_bitrate_outcome o, char *buf, size_t size) {
        size_t n = 0;
        buf[0] = 0;
        for (size_t i = 0; i < s->p.n_devices; i++) {
                const lss_bitrate_device *d = &s->p.devices[i];
                if (d->outcome != o)
                        continue;
                if (n + 40 >= size) {
                        snprintf(buf + n, size - n, "%s...", n ? ", " : "");
                        return;
                }
                n += (size_t) snprintf(buf + n, size - n, "%s%08x:%08x:%08x:%08x", n ? ", " : "", d->id.vendor,
                                       d->id.product, d->id.revision, d->id.serial);
        }
}

static size_t count(const lss_bitrate_state *s, enum lss_bitrate_outcome o) {
        size_t n = 0;
        for (size_t i = 0; i < s->p.n_devices; i++)
                n += s->p.devices[i].outcome == o;
        return n;
}

static void progress(lss_master *m, lss_bitrate_state *s, unsigned phase) {
        /* phases 0..2 (reach, configure, verify), each over the devices */
        double n = s->p.n_devices ? (double) s->p.n_devices : 1.0;
        master_progress(m, ((double) phase + (double) s->i / n) / 3.0);
}

/* 1. every device is there, before anything is changed */
static int reach_all(lss_master *m, lss_bitrate_state *s) {
        char ids[300];

        PT_BEGIN(&s->cpc);
        for (s->i = 0; s->i < s->p.n_devices; s->i++) {
                progress(m, s, 0);
                /* every silence before the activation ends the change: a
                 * verdict, asked again patiently first (a stalled host) */
                SELECT_RETRIED(m, &s->cpc, s->attempt, &s->p.devices[s->i].id);
                AGAIN_PATIENTLY_IF_SILENT(m, SELECT_RETRIED(m, &s->cpc, s->attempt, &s->p.devices[s->i].id));
                s->p.devices[s->i].outcome = step_answered(m) ? LSS_BITRATE_REACHED : LSS_BITRATE_UNREACHABLE;
                s->n_bad += !step_answered(m);
                SEND(m, &s->cpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        }
        if (s->n_bad > 0) {
                list_devices(s, LSS_BITRATE_UNREACHABLE, ids, sizeof(ids));
                master_fail_at(m, LSS_E_NOT_FOUND, LSS_SERVICE_SWITCH_SELECTIVE, LSS_REASON_NO_ANSWER,
                               "%zu device%s did not answer at %u bit/s, nothing changed: %s", s->n_bad,
                               s->n_bad == 1 ? "" : "s", s->p.old_bitrate, ids);
        }
        PT_END(&s->cpc);
}

/* 2. one by one: the new timing, stop at the first refusal */
static int configure_each(lss_master *m, lss_bitrate_state *s) {
        PT_BEGIN(&s->cpc);
        for (s->i = 0; s->i < s->p.n_devices; s->i++) {
                lss_bitrate_device *d = &s->p.devices[s->i];
                progress(m, s, 1);
                SELECT_RETRIED(m, &s->cpc, s->attempt, &s->p.devices[s->i].id);
                AGAIN_PATIENTLY_IF_SILENT(m, SELECT_RETRIED(m, &s->cpc, s->attempt, &s->p.devices[s->i].id));
                d = &s->p.devices[s->i];
                if (!step_answered(m)) {
                        d->outcome = LSS_BITRATE_UNREACHABLE;
                        master_fail_at(m, LSS_E_NOT_FOUND, LSS_SERVICE_SWITCH_SELECTIVE, LSS_REASON_NO_ANSWER,
                                       "device %08x:%08x:%08x:%08x stopped answering", d->id.vendor, d->id.product,
                                       d->id.revision, d->id.serial);
                        goto out;
                }
                s->configuring = true;
                REQUEST_RETRIED(m, &s->cpc, s->attempt, lss_encode_configure_bit_timing(&f__, 0, s->index),
                                LSS_CS_CONFIGURE_BIT_TIMING);
                AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->cpc, s->attempt,
                                                             lss_encode_configure_bit_timing(&f__, 0, s->index),
                                                             LSS_CS_CONFIGURE_BIT_TIMING));
                s->configuring = false;
                d = &s->p.devices[s->i];
                if (!step_answered(m) || step_conflict(m))
                        s->unsure = s->i + 1; /* its answer lost, or a second slave's */
                if (!step_answered(m)) {
                        d->outcome = LSS_BITRATE_SILENT;
                        master_fail_at(m, LSS_E_REJECTED, LSS_SERVICE_CONFIGURE_BIT_TIMING, LSS_REASON_NO_ANSWER,
                                       "device %08x:%08x:%08x:%08x did not answer Configure Bit Timing (table 0, "
                                       "index %u): taken as a refusal, nothing activated", d->id.vendor,
                                       d->id.product, d->id.revision, d->id.serial, s->index);
                        goto out;
                }
                if (step_conflict(m)) {
                        master_fail_at(m, LSS_E_CONFLICT, LSS_SERVICE_CONFIGURE_BIT_TIMING,
                                       LSS_REASON_SEVERAL_ANSWERS,
                                       "more than one slave answered Configure Bit Timing (duplicate identity?)");
                        goto out;
                }
                d->err = m->step.answer.data[1];
                d->spec = m->step.answer.data[2];
                if (d->err != 0) {
                        d->outcome = LSS_BITRATE_REFUSED;
                        m->result.err = d->err;
                        m->result.spec = d->spec;
                        master_fail_at(m, LSS_E_REJECTED, LSS_SERVICE_CONFIGURE_BIT_TIMING, LSS_REASON_REFUSED,
                                       "device %08x:%08x:%08x:%08x refused %u bit/s (table 0, index %u): error %u, "
                                       "spec %u; nothing activated", d->id.vendor, d->id.product, d->id.revision,
                                       d->id.serial, s->p.bitrate, s->index, m->result.err, m->result.spec);
                        goto out;
                }
                d->outcome = LSS_BITRATE_CONFIGURED;
                SEND(m, &s->cpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        }
out:;
        PT_END(&s->cpc);
}

/* 3. everybody at once; from here on the change cannot be taken back */
static int activate(lss_master *m, lss_bitrate_state *s) {
        PT_BEGIN(&s->cpc);
        s->committed = true;
        m->step = (lss_step) { .kind = STEP_DELAY };
        {
                lss_frame f;
                lss_encode_switch_global(&f, LSS_MODE_CONFIGURATION);
                step_add_tx(m, &f);
                lss_encode_activate_bit_timing(&f, s->p.delay_ms);
                step_add_tx(m, &f);
        }
        /* a quarter of the first delay period: the activation is surely out
         * of the controller before the host interface is taken down */
        m->step.wait_us = (uint32_t) s->p.delay_ms * 250u;
        step_start(m);
        PT_YIELD(&s->cpc);
        /* sent_at was moved to the real write by on_sent */
        s->heard_at = m->step.sent_at + m->step.tx_us;
        if (m->timing.cfg.bitrate != 0)
                m->timing.cfg.bitrate = s->p.bitrate; /* frame times at the new rate */

        s->retune = LSS_RETUNE_WANTED;
        m->step = (lss_step) { .kind = STEP_DELAY, .wait_us = RETUNE_WAIT_MAX_US };
        step_start(m);
        if (m->retune_fn)
                m->retune_fn(m->retune_ud);
        PT_YIELD(&s->cpc);
        if (s->retune == LSS_RETUNE_WANTED)
                s->retune = LSS_RETUNE_TIMEOUT;

        /* silent until the slaves' second delay period is over, plus a
         * margin: the activation may have gone on the wire later than the
         * write (tx queue, scheduling), and a frame inside a slave's window
         * is lost to it */
        {
                uint64_t end = s->heard_at + 2u * (uint64_t) s->p.delay_ms * 1000u +
                               lss_timing_answer_guard(&m->timing) + (uint64_t) s->p.delay_ms * 250u;
                if (end > m->now) {
                        m->step = (lss_step) { .kind = STEP_DELAY, .wait_us = (uint32_t) (end - m->now) };
                        step_start(m);
                        PT_YIELD(&s->cpc);
                }
        }
        s->committed = false;
        PT_END(&s->cpc);
}

/* 4. each device at the new rate (and stored, when asked) */
static int verify_each(lss_master *m, lss_bitrate_state *s) {
        char ids[300];

        PT_BEGIN(&s->cpc);
        SEND(m, &s->cpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        s->n_bad = 0;
        for (s->i = 0; s->i < s->p.n_devices; s->i++) {
                progress(m, s, 2);
                if (s->p.devices[s->i].no_select) {
                        /* no selective switch: its SDO server answers at the new rate */
                        STEP_RETRIED(m, &s->cpc, s->attempt, step_node_in_use(m, s->p.devices[s->i].node_id));
                        AGAIN_PATIENTLY_IF_SILENT(m, STEP_RETRIED(m, &s->cpc, s->attempt,
                                                                  step_node_in_use(m, s->p.devices[s->i].node_id)));
                        s->p.devices[s->i].outcome = step_answered(m) ? LSS_BITRATE_SWITCHED : LSS_BITRATE_LOST;
                        s->n_bad += !step_answered(m);
                        continue;
                }
                /* "Silent at the new rate" is a verdict: a host stalled
                 * right after the switch holds answers back far beyond the
                 * waits (the VM, loaded: 38 ms), so silence is asked again
                 * patiently first. */
                for (s->attempt_conflict = 0;; s->attempt_conflict++) {
                        SELECT_RETRIED(m, &s->cpc, s->attempt, &s->p.devices[s->i].id);
                        AGAIN_PATIENTLY_IF_SILENT(m, SELECT_RETRIED(m, &s->cpc, s->attempt, &s->p.devices[s->i].id));
                        if (!step_answered(m))
                                break;
                        /* and a second, different answer: a stray 44 cannot make a device look switched */
                        REQUEST_RETRIED(m, &s->cpc, s->attempt, lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                                        LSS_CS_INQUIRE_NODE_ID);
                        AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->cpc, s->attempt,
                                                                     lss_encode_inquire(&f__, LSS_FIELD_COUNT),
                                                                     LSS_CS_INQUIRE_NODE_ID));
                        if (!step_conflict(m) || s->attempt_conflict >= m->timing.cfg.retries)
                                break;
                        /* more than one slave still in configuration: the switch
                         * to waiting reached some inside their window; again */
                        m->stats.retries++;
                        SEND(m, &s->cpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                }
                if (!step_answered(m) || step_conflict(m)) {
                        s->p.devices[s->i].outcome = LSS_BITRATE_LOST;
                        s->n_bad++;
                        SEND(m, &s->cpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
                        continue;
                }
                s->p.devices[s->i].outcome = LSS_BITRATE_SWITCHED;
                if (s->p.store) {
                        REQUEST_RETRIED(m, &s->cpc, s->attempt, lss_encode_store(&f__), LSS_CS_STORE);
                        AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->cpc, s->attempt, lss_encode_store(&f__),
                                                                     LSS_CS_STORE));
                        if (step_answered(m) && m->step.answer.data[1] == 0)
                                s->p.devices[s->i].outcome = LSS_BITRATE_STORED;
                        else {
                                s->p.devices[s->i].outcome = LSS_BITRATE_STORE_FAILED;
                                s->p.devices[s->i].err = step_answered(m) ? m->step.answer.data[1] : 0;
                                s->p.devices[s->i].spec = step_answered(m) ? m->step.answer.data[2] : 0;
                        }
                }
                SEND(m, &s->cpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        }
        master_progress(m, 1.0);

        if (s->n_bad > 0) {
                list_devices(s, LSS_BITRATE_LOST, ids, sizeof(ids));
                master_fail_at(m, LSS_E_INCOMPLETE, LSS_SERVICE_ACTIVATE_BIT_TIMING, LSS_REASON_NO_ANSWER,
                            "partial switch: %zu of %zu device%s silent at %u bit/s (still at %u bit/s, in "
                            "configuration state?)%s: %s",
                            s->n_bad, s->p.n_devices, s->p.n_devices == 1 ? "" : "s", s->p.bitrate, s->p.old_bitrate,
                            s->retune == LSS_RETUNE_FAILED || s->retune == LSS_RETUNE_TIMEOUT ?
                                    "; the host interface was not retuned" : "",
                            ids);
        } else if (s->retune == LSS_RETUNE_FAILED || s->retune == LSS_RETUNE_TIMEOUT) {
                master_fail(m, LSS_E_INCOMPLETE, "the devices switched to %u bit/s but the host interface was not "
                            "retuned (%s)", s->p.bitrate, lss_retune_name(s->retune));
        } else if (count(s, LSS_BITRATE_STORE_FAILED) > 0) {
                list_devices(s, LSS_BITRATE_STORE_FAILED, ids, sizeof(ids));
                master_fail_at(m, LSS_E_REJECTED, LSS_SERVICE_STORE, LSS_REASON_REFUSED,
                               "switched to %u bit/s, but Store Configuration failed on: %s", s->p.bitrate, ids);
        }
        PT_END(&s->cpc);
}

/* Nothing activated; the devices that accepted go back to the old timing,
 * or a later Store Configuration would persist the new one; so does the
 * one whose answer was lost or not alone (it may have taken it). */
static int revert(lss_master *m, lss_bitrate_state *s) {
        PT_BEGIN(&s->cpc);
        SEND(m, &s->cpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        if (!s->can_revert)
                goto out;
        for (s->i = 0; s->i < s->p.n_devices; s->i++) {
                if (s->p.devices[s->i].outcome != LSS_BITRATE_CONFIGURED && s->unsure != s->i + 1)
                        continue;
                /* a device not reverted keeps the new timing (a later Store
                 * persists it): asked again, patiently when silent */
                SELECT_RETRIED(m, &s->cpc, s->attempt, &s->p.devices[s->i].id);
                AGAIN_PATIENTLY_IF_SILENT(m, SELECT_RETRIED(m, &s->cpc, s->attempt, &s->p.devices[s->i].id));
                if (!step_answered(m))
                        continue;
                REQUEST_RETRIED(m, &s->cpc, s->attempt, lss_encode_configure_bit_timing(&f__, 0, s->old_index),
                                LSS_CS_CONFIGURE_BIT_TIMING);
                AGAIN_PATIENTLY_IF_SILENT(m, REQUEST_RETRIED(m, &s->cpc, s->attempt,
                                                             lss_encode_configure_bit_timing(&f__, 0, s->old_index),
                                                             LSS_CS_CONFIGURE_BIT_TIMING));
                /* the unsure one keeps its outcome (silent, or none for a conflict) */
                if (step_answered(m) && !step_conflict(m) && m->step.answer.data[1] == 0 &&
                    s->p.devices[s->i].outcome == LSS_BITRATE_CONFIGURED)
                        s->p.devices[s->i].outcome = LSS_BITRATE_REVERTED;
                SEND(m, &s->cpc, lss_encode_switch_global(&f__, LSS_MODE_WAITING));
        }
out:;
        PT_END(&s->cpc);
}

/* The phases, each a child; a refusal before the activation reverts. */
static int proc_bitrate(lss_master *m) {
        lss_bitrate_state *s = &m->br;

        PT_BEGIN(&s->pc);
        if (s->p.global) {
                /* 1 and 2 at once, for devices not selectable one by one */
                s->gpc = 0;
                PT_CALL(&s->pc, proc_bitrate_global_configure(m, s));
                if (m->result.status != LSS_OK)
                        goto revert;
        } else {
                s->cpc = 0;
                PT_CALL(&s->pc, reach_all(m, s));
                if (m->result.status != LSS_OK)
                        goto out;
                s->cpc = 0;
                PT_CALL(&s->pc, configure_each(m, s));
                if (m->result.status != LSS_OK)
                        goto revert;
        }
        s->cpc = 0;
        PT_CALL(&s->pc, activate(m, s));
        if (s->foreign) {
                /* another master spoke in the window: the devices switched,
                 * the host followed; nothing more but the switch to waiting
                 * that ends a procedure (at the new rate). The failed service
                 * says it: Activate Bit Timing had gone out. */
                master_fail_at(m, LSS_E_FOREIGN_MASTER, LSS_SERVICE_ACTIVATE_BIT_TIMING, LSS_REASON_NONE,
                               "another LSS master is active (%s)", s->foreign_frame);
                goto out;
        }
        s->cpc = 0;
        PT_CALL(&s->pc, verify_each(m, s));
        goto out;
revert:
        s->cpc = 0;
        PT_CALL(&s->pc, revert(m, s));
out:;
        PT_END(&s->pc);
}

int lss_master_set_bitrate(lss_master *m, const lss_bitrate_params *p, uint64_t now) {
        int index = lss_bit_timing_index(p->bitrate);
        int old = lss_bit_timing_index(p->old_bitrate);

        if (index < 0 || p->delay_ms == 0 || (p->n_devices > 0 && !p->devices))
                return -EINVAL;
        for (size_t i = 0; i < p->n_devices; i++)
                if (p->devices[i].no_select && (!p->global || !lss_node_id_valid(p->devices[i].node_id)))
                        return -EINVAL;
        if (m->running)
                return -EBUSY;
        memset(&m->br, 0, sizeof(m->br));
        m->br.p = *p;
        m->br.index = (uint8_t) index;
        m->br.can_revert = old >= 0;
        m->br.old_index = old >= 0 ? (uint8_t) old : 0;
        for (size_t i = 0; i < p->n_devices; i++) {
                p->devices[i].outcome = LSS_BITRATE_PENDING;
                p->devices[i].err = p->devices[i].spec = 0;
        }
        return master_start_procedure(m, proc_bitrate, now);
}

bool lss_master_retune_wanted(const lss_master *m, uint32_t *bitrate, uint64_t *deadline) {
        if (!m->running || m->proc != proc_bitrate || m->br.retune != LSS_RETUNE_WANTED)
                return false;
        if (bitrate)
                *bitrate = m->br.p.bitrate;
        if (deadline)
                *deadline = m->br.heard_at + (uint64_t) m->br.p.delay_ms * 1000u;
        return true;
}

void lss_master_retune_done(lss_master *m, enum lss_retune how, uint64_t now) {
        if (!lss_master_retune_wanted(m, NULL, NULL))
                return;
        if (how != LSS_RETUNE_DONE && how != LSS_RETUNE_SKIPPED)
                how = LSS_RETUNE_FAILED;
        m->br.retune = how;
        /* end the wait now: the step's deadline moves to its start */
        m->step.wait_us = 0;
        lss_master_on_time(m, now > m->now ? now : m->now);
}

enum lss_retune lss_master_retune_state(const lss_master *m) {
        return m->br.retune;
}

bool bitrate_on_foreign(lss_master *m, const char *frame) {
        if (!lss_master_bitrate_committed(m)) {
                /* the device asked last may have taken the new rate: it is named as configured */
                if (m->running && m->proc == proc_bitrate && m->br.configuring && m->br.i < m->br.p.n_devices)
                        m->br.p.devices[m->br.i].outcome = LSS_BITRATE_CONFIGURED;
                return false;
        }
        if (!m->br.foreign)
                snprintf(m->br.foreign_frame, sizeof(m->br.foreign_frame), "%s", frame);
        m->br.foreign = true;
        return true;
}

bool lss_master_bitrate_committed(const lss_master *m) {
        return m->running && m->proc == proc_bitrate && m->br.committed;
}
