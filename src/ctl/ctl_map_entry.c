/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <inttypes.h>
#include <stdio.h>
#include <string.h>

#include "ctl/ctl_map_entry.h"

void ctl_print_map_entry(const uint32_t id[4], bool revision_known, uint8_t node_id, bool active, bool comma) {
        printf("      %s{ vendor = 0x%08" PRIx32 "; product = 0x%08" PRIx32 "; ", active ? "" : "# ", id[0], id[1]);
        if (revision_known)
                printf("revision = 0x%08" PRIx32 "; ", id[2]);
        printf("serial = 0x%08" PRIx32 "; node_id = ", id[3]);
        if (node_id >= 1 && node_id <= 127)
                printf("%u; }", node_id);
        else
                printf("N; }");
        if (comma)
                putchar(',');
}

void ctl_print_replacement(const char *ifname, const uint32_t id[4], uint8_t node_id, const char *outcome,
                           const char *detail) {
        bool dry = strcmp(outcome, "would-replace") == 0;
        if (!dry && strcmp(outcome, "replaced") != 0)
                return;
        printf("\n%s: device 0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 " %s at node-ID %u.\n"
               "%s the map entry of the missing device in lssd.conf(5) by:\n",
               ifname, id[0], id[1], id[2], id[3], detail, node_id, dry ? "After the pass, replace" : "Replace");
        ctl_print_map_entry(id, true, node_id, true, false);
        putchar('\n');
}
