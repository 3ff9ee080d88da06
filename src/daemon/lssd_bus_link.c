/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "daemon/lssd_bus_private.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_path.h"

/* ---- link ---- */

void bus_on_link_state(void *userdata, lss_link_state old_state, lss_link_state new_state) {
        lssd_bus *b = userdata;
        /* the fd is still open now but not after we return: forget it here */
        if (new_state == LSS_LINK_GONE) {
                b->io_source = sd_event_source_disable_unref(b->io_source);
                b->io_fd = -1;
        }
        b->link_changed = true;
}

void bus_after_link_change(lssd_bus *b) {
        lss_link_state old = b->link, now_state = lss_transport_link(&b->transport);
        b->link_changed = false;
        b->link = now_state;
        bus_update_io(b, true);
        if (old == now_state)
                return;

        if (bus_retune_caused(b, now_state)) {
                /* our own retune (down, bit timing, up): the job goes on */
                log_info("%s: link %s (SetBitrate retune)", b->ifname, lss_link_state_to_string(now_state));
                bus_process(b);
                return;
        }
        if (now_state == LSS_LINK_GONE)
                log_notice("%s: link gone: no interface %s any more; served again when it appears", b->ifname,
                           b->ifname);
        else
                log_notice("%s: link %s", b->ifname, lss_link_state_to_string(now_state));
        if (now_state != LSS_LINK_UP && b->engine_running) {
                char why[64];
                snprintf(why, sizeof(why), "%s went %s", b->ifname, lss_link_state_to_string(now_state));
                lss_master_on_bus_error(b->engine, LSS_E_BUS_DOWN, why, bus_now(b));
        }
        /* whatever happened while we could not talk: the first frame is switch-global waiting */
        if (now_state == LSS_LINK_UP) {
                bus_queue_reset(b, true);
                bus_queue_boot_pass(b);
        }
        bus_process(b);
}

void lssd_bus_link_event(lssd_bus *b, const rtnl_link *link) {
        const lss_link_event ev = {
                .ifindex = link->ifindex,
                .ifname = link->ifname,
                .present = !link->removed,
                .flags = link->flags,
        };
        int r = lss_transport_link_event(&b->transport, &ev);
        if (r == -EOPNOTSUPP)
                return; /* the host's links do not matter to this transport (simulated bus) */
        if (r < 0)
                log_warning("%s: failed to re-open: %s", b->ifname, strerror(-r));
        if (link->ifname[0] && strcmp(link->ifname, b->ifname) == 0 && !link->removed) {
                uint32_t rate = strcmp(link->kind, "can") == 0 ? link->bitrate : 0;
                bool virt = strcmp(link->kind, "vcan") == 0 || strcmp(link->kind, "vxcan") == 0;
                if (rate != b->link_bitrate || virt != b->link_virtual) {
                        b->link_bitrate = rate;
                        b->link_virtual = virt;
                        bus_update_timing(b);
                        bus_update_published(b);
                        bus_flush_changes(b);
                }
        }
        if (r != 0 || b->link_changed)
                bus_after_link_change(b);
}
