/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* org.lssd.LSS1.Manager */
#include "daemon/lssd_bus.h"
#include "daemon/lssd_context.h"
#include "daemon/lssd_errors.h"
#include "daemon/lssd_validate.h"
#include "daemon/lssd_vtables.h"

#ifndef LSSD_VERSION
#define LSSD_VERSION "unknown"
#endif

static int property_get_version(sd_bus *bus, const char *path, const char *interface, const char *property,
                                sd_bus_message *reply, void *userdata, sd_bus_error *error) {
        return sd_bus_message_append(reply, "s", LSSD_VERSION);
}

static int property_get_buses(sd_bus *bus, const char *path, const char *interface, const char *property,
                              sd_bus_message *reply, void *userdata, sd_bus_error *error) {
        lssd_context *ctx = userdata;
        int r = sd_bus_message_open_container(reply, 'a', "o");
        if (r < 0)
                return r;
        for (size_t i = 0; i < ctx->n_buses; i++) {
                if (lssd_bus_removing(ctx->buses[i]))
                        continue;
                r = sd_bus_message_append(reply, "o", lssd_bus_object_path(ctx->buses[i]));
                if (r < 0)
                        return r;
        }
        return sd_bus_message_close_container(reply);
}

static int method_get_bus(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        lssd_context *ctx = userdata;
        const char *ifname;
        int r;

        r = sd_bus_message_read(m, "s", &ifname);
        if (r < 0)
                return r;
        r = lssd_validate_ifname("interface", ifname, error);
        if (r < 0)
                return r;
        lssd_bus *b = lssd_context_find_bus(ctx, ifname);
        if (!b || lssd_bus_removing(b))
                return sd_bus_error_setf(error, LSSD_ERROR_NOT_FOUND, "lssd does not serve a bus '%s'", ifname);
        return sd_bus_reply_method_return(m, "o", lssd_bus_object_path(b));
}

static int method_reload_config(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        lssd_context *ctx = userdata;
        int r;

        r = lssd_auth_check(&ctx->auth, m, LSSD_ACTION_RELOAD, error);
        if (r != 0)
                return r;
        r = lssd_context_reload(ctx, error);
        if (r < 0)
                return r;
        return sd_bus_reply_method_return(m, NULL);
}

const sd_bus_vtable lssd_manager_vtable[] = {
        SD_BUS_VTABLE_START(0),

        SD_BUS_PROPERTY("Version", "s", property_get_version, 0, SD_BUS_VTABLE_PROPERTY_CONST),
        SD_BUS_PROPERTY("Buses", "ao", property_get_buses, 0, SD_BUS_VTABLE_PROPERTY_EMITS_CHANGE),

        SD_BUS_METHOD_WITH_ARGS("ReloadConfig", SD_BUS_NO_ARGS, SD_BUS_NO_RESULT, method_reload_config,
                                SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD_WITH_ARGS("GetBus",
                                SD_BUS_ARGS("s", interface),
                                SD_BUS_RESULT("o", bus),
                                method_get_bus, SD_BUS_VTABLE_UNPRIVILEGED),

        SD_BUS_VTABLE_END
};
