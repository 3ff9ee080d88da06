/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Calls that start a job on a bus: sent asynchronously and waited for in an
 * event loop, so that a progress bar can follow the bus's Job and Progress
 * properties (on a terminal) and ^C can Cancel() the job before lssctl
 * exits with 130. */
#pragma once

#include <stdbool.h>
#include <systemd/sd-bus.h>
#include <systemd/sd-event.h>

#include "ctl/ctl.h"

typedef struct ctl_runner ctl_runner;

/* Takes SIGINT and SIGTERM over (blocked, read from the event loop) until
 * ctl_runner_free(). `progress`: draw a bar on stderr. */
int ctl_runner_new(ctl_context *c, bool progress, ctl_runner **ret);
ctl_runner *ctl_runner_free(ctl_runner *run);

/* Sends `m` (a method call on bus object `bus_path`) and waits for the
 * answer. `job` is the name the Job property shows while it runs (for the
 * bar, and to know what ^C may cancel). Returns 0 with *ret_reply, or a
 * negative errno with `error` set (an lssd error), or -EINTR after ^C
 * (the running job was cancelled when it was this one). */
int ctl_runner_call(ctl_runner *run, sd_bus_message *m, const char *bus_path, const char *ifname, const char *job,
                    sd_bus_message **ret_reply, sd_bus_error *error);
