/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <string.h>

#include "daemon/lssd_errors.h"
#include "daemon/lssd_job_reply.h"
#include "daemon/lssd_log.h"

/* Failing to send a reply only means the caller is gone: log it and go on. */
void lssd_job_reply_error(lssd_job *j, const sd_bus_error *e) {
        if (!j->request)
                return;
        int r = sd_bus_reply_method_error(j->request, e);
        if (r < 0)
                log_debug("Failed to send error reply to %s: %s", j->sender ? j->sender : "?", strerror(-r));
}

void lssd_job_reply_message(lssd_job *j, sd_bus_message *reply) {
        int r = sd_bus_message_send(reply);
        if (r < 0)
                log_debug("Failed to send reply to %s: %s", j->sender ? j->sender : "?", strerror(-r));
}

void lssd_job_reply_done(lssd_job_env *e, lssd_job *j, const char *what, lssd_job_reply_fill fill,
                         const void *userdata) {
        if (!j->request)
                return;
        sd_bus_message *reply = NULL;
        int k = sd_bus_message_new_method_return(j->request, &reply);
        if (k >= 0)
                k = fill(reply, userdata);
        if (k >= 0)
                lssd_job_reply_message(j, reply);
        else
                log_error("%s: failed to build the reply of %s: %s", e->ifname, what, strerror(-k));
        sd_bus_message_unref(reply);
}

void lssd_job_reply_empty(lssd_job *j) {
        if (!j->request)
                return;
        int r = sd_bus_reply_method_return(j->request, NULL);
        if (r < 0)
                log_debug("Failed to send reply to %s: %s", j->sender ? j->sender : "?", strerror(-r));
}

void lssd_job_abort(lssd_job *j, const char *error_name, const char *message) {
        sd_bus_error err = SD_BUS_ERROR_NULL;
        sd_bus_error_set(&err, error_name, message);
        lssd_job_reply_error(j, &err);
        sd_bus_error_free(&err);
        j->result = error_name && strcmp(error_name, LSSD_ERROR_CANCELLED) == 0 ? "cancelled" : "failed";
}

/* An engine operation that could not even start (a bug, or out of memory). */
int lssd_job_start_failed(lssd_job_env *e, lssd_job *j, int r) {
        sd_bus_error err = SD_BUS_ERROR_NULL;
        log_error("%s: failed to start %s: %s", e->ifname, lssd_job_name(j), strerror(-r));
        sd_bus_error_set_errno(&err, r);
        lssd_job_reply_error(j, &err);
        sd_bus_error_free(&err);
        j->result = "failed";
        return 0;
}
