/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* org.lssd.LSS1.Device */
#include "daemon/lssd_bus.h"
#include "daemon/lssd_device.h"
#include "daemon/lssd_validate.h"
#include "daemon/lssd_vtables.h"

static int property_get_state(sd_bus *bus, const char *path, const char *interface, const char *property,
                              sd_bus_message *reply, void *userdata, sd_bus_error *error) {
        const lssd_device *d = userdata;
        return sd_bus_message_append(reply, "s", d->state);
}

static int property_get_revision_known(sd_bus *bus, const char *path, const char *interface, const char *property,
                                       sd_bus_message *reply, void *userdata, sd_bus_error *error) {
        const lssd_device *d = userdata;
        return sd_bus_message_append(reply, "b", !d->revision_unknown);
}

static int property_get_found_by(sd_bus *bus, const char *path, const char *interface, const char *property,
                                 sd_bus_message *reply, void *userdata, sd_bus_error *error) {
        const lssd_device *d = userdata;
        int r = sd_bus_message_open_container(reply, 'a', "s");
        if (r >= 0 && (d->found_by & LSSD_FOUND_LSS))
                r = sd_bus_message_append(reply, "s", LSSD_FOUND_BY_LSS);
        if (r >= 0 && (d->found_by & LSSD_FOUND_SDO))
                r = sd_bus_message_append(reply, "s", LSSD_FOUND_BY_SDO);
        return r < 0 ? r : sd_bus_message_close_container(reply);
}

static int method_assign_node_id(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        lssd_device *d = userdata;
        lssd_assign_options o;
        uint8_t node_id;
        int r;

        r = sd_bus_message_read(m, "y", &node_id);
        if (r < 0)
                return r;
        r = lssd_validate_node_id("node_id", node_id, error);
        if (r < 0)
                return r;
        r = lssd_assign_options_read(m, &o, error);
        if (r < 0)
                return r;

        return lssd_bus_method_assign(d->bus, m, &d->id, node_id, &o, error);
}

const sd_bus_vtable lssd_device_vtable[] = {
        SD_BUS_VTABLE_START(0),

        SD_BUS_PROPERTY("VendorId", "u", NULL, offsetof(lssd_device, id.vendor), SD_BUS_VTABLE_PROPERTY_CONST),
        SD_BUS_PROPERTY("ProductCode", "u", NULL, offsetof(lssd_device, id.product), SD_BUS_VTABLE_PROPERTY_CONST),
        SD_BUS_PROPERTY("RevisionNumber", "u", NULL, offsetof(lssd_device, id.revision),
                        SD_BUS_VTABLE_PROPERTY_CONST),
        SD_BUS_PROPERTY("SerialNumber", "u", NULL, offsetof(lssd_device, id.serial), SD_BUS_VTABLE_PROPERTY_CONST),
        SD_BUS_PROPERTY("RevisionKnown", "b", property_get_revision_known, 0, SD_BUS_VTABLE_PROPERTY_CONST),
        SD_BUS_PROPERTY("NodeId", "y", NULL, offsetof(lssd_device, node_id), SD_BUS_VTABLE_PROPERTY_EMITS_CHANGE),
        SD_BUS_PROPERTY("MappedNodeId", "y", NULL, offsetof(lssd_device, mapped_node_id),
                        SD_BUS_VTABLE_PROPERTY_EMITS_CHANGE),
        SD_BUS_PROPERTY("State", "s", property_get_state, 0, SD_BUS_VTABLE_PROPERTY_EMITS_CHANGE),
        SD_BUS_PROPERTY("LastSeen", "t", NULL, offsetof(lssd_device, last_seen), SD_BUS_VTABLE_PROPERTY_EMITS_CHANGE),
        SD_BUS_PROPERTY(LSSD_DEVICE_FOUND_BY, "as", property_get_found_by, 0, SD_BUS_VTABLE_PROPERTY_EMITS_CHANGE),

        SD_BUS_METHOD_WITH_ARGS("AssignNodeId",
                                SD_BUS_ARGS("y", node_id, "a{sv}", options),
                                SD_BUS_NO_RESULT,
                                method_assign_node_id, SD_BUS_VTABLE_UNPRIVILEGED),

        SD_BUS_VTABLE_END
};
