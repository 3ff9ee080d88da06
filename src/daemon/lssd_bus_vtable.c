/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* org.lssd.LSS1.Bus. Handlers read → validate → no-op fast path → authorize
 * (polkit: the handler may run twice, lssd_auth.h) → queue a job (deferred
 * reply) or act → reply. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_bitrate.h"
#include "daemon/lssd_bitrate_method.h"
#include "daemon/lssd_bus.h"
#include "daemon/lssd_taken.h"
#include "daemon/lssd_errors.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_validate.h"
#include "daemon/lssd_vtables.h"

static int property_get_interface(sd_bus *bus, const char *path, const char *interface, const char *property,
                                  sd_bus_message *reply, void *userdata, sd_bus_error *error) {
        return sd_bus_message_append(reply, "s", lssd_bus_ifname(userdata));
}

static int property_get_progress(sd_bus *bus, const char *path, const char *interface, const char *property,
                                 sd_bus_message *reply, void *userdata, sd_bus_error *error) {
        return sd_bus_message_append(reply, "d", lssd_bus_progress(userdata));
}

static int property_get_state(sd_bus *bus, const char *path, const char *interface, const char *property,
                              sd_bus_message *reply, void *userdata, sd_bus_error *error) {
        return sd_bus_message_append(reply, "s", lssd_bus_state(userdata));
}

static int property_get_bitrate(sd_bus *bus, const char *path, const char *interface, const char *property,
                                sd_bus_message *reply, void *userdata, sd_bus_error *error) {
        return sd_bus_message_append(reply, "u", lssd_bus_bitrate(userdata));
}

static int property_get_job(sd_bus *bus, const char *path, const char *interface, const char *property,
                            sd_bus_message *reply, void *userdata, sd_bus_error *error) {
        return sd_bus_message_append(reply, "s", lssd_bus_job_name(userdata));
}

static int property_get_last_pass(sd_bus *bus, const char *path, const char *interface, const char *property,
                                  sd_bus_message *reply, void *userdata, sd_bus_error *error) {
        const lssd_pass_record *p = &lssd_bus_job_env(userdata)->last_pass;
        int r = sd_bus_message_open_container(reply, 'r', "ttssa{su}");
        if (r >= 0)
                r = sd_bus_message_append(reply, "ttss", p->started_us, p->duration_us,
                                          p->started_us == 0 ? "" : p->boot ? "boot" : "call", p->result);
        if (r >= 0)
                r = sd_bus_message_open_container(reply, 'a', "{su}");
        for (unsigned k = 0; r >= 0 && p->started_us != 0 && k <= LSS_OUTCOME_FAILED; k++)
                r = sd_bus_message_append(reply, "{su}", lss_outcome_name((enum lss_outcome_kind) k), p->counts[k]);
        if (r >= 0)
                r = sd_bus_message_close_container(reply);
        if (r >= 0)
                r = sd_bus_message_close_container(reply);
        return r;
}

static int property_get_foreign_master(sd_bus *bus, const char *path, const char *interface, const char *property,
                                       sd_bus_message *reply, void *userdata, sd_bus_error *error) {
        lssd_bus_foreign f;
        lssd_bus_foreign_get(userdata, &f);
        return sd_bus_message_append(reply, "(btts)", f.active, f.since_us, f.last_us, f.frame);
}

static int property_get_queue_length(sd_bus *bus, const char *path, const char *interface, const char *property,
                                     sd_bus_message *reply, void *userdata, sd_bus_error *error) {
        const lssd_bus *b = userdata;
        return sd_bus_message_append(reply, "u", (uint32_t) lssd_bus_queue_length(b));
}

/* Authorize, then lssd_bus_queue_job(). While polkit is asked the job is
 * dropped: the call comes again with the answer and makes it anew. */
static int submit(lssd_bus *b, sd_bus_message *m, lssd_job *j, lssd_action action, bool raw, sd_bus_error *error) {
        int r = lssd_auth_check(lssd_bus_auth(b), m, action, error);
        if (r != 0) {
                lssd_job_free(j);
                return r;
        }
        return lssd_bus_queue_job(b, m, j, raw, error);
}

/* Cancel needs the action of the job it cancels. */
static lssd_action job_action(lssd_job_type type) {
        switch (type) {
        case LSSD_JOB_SCAN:
                return LSSD_ACTION_SCAN;
        case LSSD_JOB_SET_BITRATE:
                return LSSD_ACTION_SET_BITRATE;
        case LSSD_JOB_RAW:
        case LSSD_JOB_EXECUTE:
                return LSSD_ACTION_RAW;
        default:
                return LSSD_ACTION_ASSIGN;
        }
}

static int method_scan(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        lssd_bus *b = userdata;
        lssd_scan_options o;
        lssd_job *j;
        int r;

        r = lssd_scan_options_read(m, &o, error);
        if (r < 0)
                return r;

        r = lssd_job_new(LSSD_JOB_SCAN, m, &j);
        if (r < 0)
                return r;
        j->scan_sdo = o.sdo;
        for (size_t i = 0; r >= 0 && i < lssd_bus_config_of(b)->n_devices; i++)
                r = lssd_job_add_pair(j, lssd_bus_config_of(b)->devices[i].identity.vendor, lssd_bus_config_of(b)->devices[i].identity.product);
        if (r >= 0 && o.has_vendor)
                r = lssd_job_add_pair(j, o.vendor, o.product);
        if (r < 0) {
                lssd_job_free(j);
                return r;
        }
        return submit(b, m, j, LSSD_ACTION_SCAN, false, error);
}

static int method_assign_node_id(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        lssd_bus *b = userdata;
        lss_identity id;
        lssd_assign_options o;
        uint8_t node_id;
        int r;

        r = sd_bus_message_read(m, "uuuuy", &id.vendor, &id.product, &id.revision, &id.serial, &node_id);
        if (r < 0)
                return r;
        r = lssd_validate_node_id("node_id", node_id, error);
        if (r < 0)
                return r;
        r = lssd_assign_options_read(m, &o, error);
        if (r < 0)
                return r;

        return lssd_bus_method_assign(b, m, &id, node_id, &o, error);
}

int lssd_bus_method_assign(lssd_bus *b, sd_bus_message *m, const lss_identity *id, uint8_t node_id,
                           const lssd_assign_options *o, sd_bus_error *error) {
        lssd_job *j;
        int r;

        r = lssd_auth_check(lssd_bus_auth(b), m, LSSD_ACTION_ASSIGN, error);
        if (r != 0)
                return r;
        /* never give a node-ID another device answers to; the job looks again, and probes */
        if (!o->force && lssd_devices_with_node_id(lssd_bus_devices(b), node_id, id))
                return lssd_taken_error(lssd_bus_job_env(b), error, node_id, id, NULL);

        r = lssd_job_new(LSSD_JOB_ASSIGN, m, &j);
        if (r < 0)
                return r;
        j->identity = *id;
        j->node_id = node_id;
        j->assign = *o;
        return lssd_bus_queue_job(b, m, j, false, error);
}

/* The same rules as AssignNodeId: authorized, then queued as a job */
static int method_unassign_node_id(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        lssd_bus *b = userdata;
        lss_identity id;
        lssd_unassign_options o;
        lssd_job *j;
        int r;

        r = sd_bus_message_read(m, "uuuu", &id.vendor, &id.product, &id.revision, &id.serial);
        if (r < 0)
                return r;
        r = lssd_unassign_options_read(m, &o, error);
        if (r < 0)
                return r;

        r = lssd_job_new(LSSD_JOB_UNASSIGN, m, &j);
        if (r < 0)
                return r;
        j->identity = id;
        j->unassign = o;
        return submit(b, m, j, LSSD_ACTION_ASSIGN, false, error);
}

static int method_auto_assign(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        lssd_bus *b = userdata;
        lssd_autoassign_options o;
        lssd_job *j;
        int r;

        r = lssd_autoassign_options_read(m, &o, error);
        if (r < 0)
                return r;

        r = lssd_job_new(LSSD_JOB_AUTO_ASSIGN, m, &j);
        if (r < 0)
                return r;
        r = lssd_job_set_plan(j, lssd_bus_config_of(b));
        if (r < 0) {
                lssd_job_free(j);
                return r;
        }
        if (o.has_store)
                j->plan.store = o.store;
        if (o.has_nmt_stop)
                j->plan.nmt_stop = o.nmt_stop;
        j->plan.dry_run = o.dry_run;
        return submit(b, m, j, LSSD_ACTION_ASSIGN, false, error);
}

static int method_set_bitrate(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        lssd_bus *b = userdata;
        uint32_t bitrate;
        uint16_t delay;
        int r;

        r = sd_bus_message_read(m, "uq", &bitrate, &delay);
        if (r < 0)
                return r;
        r = lssd_validate_bitrate("bitrate", bitrate, error);
        if (r < 0)
                return r;
        if (delay < LSSD_SWITCH_DELAY_MIN_MS || delay > LSSD_SWITCH_DELAY_MAX_MS)
                return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS,
                                         "Invalid switch_delay_ms %u: must be %u..%u (the host interface is "
                                         "retuned inside the first delay period)",
                                         delay, LSSD_SWITCH_DELAY_MIN_MS, LSSD_SWITCH_DELAY_MAX_MS);
        return lssd_bitrate_method(b, m, bitrate, delay, error);
}

static int method_cancel(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        lssd_bus *b = userdata;
        int r;

        if (!lssd_bus_running_job(b) || lssd_bus_running_job(b)->type == LSSD_JOB_RESET) /* nothing to cancel */
                return sd_bus_reply_method_return(m, NULL);
        r = lssd_auth_check(lssd_bus_auth(b), m, job_action(lssd_bus_running_job(b)->type), error);
        if (r != 0)
                return r;
        r = lssd_bus_cancel(b, sd_bus_message_get_sender(m), error);
        if (r < 0)
                return r;
        return sd_bus_reply_method_return(m, NULL);
}

static int method_acquire(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        lssd_bus *b = userdata;
        const char *sender = sd_bus_message_get_sender(m);
        int r;

        if (lssd_bus_holder(b) && sender && strcmp(lssd_bus_holder(b), sender) == 0)
                return sd_bus_reply_method_return(m, NULL);
        r = lssd_auth_check(lssd_bus_auth(b), m, LSSD_ACTION_RAW, error);
        if (r != 0)
                return r;
        r = lssd_bus_acquire(b, m, error);
        if (r < 0)
                return r;
        return sd_bus_reply_method_return(m, NULL);
}

static int method_release(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        lssd_bus *b = userdata;
        int r;

        if (!lssd_bus_holder(b))
                return sd_bus_reply_method_return(m, NULL);
        r = lssd_auth_check(lssd_bus_auth(b), m, LSSD_ACTION_RAW, error);
        if (r != 0)
                return r;
        r = lssd_bus_release(b, sd_bus_message_get_sender(m), error);
        if (r < 0)
                return r;
        return sd_bus_reply_method_return(m, NULL);
}

/* Every raw service: the member name says which. */
static int method_raw(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        lssd_bus *b = userdata;
        lssd_raw_step step;
        lssd_job *j;
        int r, op;

        op = lssd_raw_op_from_string(sd_bus_message_get_member(m));
        if (op < 0)
                return -EINVAL;
        r = lssd_raw_step_read_args(m, (lssd_raw_op) op, &step, error);
        if (r < 0)
                return r;

        r = lssd_job_new(LSSD_JOB_RAW, m, &j);
        if (r < 0)
                return r;
        j->steps = malloc(sizeof(*j->steps));
        if (!j->steps) {
                lssd_job_free(j);
                return -ENOMEM;
        }
        j->steps[0] = step;
        j->n_steps = 1;
        return submit(b, m, j, LSSD_ACTION_RAW, true, error);
}

static int method_execute(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        lssd_bus *b = userdata;
        lssd_raw_step *steps = NULL;
        size_t n = 0;
        lssd_job *j;
        int r;

        r = lssd_execute_steps_read(m, &steps, &n, error);
        if (r < 0)
                return r;
        if (n == 0) { /* nothing to run, nothing sent */
                free(steps);
                return sd_bus_reply_method_return(m, "av", 0);
        }

        r = lssd_job_new(LSSD_JOB_EXECUTE, m, &j);
        if (r < 0) {
                free(steps);
                return r;
        }
        j->steps = steps;
        j->n_steps = n;
        return submit(b, m, j, LSSD_ACTION_RAW, false, error);
}

const sd_bus_vtable lssd_bus_vtable[] = {
        SD_BUS_VTABLE_START(0),

        SD_BUS_PROPERTY("Interface", "s", property_get_interface, 0, SD_BUS_VTABLE_PROPERTY_CONST),
        SD_BUS_PROPERTY("State", "s", property_get_state, 0, SD_BUS_VTABLE_PROPERTY_EMITS_CHANGE),
        SD_BUS_PROPERTY("Bitrate", "u", property_get_bitrate, 0, SD_BUS_VTABLE_PROPERTY_EMITS_CHANGE),
        SD_BUS_PROPERTY("Job", "s", property_get_job, 0, SD_BUS_VTABLE_PROPERTY_EMITS_CHANGE),
        SD_BUS_PROPERTY("Progress", "d", property_get_progress, 0, SD_BUS_VTABLE_PROPERTY_EMITS_CHANGE),
        SD_BUS_PROPERTY("LastPass", "(ttssa{su})", property_get_last_pass, 0, SD_BUS_VTABLE_PROPERTY_EMITS_CHANGE),
        SD_BUS_PROPERTY("QueueLength", "u", property_get_queue_length, 0, SD_BUS_VTABLE_PROPERTY_EMITS_CHANGE),
        SD_BUS_PROPERTY("ForeignMaster", "(btts)", property_get_foreign_master, 0,
                        SD_BUS_VTABLE_PROPERTY_EMITS_CHANGE),

        SD_BUS_METHOD_WITH_ARGS("Scan",
                                SD_BUS_ARGS("a{sv}", options),
                                SD_BUS_RESULT("a(uuuuy)", devices, "as", notes),
                                method_scan, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("AutoAssign",
                                SD_BUS_ARGS("a{sv}", options),
                                SD_BUS_RESULT("a(uuuuyyss)", outcomes, "s", result),
                                method_auto_assign, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("AssignNodeId",
                                SD_BUS_ARGS("u", vendor, "u", product, "u", revision, "u", serial, "y", node_id,
                                            "a{sv}", options),
                                SD_BUS_NO_RESULT,
                                method_assign_node_id, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("UnassignNodeId",
                                SD_BUS_ARGS("u", vendor, "u", product, "u", revision, "u", serial, "a{sv}", options),
                                SD_BUS_RESULT("y", old_node_id, "b", stored, "b", in_effect, "s", message,
                                              "s", warning),
                                method_unassign_node_id, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("SetBitrate",
                                SD_BUS_ARGS("u", bitrate, "q", switch_delay_ms, "a{sv}", options),
                                SD_BUS_RESULT("a(uuuus)", devices),
                                method_set_bitrate, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("Cancel", SD_BUS_NO_ARGS, SD_BUS_NO_RESULT, method_cancel,
                                SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("Acquire", SD_BUS_NO_ARGS, SD_BUS_NO_RESULT, method_acquire,
                                SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("Release", SD_BUS_NO_ARGS, SD_BUS_NO_RESULT, method_release,
                                SD_BUS_VTABLE_UNPRIVILEGED),

        SD_BUS_METHOD_WITH_ARGS("SwitchModeGlobal",
                                SD_BUS_ARGS("y", mode),
                                SD_BUS_NO_RESULT,
                                method_raw, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("SwitchModeSelective",
                                SD_BUS_ARGS("u", vendor, "u", product, "u", revision, "u", serial),
                                SD_BUS_RESULT("b", found),
                                method_raw, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("ConfigureNodeId",
                                SD_BUS_ARGS("y", node_id),
                                SD_BUS_NO_RESULT,
                                method_raw, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("ConfigureBitTiming",
                                SD_BUS_ARGS("y", table, "y", index),
                                SD_BUS_NO_RESULT,
                                method_raw, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("ActivateBitTiming",
                                SD_BUS_ARGS("q", delay_ms),
                                SD_BUS_NO_RESULT,
                                method_raw, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("StoreConfiguration", SD_BUS_NO_ARGS, SD_BUS_NO_RESULT, method_raw,
                                SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("InquireIdentity",
                                SD_BUS_NO_ARGS,
                                SD_BUS_RESULT("(uuuu)", identity),
                                method_raw, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("InquireNodeId",
                                SD_BUS_NO_ARGS,
                                SD_BUS_RESULT("y", node_id),
                                method_raw, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("IdentifyRemoteSlaves",
                                SD_BUS_ARGS("u", vendor, "u", product, "u", rev_lo, "u", rev_hi, "u", serial_lo,
                                            "u", serial_hi),
                                SD_BUS_RESULT("b", found),
                                method_raw, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("IdentifyNonConfigured",
                                SD_BUS_NO_ARGS,
                                SD_BUS_RESULT("b", found),
                                method_raw, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("Fastscan",
                                SD_BUS_ARGS("a{sv}", known),
                                SD_BUS_RESULT("(uuuu)", identity),
                                method_raw, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("Execute",
                                SD_BUS_ARGS("a(sv)", steps),
                                SD_BUS_RESULT("av", results),
                                method_execute, SD_BUS_VTABLE_UNPRIVILEGED),

        SD_BUS_SIGNAL_WITH_ARGS(LSSD_SIGNAL_DEVICE_FOUND, SD_BUS_ARGS("o", device), 0),
        SD_BUS_SIGNAL_WITH_ARGS(LSSD_SIGNAL_NODE_ID_ASSIGNED, SD_BUS_ARGS("o", device, "y", old, "y", new), 0),
        SD_BUS_SIGNAL_WITH_ARGS(LSSD_SIGNAL_UNKNOWN_DEVICE,
                                SD_BUS_ARGS("u", vendor, "u", product, "u", revision, "u", serial), 0),
        SD_BUS_SIGNAL_WITH_ARGS(LSSD_SIGNAL_DEVICE_REPLACED,
                                SD_BUS_ARGS("(uuuu)", old, "(uuuu)", new, "y", node_id), 0),
        SD_BUS_SIGNAL_WITH_ARGS(LSSD_SIGNAL_JOB_FINISHED, SD_BUS_ARGS("s", job, "s", result), 0),

        SD_BUS_VTABLE_END
};
