/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Telling systemd how lssd is: STATUS= always, READY=1 once start-up is done
 * and the boot auto-assign passes on buses that are up have ended, and
 * meanwhile EXTEND_TIMEOUT_USEC= as long as those passes make progress, up
 * to LSSD_BOOT_READY_LIMIT_USEC; the journal says "Ready" when READY=1 goes. */
#pragma once

#include <stdbool.h>

#include "daemon/lssd_context.h"

#define LSSD_EXTEND_EVERY_USEC (10u * 1000000u)           /* how often a running pass extends */
#define LSSD_EXTEND_BY_USEC (30u * 1000000u)              /* by how much each time */
/* a bus that is there but down at start holds READY=1 this long (the first extension tick ends it) */
#define LSSD_LINK_GRACE_USEC LSSD_EXTEND_EVERY_USEC
#define LSSD_BOOT_READY_LIMIT_USEC (30ull * 60u * 1000000u) /* READY=1 anyway after this long */

/* The status line (and READY=1 with `ready`). */
void lssd_ready_status(lssd_context *ctx, bool ready);
/* Start-up is done: READY=1 now, or once every boot auto-assign pass on a
 * bus that is up finished or gave up (a bus that is not there does not hold
 * it back: STATUS= says it is waited for; one that is there but down holds it
 * for LSSD_LINK_GRACE_USEC, then no more). */
void lssd_ready_startup_done(lssd_context *ctx);
/* A bus's boot pass ended. */
void lssd_ready_boot_pass_done(lssd_context *ctx);
