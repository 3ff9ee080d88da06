/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Internal to src/config: a bus's `dcf` patterns, expanded and read into
 * its map after the entries of its `devices` (config/dcf.h). */
#pragma once

#include "config/lssconf.h"
#include "config/lssconf_check.h"

/* Reads the DCFs src->dcf names (relative patterns in dir; dir NULL: none
 * is read, a warning says so) and appends their entries to b->devices
 * (and src->devices), each with its source in c->sources. Entries the same
 * as one of `devices` are that entry; conflicts with it, errors in a DCF, a
 * pattern without '*', '?' or '[' naming no file, and node-IDs in the pool
 * are errors; devices left out, a pattern matching no file and a Baudrate
 * other than the bus's are warnings. name is the configuration file.
 * Returns 0 or -ENOMEM. */
int lssconf_read_bus_dcfs(const char *name, const char *dir, size_t bus_index, lssconf *c, lssconf_bus *b,
                          lssconf_bus_src *src, lssconf_diag *diag);
