/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include "lss/lss_loss.h"

void lss_loss_answered(lss_loss *l, unsigned silent, unsigned n_tx) {
        l->frames += (uint64_t) (silent + 1u) * (n_tx + 1u);
        l->lost += silent;
}

void lss_loss_rx_lost(lss_loss *l) {
        l->lost++;
}

unsigned lss_loss_asks(const lss_loss *l, unsigned n_tx, unsigned base) {
        if (l->lost == 0)
                return base;
        /* A silent ask is mostly one frame lost of its request and answer:
         * lost / frames is the loss per frame. One more loss than seen,
         * so that a few asks do not make it look small. */
        double p = (double) (l->lost + 1u) / (double) (l->frames + 1u);
        double q = p * (n_tx + 1u); /* one question unanswered */
        if (q > 0.5)
                q = 0.5;
        unsigned k = 1;
        for (double miss = q; miss * 1e6 > LSS_LOSS_MISS_PPM && k < LSS_LOSS_ASKS_MAX; miss *= q)
                k++;
        return k > base ? k : base;
}
