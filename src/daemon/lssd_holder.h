/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Who holds a bus (Acquire): one D-Bus client at a time, until it calls
 * Release or leaves the bus. Watching the client is behind ops (sd-bus's
 * sd_bus_track in lssd, a fake in the unit tests); when the watch says the
 * client left, lssd_holder_gone() tells the owner and drops it. */
#pragma once

#include <stdbool.h>
#include <systemd/sd-bus.h>

typedef struct lssd_holder lssd_holder;

typedef struct lssd_holder_ops {
        /* watch the sender of m: call lssd_holder_gone(h) when it leaves */
        int (*watch)(lssd_holder *h, sd_bus_message *m);
        void (*unwatch)(lssd_holder *h);
} lssd_holder_ops;

struct lssd_holder {
        char *name;                      /* unique name of the holder, NULL: nobody */
        void *watch;                     /* the ops' handle */
        const lssd_holder_ops *ops;      /* NULL: lssd_holder_sd_bus_ops */
        void (*on_gone)(lssd_holder *h, void *userdata); /* the holder left the bus (name still set) */
        void *userdata;
};

/* sd_bus_track on the message's connection. */
extern const lssd_holder_ops lssd_holder_sd_bus_ops;

void lssd_holder_init(lssd_holder *h, const lssd_holder_ops *ops,
                      void (*on_gone)(lssd_holder *h, void *userdata), void *userdata);
bool lssd_holder_is(const lssd_holder *h, const char *sender);
/* `sender` (of m) holds the bus now: 1; 0 when it did already; -EBUSY when
 * somebody else does; negative errno when it cannot be watched. */
int lssd_holder_take(lssd_holder *h, const char *sender, sd_bus_message *m);
/* Nobody holds it (no-op when nobody did). */
void lssd_holder_drop(lssd_holder *h);
/* The watch saw the holder leave: on_gone, then dropped (if on_gone did not). */
void lssd_holder_gone(lssd_holder *h);
