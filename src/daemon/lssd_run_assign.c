/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <stdio.h>
#include <string.h>

#include "daemon/lssd_errors.h"
#include "daemon/lssd_job_reply.h"
#include "daemon/lssd_run.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_taken.h"

/* ---- AssignNodeId ---- */

int lssd_run_assign(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        char ident[40];
        lssd_identity_format(&j->identity, ident, sizeof(ident));

        if (!r) {
                unsigned flags = (j->assign.store ? LSS_ASSIGN_STORE : 0u) |
                                 (j->assign.verify ? LSS_ASSIGN_VERIFY : 0u) |
                                 (j->assign.force ? 0u : LSS_ASSIGN_CHECK_FREE);
                lssd_taken_check(e, true);
                int k = lss_master_assign(e->engine, &j->identity, j->node_id, flags, lssd_job_env_now(e));
                return k < 0 ? lssd_job_start_failed(e, j, k) : 1;
        }

        if (r->status != LSS_OK) {
                sd_bus_error err = SD_BUS_ERROR_NULL;
                lssd_device *held = NULL;
                if (r->may_hold && lssd_devices_get(e->devices, &j->identity, true, r->node_id, lssd_realtime_us(),
                                                    &held) >= 0) {
                        /* Configure Node-ID went out: it may hold the node-ID, nobody else gets it */
                        held->kept_node_id = j->node_id;
                        held->pending_reset = false;
                }
                if (r->in_use)
                        lssd_taken_error(e, &err, j->node_id, &j->identity, NULL);
                else
                        lssd_error_from_result(&err, r, r->failed_service, NULL);
                lssd_log_device(LOG_WARNING, e->ifname, &j->identity, j->node_id,
                                "%s: AssignNodeId %s -> node %u failed: %s", e->ifname, ident, j->node_id,
                                err.message);
                lssd_job_reply_error(j, &err);
                sd_bus_error_free(&err);
                j->result = lssd_status_to_result(r->status);
                /* the slave is not where we thought: it is not missing though, it did not answer a selective switch */
                return 0;
        }

        lssd_device *d = NULL;
        int k = lssd_devices_get(e->devices, &j->identity, true, j->node_id, lssd_realtime_us(), &d);
        if (k >= 0) {
                uint8_t old = r->node_id;
                if (d->node_id != j->node_id)
                        d->changed |= LSSD_DEVICE_CHANGED_NODE_ID;
                d->node_id = j->node_id;
                lssd_heard_owner(e->heard, j->node_id, &j->identity);
                d->assigned = true;
                d->pooled = false;
                d->blocked = false;
                d->missing = false;
                d->pending_reset = r->pending_reset;
                d->kept_node_id = 0;
                d->last_seen = lssd_realtime_us();
                d->changed |= LSSD_DEVICE_CHANGED_LAST_SEEN;
                lssd_devices_refresh(e->devices);
                if (r->changed && e->dbus)
                        (void) sd_bus_emit_signal(e->dbus, e->path, LSSD_BUS_IFACE, LSSD_SIGNAL_NODE_ID_ASSIGNED, "oyy",
                                                  d->path, old, j->node_id);
        } else
                log_error("%s: failed to record device %s: %s", e->ifname, ident, strerror(-k));

        char stored[80] = "";
        if (r->not_stored)
                snprintf(stored, sizeof(stored), ", not stored (device cannot store: %s)",
                         lss_store_error_name(r->err));
        else if (r->changed && j->assign.store)
                snprintf(stored, sizeof(stored), ", stored");
        lssd_log_device(r->pending_reset ? LOG_WARNING : LOG_NOTICE, e->ifname, &j->identity, j->node_id,
                        "%s: device %s: node-ID %u -> %u%s%s%s", e->ifname, ident, r->node_id, j->node_id,
                        r->changed ? "" : " (already set)", stored, r->pending_reset ? ", " LSSD_PENDING_RESET_TEXT : "");
        j->result = "done";
        lssd_job_reply_empty(j);
        return 0;
}

/* ---- UnassignNodeId: back to non-configured ---- */

static void append_sentence(char *buf, size_t size, const char *text) {
        size_t n = strlen(buf);
        if (n < size)
                snprintf(buf + n, size - n, "%s%s", n ? "; " : "", text);
}

typedef struct unassign_outcome {
        uint8_t old;
        const lss_result *result;
        const char *message, *warning;
} unassign_outcome;

static int fill_unassign(sd_bus_message *reply, const void *userdata) {
        const unassign_outcome *o = userdata;
        return sd_bus_message_append(reply, "ybbss", o->old, o->result->stored, o->result->in_effect, o->message,
                                     o->warning);
}

int lssd_run_unassign(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        char ident[40];
        lssd_identity_format(&j->identity, ident, sizeof(ident));

        if (!r) {
                unsigned flags = (j->unassign.store ? LSS_UNASSIGN_STORE : 0u) |
                                 (j->unassign.reset ? LSS_UNASSIGN_RESET : 0u);
                int k = lss_master_unassign(e->engine, &j->identity, flags, lssd_job_env_now(e));
                return k < 0 ? lssd_job_start_failed(e, j, k) : 1;
        }

        uint8_t old = r->node_id;
        if (r->status != LSS_OK) {
                sd_bus_error err = SD_BUS_ERROR_NULL;
                lssd_error_from_result(&err, r, r->failed_service, NULL);
                lssd_log_device(LOG_WARNING, e->ifname, &j->identity, old, "%s: UnassignNodeId %s failed: %s",
                                e->ifname, ident, err.message);
                lssd_job_reply_error(j, &err);
                sd_bus_error_free(&err);
                j->result = lssd_status_to_result(r->status);
                return 0;
        }

        /* it answered: lssd knows it from now on, at the node-ID it runs with */
        lssd_device *d = NULL;
        uint8_t now_id = r->in_effect ? LSS_NODE_ID_UNCONFIGURED : old;
        int k = lssd_devices_get(e->devices, &j->identity, true, now_id, lssd_realtime_us(), &d);
        if (k >= 0) {
                if (d->node_id != now_id)
                        d->changed |= LSSD_DEVICE_CHANGED_NODE_ID;
                d->node_id = now_id;
                if (r->in_effect) {
                        lssd_heard_owner(e->heard, LSS_NODE_ID_UNCONFIGURED, &j->identity);
                        d->assigned = d->pooled = false;
                }
                /* 255 configured: whatever it held before is given up */
                d->pending_reset = false;
                d->kept_node_id = 0;
                d->blocked = false;
                d->missing = false;
                d->last_seen = lssd_realtime_us();
                d->changed |= LSSD_DEVICE_CHANGED_LAST_SEEN;
                lssd_devices_refresh(e->devices);
                if (r->in_effect && old != LSS_NODE_ID_UNCONFIGURED && e->dbus)
                        (void) sd_bus_emit_signal(e->dbus, e->path, LSSD_BUS_IFACE, LSSD_SIGNAL_NODE_ID_ASSIGNED, "oyy",
                                                  d->path, old, LSS_NODE_ID_UNCONFIGURED);
        } else
                log_error("%s: failed to record device %s: %s", e->ifname, ident, strerror(-k));

        /* what happened, and what remains */
        char message[200], warning[400] = "", s[200];
        const char *store_part = r->stored ? ", stored" : r->not_stored ? ", not stored" : ", not stored (store=false)";
        if (old == LSS_NODE_ID_UNCONFIGURED)
                snprintf(message, sizeof(message), "non-configured already (node-ID 255)%s", store_part);
        else if (r->in_effect)
                snprintf(message, sizeof(message), "node-ID %u -> 255 (non-configured)%s; reset, it runs "
                         "non-configured now", old, store_part);
        else
                snprintf(message, sizeof(message), "node-ID %u -> 255 (non-configured) pending%s", old, store_part);
        if (old != LSS_NODE_ID_UNCONFIGURED && !r->in_effect) {
                snprintf(s, sizeof(s), "the device keeps node-ID %u until it is reset or power-cycled; use the "
                         "option reset (lssctl unassign --reset)", old);
                append_sentence(warning, sizeof(warning), s);
        }
        if (r->not_stored) {
                snprintf(s, sizeof(s), "the device cannot store (%s): its stored node-ID comes back at the next "
                         "power cycle", lss_store_error_name(r->err));
                append_sentence(warning, sizeof(warning), s);
        } else if (!r->stored) {
                if (old != LSS_NODE_ID_UNCONFIGURED)
                        snprintf(s, sizeof(s), "not stored: node-ID %u comes back at the next power cycle", old);
                else
                        snprintf(s, sizeof(s), "not stored: the stored node-ID applies at the next power cycle");
                append_sentence(warning, sizeof(warning), s);
        }
        if (d && d->mapped_node_id != 0) {
                snprintf(s, sizeof(s), "the map gives this device node-ID %u: the next auto-assign pass (also the "
                         "one at boot) gives it back", d->mapped_node_id);
                append_sentence(warning, sizeof(warning), s);
        }
        lssd_log_device(LOG_NOTICE, e->ifname, &j->identity, old, "%s: device %s: %s%s%s", e->ifname, ident, message,
                        warning[0] ? "; " : "", warning);
        j->result = "done";
        const unassign_outcome o = { old, r, message, warning };
        lssd_job_reply_done(e, j, "UnassignNodeId", fill_unassign, &o);
        return 0;
}
