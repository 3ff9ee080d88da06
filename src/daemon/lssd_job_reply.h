/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* How a job answers its caller: the deferred reply to the kept request
 * message (nothing for internal jobs), and the error replies every runner
 * shares. Failing to send only means the caller is gone: logged, not fatal. */
#pragma once

#include <systemd/sd-bus.h>

#include "daemon/lssd_job_queue.h"
#include "daemon/lssd_job_env.h"

void lssd_job_reply_error(lssd_job *j, const sd_bus_error *e);
/* Sends `reply` (made from j->request). */
void lssd_job_reply_message(lssd_job *j, sd_bus_message *reply);
void lssd_job_reply_empty(lssd_job *j);
/* Appends a job's outcome to its method return. */
typedef int (*lssd_job_reply_fill)(sd_bus_message *reply, const void *userdata);
/* The reply of a job that succeeded: a method return to j->request filled
 * by `fill`, then sent; one that cannot be built is logged as "the reply
 * of `what`" (the caller then gets none: sd-bus answers when the request
 * is dropped). Nothing for an internal job. */
void lssd_job_reply_done(lssd_job_env *e, lssd_job *j, const char *what, lssd_job_reply_fill fill,
                         const void *userdata);
/* Ends a job that will not run (dropped from the queue) with an error reply. */
void lssd_job_abort(lssd_job *j, const char *error_name, const char *message);
/* An engine operation that could not even start (a bug, or out of memory):
 * logs, answers with the errno, result "failed". Returns 0 (the job is over). */
int lssd_job_start_failed(lssd_job_env *e, lssd_job *j, int r);
