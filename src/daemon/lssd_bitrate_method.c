/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <stdbool.h>

#include "daemon/lssd_auth.h"
#include "daemon/lssd_bitrate_method.h"
#include "daemon/lssd_errors.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_options.h"

typedef struct bitrate_options {
        bool store, skip_missing, global;
} bitrate_options;

static const lssd_option bitrate_table[] = {
        LSSD_OPTION("store", 'b', bitrate_options, store),
        LSSD_OPTION("skip_missing", 'b', bitrate_options, skip_missing),
        LSSD_OPTION(LSSD_BITRATE_OPTION_GLOBAL, 'b', bitrate_options, global),
        LSSD_OPTION_END,
};

int lssd_bitrate_method(lssd_bus *b, sd_bus_message *m, uint32_t bitrate, uint16_t switch_delay_ms,
                        sd_bus_error *error) {
        bitrate_options o = { .store = lssd_bus_config_of(b)->store };
        lssd_job *j;
        int r;

        r = lssd_options_read(m, "options", bitrate_table, &o, error);
        if (r < 0)
                return r;
        r = lssd_auth_check(lssd_bus_auth(b), m, LSSD_ACTION_SET_BITRATE, error);
        if (r != 0)
                return r;
        /* changing a whole network's rate is opt-in per bus, and on a real
         * controller it needs CAP_NET_ADMIN, which only that opt-in grants */
        if (!lssd_bus_config_of(b)->bitrate_change)
                return sd_bus_error_setf(error, LSSD_ERROR_NOT_SUPPORTED,
                                         "Bit-rate changes are not enabled for %s: set bitrate_change = true for "
                                         "this bus in lssd.conf (see lssd(8) for what to check first)",
                                         lssd_bus_ifname(b));
        /* already there: nothing to send */
        if (bitrate == lssd_bus_bitrate(b)) {
                log_info("%s: SetBitrate %u bit/s: the bus runs at that rate already", lssd_bus_ifname(b), bitrate);
                return sd_bus_reply_method_return(m, "a(uuuus)", 0);
        }

        r = lssd_job_new(LSSD_JOB_SET_BITRATE, m, &j);
        if (r < 0)
                return r;
        j->bitrate = bitrate;
        j->switch_delay_ms = switch_delay_ms;
        j->bitrate_store = o.store;
        j->bitrate_skip_missing = o.skip_missing;
        j->bitrate_global = o.global;
        /* the map's and the known devices' pairs by slowscan; the others by SDO */
        for (size_t i = 0; r >= 0 && i < lssd_bus_config_of(b)->n_devices; i++)
                r = lssd_job_add_pair(j, lssd_bus_config_of(b)->devices[i].identity.vendor, lssd_bus_config_of(b)->devices[i].identity.product);
        for (lssd_device *d = lssd_bus_devices(b)->head; r >= 0 && d; d = d->next)
                r = lssd_job_add_pair(j, d->id.vendor, d->id.product);
        if (r < 0) {
                lssd_job_free(j);
                return r;
        }
        return lssd_bus_queue_job(b, m, j, false, error);
}
