/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdio.h>
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>

#include "ctl/ctl_objects.h"

static int read_string(sd_bus_message *m, char **target) {
        const char *s;
        int r = sd_bus_message_read(m, "v", "s", &s);
        if (r < 0)
                return r;
        char *d = strdup(s);
        if (!d)
                return -ENOMEM;
        free(*target);
        *target = d;
        return 0;
}

/* one property of a{sv}: the reader for its name, or skip it */
typedef int (*prop_reader)(sd_bus_message *m, const char *name, void *userdata);

static int read_props(sd_bus_message *m, prop_reader reader, void *userdata) {
        int r = sd_bus_message_enter_container(m, 'a', "{sv}");
        if (r < 0)
                return r;
        while ((r = sd_bus_message_enter_container(m, 'e', "sv")) > 0) {
                const char *name;
                r = sd_bus_message_read(m, "s", &name);
                if (r < 0)
                        return r;
                r = reader(m, name, userdata);
                if (r < 0)
                        return r;
                if (r == 0) {
                        r = sd_bus_message_skip(m, "v");
                        if (r < 0)
                                return r;
                }
                r = sd_bus_message_exit_container(m);
                if (r < 0)
                        return r;
        }
        if (r < 0)
                return r;
        return sd_bus_message_exit_container(m);
}

/* a property of the expected type; 1: read, 0: not this one (skip) */
static int read_typed(sd_bus_message *m, char type, void *p) {
        const char *contents;
        char t;
        int r = sd_bus_message_peek_type(m, &t, &contents);
        if (r < 0)
                return r;
        if (t != 'v' || !contents || contents[0] != type || contents[1])
                return 0;
        char sig[2] = { type, 0 };
        r = sd_bus_message_read(m, "v", sig, p);
        return r < 0 ? r : 1;
}

static int read_last_pass(sd_bus_message *m, ctl_bus_info *b) {
        const char *kind, *result, *outcome;
        uint32_t n;
        size_t len = 0;
        int r = sd_bus_message_enter_container(m, 'v', "(ttssa{su})");
        if (r >= 0)
                r = sd_bus_message_enter_container(m, 'r', "ttssa{su}");
        if (r >= 0)
                r = sd_bus_message_read(m, "ttss", &b->pass_started, &b->pass_duration, &kind, &result);
        if (r < 0)
                return r;
        snprintf(b->pass_kind, sizeof(b->pass_kind), "%s", kind);
        snprintf(b->pass_result, sizeof(b->pass_result), "%s", result);
        r = sd_bus_message_enter_container(m, 'a', "{su}");
        while (r >= 0 && (r = sd_bus_message_read(m, "{su}", &outcome, &n)) > 0)
                if (n > 0 && len < sizeof(b->pass_counts))
                        len += (size_t) snprintf(b->pass_counts + len, sizeof(b->pass_counts) - len, "%s%" PRIu32 " %s",
                                                 len ? ", " : "", n, outcome);
        for (int k = 0; r >= 0 && k < 3; k++)
                r = sd_bus_message_exit_container(m);
        return r < 0 ? r : 1;
}

/* ForeignMaster (btts); 1: read, 0: another type (skip) */
static int read_foreign(sd_bus_message *m, ctl_bus_info *b) {
        const char *contents, *frame;
        int active;
        char t;
        int r = sd_bus_message_peek_type(m, &t, &contents);
        if (r < 0)
                return r;
        if (t != 'v' || !contents || strcmp(contents, "(btts)") != 0)
                return 0;
        r = sd_bus_message_read(m, "v", "(btts)", &active, &b->foreign_since, &b->foreign_last, &frame);
        if (r < 0)
                return r;
        b->foreign_active = active;
        snprintf(b->foreign_frame, sizeof(b->foreign_frame), "%s", frame);
        return 1;
}

static int bus_prop(sd_bus_message *m, const char *name, void *userdata) {
        ctl_bus_info *b = userdata;
        int r;

        if (strcmp(name, "Interface") == 0)
                return (r = read_string(m, &b->ifname)) < 0 ? r : 1;
        if (strcmp(name, "State") == 0)
                return (r = read_string(m, &b->state)) < 0 ? r : 1;
        if (strcmp(name, "Job") == 0)
                return (r = read_string(m, &b->job)) < 0 ? r : 1;
        if (strcmp(name, "Bitrate") == 0)
                return read_typed(m, 'u', &b->bitrate);
        if (strcmp(name, "QueueLength") == 0)
                return read_typed(m, 'u', &b->queue_length);
        if (strcmp(name, "Progress") == 0)
                return read_typed(m, 'd', &b->progress);
        if (strcmp(name, "LastPass") == 0)
                return read_last_pass(m, b);
        if (strcmp(name, "ForeignMaster") == 0)
                return read_foreign(m, b);
        return 0;
}

/* FoundBy (as); 1: read, 0: another type (skip) */
static int read_found_by(sd_bus_message *m, ctl_device_info *d) {
        const char *contents, *s;
        char t;
        int r = sd_bus_message_peek_type(m, &t, &contents);
        if (r < 0)
                return r;
        if (t != 'v' || !contents || strcmp(contents, "as") != 0)
                return 0;
        r = sd_bus_message_enter_container(m, 'v', "as");
        if (r >= 0)
                r = sd_bus_message_enter_container(m, 'a', "s");
        while (r >= 0 && (r = sd_bus_message_read_basic(m, 's', &s)) > 0) {
                d->found_lss |= strcmp(s, LSSD_FOUND_BY_LSS) == 0;
                d->found_sdo |= strcmp(s, LSSD_FOUND_BY_SDO) == 0;
        }
        if (r >= 0)
                r = sd_bus_message_exit_container(m);
        if (r >= 0)
                r = sd_bus_message_exit_container(m);
        return r < 0 ? r : 1;
}

static int device_prop(sd_bus_message *m, const char *name, void *userdata) {
        ctl_device_info *d = userdata;
        static const char *const ids[4] = { "VendorId", "ProductCode", "RevisionNumber", "SerialNumber" };
        int r;

        for (size_t i = 0; i < 4; i++)
                if (strcmp(name, ids[i]) == 0)
                        return read_typed(m, 'u', &d->id[i]);
        if (strcmp(name, "NodeId") == 0)
                return read_typed(m, 'y', &d->node_id);
        if (strcmp(name, "MappedNodeId") == 0)
                return read_typed(m, 'y', &d->mapped_node_id);
        if (strcmp(name, "LastSeen") == 0)
                return read_typed(m, 't', &d->last_seen);
        if (strcmp(name, "RevisionKnown") == 0) {
                int known = 1;
                r = read_typed(m, 'b', &known);
                d->revision_unknown = r > 0 && !known;
                return r;
        }
        if (strcmp(name, "State") == 0)
                return (r = read_string(m, &d->state)) < 0 ? r : 1;
        if (strcmp(name, LSSD_DEVICE_FOUND_BY) == 0)
                return read_found_by(m, d);
        return 0;
}

static int manager_prop(sd_bus_message *m, const char *name, void *userdata) {
        ctl_objects *o = userdata;
        int r;

        if (strcmp(name, "Version") == 0)
                return (r = read_string(m, &o->version)) < 0 ? r : 1;
        return 0;
}

static int grow(void **array, size_t n, size_t size) {
        void *v = realloc(*array, (n + 1) * size);
        if (!v)
                return -ENOMEM;
        memset((char *) v + n * size, 0, size);
        *array = v;
        return 0;
}

static int read_object(sd_bus_message *m, ctl_objects *o) {
        const char *path;
        int r = sd_bus_message_read(m, "o", &path);
        if (r < 0)
                return r;
        r = sd_bus_message_enter_container(m, 'a', "{sa{sv}}");
        if (r < 0)
                return r;
        while ((r = sd_bus_message_enter_container(m, 'e', "sa{sv}")) > 0) {
                const char *iface;
                r = sd_bus_message_read(m, "s", &iface);
                if (r < 0)
                        return r;
                if (strcmp(iface, LSSD_BUS_IFACE) == 0) {
                        r = grow((void **) &o->buses, o->n_buses, sizeof(ctl_bus_info));
                        if (r < 0)
                                return r;
                        ctl_bus_info *b = &o->buses[o->n_buses++];
                        b->path = strdup(path);
                        if (!b->path)
                                return -ENOMEM;
                        r = read_props(m, bus_prop, b);
                } else if (strcmp(iface, LSSD_DEVICE_IFACE) == 0) {
                        r = grow((void **) &o->devices, o->n_devices, sizeof(ctl_device_info));
                        if (r < 0)
                                return r;
                        ctl_device_info *d = &o->devices[o->n_devices++];
                        d->path = strdup(path);
                        if (!d->path)
                                return -ENOMEM;
                        r = ctl_path_ifname(path, &d->ifname);
                        if (r < 0)
                                return r;
                        r = read_props(m, device_prop, d);
                } else
                        r = sd_bus_message_skip(m, "a{sv}");
                if (r < 0)
                        return r;
                r = sd_bus_message_exit_container(m);
                if (r < 0)
                        return r;
        }
        if (r < 0)
                return r;
        return sd_bus_message_exit_container(m);
}

/* where a bus stands in Manager.Buses; buses not listed go last */
static size_t bus_rank(char **order, size_t n, const char *path) {
        for (size_t i = 0; i < n; i++)
                if (strcmp(order[i], path) == 0)
                        return i;
        return n;
}

static int compare_devices(const void *a, const void *b) {
        const ctl_device_info *x = a, *y = b;
        int r = strcmp(x->ifname ? x->ifname : "", y->ifname ? y->ifname : "");
        if (r != 0)
                return r;
        for (size_t i = 0; i < 4; i++)
                if (x->id[i] != y->id[i])
                        return x->id[i] < y->id[i] ? -1 : 1;
        return 0;
}

int ctl_objects_load(ctl_context *c, ctl_objects *ret) {
        sd_bus_error error = SD_BUS_ERROR_NULL;
        sd_bus_message *reply = NULL;
        char **order = NULL;
        ctl_objects o = { 0 };
        int r;

        r = ctl_connect(c);
        if (r < 0)
                return r;
        r = sd_bus_call_method(c->bus, LSSD_BUS_NAME, LSSD_MANAGER_PATH, "org.freedesktop.DBus.Properties", "GetAll",
                               &error, &reply, "s", LSSD_MANAGER_IFACE);
        if (r < 0) {
                r = ctl_bus_fail(c, &error, r, "Failed to read lssd's properties");
                goto finish;
        }
        r = read_props(reply, manager_prop, &o);
        if (r < 0)
                goto parse_error;
        reply = sd_bus_message_unref(reply);

        r = sd_bus_get_property_strv(c->bus, LSSD_BUS_NAME, LSSD_MANAGER_PATH, LSSD_MANAGER_IFACE, "Buses", &error,
                                     &order);
        if (r < 0) {
                r = ctl_bus_fail(c, &error, r, "Failed to read the list of buses");
                goto finish;
        }

        r = sd_bus_call_method(c->bus, LSSD_BUS_NAME, LSSD_ROOT_PATH, "org.freedesktop.DBus.ObjectManager",
                               "GetManagedObjects", &error, &reply, NULL);
        if (r < 0) {
                r = ctl_bus_fail(c, &error, r, "Failed to list lssd's objects");
                goto finish;
        }
        r = sd_bus_message_enter_container(reply, 'a', "{oa{sa{sv}}}");
        if (r < 0)
                goto parse_error;
        while ((r = sd_bus_message_enter_container(reply, 'e', "oa{sa{sv}}")) > 0) {
                r = read_object(reply, &o);
                if (r < 0)
                        goto parse_error;
                r = sd_bus_message_exit_container(reply);
                if (r < 0)
                        goto parse_error;
        }
        if (r < 0)
                goto parse_error;

        /* Manager.Buses order, and only buses it lists (a bus being removed may linger) */
        size_t n_order = 0;
        while (order && order[n_order])
                n_order++;
        for (size_t i = 0; i < o.n_buses; i++)
                for (size_t k = i + 1; k < o.n_buses; k++)
                        if (bus_rank(order, n_order, o.buses[k].path) < bus_rank(order, n_order, o.buses[i].path)) {
                                ctl_bus_info t = o.buses[i];
                                o.buses[i] = o.buses[k];
                                o.buses[k] = t;
                        }
        if (o.n_devices > 1)
                qsort(o.devices, o.n_devices, sizeof(ctl_device_info), compare_devices);

        *ret = o;
        o = (ctl_objects) { 0 };
        r = 0;
        goto finish;

parse_error:
        r = ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to parse lssd's answer: %s", strerror(-r));
finish:
        if (order)
                for (char **s = order; *s; s++)
                        free(*s);
        free(order);
        ctl_objects_done(&o);
        sd_bus_message_unref(reply);
        sd_bus_error_free(&error);
        return r;
}

void ctl_objects_done(ctl_objects *o) {
        for (size_t i = 0; i < o->n_buses; i++) {
                free(o->buses[i].path);
                free(o->buses[i].ifname);
                free(o->buses[i].state);
                free(o->buses[i].job);
        }
        for (size_t i = 0; i < o->n_devices; i++) {
                free(o->devices[i].path);
                free(o->devices[i].ifname);
                free(o->devices[i].state);
        }
        free(o->buses);
        free(o->devices);
        free(o->version);
        *o = (ctl_objects) { 0 };
}
