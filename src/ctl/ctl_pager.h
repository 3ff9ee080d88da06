/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Output through a pager when stdout is a terminal, as systemd's tools do:
 * $SYSTEMD_PAGER, else $PAGER, else less (with LESS=FRXMK: quits when the
 * text fits), else more. An empty value or "cat" means no pager. */
#pragma once

#include <sys/types.h>

typedef struct ctl_pager {
        pid_t pid;      /* 0: no pager runs */
} ctl_pager;

/* Starts the pager and points stdout at it; does nothing when stdout is
 * not a terminal or no pager is wanted. */
int ctl_pager_open(ctl_pager *p);
/* Flushes stdout, closes the pipe and waits for the pager. */
void ctl_pager_close(ctl_pager *p);
