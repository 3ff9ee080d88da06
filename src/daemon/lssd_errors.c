/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <stdio.h>

#include "daemon/lssd_errors.h"

#define LSSD_ERROR_MAP_ENTRY(sym, errno_, exit_status, sentence) SD_BUS_ERROR_MAP(LSSD_ERROR_##sym, errno_),
const sd_bus_error_map lssd_error_map[] = {
        LSSD_ERRORS(LSSD_ERROR_MAP_ENTRY)
        SD_BUS_ERROR_MAP_END
};

/* The confirmed services whose answers carry error codes. */
static bool answers_with_error_code(enum lss_service s) {
        return s == LSS_SERVICE_CONFIGURE_NODE_ID || s == LSS_SERVICE_CONFIGURE_BIT_TIMING || s == LSS_SERVICE_STORE;
}

const char *lssd_lss_error_meaning(enum lss_service s, uint8_t err) {
        if (err == 0)
                return "success";
        if (err == 255)
                return "manufacturer-specific";
        switch (s) {
        case LSS_SERVICE_CONFIGURE_NODE_ID:
                return err == 1 ? "node-ID out of range" : "reserved";
        case LSS_SERVICE_CONFIGURE_BIT_TIMING:
                return err == 1 ? "bit rate not supported" : "reserved";
        case LSS_SERVICE_STORE:
                return err == 1 ? "store not supported" : err == 2 ? "storage media access error" : "reserved";
        default:
                return "reserved";
        }
}

static const struct {
        const char *error;
        const char *result;
} status_table[] = {
        [LSS_OK] = { NULL, "done" },
        [LSS_E_NO_RESPONSE] = { LSSD_ERROR_NO_RESPONSE, "no-response" },
        [LSS_E_REJECTED] = { LSSD_ERROR_REJECTED, "rejected" },
        [LSS_E_CONFLICT] = { LSSD_ERROR_CONFLICT, "conflict" },
        [LSS_E_NOT_FOUND] = { LSSD_ERROR_NOT_FOUND, "not-found" },
        [LSS_E_BUS_DOWN] = { LSSD_ERROR_BUS_DOWN, "bus-down" },
        [LSS_E_BUS_OFF] = { LSSD_ERROR_BUS_OFF, "bus-off" },
        [LSS_E_CANCELLED] = { LSSD_ERROR_CANCELLED, "cancelled" },
        [LSS_E_INVALID] = { SD_BUS_ERROR_INVALID_ARGS, "invalid" },
        /* the assignment went out but no boot-up confirmed it */
        [LSS_E_VERIFY] = { LSSD_ERROR_NO_RESPONSE, "not-verified" },
        /* several slaves disturbed each other's answers */
        [LSS_E_INCOMPLETE] = { LSSD_ERROR_CONFLICT, "incomplete" },
        [LSS_E_FOREIGN_MASTER] = { LSSD_ERROR_FOREIGN_MASTER, "foreign-master" },
};

const char *lssd_status_to_error_name(enum lss_status s) {
        if ((unsigned) s >= sizeof(status_table) / sizeof(status_table[0]))
                return LSSD_ERROR_NO_RESPONSE;
        return status_table[s].error;
}

const char *lssd_status_to_result(enum lss_status s) {
        if ((unsigned) s >= sizeof(status_table) / sizeof(status_table[0]))
                return "failed";
        return status_table[s].result;
}

int lssd_error_from_result(sd_bus_error *error, const lss_result *r, enum lss_service service, const char *prefix) {
        const char *name = lssd_status_to_error_name(r->status);

        if (!name) /* not a failure: callers should not get here */
                name = LSSD_ERROR_NO_RESPONSE;
        if (!prefix)
                prefix = "";

        if (r->status == LSS_E_REJECTED && answers_with_error_code(service))
                return sd_bus_error_setf(error, name, "%s%s rejected by the slave: error %u (%s), spec %u", prefix,
                                         lss_service_name(service), r->err,
                                         lssd_lss_error_meaning(service, r->err), r->spec);

        if (r->message[0])
                return sd_bus_error_setf(error, name, "%s%s", prefix, r->message);
        return sd_bus_error_setf(error, name, "%s%s", prefix, lssd_status_to_result(r->status));
}
