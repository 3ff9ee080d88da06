/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <string.h>

#include "daemon/lssd_unstored.h"

void lssd_unstored_open(lssd_unstored *u, uint64_t now) {
        u->from = now;
        u->until = now + LSSD_UNSTORED_WINDOW_US;
}

void lssd_unstored_note(lssd_unstored *u, const lss_frame *f, uint64_t rx) {
        uint8_t node, state;
        /* NMT state 0 is a boot-up, any other a heartbeat */
        if (rx >= u->from && rx <= u->until && bootup_decode(f, &node, &state) && state == 0)
                u->ids[node] = true;
}

const bool *lssd_unstored_table(const lssd_unstored *u) {
        return u->ids;
}

void lssd_unstored_forget(lssd_unstored *u) {
        memset(u->ids, 0, sizeof(u->ids));
}
