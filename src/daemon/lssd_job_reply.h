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
/* Ends a job that will not run (dropped from the queue) with an error reply. */
void lssd_job_abort(lssd_job *j, const char *error_name, const char *message);
/* An engine operation that could not even start (a bug, or out of memory):
 * logs, answers with the errno, result "failed". Returns 0 (the job is over). */
int lssd_job_start_failed(lssd_job_env *e, lssd_job *j, int r);
