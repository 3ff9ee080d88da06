/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Internal to src/config: a lexical pass over the file before libconfig
 * sees it.
 *
 * libconfig 1.5 (Debian 12) truncates integer literals silently: a decimal
 * beyond int32 is stored as a wrapped int (4294967295 reads as -1, 4294967296
 * as 0) and a hex literal beyond 32 bits too (0x1FFFFFFFF reads as
 * 0xFFFFFFFF). Nothing in the parsed tree tells these apart from honest
 * values, so this pass finds such literals and appends the `L` suffix, which
 * makes libconfig store them as exact int64 values; later range checks then
 * see the real number. Literals beyond 64 bits are errors here. Insertions
 * never add lines, so libconfig's line numbers stay right.
 *
 * It also refuses NUL bytes (libconfig would stop reading at the first one)
 * and `@include` (libconfig would open other files relative to the cwd), and
 * finds a block comment left open, which libconfig silently takes to run to
 * the end of the file. */
#pragma once

#include <stddef.h>

#include "config/lssconf_diag.h"

/* On success *ret is a new NUL-terminated copy of text, possibly with
 * suffixes added, and *ret_open_comment_line the line of a comment left open
 * (0 if none; the caller reports it unless libconfig finds an earlier
 * syntax error). -EINVAL with errors in diag, -ENOMEM. */
int lssconf_prescan(const char *text, size_t len, const char *name, lssconf_diag *diag,
                        char **ret, unsigned *ret_open_comment_line);
