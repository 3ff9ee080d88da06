/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Test driver: the engine over the real SocketCAN transport, no daemon.
 *   lss-vcan-master IFACE seed            the seed example (raw services)
 *   lss-vcan-master IFACE enumerate       every non-configured slave
 *   lss-vcan-master IFACE assign-all N    fastscan + assign N, N+1, ... until none is left
 *   lss-vcan-master IFACE nmt-stop        NMT Stop to all nodes
 *   lss-vcan-master IFACE autoassign [--nmt-stop] [--any-revision] V:P:R:S=NODE...
 *                                         the auto-assignment pass with that map
 *   lss-vcan-master IFACE replug          wait until IFACE is deleted and created
 *                                         again (re-open by name), then enumerate
 * Prints "device V:P:R:S NODEID" / "assigned V:P:R:S NODEID" lines and a
 * final "status NAME message" line; exit 0 only on success. */
#include <errno.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "can/rtnl_watch.h"
#include "can/socketcan.h"
#include "can/tx_echo.h"
#include "lss/lss_autoassign.h"
#include "lss/lss_master.h"
#include "util/time_util.h"

/* The port echoes our frames (CAN_RAW_RECV_OWN_MSGS): the engine then
 * drains by the echo, as in lssd (lss_master_set_tx_confirm()). */
static const lss_result *drive(lss_master *m, socketcan_port *p) {
        lss_tx_echo echo = {};
        lss_master_set_tx_confirm(m, socketcan_port_echoes(p));
        for (;;) {
                lss_frame f;
                bool sent = false;
                uint64_t t_send = 0;
                while (lss_master_next_tx(m, &f)) {
                        /* taken before the last write: see lss_master_on_sent() */
                        t_send = socketcan_port_now(p);
                        /* a full tx queue: this tool may block, 100 ms at most */
                        uint64_t until = t_send + 100000u;
                        int r;
                        while ((r = socketcan_port_send(p, &f)) == -EAGAIN && socketcan_port_now(p) < until)
                                (void) poll(NULL, 0, 1);
                        if (getenv("LSS_DEBUG"))
                                fprintf(stderr, "send %03X %02X%02X fd %d ifindex %d state %d -> %d at %llu\n", (unsigned) f.id,
                                        f.data[0], f.data[5], socketcan_port_fd(p), socketcan_port_ifindex(p),
                                        socketcan_port_state(p), r, (unsigned long long) t_send);
                        if (r < 0) {
                                lss_master_on_bus_error(m, LSS_E_BUS_DOWN, strerror(-r), socketcan_port_now(p));
                                return lss_master_result(m);
                        }
                        lss_tx_echo_written(&echo, &f, t_send);
                        sent = true;
                }
                if (sent)
                        lss_master_on_sent(m, t_send);
                if (lss_master_done(m))
                        return lss_master_result(m);
                uint64_t now = socketcan_port_now(p), dl = lss_master_deadline(m);
                int timeout = dl == UINT64_MAX ? 1000 : dl <= now ? 0 : (int) us_to_ms_up(dl - now);
                struct pollfd pfd = { .fd = socketcan_port_fd(p), .events = POLLIN };
                if (poll(&pfd, 1, timeout) < 0 && errno != EINTR)
                        return lss_master_result(m);
                uint64_t rx;
                int r;
                while ((r = socketcan_port_recv(p, &f, &rx)) > 0) {
                        if (getenv("LSS_DEBUG"))
                                fprintf(stderr, "recv %03X %02X%02X%s rx %llu now %llu\n", (unsigned) f.id, f.data[0], f.data[5],
                                        (f.flags & LSS_FRAME_ECHO) ? " echo" : "",
                                        (unsigned long long) rx, (unsigned long long) socketcan_port_now(p));
                        if (!(f.flags & LSS_FRAME_ECHO))
                                lss_master_on_frame(m, &f, rx);
                        else if (lss_tx_echo_confirms(&echo, &f, rx))
                                lss_master_on_tx_confirmed(m, rx);
                }
                if (r < 0) {
                        lss_master_on_bus_error(m, LSS_E_BUS_DOWN, strerror(-r), socketcan_port_now(p));
                        return lss_master_result(m);
                }
                lss_transport_status st;
                socketcan_port_status(p, &st);
                if (st.events & LSS_BUS_EVENT_RX_OVERFLOW)
                        lss_master_on_rx_lost(m, socketcan_port_now(p));
                if (lss_master_deadline(m) <= socketcan_port_now(p))
                        lss_master_on_time(m, socketcan_port_now(p));
        }
}

static void on_link(const rtnl_link *l, void *userdata) {
        socketcan_port_link_event(userdata, l->ifindex, l->ifname, !l->removed, l->flags);
}

/* Follow rtnetlink until the port went away and is up again. */
static int wait_replug(socketcan_port *p) {
        rtnl_watch *w;
        int r = rtnl_watch_new(NULL, on_link, p, &w);
        if (r < 0)
                return r;
        int first = socketcan_port_ifindex(p);
        bool gone = false;
        printf("waiting for %s to be replugged\n", socketcan_port_ifname(p));
        for (int i = 0; i < 600; i++) {
                struct pollfd pfd = { .fd = rtnl_watch_fd(w), .events = POLLIN };
                if (poll(&pfd, 1, 100) > 0)
                        rtnl_watch_process(w);
                if (socketcan_port_state(p) == LSS_LINK_GONE)
                        gone = true;
                if (gone && socketcan_port_state(p) == LSS_LINK_UP) {
                        printf("replugged: ifindex %d -> %d\n", first, socketcan_port_ifindex(p));
                        rtnl_watch_free(w);
                        return 0;
                }
        }
        rtnl_watch_free(w);
        return -ETIMEDOUT;
}

static int report(const lss_result *r) {
        if (getenv("LSS_DEBUG"))
                fprintf(stderr, "result: %zu devices\n", r->n_devices);
        printf("status %s %s\n", lss_status_name(r->status), r->message);
        return r->status == LSS_OK ? 0 : 1;
}

static void print_id(const char *what, const lss_identity *id, unsigned node) {
        printf("%s %08x:%08x:%08x:%08x %u\n", what, id->vendor, id->product, id->revision, id->serial, node);
}

int main(int argc, char **argv) {
        if (argc < 3) {
                fprintf(stderr, "usage: %s IFACE seed|enumerate|assign-all N\n", argv[0]);
                return 2;
        }
        setvbuf(stdout, NULL, _IOLBF, 0);
        socketcan_port *p;
        int r = socketcan_port_open(argv[1], NULL, &p);
        if (r < 0 || socketcan_port_state(p) != LSS_LINK_UP) {
                fprintf(stderr, "cannot open %s: %s\n", argv[1], r < 0 ? strerror(-r) : "not up");
                return 1;
        }
        /* lssd's own timing (lss_timeout_ms 20, adaptive): what users run */
        lss_timing_config c;
        lss_timing_config_default(&c);
        lss_master *m = lss_master_new(&c);
        const lss_result *res;
        int rc = 0;
        uint64_t now = socketcan_port_now(p);

        if (strcmp(argv[2], "seed") == 0) {
                lss_master_switch_global(m, LSS_MODE_CONFIGURATION, now);
                drive(m, p);
                lss_master_configure_node_id(m, 0x44, socketcan_port_now(p));
                rc |= report(drive(m, p));
                lss_master_store(m, socketcan_port_now(p));
                rc |= report(drive(m, p));
                lss_master_switch_global(m, LSS_MODE_WAITING, socketcan_port_now(p));
                rc |= report(drive(m, p));
        } else if (strcmp(argv[2], "autoassign") == 0) {
                lss_map_entry map[128];
                lss_autoassign_plan plan = { .map = map, .store = true };
                bool any_rev = false;
                for (int i = 3; i < argc; i++) {
                        unsigned v, pr, rv, se, node;
                        if (strcmp(argv[i], "--nmt-stop") == 0)
                                plan.nmt_stop = true;
                        else if (strcmp(argv[i], "--any-revision") == 0)
                                any_rev = true;
                        else if (plan.n_map < 128 && sscanf(argv[i], "%x:%x:%x:%x=%u", &v, &pr, &rv, &se, &node) == 5)
                                map[plan.n_map++] = (lss_map_entry) { .id = { v, pr, rv, se }, .revision_known = !any_rev,
                                                                      .node_id = (uint8_t) node };
                        else {
                                fprintf(stderr, "bad map entry %s\n", argv[i]);
                                return 2;
                        }
                }
                if (lss_master_autoassign(m, &plan, now) < 0) {
                        fprintf(stderr, "bad plan\n");
                        return 2;
                }
                res = drive(m, p);
                size_t n;
                const lss_outcome *o = lss_master_outcomes(m, &n);
                for (size_t i = 0; i < n; i++)
                        printf("outcome %08x:%08x:%08x:%08x %s %u %u %s\n", o[i].id.vendor, o[i].id.product,
                               o[i].id.revision, o[i].id.serial, lss_outcome_name(o[i].kind), o[i].old_node_id,
                               o[i].new_node_id, o[i].message);
                rc = report(res);
        } else if (strcmp(argv[2], "nmt-stop") == 0) {
                lss_master_nmt(m, NMT_CS_STOP, 0, now);
                rc = report(drive(m, p));
        } else if (strcmp(argv[2], "enumerate") == 0 || strcmp(argv[2], "replug") == 0) {
                if (strcmp(argv[2], "replug") == 0) {
                        if ((r = wait_replug(p)) < 0) {
                                printf("status replug-failed %s\n", strerror(-r));
                                return 1;
                        }
                        /* the test starts the simulated slaves on the new interface, then says go */
                        char go[8];
                        if (!fgets(go, sizeof(go), stdin))
                                return 1;
                }
                lss_master_enumerate(m, NULL, socketcan_port_now(p));
                res = drive(m, p);
                for (size_t i = 0; i < res->n_devices; i++)
                        print_id("device", &res->devices[i].id, res->devices[i].node_id);
                rc = report(res);
        } else if (strcmp(argv[2], "assign-all") == 0 && argc > 3) {
                unsigned node = (unsigned) atoi(argv[3]);
                for (;; node++) {
                        lss_master_fastscan_assign(m, NULL, (uint8_t) node, LSS_ASSIGN_STORE | LSS_ASSIGN_VERIFY,
                                                   socketcan_port_now(p));
                        res = drive(m, p);
                        if (res->status == LSS_E_NOT_FOUND)
                                break;
                        if (res->status != LSS_OK) {
                                rc = report(res);
                                break;
                        }
                        print_id("assigned", &res->id, node);
                }
                if (rc == 0)
                        printf("status ok\n");
        } else {
                fprintf(stderr, "unknown command %s\n", argv[2]);
                rc = 2;
        }
        lss_master_free(m);
        socketcan_port_free(p);
        return rc;
}
