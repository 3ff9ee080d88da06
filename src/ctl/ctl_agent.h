/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The polkit text agent, as hostnamectl starts it: before a command that
 * lssd asks polkit about, pkttyagent is started for lssctl's process, on
 * the terminal, so that an administrator can authenticate there (lssd(8),
 * AUTHORIZATION). Not for root (never asked), without a terminal on stdin
 * or a controlling one, or where polkit is not installed; --no-ask-password
 * leaves it out. */
#pragma once

#include <stdbool.h>

#define CTL_POLKIT_AGENT "/usr/bin/pkttyagent"
#define CTL_AGENT_WAIT_MS 10000 /* for the agent to register */

/* 1: started and registered (or given up on after CTL_AGENT_WAIT_MS);
 * 0: not needed; <0: could not start it (a negative errno). */
int ctl_agent_open(void);
/* Whether an agent runs: it may prompt on the terminal any moment. */
bool ctl_agent_running(void);
/* Stops the agent, if one was started. */
void ctl_agent_close(void);
