/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* A SocketCAN port behind the transport seam (can/transport.h). */
#include "can/rtnl_watch.h"
#include "can/socketcan.h"

static int tp_send(void *impl, const lss_frame *f) {
        return socketcan_port_send(impl, f);
}

static int tp_recv(void *impl, lss_frame *f, uint64_t *rx_us) {
        return socketcan_port_recv(impl, f, rx_us);
}

static int tp_get_fd(void *impl) {
        return socketcan_port_fd(impl);
}

static uint64_t tp_now(void *impl) {
        return socketcan_port_now(impl);
}

static int tp_status(void *impl, lss_transport_status *st) {
        socketcan_port_status(impl, st);
        return 0;
}

static lss_link_state tp_link(void *impl) {
        return socketcan_port_state(impl);
}

static bool tp_echoes(void *impl) {
        return socketcan_port_echoes(impl);
}

static int tp_link_event(void *impl, const lss_link_event *ev) {
        return socketcan_port_link_event(impl, ev->ifindex, ev->ifname, ev->present, ev->flags);
}

/* Link down, bit timing, link up; then a fresh socket: the old one carries
 * a pending ENETDOWN from the link going down. A failed re-open leaves the
 * port gone until rtnetlink reports the interface again: the rate is set. */
static int tp_retune(void *impl, uint32_t bitrate) {
        socketcan_port *p = impl;
        int r = rtnl_set_can_bitrate(socketcan_port_sys(p), socketcan_port_ifname(p), bitrate);
        if (r < 0)
                return r;
        (void) socketcan_port_reopen(p);
        return 0;
}

static void tp_close(void *impl) {
        socketcan_port_free(impl);
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
        .retune = tp_retune,
        .close = tp_close,
};

void socketcan_port_transport(socketcan_port *p, lss_transport *ret) {
        ret->ops = &socketcan_transport_ops;
        ret->impl = p;
}
