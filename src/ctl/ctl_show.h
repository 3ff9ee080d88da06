/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Pieces of output the verbs share. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ctl/ctl_json.h"
#include "ctl/ctl_table.h"

/* "vendor", "product", "revision", "serial" keys. */
void ctl_json_identity(ctl_json *j, const uint32_t id[4]);
/* Four cells, 0x%08x each, with "-" for a revision that is not known (RevisionKnown false). */
void ctl_table_identity_full(ctl_table *t, const uint32_t id[4], bool revision_known);
