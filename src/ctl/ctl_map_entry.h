/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Devices as map entries of lssd.conf(5): scan --as-config, and the entry
 * auto-assign says to put in for a device that replaced a missing one. */
#pragma once

#include <stdbool.h>
#include <stdint.h>

/* One entry line (no newline), 0x%08x as lssd.conf(5) shows them; node_id
 * outside 1..127 is written N; commented out unless active; no revision
 * when it is not known (a map entry without one). */
void ctl_print_map_entry(const uint32_t id[4], bool revision_known, uint8_t node_id, bool active, bool comma);

/* auto-assign: outcome "replaced" or "would-replace" (else nothing): what
 * it replaced (the reply's detail) and the map entry that replaces the old one. */
void ctl_print_replacement(const char *ifname, const uint32_t id[4], uint8_t node_id, const char *outcome,
                           const char *detail);
