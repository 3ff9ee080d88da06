/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Public face of the engine: starting operations, feeding events, results. */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lss/lss_internal.h"
#include "lss/lss_autoassign.h"

const char *lss_status_name(enum lss_status s) {
        static const char *const names[] = {
                [LSS_OK] = "ok",
                [LSS_E_NO_RESPONSE] = "no-response",
                [LSS_E_REJECTED] = "rejected",
                [LSS_E_CONFLICT] = "conflict",
                [LSS_E_NOT_FOUND] = "not-found",
                [LSS_E_BUS_DOWN] = "bus-down",
                [LSS_E_BUS_OFF] = "bus-off",
                [LSS_E_CANCELLED] = "cancelled",
                [LSS_E_INVALID] = "invalid",
                [LSS_E_VERIFY] = "not-verified",
                [LSS_E_INCOMPLETE] = "incomplete",
                [LSS_E_FOREIGN_MASTER] = "foreign-master",
        };
        return (unsigned) s < sizeof(names) / sizeof(names[0]) && names[s] ? names[s] : "unknown";
}

const char *lss_service_name(enum lss_service s) {
        static const char *const names[_LSS_SERVICE_MAX] = {
                [LSS_SERVICE_NONE] = "none",
                [LSS_SERVICE_SWITCH_SELECTIVE] = "Switch State Selective",
                [LSS_SERVICE_CONFIGURE_NODE_ID] = "Configure Node-ID",
                [LSS_SERVICE_CONFIGURE_BIT_TIMING] = "Configure Bit Timing",
                [LSS_SERVICE_ACTIVATE_BIT_TIMING] = "Activate Bit Timing",
                [LSS_SERVICE_STORE] = "Store Configuration",
                [LSS_SERVICE_INQUIRE] = "Inquire",
                [LSS_SERVICE_FASTSCAN] = "Fastscan",
                [LSS_SERVICE_VERIFY] = "verification",
        };
        return (unsigned) s < _LSS_SERVICE_MAX ? names[s] : NULL;
}

const char *lss_reason_name(enum lss_reason r) {
        static const char *const names[_LSS_REASON_MAX] = {
                [LSS_REASON_NONE] = "none",
                [LSS_REASON_NO_ANSWER] = "no-answer",
                [LSS_REASON_REFUSED] = "refused",
                [LSS_REASON_SEVERAL_ANSWERS] = "several-answers",
                [LSS_REASON_IN_USE] = "in-use",
                [LSS_REASON_NOT_CONFIRMED] = "not-confirmed",
                [LSS_REASON_UNRESOLVED] = "unresolved",
        };
        return (unsigned) r < _LSS_REASON_MAX ? names[r] : NULL;
}

lss_master *lss_master_new(const lss_timing_config *cfg) {
        lss_master *m = calloc(1, sizeof(*m));
        if (!m)
                return NULL;
        lss_timing_config def;
        if (!cfg) {
                lss_timing_config_default(&def);
                cfg = &def;
        }
        lss_timing_init(&m->timing, cfg);
        return m;
}

void lss_master_free(lss_master *m) {
        if (!m)
                return;
        free(m->devices);
        free(m->announced);
        free(m->left);
        free(m->sc.stack);
        free(m->sc.cand);
        lss_autoassign_free_state(m);
        lss_sdo_discover_free_state(m);
        free(m);
}

void lss_master_set_timing(lss_master *m, const lss_timing_config *cfg) {
        lss_timing t = m->timing;
        lss_timing_init(&m->timing, cfg);
        /* what was measured on this bus stays true */
        memcpy(m->timing.samples, t.samples, sizeof(t.samples));
        m->timing.n_samples = t.n_samples;
        m->timing.next = t.next;
        m->timing.patience_us = t.patience_us;
        m->timing.stalled = t.stalled;
        m->patient = false; /* the new configuration holds at once */
}

void lss_master_set_progress(lss_master *m, lss_progress_fn fn, void *userdata) {
        m->progress = fn;
        m->progress_ud = userdata;
}

void master_progress(lss_master *m, double p) {
        p = p < 0 ? 0 : p > 1 ? 1 : p;
        if (m->progress)
                m->progress(m->progress_ud, m->prog_base + m->prog_span * p);
}

void lss_master_set_retune(lss_master *m, lss_retune_fn fn, void *userdata) {
        m->retune_fn = fn;
        m->retune_ud = userdata;
}

void lss_master_set_found(lss_master *m, lss_found_fn fn, void *userdata) {
        m->found_fn = fn;
        m->found_ud = userdata;
}

void master_found(lss_master *m, const lss_identity *id, uint8_t node_id, uint8_t aside_node_id) {
        for (size_t i = 0; i < m->n_announced; i++)
                if (lss_identity_equal(&m->announced[i], id))
                        return;
        if (m->n_announced == m->cap_announced) {
                size_t cap = m->cap_announced ? m->cap_announced * 2 : 16;
                lss_identity *a = realloc(m->announced, cap * sizeof(*a));
                if (a) {
                        m->announced = a;
                        m->cap_announced = cap;
                }
        }
        /* out of memory: announced, just not remembered */
        if (m->n_announced < m->cap_announced)
                m->announced[m->n_announced++] = *id;
        if (m->found_fn) {
                lss_device d = { .id = *id, .node_id = node_id, .aside_node_id = aside_node_id };
                m->found_fn(m->found_ud, &d);
        }
}

void lss_master_set_expected_finds(lss_master *m, unsigned n) {
        m->expected_finds = n;
}

const char *lss_store_error_name(uint8_t err) {
        switch (err) {
        case LSS_ERR_OK: return "stored";
        case LSS_ERR_STORE_NOT_SUPPORTED: return "storing not supported";
        case LSS_ERR_STORE_MEDIA: return "storage media access error";
        case LSS_ERR_SPECIFIC: return "manufacturer-specific error";
        default: return "reserved error code";
        }
}

void master_fail(lss_master *m, enum lss_status st, const char *fmt, ...) {
        va_list ap;
        m->result.status = st;
        m->result.failed_service = LSS_SERVICE_NONE;
        m->result.reason = LSS_REASON_NONE;
        va_start(ap, fmt);
        vsnprintf(m->result.message, sizeof(m->result.message), fmt, ap);
        va_end(ap);
}

void master_fail_at(lss_master *m, enum lss_status st, enum lss_service service, enum lss_reason reason,
                    const char *fmt, ...) {
        va_list ap;
        m->result.status = st;
        m->result.failed_service = service;
        m->result.reason = reason;
        va_start(ap, fmt);
        vsnprintf(m->result.message, sizeof(m->result.message), fmt, ap);
        va_end(ap);
}

int master_add_device(lss_master *m, const lss_identity *id, uint8_t node_id) {
        if (m->n_devices == m->cap_devices) {
                size_t cap = m->cap_devices ? m->cap_devices * 2 : 16;
                lss_device *d = realloc(m->devices, cap * sizeof(*d));
                if (!d)
                        return -ENOMEM;
                m->devices = d;
                m->cap_devices = cap;
        }
        m->devices[m->n_devices++] = (lss_device) { .id = *id, .node_id = node_id };
        return 0;
}

static void queue_switch_waiting(lss_master *m) {
        lss_frame f;
        lss_encode_switch_global(&f, LSS_MODE_WAITING);
        (void) step_queue_tx(m, &f);
}

static void finish(lss_master *m) {
        m->running = false;
        m->done = true;
        m->step.phase = PHASE_IDLE;
        m->result.devices = m->devices;
        m->result.n_devices = m->n_devices;
        m->stats.timeout_us = lss_timing_wait(&m->timing, LSS_WAIT_ANSWER);
        m->stats.latency_min_us = lss_timing_min(&m->timing);
        m->stats.latency_max_us = lss_timing_max(&m->timing);
}

static void cancel_now(lss_master *m) {
        master_fail(m, LSS_E_CANCELLED, "cancelled");
        queue_switch_waiting(m);
        finish(m);
}

/* A cancel put off while an assignment's Configure Node-ID was out is
 * due once the assignment is over (lss_master_cancel). */
static bool cancel_due(const lss_master *m) {
        return m->cancelling && !m->sc.restore && !m->as.configuring;
}

/* Run the procedure for as long as it does not wait for the bus. */
static void advance(lss_master *m) {
        while (m->running) {
                if (m->step.phase != PHASE_DONE && m->step.phase != PHASE_IDLE) {
                        if (cancel_due(m)) {
                                m->txq_len = 0; /* the next step's request is not sent */
                                cancel_now(m);
                        }
                        return;
                }
                if (m->proc(m) == PT_DONE) {
                        /* procedures (not raw services) leave every slave in waiting,
                         * also on failure */
                        if (m->result.status != LSS_OK && m->procedure)
                                queue_switch_waiting(m);
                        finish(m);
                        return;
                }
        }
}

void master_patient_begin(lss_master *m, uint32_t wait_us) {
        if (!m->patient)
                m->calm_cfg = m->timing.cfg;
        m->patient = true;
        m->timing.cfg.timeout_us = wait_us;
        m->timing.cfg.guard_floor_us = wait_us / 4;
        m->timing.cfg.adaptive = false;
        if (m->timing.cfg.retries > 1)
                m->timing.cfg.retries = 1;
}

void master_patient_end(lss_master *m) {
        if (m->patient)
                m->timing.cfg = m->calm_cfg;
        m->patient = m->asking_again = false;
}

static int start_op(lss_master *m, lss_proc_fn proc, bool procedure, uint64_t now) {
        if (m->running)
                return -EBUSY;
        master_patient_end(m);
        m->proc = proc;
        m->procedure = procedure;
        m->pc = 0;
        m->running = true;
        m->done = false;
        m->cancelling = false;
        m->sc.restore = false;
        if (now < m->now) /* a caller's clock that went back: no estimate holds */
                m->wire_until = m->answers_until = m->strays_until = 0;
        m->now = now;
        m->n_devices = 0;
        m->n_announced = 0;
        m->n_left = 0;
        m->as.configuring = false;
        m->txq_head = m->txq_len = 0;
        memset(&m->result, 0, sizeof(m->result));
        m->result.node_id = LSS_NODE_ID_UNCONFIGURED;
        m->step.phase = PHASE_IDLE;
        m->prog_base = 0;
        m->prog_span = 1;
        m->stats.patience_us = m->timing.patience_us;
        m->loss = (lss_loss) { 0 };
        advance(m);
        return 0;
}

int master_start_procedure(lss_master *m, lss_proc_fn proc, uint64_t now) {
        return start_op(m, proc, true, now);
}

/* ---- raw services ---- */

/* A raw service's answer is its caller's verdict, and nothing follows it
 * that a wait could hold up: an answer that comes after the adaptive wait (a
 * loaded host stalls one for 100-200 ms) is still taken, in a late guard of
 * at least this long. Only silence costs it. */
#define RAW_LATE_FLOOR_US 250000u
#define RAW_REQUEST(m, pc, frame_expr, cs) \
        do { lss_frame f__; frame_expr; step_lss(m, cs); step_add_tx(m, &f__); raw_patient(m); step_start(m); \
             PT_YIELD(pc); } while (0)

static void raw_patient(lss_master *m) {
        m->step.late_us = lss_timing_patient_wait(&m->timing, RAW_LATE_FLOOR_US);
}

static int proc_switch_global(lss_master *m) {
        PT_BEGIN(&m->pc);
        STEP_REQUEST(m, &m->pc, lss_encode_switch_global(&f__, m->arg.sg.mode), -1);
        PT_END(&m->pc);
}

static int proc_switch_selective(lss_master *m) {
        PT_BEGIN(&m->pc);
        step_selective(m, &m->sel_id);
        raw_patient(m);
        PT_YIELD(&m->pc);
        m->result.found = step_answered(m);
        if (!m->result.found)
                master_fail_at(m, LSS_E_NO_RESPONSE, LSS_SERVICE_SWITCH_SELECTIVE, LSS_REASON_NO_ANSWER,
                               "no slave answered the selective switch");
        PT_END(&m->pc);
}

/* The checks every confirmed single-slave service shares. */
static bool single_answer_ok(lss_master *m, enum lss_service service, const char *what) {
        if (!step_answered(m)) {
                master_fail_at(m, LSS_E_NO_RESPONSE, service, LSS_REASON_NO_ANSWER,
                               "%s: no answer (is a slave in configuration state?)", what);
                return false;
        }
        if (step_conflict(m)) {
                master_fail_at(m, LSS_E_CONFLICT, service, LSS_REASON_SEVERAL_ANSWERS,
                               "%s: different answers from more than one slave in configuration state", what);
                return false;
        }
        return true;
}

static bool error_code_ok(lss_master *m, enum lss_service service) {
        m->result.err = m->step.answer.data[1];
        m->result.spec = m->step.answer.data[2];
        if (m->result.err == 0)
                return true;
        master_fail_at(m, LSS_E_REJECTED, service, LSS_REASON_REFUSED, "%s rejected by the slave: error %u, spec %u",
                       lss_service_name(service), m->result.err, m->result.spec);
        return false;
}

static int proc_configure_node_id(lss_master *m) {
        PT_BEGIN(&m->pc);
        RAW_REQUEST(m, &m->pc, lss_encode_configure_node_id(&f__, m->arg.raw.a), LSS_CS_CONFIGURE_NODE_ID);
        if (single_answer_ok(m, LSS_SERVICE_CONFIGURE_NODE_ID, "Configure Node-ID"))
                error_code_ok(m, LSS_SERVICE_CONFIGURE_NODE_ID);
        PT_END(&m->pc);
}

/* lss_master_configure_node_id_checked(); arg.raw.a: the node-ID */
static int proc_configure_node_id_checked(lss_master *m) {
        uint8_t node_id = m->arg.raw.a;
        PT_BEGIN(&m->pc);
        if (!lss_node_id_valid(node_id))
                goto configure;
        /* identical answers from several slaves merge on the wire: the
         * serial tells them apart */
        RAW_REQUEST(m, &m->pc, lss_encode_inquire(&f__, LSS_FIELD_SERIAL), LSS_CS_INQUIRE_SERIAL);
        if (step_conflict(m)) {
                master_fail_at(m, LSS_E_CONFLICT, LSS_SERVICE_CONFIGURE_NODE_ID, LSS_REASON_SEVERAL_ANSWERS,
                               "more than one slave is in configuration state: Configure Node-ID %u would give "
                               "node-ID %u to all of them", node_id, node_id);
                goto out;
        }
        RAW_REQUEST(m, &m->pc, lss_encode_inquire(&f__, LSS_FIELD_COUNT), LSS_CS_INQUIRE_NODE_ID);
        if (step_answered(m) && !step_conflict(m) && m->step.answer.data[1] == node_id)
                goto configure; /* its own node-ID */
        if (m->taken_fn && m->taken_fn(m->taken_ud, node_id, NULL)) {
                m->result.in_use = true;
                master_fail_at(m, LSS_E_CONFLICT, LSS_SERVICE_CONFIGURE_NODE_ID, LSS_REASON_IN_USE,
                               "node-ID %u already answered on the bus", node_id);
                goto out;
        }
        step_node_in_use(m, node_id);
        PT_YIELD(&m->pc);
        if (m->step.n_answers > 0) {
                m->result.in_use = true;
                master_fail_at(m, LSS_E_CONFLICT, LSS_SERVICE_CONFIGURE_NODE_ID, LSS_REASON_IN_USE,
                               "node-ID %u already answers on the bus", node_id);
                goto out;
        }
configure:
        RAW_REQUEST(m, &m->pc, lss_encode_configure_node_id(&f__, node_id), LSS_CS_CONFIGURE_NODE_ID);
        if (single_answer_ok(m, LSS_SERVICE_CONFIGURE_NODE_ID, "Configure Node-ID"))
                error_code_ok(m, LSS_SERVICE_CONFIGURE_NODE_ID);
out:;
        PT_END(&m->pc);
}

static int proc_configure_bit_timing(lss_master *m) {
        PT_BEGIN(&m->pc);
        RAW_REQUEST(m, &m->pc, lss_encode_configure_bit_timing(&f__, m->arg.raw.a, m->arg.raw.b),
                    LSS_CS_CONFIGURE_BIT_TIMING);
        if (single_answer_ok(m, LSS_SERVICE_CONFIGURE_BIT_TIMING, "Configure Bit Timing"))
                error_code_ok(m, LSS_SERVICE_CONFIGURE_BIT_TIMING);
        PT_END(&m->pc);
}

static int proc_activate_bit_timing(lss_master *m) {
        PT_BEGIN(&m->pc);
        STEP_REQUEST(m, &m->pc, lss_encode_activate_bit_timing(&f__, m->arg.raw.u16), -1);
        PT_END(&m->pc);
}

static int proc_store(lss_master *m) {
        PT_BEGIN(&m->pc);
        RAW_REQUEST(m, &m->pc, lss_encode_store(&f__), LSS_CS_STORE);
        if (single_answer_ok(m, LSS_SERVICE_STORE, "Store Configuration"))
                error_code_ok(m, LSS_SERVICE_STORE);
        PT_END(&m->pc);
}

static const char *const inquire_names[] = { "Inquire Vendor-ID", "Inquire Product-Code", "Inquire Revision",
                                             "Inquire Serial", "Inquire Node-ID" };

static int proc_inquire(lss_master *m) {
        PT_BEGIN(&m->pc);
        RAW_REQUEST(m, &m->pc, lss_encode_inquire(&f__, m->arg.inq.field),
                    LSS_CS_INQUIRE_VENDOR + (int) m->arg.inq.field);
        if (single_answer_ok(m, LSS_SERVICE_INQUIRE, inquire_names[m->arg.inq.field])) {
                if (m->arg.inq.field == LSS_FIELD_COUNT)
                        m->result.node_id = m->step.answer.data[1];
                else
                        m->result.value = lss_get_u32(m->step.answer.data + 1);
        }
        PT_END(&m->pc);
}

static int proc_inquire_identity(lss_master *m) {
        PT_BEGIN(&m->pc);
        for (m->arg.inq.i = 0; m->arg.inq.i < LSS_FIELD_COUNT; m->arg.inq.i++) {
                RAW_REQUEST(m, &m->pc, lss_encode_inquire(&f__, m->arg.inq.i),
                            LSS_CS_INQUIRE_VENDOR + (int) m->arg.inq.i);
                if (!single_answer_ok(m, LSS_SERVICE_INQUIRE, inquire_names[m->arg.inq.i]))
                        break;
                lss_identity_set_field(&m->result.id, m->arg.inq.i, lss_get_u32(m->step.answer.data + 1));
        }
        PT_END(&m->pc);
}

static int proc_identify_remote(lss_master *m) {
        PT_BEGIN(&m->pc);
        step_identify(m, &m->arg.ir);
        m->step.discovery = true;
        step_start(m);
        PT_YIELD(&m->pc);
        m->result.found = step_answered(m);
        PT_END(&m->pc);
}

static int proc_identify_non_configured(lss_master *m) {
        PT_BEGIN(&m->pc);
        step_lss(m, LSS_CS_IDENTIFY_NON_CONFIGURED_SLAVE);
        m->step.discovery = true;
        {
                lss_frame f;
                lss_encode_identify_non_configured(&f);
                step_add_tx(m, &f);
        }
        step_start(m);
        PT_YIELD(&m->pc);
        m->result.found = step_answered(m);
        PT_END(&m->pc);
}

static int proc_nmt(lss_master *m) {
        PT_BEGIN(&m->pc);
        STEP_REQUEST(m, &m->pc, nmt_encode(&f__, m->arg.nmt.cs, m->arg.nmt.node), -1);
        PT_END(&m->pc);
}

/* The raw Fastscan: a found identity counts only when the slave in
 * configuration confirms it by Inquire Identity (a slave answering requests
 * that do not match it makes one up, e.g. 0:0:0:0). */
static int proc_fastscan_top(lss_master *m) {
        PT_BEGIN(&m->pc);
        PT_CALL(&m->pc, proc_fastscan(m, &m->fs));
        if (m->fs.found) {
                for (unsigned i = 0; i < LSS_FIELD_COUNT; i++)
                        lss_identity_set_field(&m->sc.found, i, m->fs.value[i]);
                m->sc.cpc = 0;
                PT_CALL(&m->pc, proc_confirm_found(m, &m->sc, false));
                m->sc.n_other = m->sc.confirm == CONFIRM_OTHER;
                if (m->sc.confirm == CONFIRM_OTHER || m->sc.confirm == CONFIRM_UNCLEAR) {
                        /* Another identity or several answered: two slaves in
                         * configuration (one went there on a confirmation
                         * answered late) do that too. Wait longer, everybody
                         * to waiting, and ask for F alone. */
                        lss_timing_on_stray(&m->timing);
                        m->sc.cpc = 0;
                        PT_CALL(&m->pc, proc_confirm_by_selection(m, &m->sc));
                        if (m->sc.confirm == CONFIRM_NOBODY && m->sc.n_other)
                                m->sc.confirm = CONFIRM_OTHER;
                }
                m->result.id = m->sc.found;
                if (m->sc.confirm == CONFIRM_OK)
                        m->result.found = true;
                else if (m->sc.confirm == CONFIRM_NOBODY)
                        master_fail_at(m, LSS_E_NOT_FOUND, LSS_SERVICE_FASTSCAN, LSS_REASON_NOT_CONFIRMED,
                                       "no device: fastscan made up %08x:%08x:%08x:%08x but no slave in "
                                       "configuration state confirmed it", m->sc.found.vendor, m->sc.found.product,
                                       m->sc.found.revision, m->sc.found.serial);
                else if (m->sc.confirm == CONFIRM_OTHER) {
                        m->result.id = m->sc.other;
                        master_fail_at(m, LSS_E_CONFLICT, LSS_SERVICE_FASTSCAN, LSS_REASON_NOT_CONFIRMED,
                                    "slave %08x:%08x:%08x:%08x was in configuration state after a "
                                    "Fastscan for %08x:%08x:%08x:%08x, which did not answer a selective "
                                    "switch: it entered configuration for another identity (it does not "
                                    "follow CiA 305) or on an earlier Fastscan whose answer came late",
                                    m->sc.other.vendor, m->sc.other.product, m->sc.other.revision, m->sc.other.serial,
                                    m->sc.found.vendor, m->sc.found.product, m->sc.found.revision,
                                    m->sc.found.serial);
                } else
                        master_fail_at(m, LSS_E_CONFLICT, LSS_SERVICE_FASTSCAN, LSS_REASON_SEVERAL_ANSWERS,
                                       "the identity fastscan found could not be confirmed: "
                                       "several slaves answered Inquire Identity");
        } else if (m->fs.none)
                master_fail_at(m, LSS_E_NOT_FOUND, LSS_SERVICE_FASTSCAN, LSS_REASON_NO_ANSWER,
                               "no device: no non-configured slave answered the fastscan");
        else
                master_fail_at(m, LSS_E_INCOMPLETE, LSS_SERVICE_FASTSCAN, LSS_REASON_UNRESOLVED,
                               "fastscan did not converge after %u attempts", m->fs.attempt);
        PT_END(&m->pc);
}

static int proc_enumerate_top(lss_master *m) {
        PT_BEGIN(&m->pc);
        PT_CALL(&m->pc, proc_enumerate(m, &m->sc));
        PT_END(&m->pc);
}

static int proc_slowscan_top(lss_master *m) {
        PT_BEGIN(&m->pc);
        PT_CALL(&m->pc, proc_slowscan(m, &m->sc));
        PT_END(&m->pc);
}

static int proc_assign_top(lss_master *m) {
        PT_BEGIN(&m->pc);
        PT_CALL(&m->pc, proc_assign(m, &m->as));
        PT_END(&m->pc);
}

static int proc_unassign_top(lss_master *m) {
        PT_BEGIN(&m->pc);
        PT_CALL(&m->pc, proc_unassign(m, &m->as));
        PT_END(&m->pc);
}

static int proc_fastscan_assign_top(lss_master *m) {
        PT_BEGIN(&m->pc);
        PT_CALL(&m->pc, proc_fastscan_assign(m, &m->as));
        PT_END(&m->pc);
}

int lss_master_switch_global(lss_master *m, enum lss_mode mode, uint64_t now) {
        if (mode != LSS_MODE_WAITING && mode != LSS_MODE_CONFIGURATION)
                return -EINVAL;
        if (m->running)
                return -EBUSY;
        m->arg.sg.mode = mode;
        return start_op(m, proc_switch_global, false, now);
}

int lss_master_switch_selective(lss_master *m, const lss_identity *id, uint64_t now) {
        if (m->running)
                return -EBUSY;
        m->sel_id = *id;
        return start_op(m, proc_switch_selective, false, now);
}

int lss_master_configure_node_id(lss_master *m, uint8_t node_id, uint64_t now) {
        if (!lss_node_id_valid(node_id) && node_id != LSS_NODE_ID_UNCONFIGURED)
                return -EINVAL;
        if (m->running)
                return -EBUSY;
        m->arg.raw.a = node_id;
        return start_op(m, proc_configure_node_id, false, now);
}

int lss_master_configure_node_id_checked(lss_master *m, uint8_t node_id, uint64_t now) {
        if (!lss_node_id_valid(node_id) && node_id != LSS_NODE_ID_UNCONFIGURED)
                return -EINVAL;
        if (m->running)
                return -EBUSY;
        m->arg.raw.a = node_id;
        return start_op(m, proc_configure_node_id_checked, false, now);
}

void lss_master_set_taken_check(lss_master *m, lss_taken_fn fn, void *userdata) {
        m->taken_fn = fn;
        m->taken_ud = userdata;
}

int lss_master_configure_bit_timing(lss_master *m, uint8_t table, uint8_t index, uint64_t now) {
        if (m->running)
                return -EBUSY;
        m->arg.raw.a = table;
        m->arg.raw.b = index;
        return start_op(m, proc_configure_bit_timing, false, now);
}

int lss_master_activate_bit_timing(lss_master *m, uint16_t delay_ms, uint64_t now) {
        if (m->running)
                return -EBUSY;
        m->arg.raw.u16 = delay_ms;
        return start_op(m, proc_activate_bit_timing, false, now);
}

int lss_master_store(lss_master *m, uint64_t now) {
        if (m->running)
                return -EBUSY;
        return start_op(m, proc_store, false, now);
}

int lss_master_inquire(lss_master *m, unsigned field, uint64_t now) {
        if (field > LSS_FIELD_COUNT)
                return -EINVAL;
        if (m->running)
                return -EBUSY;
        m->arg.inq.field = field;
        return start_op(m, proc_inquire, false, now);
}

int lss_master_inquire_identity(lss_master *m, uint64_t now) {
        if (m->running)
                return -EBUSY;
        return start_op(m, proc_inquire_identity, false, now);
}

static bool range_valid(const lss_identify_range *r) {
        return r->rev_lo <= r->rev_hi && r->serial_lo <= r->serial_hi;
}

int lss_master_identify_remote(lss_master *m, const lss_identify_range *r, uint64_t now) {
        if (!range_valid(r))
                return -EINVAL;
        if (m->running)
                return -EBUSY;
        m->arg.ir = *r;
        return start_op(m, proc_identify_remote, false, now);
}

int lss_master_identify_non_configured(lss_master *m, uint64_t now) {
        if (m->running)
                return -EBUSY;
        return start_op(m, proc_identify_non_configured, false, now);
}

static bool known_valid(const lss_fastscan_known *k) {
        for (unsigned i = 0; k && i < LSS_FIELD_COUNT; i++)
                if (k->known_bits[i] > 32)
                        return false;
        return true;
}

static void set_known(lss_fastscan_known *dst, const lss_fastscan_known *k) {
        if (k)
                *dst = *k;
        else
                memset(dst, 0, sizeof(*dst));
}

int lss_master_fastscan(lss_master *m, const lss_fastscan_known *known, uint64_t now) {
        if (!known_valid(known))
                return -EINVAL;
        if (m->running)
                return -EBUSY;
        memset(&m->fs, 0, sizeof(m->fs));
        set_known(&m->fs.known, known);
        return start_op(m, proc_fastscan_top, false, now);
}

int lss_master_nmt(lss_master *m, enum nmt_cs cs, uint8_t node_id, uint64_t now) {
        if (node_id > LSS_NODE_ID_MAX)
                return -EINVAL;
        if (m->running)
                return -EBUSY;
        m->arg.nmt.cs = cs;
        m->arg.nmt.node = node_id;
        return start_op(m, proc_nmt, false, now);
}

static int start_enumerate(lss_master *m, const lss_fastscan_known *known, bool keep_stopped, uint64_t now) {
        if (!known_valid(known))
                return -EINVAL;
        if (m->running)
                return -EBUSY;
        memset(&m->sc.known, 0, sizeof(m->sc.known));
        set_known(&m->sc.known, known);
        m->sc.pc = m->sc.vpc = 0;
        m->sc.avoid = NULL;
        m->sc.direct = NULL;
        m->sc.keep_stopped = keep_stopped;
        m->sc.no_set_aside = false;
        m->sc.listen = m->sc.patient_end = true;
        return start_op(m, proc_enumerate_top, true, now);
}

int lss_master_enumerate(lss_master *m, const lss_fastscan_known *known, uint64_t now) {
        return start_enumerate(m, known, false, now);
}

int lss_master_enumerate_stopped(lss_master *m, const lss_fastscan_known *known, uint64_t now) {
        return start_enumerate(m, known, true, now);
}

int lss_master_slowscan(lss_master *m, const lss_identify_range *r, uint64_t now) {
        if (!range_valid(r))
                return -EINVAL;
        if (m->running)
                return -EBUSY;
        m->sc.range = *r;
        m->sc.pc = m->sc.vpc = 0;
        return start_op(m, proc_slowscan_top, true, now);
}

int lss_master_assign(lss_master *m, const lss_identity *id, uint8_t node_id, unsigned flags, uint64_t now) {
        if (!lss_node_id_valid(node_id))
                return -EINVAL;
        if (m->running)
                return -EBUSY;
        memset(&m->as, 0, sizeof(m->as));
        m->as.id = *id;
        m->as.node_id = node_id;
        m->as.flags = flags;
        return start_op(m, proc_assign_top, true, now);
}

int lss_master_unassign(lss_master *m, const lss_identity *id, unsigned flags, uint64_t now) {
        if (flags & ~(unsigned) (LSS_UNASSIGN_STORE | LSS_UNASSIGN_RESET))
                return -EINVAL;
        if (m->running)
                return -EBUSY;
        memset(&m->as, 0, sizeof(m->as));
        m->as.id = *id;
        m->as.flags = flags;
        return start_op(m, proc_unassign_top, true, now);
}

int lss_master_fastscan_assign(lss_master *m, const lss_fastscan_known *known, uint8_t node_id, unsigned flags,
                               uint64_t now) {
        if (!lss_node_id_valid(node_id) || !known_valid(known))
                return -EINVAL;
        if (m->running)
                return -EBUSY;
        memset(&m->as, 0, sizeof(m->as));
        set_known(&m->as.fs.known, known);
        m->as.node_id = node_id;
        m->as.flags = flags;
        return start_op(m, proc_fastscan_assign_top, true, now);
}

/* ---- another LSS master ---- */

/* The slaves the enumeration set aside and has not given back yet. */
static void keep_left_aside(lss_master *m) {
        const lss_scan_state *s = &m->sc;
        if (!s->restore)
                return;
        for (size_t i = 0; i < s->n_cand; i++) {
                const lss_device *d = &s->cand[i];
                if (!d->aside_node_id || !s->back_due[d->aside_node_id])
                        continue;
                if (m->n_left == m->cap_left) {
                        size_t cap = m->cap_left ? m->cap_left * 2 : 8;
                        lss_device *l = realloc(m->left, cap * sizeof(*l));
                        if (!l)
                                return; /* out of memory: the journal of the pass named them */
                        m->left = l;
                        m->cap_left = cap;
                }
                m->left[m->n_left++] = *d;
        }
}

/* A request of another master (lss_master.h, "another LSS master"). */
static void on_foreign(lss_master *m, const lss_frame *f) {
        char frame[32];

        m->stats.foreign_requests++;
        if (!m->running)
                return;
        lss_frame_format(f, frame, sizeof(frame));
        if (bitrate_on_foreign(m, frame))
                return; /* past the activation: it ends after its window */
        master_fail(m, LSS_E_FOREIGN_MASTER, "another LSS master is active (%s)", frame);
        if (m->as.configuring) {
                /* its Configure Node-ID went out: the slave may hold that node-ID */
                m->result.may_hold = true;
                m->result.id = m->as.id;
        }
        aa_on_foreign(m);
        keep_left_aside(m);
        m->sc.restore = false;
        /* nothing more of this operation goes out; a procedure leaves nobody
         * in configuration, where the other master's Configure would reach it */
        m->txq_len = 0;
        if (m->procedure)
                queue_switch_waiting(m);
        finish(m);
}

const lss_device *lss_master_left_aside(const lss_master *m, size_t *n) {
        *n = m->n_left;
        return m->left;
}

/* ---- driving ---- */

void lss_master_on_frame(lss_master *m, const lss_frame *f, uint64_t rx_us) {
        if (rx_us > m->now)
                m->now = rx_us;
        if (lss_is_foreign_request(f)) {
                on_foreign(m, f);
                return;
        }
        if (!m->running) {
                m->stats.ignored_frames++;
                step_on_stray(m, f);
                return;
        }
        step_on_frame(m, f, rx_us);
        advance(m);
}

void lss_master_on_time(lss_master *m, uint64_t now) {
        if (now > m->now)
                m->now = now;
        if (!m->running)
                return;
        step_on_time(m, now);
        advance(m);
}

void lss_master_on_sent(lss_master *m, uint64_t now) {
        if (now > m->now)
                m->now = now;
        m->reports_writes = true;
        if (!m->running || m->step.confirmed)
                return;
        /* A host stalled between the step's start and this write ran its
         * wait out before the request was out: the wait starts now (else the
         * step ended at once, silent, and the next request followed its own
         * within a frame time: engine-vcan's witness in a loaded VM). */
        if (m->step.phase == PHASE_LATE_GUARD && !m->step.written)
                m->step.phase = PHASE_WAIT;
        /* timeouts run from the moment the request really left */
        if (m->step.phase == PHASE_WAIT) {
                if (now > m->step.sent_at)
                        m->step.sent_at = now;
                m->step.written = true;
        }
}

void lss_master_set_tx_confirm(lss_master *m, bool on) {
        m->tx_confirm = on;
}

void lss_master_on_tx_confirmed(lss_master *m, uint64_t at) {
        if (at > m->now)
                m->now = at;
        if (m->running)
                step_on_tx_confirmed(m, at);
}

void lss_master_on_rx_lost(lss_master *m, uint64_t now) {
        (void) now;
        if (m->running)
                lss_loss_rx_lost(&m->loss);
        if (m->running && m->step.phase != PHASE_IDLE && m->step.phase != PHASE_DONE)
                m->step.void_ = true;
}

void lss_master_on_bus_error(lss_master *m, enum lss_status status, const char *why, uint64_t now) {
        if (now > m->now)
                m->now = now;
        if (!m->running)
                return;
        master_fail(m, status, "%s", why ? why : lss_status_name(status));
        m->txq_len = 0;
        finish(m);
}

void lss_master_cancel(lss_master *m, uint64_t now) {
        if (now > m->now)
                m->now = now;
        if (!m->running)
                return;
        m->cancelling = true;
        if (m->sc.restore)
                return; /* the enumeration gives the slaves it set aside back their 255 first */
        /* An assignment whose Configure Node-ID went out ends first,
         * verified and reported: cut off, the slave would keep the node-ID
         * pending, or hold it with no outcome saying so. */
        if (m->as.configuring)
                return;
        cancel_now(m);
}

bool lss_master_next_tx(lss_master *m, lss_frame *f) {
        if (m->txq_len == 0)
                return false;
        *f = m->txq[m->txq_head];
        m->txq_head = (m->txq_head + 1) % LSS_TXQ_LEN;
        m->txq_len--;
        m->wire_until = (m->wire_until > m->now ? m->wire_until : m->now) + lss_timing_frame_us(&m->timing, f);
        return true;
}

uint64_t lss_master_deadline(const lss_master *m) {
        return m->running ? step_deadline(m) : UINT64_MAX;
}

bool lss_master_busy(const lss_master *m) {
        return m->running;
}

bool lss_master_done(const lss_master *m) {
        return m->done && m->txq_len == 0;
}

const lss_result *lss_master_result(const lss_master *m) {
        return &m->result;
}

const lss_master_stats *lss_master_get_stats(const lss_master *m) {
        return &m->stats;
}
