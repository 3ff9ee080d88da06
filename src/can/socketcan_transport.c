/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* A SocketCAN port behind the transport seam (can/transport.h), with the
 * rtnetlink retune of its controller. */
#include <errno.h>
#include <stdlib.h>

#include "can/rtnl_retune.h"
#include "can/socketcan.h"

typedef struct sc_transport {
        socketcan_port *port;
        rtnl_retune *retune;    /* the last one, kept after its end for its link changes */
} sc_transport;

static socketcan_port *port_of(void *impl) {
        return ((sc_transport *) impl)->port;
}

static int tp_send(void *impl, const lss_frame *f) {
        return socketcan_port_send(port_of(impl), f);
}

static int tp_recv(void *impl, lss_frame *f, uint64_t *rx_us) {
        return socketcan_port_recv(port_of(impl), f, rx_us);
}

static int tp_get_fd(void *impl) {
        return socketcan_port_fd(port_of(impl));
}

static uint64_t tp_now(void *impl) {
        return socketcan_port_now(port_of(impl));
}

static int tp_status(void *impl, lss_transport_status *st) {
        socketcan_port_status(port_of(impl), st);
        return 0;
}

static lss_link_state tp_link(void *impl) {
        return socketcan_port_state(port_of(impl));
}

static bool tp_echoes(void *impl) {
        return socketcan_port_echoes(port_of(impl));
}

static int tp_link_event(void *impl, const lss_link_event *ev) {
        return socketcan_port_link_event(port_of(impl), ev->ifindex, ev->ifname, ev->present, ev->flags);
}

/* Done: a fresh socket, the old one carries a pending ENETDOWN from the
 * link going down. A failed re-open leaves the port gone until rtnetlink
 * reports the interface again: the rate is set. */
static int retune_result(sc_transport *t, int r, lss_retune_wait *wait) {
        if (r == 0) {
                wait->fd = rtnl_retune_fd(t->retune);
                wait->deadline = rtnl_retune_deadline(t->retune);
        } else if (r > 0)
                (void) socketcan_port_reopen(t->port);
        return r;
}

static int tp_retune_start(void *impl, uint32_t bitrate, lss_retune_wait *wait) {
        sc_transport *t = impl;
        t->retune = rtnl_retune_free(t->retune);
        int r = rtnl_retune_start(socketcan_port_sys(t->port), socketcan_port_ifname(t->port), bitrate, &t->retune);
        return r < 0 ? r : retune_result(t, r, wait);
}

static int tp_retune_step(void *impl, lss_retune_wait *wait) {
        sc_transport *t = impl;
        return retune_result(t, rtnl_retune_step(t->retune), wait);
}

static bool tp_retune_caused(void *impl, lss_link_state new_state) {
        sc_transport *t = impl;
        return t->retune && new_state != LSS_LINK_GONE && rtnl_retune_claim(t->retune, new_state == LSS_LINK_UP);
}

static void tp_close(void *impl) {
        sc_transport *t = impl;
        rtnl_retune_free(t->retune);
        socketcan_port_free(t->port);
        free(t);
}

static const lss_transport_ops socketcan_transport_ops = {
        .kind = "SocketCAN",
        .send = tp_send,
        .recv = tp_recv,
        .get_fd = tp_get_fd,
        .now = tp_now,
        .status = tp_status,
        .link = tp_link,
        .echoes = tp_echoes,
        .link_event = tp_link_event,
        .retune_start = tp_retune_start,
        .retune_step = tp_retune_step,
        .retune_caused = tp_retune_caused,
        .close = tp_close,
};

int socketcan_port_transport(socketcan_port *p, lss_transport *ret) {
        sc_transport *t = calloc(1, sizeof(*t));
        if (!t)
                return -ENOMEM;
        t->port = p;
        ret->ops = &socketcan_transport_ops;
        ret->impl = t;
        return 0;
}
