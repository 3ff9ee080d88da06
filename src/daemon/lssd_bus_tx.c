/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Writing what the engine hands out without ever blocking the event loop.
 *
 * A frame the transport refuses (-EAGAIN: tx queue full) is held and written
 * again from a 1 ms timer (POLLOUT does not reflect the device queue that
 * said ENOBUFS); the frames behind it stay in the engine's own queue, so
 * nothing is reordered or dropped. While a frame is held this bus stands
 * still as it did behind the blocking write it replaces (the engine hears
 * no time and no frames, no job ends or starts), and every other bus and
 * D-Bus caller is served. A held frame still refused after LSSD_TX_TIMEOUT_MS
 * ends the running operation. */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "daemon/lssd_bus_private.h"
#include "daemon/lssd_log.h"

#define TX_RETRY_US 1000u

bool bus_tx_pending(const lssd_bus *b) {
        return b->tx_held;
}

static int on_tx_retry(sd_event_source *s, uint64_t usec, void *userdata) {
        bus_process(userdata);
        return 0;
}

int bus_tx_init(lssd_bus *b) {
        int r = sd_event_add_time(b->host.event, &b->tx_retry_source, CLOCK_MONOTONIC, UINT64_MAX, 1, on_tx_retry, b);
        if (r < 0)
                return r;
        return sd_event_source_set_enabled(b->tx_retry_source, SD_EVENT_OFF);
}

/* Waiting for room: the retry timer on, the socket not read (its frames are
 * judged by the engine after our write, as they were behind a blocking one). */
static void tx_wait(lssd_bus *b, bool on) {
        if (b->io_source)
                (void) sd_event_source_set_enabled(b->io_source, on ? SD_EVENT_OFF : SD_EVENT_ON);
        if (!on) {
                (void) sd_event_source_set_enabled(b->tx_retry_source, SD_EVENT_OFF);
                return;
        }
        int r = sd_event_source_set_time_relative(b->tx_retry_source, TX_RETRY_US);
        if (r >= 0)
                r = sd_event_source_set_enabled(b->tx_retry_source, SD_EVENT_ONESHOT);
        if (r < 0)
                log_error("%s: failed to arm the transmit retry: %s", b->ifname, strerror(-r));
}

/* The engine hears about the frames written so far, then the failure; the
 * frames behind the failed one are dropped, never reordered. */
static void tx_fail(lssd_bus *b, int err) {
        lss_frame f;
        char why[128];

        b->tx_held = false;
        tx_wait(b, false);
        if (b->tx_sent_at > 0)
                lss_master_on_sent(b->engine, b->tx_sent_at);
        b->tx_sent_at = 0;

        enum lss_status st = b->bus_state == LSS_BUS_OFF ? LSS_E_BUS_OFF : LSS_E_BUS_DOWN;
        if (err == -ENETDOWN)
                snprintf(why, sizeof(why), "%s is down", b->ifname);
        else if (err == -ENODEV || err == -ENXIO)
                snprintf(why, sizeof(why), "%s does not exist", b->ifname);
        else if (err == -ETIMEDOUT)
                snprintf(why, sizeof(why), "%s: transmit queue stayed full (is any other node acknowledging?)",
                         b->ifname);
        else
                snprintf(why, sizeof(why), "%s: send failed: %s", b->ifname, strerror(-err));
        log_warning("%s", why);
        lss_master_on_bus_error(b->engine, st, why, bus_now(b));
        while (lss_master_next_tx(b->engine, &f))
                ;
}

static void tx_written(lssd_bus *b, const lss_frame *f, uint64_t t) {
        b->tx_sent_at = t;
        lssd_heard_tx(&b->heard, f);
        lss_tx_echo_written(&b->echo, f, t);
}

/* Writes what the engine wants sent, as far as the transport takes it. */
void bus_flush_tx(lssd_bus *b) {
        for (;;) {
                if (!b->tx_held) {
                        if (!lss_master_next_tx(b->engine, &b->tx_frame))
                                break;
                        b->tx_held = true;
                        b->tx_deadline = 0;
                }
                /* An answer may arrive before send() even returns (a slave on
                 * another CPU, a virtual bus): the frame counts as sent when
                 * we hand it to the kernel, or the engine would take the
                 * answer for a stale frame. */
                uint64_t t = bus_now(b);
                int r = lss_transport_send(&b->transport, &b->tx_frame);
                if (r == -EAGAIN) {
                        if (b->tx_deadline == 0)
                                b->tx_deadline = t + (uint64_t) LSSD_TX_TIMEOUT_MS * 1000u;
                        else if (t >= b->tx_deadline) {
                                tx_fail(b, -ETIMEDOUT);
                                return;
                        }
                        tx_wait(b, true);
                        return;
                }
                b->tx_held = false;
                if (r < 0) {
                        tx_fail(b, r);
                        return;
                }
                tx_written(b, &b->tx_frame, t);
        }
        tx_wait(b, false);
        /* only when something went out: on_sent() restarts the running wait */
        if (b->tx_sent_at > 0)
                lss_master_on_sent(b->engine, b->tx_sent_at);
        b->tx_sent_at = 0;
}
