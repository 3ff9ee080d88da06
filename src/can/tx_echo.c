/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <string.h>

#include "can/tx_echo.h"

void lss_tx_echo_written(lss_tx_echo *e, const lss_frame *f, uint64_t t) {
        if (f->id != LSS_COB_MASTER || f->flags != 0)
                return;
        e->want = *f;
        e->written_at = t;
        e->pending = true;
}

bool lss_tx_echo_confirms(lss_tx_echo *e, const lss_frame *f, uint64_t rx) {
        if (!e->pending || f->id != e->want.id || f->len != e->want.len ||
            memcmp(f->data, e->want.data, sizeof(f->data)) != 0)
                return false;
        if (rx + LSS_TX_ECHO_CLOCK_SLACK_US < e->written_at)
                return false; /* an older identical request's */
        e->pending = false;
        return true;
}

void lss_tx_echo_forget(lss_tx_echo *e) {
        e->pending = false;
}
