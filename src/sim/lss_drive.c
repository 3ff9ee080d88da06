/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include "sim/lss_drive.h"

static void flush_tx(lss_master *m, membus *bus) {
        lss_frame f;
        bool any = false;
        while (lss_master_next_tx(m, &f)) {
                membus_master_send(bus, &f);
                any = true;
        }
        if (any)
                lss_master_on_sent(m, membus_now(bus));
}

const lss_result *lss_drive(lss_master *m, membus *bus, uint64_t limit_us, lss_drive_hook hook, void *ud) {
        uint64_t start = membus_now(bus);

        flush_tx(m, bus);
        while (!lss_master_done(m)) {
                uint64_t now = membus_now(bus);
                if (now - start > limit_us) {
                        lss_master_cancel(m, now);
                        flush_tx(m, bus);
                        break;
                }
                uint64_t dl = lss_master_deadline(m), ev = membus_next_event(bus);
                uint64_t t = dl < ev ? dl : ev;
                if (t == UINT64_MAX)
                        t = now + 1000; /* nothing scheduled: let time pass */
                if (t < now)
                        t = now;
                membus_advance(bus, t);

                lss_frame f;
                uint64_t rx;
                while (membus_master_recv(bus, &f, &rx)) {
                        lss_master_on_frame(m, &f, rx);
                        flush_tx(m, bus);
                }
                if (lss_master_deadline(m) <= membus_now(bus)) {
                        lss_master_on_time(m, membus_now(bus));
                        flush_tx(m, bus);
                }
                if (hook) {
                        hook(ud, bus, m);
                        flush_tx(m, bus); /* what a cancel from the hook queued */
                }
        }
        /* let the last frames (switch to waiting) reach the slaves */
        membus_advance(bus, membus_now(bus) + 2000);
        lss_frame f;
        uint64_t rx;
        while (membus_master_recv(bus, &f, &rx))
                ;
        return lss_master_result(m);
}

void lss_drive_idle(membus *bus, uint64_t us) {
        membus_advance(bus, membus_now(bus) + us);
        lss_frame f;
        uint64_t rx;
        while (membus_master_recv(bus, &f, &rx))
                ;
}
