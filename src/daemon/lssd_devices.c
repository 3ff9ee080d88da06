/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <string.h>

#include "daemon/lssd_devices.h"

void lssd_devices_init(lssd_devices *ds, lssd_bus *owner, const char *ifname, const lssd_devices_ops *ops,
                       void *userdata) {
        *ds = (lssd_devices) { .owner = owner, .ifname = ifname, .ops = ops, .userdata = userdata };
}

void lssd_devices_clear(lssd_devices *ds) {
        while (ds->head) {
                lssd_device *d = ds->head;
                ds->head = d->next;
                ds->n--;
                if (ds->ops && ds->ops->removed)
                        ds->ops->removed(ds->userdata, d);
                lssd_device_free(d);
        }
}

static uint8_t mapped_node_id(const lssd_devices *ds, const lss_identity *id);

void lssd_devices_set_config(lssd_devices *ds, const lssconf_bus *config) {
        ds->config = config;
        /* a device known only from a map entry (never seen: LastSeen 0) goes
         * with the entry; one that was seen stays, unmapped now */
        for (lssd_device **p = &ds->head; *p;) {
                lssd_device *d = *p;
                if (d->last_seen != 0 || mapped_node_id(ds, &d->id) != 0) {
                        p = &d->next;
                        continue;
                }
                *p = d->next;
                ds->n--;
                if (ds->ops && ds->ops->removed)
                        ds->ops->removed(ds->userdata, d);
                lssd_device_free(d);
        }
}

lssd_device *lssd_devices_find(const lssd_devices *ds, const lss_identity *id) {
        for (lssd_device *d = ds->head; d; d = d->next)
                if (lss_identity_equal(&d->id, id))
                        return d;
        return NULL;
}

lssd_device *lssd_devices_with_node_id(const lssd_devices *ds, uint8_t node_id, const lss_identity *except) {
        if (!lss_node_id_valid(node_id))
                return NULL;
        for (lssd_device *d = ds->head; d; d = d->next)
                if (!d->missing && d->node_id == node_id && !(except && lss_identity_equal(&d->id, except)))
                        return d;
        return NULL;
}

static uint8_t mapped_node_id(const lssd_devices *ds, const lss_identity *id) {
        const lssconf_device *c = ds->config ? lssconf_lookup_device(ds->config, id) : NULL;
        return c ? c->node_id : 0;
}

static const char *device_state(const lssd_devices *ds, const lssd_device *d) {
        bool conflict = lssd_devices_with_node_id(ds, d->node_id, &d->id) != NULL;
        /* not given its node-ID because another device answers to it: say so even while non-configured */
        if (d->blocked && !d->missing)
                return "conflict";
        return lssd_device_state(d->node_id, d->mapped_node_id, d->missing, conflict, d->assigned, d->pooled,
                                 d->pending_reset);
}

lssd_device *lssd_devices_holding(const lssd_devices *ds, uint8_t node_id, const lss_identity *except) {
        if (!lss_node_id_valid(node_id))
                return NULL;
        /* missing or not, it keeps what it holds */
        for (lssd_device *d = ds->head; d; d = d->next)
                if ((d->kept_node_id == node_id || (d->pending_reset && d->node_id == node_id)) &&
                    !(except && lss_identity_equal(&d->id, except)))
                        return d;
        return NULL;
}

int lssd_devices_get(lssd_devices *ds, const lss_identity *id, bool revision_known, uint8_t node_id,
                     uint64_t now_realtime, lssd_device **ret) {
        lssd_device *d = lssd_devices_find(ds, id);
        int r;

        if (d) {
                *ret = d;
                return 0;
        }
        r = lssd_device_new(ds->owner, ds->ifname, id, &d);
        if (r < 0)
                return r;
        d->revision_unknown = !revision_known; /* before the object is announced: RevisionKnown is const */
        d->node_id = node_id;
        d->mapped_node_id = mapped_node_id(ds, id);
        d->last_seen = now_realtime;
        if (ds->ops && ds->ops->add) {
                r = ds->ops->add(ds->userdata, d);
                if (r < 0) {
                        lssd_device_free(d);
                        return r;
                }
        }
        /* append: objects keep the order they were found in */
        lssd_device **tail = &ds->head;
        while (*tail)
                tail = &(*tail)->next;
        *tail = d;
        ds->n++;
        d->state = device_state(ds, d);
        if (ds->ops && ds->ops->added)
                ds->ops->added(ds->userdata, d);
        /* a new device can put others in conflict */
        lssd_devices_refresh(ds);
        *ret = d;
        return 1;
}

void lssd_devices_refresh(lssd_devices *ds) {
        for (lssd_device *d = ds->head; d; d = d->next) {
                uint8_t mapped = mapped_node_id(ds, &d->id);
                if (mapped != d->mapped_node_id) {
                        d->mapped_node_id = mapped;
                        d->changed |= LSSD_DEVICE_CHANGED_MAPPED_NODE_ID;
                }
        }
        for (lssd_device *d = ds->head; d; d = d->next) {
                const char *s = device_state(ds, d);
                if (strcmp(s, d->state) != 0) {
                        d->state = s;
                        d->changed |= LSSD_DEVICE_CHANGED_STATE;
                }
        }
        for (lssd_device *d = ds->head; d; d = d->next) {
                char *names[6];
                size_t n = 0;
                if (!d->changed)
                        continue;
                if (d->changed & LSSD_DEVICE_CHANGED_NODE_ID)
                        names[n++] = (char *) "NodeId";
                if (d->changed & LSSD_DEVICE_CHANGED_MAPPED_NODE_ID)
                        names[n++] = (char *) "MappedNodeId";
                if (d->changed & LSSD_DEVICE_CHANGED_STATE)
                        names[n++] = (char *) "State";
                if (d->changed & LSSD_DEVICE_CHANGED_LAST_SEEN)
                        names[n++] = (char *) "LastSeen";
                if (d->changed & LSSD_DEVICE_CHANGED_FOUND_BY)
                        names[n++] = (char *) LSSD_DEVICE_FOUND_BY;
                names[n] = NULL;
                d->changed = 0;
                if (ds->ops && ds->ops->changed)
                        ds->ops->changed(ds->userdata, d, names);
        }
}

void lssd_devices_heard(lssd_devices *ds, const lss_frame *f) {
        uint8_t node, state;
        bool any = false;
        if (!bootup_decode(f, &node, &state) || state != 0)
                return;
        for (lssd_device *d = ds->head; d; d = d->next)
                if (d->pending_reset && d->node_id == node) {
                        d->pending_reset = false;
                        any = true;
                }
        if (any)
                lssd_devices_refresh(ds);
}
