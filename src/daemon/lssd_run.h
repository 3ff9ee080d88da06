/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The job runners: what each kind of job does, one engine operation at a
 * time, and how it answers its caller (lssd_run_<kind>.c, one file per kind;
 * lssd_run.c picks the runner). They see the bus only as a lssd_job_env. */
#pragma once

#include "daemon/lssd_job_queue.h"
#include "daemon/lssd_job_env.h"

/* Begins a job (r == NULL) or continues it after its engine operation ended
 * with result r. Returns 1 when another engine operation was started, 0 when
 * the job is over: its reply is sent and j->result says how it ended. */
int lssd_job_run(lssd_job_env *e, lssd_job *j, const lss_result *r);

/* What an assignment says of a device that holds its new node-ID but did not
 * boot up with it (lss_result.pending_reset): the journal's and the reply's words. */
#define LSSD_PENDING_RESET_TEXT "in effect after the device's next reset (it did not boot up with it)"

/* The runner of each kind of job, as lssd_job_run(). */
int lssd_run_reset(lssd_job_env *e, lssd_job *j, const lss_result *r);
/* 255 back to the slaves in j->aside (lss_master_give_back), lssd_run_raw.c */
int lssd_run_give_back(lssd_job_env *e, lssd_job *j, const lss_result *r);
int lssd_run_scan(lssd_job_env *e, lssd_job *j, const lss_result *r);
int lssd_run_assign(lssd_job_env *e, lssd_job *j, const lss_result *r);
int lssd_run_unassign(lssd_job_env *e, lssd_job *j, const lss_result *r);
int lssd_run_raw(lssd_job_env *e, lssd_job *j, const lss_result *r);
int lssd_run_execute(lssd_job_env *e, lssd_job *j, const lss_result *r);
int lssd_run_autoassign(lssd_job_env *e, lssd_job *j, const lss_result *r);
/* SetBitrate(), lssd_run_bitrate.c (see lssd_bitrate.h) */
int lssd_run_bitrate(lssd_job_env *e, lssd_job *j, const lss_result *r);

/* The stages that find the devices of a bus, shared by Scan and SetBitrate
 * (lssd_run_discover.c): 0 fastscan enumeration, 1..n_pairs slowscan of
 * j->pairs, then with j->scan_sdo the SDO discovery (lssd_discover_sdo_stage)
 * and the LSS confirmation of what SDO alone found (_confirm_stage). */
unsigned lssd_discover_n_stages(const lssd_job *j);
unsigned lssd_discover_sdo_stage(const lssd_job *j);
unsigned lssd_discover_confirm_stage(const lssd_job *j);
/* The part of a Scan (LSSD_SCAN_PART_*) stage j->stage belongs to. */
unsigned lssd_discover_part(const lssd_job *j);
/* Starts stage j->stage. Negative errno on failure. */
int lssd_discover_start(lssd_job_env *e, const lssd_job *j);
/* Stage j->stage ended with r: its devices join j->found (SDO's complete
 * identities by SDO, those not found by LSS to confirm). Negative errno:
 * out of memory. */
int lssd_discover_take(lssd_job_env *e, lssd_job *j, const lss_result *r);
/* Whether stage j->stage (just ended) has a successor to start. */
bool lssd_discover_more(const lssd_job *j);

/* Scan's SDO discovery ended with result r: its complete identities are
 * added to the finds (by SDO), those not found by LSS become j->sdo_cand,
 * and each node-ID that is no device is logged. Negative errno: out of
 * memory. (lssd_run_scan_sdo.c) */
int lssd_scan_take_sdo(lssd_job_env *e, lssd_job *j, const lss_result *r);

/* A Scan's progress 0..1 while its stage j->stage is at p: stages weighted
 * by the time they take (lssd_scan_progress.c). */
double lssd_scan_progress(const lssd_job_env *e, const lssd_job *j, double p);

/* How many devices an enumeration will likely find: the non-configured
 * devices seen before; 0 when none (or not known). */
unsigned lssd_run_expected_finds(const lssd_job_env *e);
/* Tells the engine that count (for its progress). */
void lssd_run_expect_finds(lssd_job_env *e);

/* The engine confirmed a device during a scan job's stage
 * (lss_master_set_found): its device object is created or updated and
 * DeviceFound (and UnknownDevice) sent now, once per device and job. */
void lssd_scan_found(lssd_job_env *e, lssd_job *j, const lss_device *f);
