/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* What each kind of job does, one engine operation at a time, and how it
 * answers its caller. */
#pragma once

#include "daemon/lssd_bus.h"
#include "daemon/lssd_job.h"

/* Begins a job (r == NULL) or continues it after its engine operation ended
 * with result r. Returns 1 when another engine operation was started, 0 when
 * the job is over: its reply is sent and j->result says how it ended. */
int lssd_job_run(lssd_bus *b, lssd_job *j, const lss_result *r);

/* Starts stage j->stage of a scan: 0 the fastscan enumeration, then one
 * slowscan per vendor/product pair of j->pairs. Negative errno on failure. */
int lssd_scan_stage_start(lssd_bus *b, const lssd_job *j);

/* The engine confirmed a device during a scan job's stage
 * (lss_master_set_found): its device object is created or updated and
 * DeviceFound (and UnknownDevice) sent now, once per device and job. */
void lssd_scan_found(lssd_bus *b, lssd_job *j, const lss_device *f);

/* Ends a job that will not run (dropped from the queue) with an error reply. */
void lssd_job_abort(lssd_job *j, const char *error_name, const char *message);
