/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <string.h>

#include "can/socketcan.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_transport_open.h"
#include "simbus/simbus.h"

static int open_simulated(const lssd_args *args, const char *ifname, uint32_t bitrate, lss_transport *ret) {
        simbus *s;
        int r = simbus_new(bitrate, &s);
        if (r < 0)
                return r;
        for (size_t i = 0; i < args->n_sim_slaves; i++) {
                const lssd_sim_slave *sl = &args->sim_slaves[i];
                if (strcmp(sl->ifname, ifname) != 0)
                        continue;
                r = simbus_add_slave(s, &sl->id, sl->node_id, sl->profile);
                if (r < 0)
                        break;
        }
        for (size_t i = 0; r >= 0 && i < args->n_sim_foreign; i++)
                if (strcmp(args->sim_foreign[i].ifname, ifname) == 0)
                        simbus_add_foreign(s, &args->sim_foreign[i]);
        simbus_transport(s, ret);
        if (r < 0)
                lss_transport_close(ret);
        return r;
}

int lssd_transport_open(const lssd_args *args, const char *ifname, uint32_t bitrate,
                        const lss_transport_hooks *hooks, lss_transport *ret) {
        if (args->simulate)
                return open_simulated(args, ifname, bitrate, ret);

        socketcan_config sc = { .hooks = *hooks };
        socketcan_port *p;
        int r = socketcan_port_open(ifname, &sc, &p);
        if (r < 0)
                return r;
        r = socketcan_port_transport(p, ret);
        if (r < 0) {
                socketcan_port_free(p);
                return r;
        }
        /* "link gone" alone does not say why: no such interface, or no CAN in this kernel at all */
        if (socketcan_port_state(p) == LSS_LINK_GONE && !socketcan_kernel_has_can(NULL)) {
                log_warning("%s: serving (SocketCAN, link gone): this kernel has no CAN support (no AF_CAN "
                            "sockets; modprobe can can-raw?): %s cannot appear until it has; lssd --simulate "
                            "runs without CAN", ifname, ifname);
                return 1;
        }
        return 0;
}
