/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Which echo of our own frames confirms the running engine step (tx
 * confirmation, lss_master_set_tx_confirm()), for every driver of the
 * engine over a transport that echoes (lssd's bus, lss-vcan-master).
 *
 * Only the echo of the last LSS request written confirms the step; the
 * echo of an older, identical request (a retry) is told apart by its time:
 * it was received before the last write. A receive time may read up to the
 * clock conversion's error early (socketcan.c, rx_time()), hence the slack. */
#pragma once

#include <stdbool.h>
#include <stdint.h>

#include "lss/lss_proto.h"

/* How much earlier than its write an echo may read. */
#define LSS_TX_ECHO_CLOCK_SLACK_US 1000u

typedef struct lss_tx_echo {
        lss_frame want;         /* the last LSS request written */
        uint64_t written_at;    /* the time taken just before its write */
        bool pending;
} lss_tx_echo;

/* `f` was written at `t`: an LSS request becomes the one to confirm. */
void lss_tx_echo_written(lss_tx_echo *e, const lss_frame *f, uint64_t t);
/* An echo received at `rx`: true when it confirms the last request (once:
 * it is no longer pending). */
bool lss_tx_echo_confirms(lss_tx_echo *e, const lss_frame *f, uint64_t rx);
/* A new socket: what the old one would have echoed never comes. */
void lss_tx_echo_forget(lss_tx_echo *e);
