/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Internal to src/config: reading a whole text file (lssd.conf, a DCF),
 * bounded, with the failure named in the diagnostics. */
#pragma once

#include <stddef.h>

#include "config/lssconf_diag.h"

/* Reads path, at most max bytes. 0 and *ret (malloc'ed, not
 * NUL-terminated), *ret_len; a negative errno with an error in diag:
 * "PATH: cannot open: ...", "PATH: larger than MAX bytes, ...",
 * "PATH: cannot read: ..." (-EFBIG when too big); -ENOMEM unreported. */
int lssconf_read_text(const char *path, size_t max, char **ret, size_t *ret_len, lssconf_diag *diag);

/* Text must not hold a NUL byte (a parser would stop reading there): 0, or
 * -EINVAL with "NAME:LINE: NUL byte, this is not a text file" in diag. */
int lssconf_text_check(const char *text, size_t len, const char *name, lssconf_diag *diag);
