/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* What each kind of job does, one engine operation at a time, and how it
 * answers its caller. */
#pragma once

#include "daemon/lssd_job.h"
#include "daemon/lssd_job_env.h"

/* The runner of each kind of job (see lssd_job_run(), lssd_job_runners.h);
 * SET_BITRATE's is lssd_bitrate_run(). */
int lssd_run_reset(lssd_job_env *e, lssd_job *j, const lss_result *r);
int lssd_run_scan(lssd_job_env *e, lssd_job *j, const lss_result *r);
int lssd_run_assign(lssd_job_env *e, lssd_job *j, const lss_result *r);
int lssd_run_unassign(lssd_job_env *e, lssd_job *j, const lss_result *r);
int lssd_run_raw(lssd_job_env *e, lssd_job *j, const lss_result *r);
int lssd_run_execute(lssd_job_env *e, lssd_job *j, const lss_result *r);
int lssd_run_autoassign(lssd_job_env *e, lssd_job *j, const lss_result *r);

/* Starts stage j->stage of a scan: 0 the fastscan enumeration, then one
 * slowscan per vendor/product pair of j->pairs. Negative errno on failure. */
int lssd_scan_stage_start(lssd_job_env *e, const lssd_job *j);

/* The engine confirmed a device during a scan job's stage
 * (lss_master_set_found): its device object is created or updated and
 * DeviceFound (and UnknownDevice) sent now, once per device and job. */
void lssd_scan_found(lssd_job_env *e, lssd_job *j, const lss_device *f);

/* Ends a job that will not run (dropped from the queue) with an error reply. */
void lssd_job_abort(lssd_job *j, const char *error_name, const char *message);
