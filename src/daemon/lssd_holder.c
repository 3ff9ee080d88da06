/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_holder.h"

static int on_track_gone(sd_bus_track *t, void *userdata) {
        lssd_holder_gone(userdata);
        return 0;
}

static int track_watch(lssd_holder *h, sd_bus_message *m) {
        sd_bus_track *t = NULL;
        int r = sd_bus_track_new(sd_bus_message_get_bus(m), &t, on_track_gone, h);
        if (r < 0)
                return r;
        r = sd_bus_track_add_sender(t, m);
        if (r < 0) {
                sd_bus_track_unref(t);
                return r;
        }
        h->watch = t;
        return 0;
}

static void track_unwatch(lssd_holder *h) {
        h->watch = sd_bus_track_unref(h->watch);
}

const lssd_holder_ops lssd_holder_sd_bus_ops = {
        .watch = track_watch,
        .unwatch = track_unwatch,
};

void lssd_holder_init(lssd_holder *h, const lssd_holder_ops *ops,
                      void (*on_gone)(lssd_holder *h, void *userdata), void *userdata) {
        *h = (lssd_holder) { .ops = ops ? ops : &lssd_holder_sd_bus_ops, .on_gone = on_gone, .userdata = userdata };
}

bool lssd_holder_is(const lssd_holder *h, const char *sender) {
        return h->name && sender && strcmp(h->name, sender) == 0;
}

int lssd_holder_take(lssd_holder *h, const char *sender, sd_bus_message *m) {
        if (lssd_holder_is(h, sender))
                return 0;
        if (h->name)
                return -EBUSY;
        char *name = strdup(sender);
        if (!name)
                return -ENOMEM;
        int r = h->ops->watch(h, m);
        if (r < 0) {
                free(name);
                return r;
        }
        h->name = name;
        return 1;
}

void lssd_holder_drop(lssd_holder *h) {
        if (!h->name)
                return;
        h->ops->unwatch(h);
        free(h->name);
        h->name = NULL;
}

void lssd_holder_gone(lssd_holder *h) {
        if (!h->name)
                return;
        if (h->on_gone)
                h->on_gone(h, h->userdata);
        lssd_holder_drop(h);
}
