/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The frame loss an operation saw, and how often a question must then be
 * asked before its silence means "nobody" (docs/engine.md, "Frame loss is
 * never a silent miss"). A scan ends with a question ("is anybody left?")
 * whose silence is taken for an answer; on a bus that loses frames one
 * slave's answer may be lost each time it is asked. The evidence is the
 * operation's own: asks that went unanswered before one just like them was
 * answered (so somebody was there), and frames the transport dropped. */
#pragma once

#include <stdint.h>

typedef struct lss_loss {
        uint64_t frames; /* of the asks answered in the end, and of the silent ones before them, each with its answer */
        uint64_t lost;   /* those silent asks, and the frames the transport dropped */
} lss_loss;

/* An ask of `n_tx` request frames answered after `silent` unanswered ones. */
void lss_loss_answered(lss_loss *l, unsigned silent, unsigned n_tx);
/* The transport dropped received frames (SO_RXQ_OVFL). */
void lss_loss_rx_lost(lss_loss *l);
/* How many times a question of `n_tx` request frames is asked before its
 * silence is believed: `base` while the operation lost nothing, else
 * enough that one slave's answer lost every time is improbable (below
 * LSS_LOSS_MISS_PPM), at most LSS_LOSS_ASKS_MAX. */
unsigned lss_loss_asks(const lss_loss *l, unsigned n_tx, unsigned base);

#define LSS_LOSS_MISS_PPM 1u
#define LSS_LOSS_ASKS_MAX 16u
