/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The one entry the bus drives its jobs through: which runner a job has. The
 * runners see the bus only as a lssd_job_env. */
#pragma once

#include "daemon/lssd_job.h"
#include "daemon/lssd_job_env.h"

/* Begins a job (r == NULL) or continues it after its engine operation ended
 * with result r. Returns 1 when another engine operation was started, 0 when
 * the job is over: its reply is sent and j->result says how it ended. */
int lssd_job_run(lssd_job_env *e, lssd_job *j, const lss_result *r);
