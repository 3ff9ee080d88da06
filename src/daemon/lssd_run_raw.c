/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <stdio.h>
#include <string.h>

#include "daemon/lssd_errors.h"
#include "daemon/lssd_job_reply.h"
#include "daemon/lssd_run.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_taken.h"

/* ---- Reset: switch-global waiting ---- */

int lssd_run_reset(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        if (!r) {
                int k = lss_master_switch_global(e->engine, LSS_MODE_WAITING, lssd_job_env_now(e));
                if (k >= 0)
                        lssd_unstored_open(&e->unstored, lssd_job_env_now(e));
                return k < 0 ? lssd_job_start_failed(e, j, k) : 1;
        }
        j->result = lssd_status_to_result(r->status);
        if (r->status != LSS_OK)
                log_warning("%s: could not switch the slaves to waiting: %s", e->ifname,
                            r->message[0] ? r->message : lssd_status_to_result(r->status));
        else
                log_debug("%s: all slaves switched to waiting", e->ifname);
        return 0;
}

/* ---- GiveBack: 255 to the slaves a broken-off enumeration set aside ---- */

int lssd_run_give_back(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        char ident[40];
        if (!r) {
                log_notice("%s: giving node-ID 255 back to %zu slave%s that a job broken off by another LSS master "
                           "left with a temporary node-ID", e->ifname, j->n_aside, j->n_aside == 1 ? "" : "s");
                int k = lss_master_give_back(e->engine, j->aside, j->n_aside, lssd_job_env_now(e));
                return k < 0 ? lssd_job_start_failed(e, j, k) : 1;
        }
        j->result = lssd_status_to_result(r->status);
        for (size_t i = 0; i < r->n_devices; i++)
                lssd_log_device(LOG_INFO, e->ifname, &r->devices[i].id, r->devices[i].node_id,
                                "%s: device %s: temporary node-ID %u given back, node-ID %u now", e->ifname,
                                lssd_identity_format(&r->devices[i].id, ident, sizeof(ident)),
                                r->devices[i].aside_node_id, r->devices[i].node_id);
        if (r->status != LSS_OK)
                log_warning("%s: could not give every slave its node-ID 255 back: %s", e->ifname,
                            r->message[0] ? r->message : lssd_status_to_result(r->status));
        return 0;
}

/* ---- raw services of the holder ---- */

static bool sender_holds(lssd_job_env *e, const lssd_job *j) {
        const char *holder = e->ops->holder(e->userdata);
        return holder && j->sender && strcmp(holder, j->sender) == 0;
}

typedef struct raw_outcome {
        const lssd_raw_step *step;
        const lss_result *result;
} raw_outcome;

static int fill_raw(sd_bus_message *reply, const void *userdata) {
        const raw_outcome *o = userdata;
        return lssd_raw_step_append_result(o->step, o->result, reply, false);
}

int lssd_run_raw(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        const lssd_raw_step *s = &j->steps[0];
        char what[96];

        if (!r) {
                /* queued while held, but the holder let go before its turn */
                if (!sender_holds(e, j)) {
                        lssd_job_abort(j, LSSD_ERROR_CANCELLED, "The bus was released before this call ran");
                        return 0;
                }
                lssd_taken_check(e, true);
                int k = lssd_raw_step_start(s, e->engine, lssd_job_env_now(e));
                return k < 0 ? lssd_job_start_failed(e, j, k) : 1;
        }

        lssd_raw_step_describe(s, what, sizeof(what));
        if (!lssd_raw_step_succeeded(s, r)) {
                sd_bus_error err = SD_BUS_ERROR_NULL;
                if (r->in_use)
                        lssd_taken_error(e, &err, s->node_id, NULL, NULL);
                else
                        lssd_raw_step_error(s, r, NULL, &err);
                log_info("%s: %s by %s: %s", e->ifname, what, j->sender ? j->sender : "?", err.message);
                lssd_job_reply_error(j, &err);
                sd_bus_error_free(&err);
                j->result = lssd_status_to_result(r->status);
                return 0;
        }

        log_info("%s: %s by %s: done", e->ifname, what, j->sender ? j->sender : "?");
        j->result = "done";
        const raw_outcome o = { s, r };
        lssd_job_reply_done(e, j, what, fill_raw, &o);
        return 0;
}

/* ---- Execute: steps, then always switch-global waiting ---- */

static int execute_start_stage(lssd_job_env *e, lssd_job *j) {
        uint64_t now = lssd_job_env_now(e);
        int k;
        if (j->stage < j->n_steps) {
                lssd_taken_check(e, true);
                k = lssd_raw_step_start(&j->steps[j->stage], e->engine, now);
        } else
                k = lss_master_switch_global(e->engine, LSS_MODE_WAITING, now);
        return k < 0 ? lssd_job_start_failed(e, j, k) : 1;
}

int lssd_run_execute(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        int k;

        if (!r) {
                j->n_stages = (unsigned) j->n_steps + 1;
                if (j->request) {
                        k = sd_bus_message_new_method_return(j->request, &j->reply);
                        if (k >= 0)
                                k = sd_bus_message_open_container(j->reply, 'a', "v");
                        if (k < 0)
                                return lssd_job_start_failed(e, j, k);
                }
                return execute_start_stage(e, j);
        }

        if (j->stage < j->n_steps) {
                const lssd_raw_step *s = &j->steps[j->stage];
                if (lssd_raw_step_succeeded(s, r)) {
                        if (j->reply) {
                                k = lssd_raw_step_append_result(s, r, j->reply, true);
                                if (k < 0)
                                        sd_bus_error_set_errno(&j->error, k);
                        }
                        j->stage++;
                } else {
                        char prefix[64];
                        snprintf(prefix, sizeof(prefix), "steps[%u] (%s): ", j->stage,
                                 lssd_raw_op_to_string(s->op));
                        if (r->in_use)
                                lssd_taken_error(e, &j->error, s->node_id, NULL, prefix);
                        else
                                lssd_raw_step_error(s, r, prefix, &j->error);
                        j->result = lssd_status_to_result(r->status);
                        j->stage = (unsigned) j->n_steps; /* straight to the final switch */
                }
                if (sd_bus_error_is_set(&j->error))
                        j->stage = (unsigned) j->n_steps;
                return execute_start_stage(e, j);
        }

        /* the final switch to waiting is done */
        if (!sd_bus_error_is_set(&j->error) && r->status != LSS_OK) {
                lssd_error_from_result(&j->error, r, LSS_SERVICE_NONE,
                                       "Switching the slaves back to waiting failed: ");
                j->result = lssd_status_to_result(r->status);
        }

        if (sd_bus_error_is_set(&j->error)) {
                log_info("%s: Execute (%zu steps) by %s failed: %s", e->ifname, j->n_steps,
                         j->sender ? j->sender : "?", j->error.message);
                lssd_job_reply_error(j, &j->error);
                if (!j->result)
                        j->result = "failed";
                return 0;
        }

        log_info("%s: Execute (%zu steps) by %s: done", e->ifname, j->n_steps, j->sender ? j->sender : "?");
        j->result = "done";
        if (j->reply) {
                k = sd_bus_message_close_container(j->reply);
                if (k >= 0)
                        lssd_job_reply_message(j, j->reply);
                else
                        log_error("%s: failed to build the reply of Execute: %s", e->ifname, strerror(-k));
        }
        return 0;
}
