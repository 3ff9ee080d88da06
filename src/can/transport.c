/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include "can/transport.h"

static const char *const link_state_table[_LSS_LINK_STATE_MAX] = {
        [LSS_LINK_UP] = "up",
        [LSS_LINK_DOWN] = "down",
        [LSS_LINK_GONE] = "gone",
};

static const char *const bus_state_table[_LSS_BUS_STATE_MAX] = {
        [LSS_BUS_ERROR_ACTIVE] = "error-active",
        [LSS_BUS_ERROR_WARNING] = "error-warning",
        [LSS_BUS_ERROR_PASSIVE] = "error-passive",
        [LSS_BUS_OFF] = "bus-off",
};

const char *lss_link_state_to_string(lss_link_state s) {
        if ((unsigned) s >= _LSS_LINK_STATE_MAX)
                return NULL;
        return link_state_table[s];
}

const char *lss_bus_state_to_string(lss_bus_state s) {
        if ((unsigned) s >= _LSS_BUS_STATE_MAX)
                return NULL;
        return bus_state_table[s];
}
