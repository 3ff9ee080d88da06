/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Pieces of output the verbs share. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ctl/ctl_json.h"
#include "ctl/ctl_table.h"

/* Colour of a device State for tables; NULL for none. */
const char *ctl_device_state_color(const char *state);
/* Local time of a LastSeen value, "never" for 0. */
void ctl_format_time(uint64_t usec, char *buf, size_t size);
/* "vendor", "product", "revision", "serial" keys. */
void ctl_json_identity(ctl_json *j, const uint32_t id[4]);
/* Four cells, 0x%08x each. */
void ctl_table_identity(ctl_table *t, const uint32_t id[4]);
/* The same, with "-" for a revision that is not known (RevisionKnown false). */
void ctl_table_identity_full(ctl_table *t, const uint32_t id[4], bool revision_known);
