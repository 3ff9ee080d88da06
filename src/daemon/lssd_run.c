/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include "daemon/lssd_job_reply.h"
#include "daemon/lssd_run.h"

int lssd_job_run(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        switch (j->type) {
        case LSSD_JOB_RESET:
                return lssd_run_reset(e, j, r);
        case LSSD_JOB_SCAN:
                return lssd_run_scan(e, j, r);
        case LSSD_JOB_ASSIGN:
                return lssd_run_assign(e, j, r);
        case LSSD_JOB_RAW:
                return lssd_run_raw(e, j, r);
        case LSSD_JOB_EXECUTE:
                return lssd_run_execute(e, j, r);
        case LSSD_JOB_AUTO_ASSIGN:
                return lssd_run_autoassign(e, j, r);
        case LSSD_JOB_SET_BITRATE:
                return lssd_run_bitrate(e, j, r);
        case LSSD_JOB_UNASSIGN:
                return lssd_run_unassign(e, j, r);
        case LSSD_JOB_GIVE_BACK:
                return lssd_run_give_back(e, j, r);
        default:
                lssd_job_abort(j, SD_BUS_ERROR_FAILED, "Unknown job type");
                return 0;
        }
}
