/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <stdio.h>
#include <string.h>

#include "daemon/lssd_errors.h"
#include "daemon/lssd_job_reply.h"
#include "daemon/lssd_run.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_taken.h"

/* ---- AutoAssign: the engine's pass over the map ---- */

/* A mapped device that is not there: the objects of it we know (any revision
 * when the map has none) are missing; only when we know none is one made from
 * the map's identity, so that the absence shows. */
static bool autoassign_mark_missing(lssd_job_env *e, const lssd_job *j, const lss_outcome *o) {
        bool marked = false;
        for (size_t i = 0; i < j->plan.n_map; i++) {
                const lss_map_entry *m = &j->plan.map[i];
                if (!lss_map_entry_matches(m, &o->id))
                        continue;
                for (lssd_device *d = e->devices->head; d; d = d->next)
                        if (lss_map_entry_matches(m, &d->id)) {
                                d->missing = true;
                                d->blocked = false;
                                marked = true;
                        }
        }
        return marked;
}

/* The map entry naming an outcome's device, NULL when the map has none. */
static const lss_map_entry *outcome_map_entry(const lssd_job *j, const lss_outcome *o) {
        for (size_t i = 0; i < j->plan.n_map; i++)
                if (lss_map_entry_matches(&j->plan.map[i], &o->id))
                        return &j->plan.map[i];
        return NULL;
}

/* A missing device's identity is the map's: without a revision there, its
 * revision (0) is not known. */
static bool outcome_revision_known(const lssd_job *j, const lss_outcome *o) {
        const lss_map_entry *m = o->kind == LSS_OUTCOME_MISSING ? outcome_map_entry(j, o) : NULL;
        return !m || m->revision_known;
}

/* Brings the Device object of one outcome up to date. */
static void autoassign_publish_one(lssd_job_env *e, const lssd_job *j, const lss_outcome *o, uint64_t now_realtime) {
        bool missing = o->kind == LSS_OUTCOME_MISSING;
        uint8_t node_id = o->new_node_id != 0 ? o->new_node_id : LSS_NODE_ID_UNCONFIGURED;
        lssd_device *d = NULL;
        char ident[40];

        if (missing && autoassign_mark_missing(e, j, o))
                return;
        /* a device first known as missing was never seen: LastSeen 0 */
        int k = lssd_devices_get(e->devices, &o->id, outcome_revision_known(j, o), node_id,
                                 missing ? 0 : lssd_realtime_us(), &d);
        if (k < 0) {
                log_error("%s: failed to record device %s: %s", e->ifname,
                          lssd_identity_format(&o->id, ident, sizeof(ident)), strerror(-k));
                return;
        }
        if (!missing)
                lssd_heard_owner(e->heard, node_id, &o->id);
        if (!missing && o->new_node_id != 0 && d->node_id != o->new_node_id) {
                d->node_id = o->new_node_id;
                d->changed |= LSSD_DEVICE_CHANGED_NODE_ID;
        }
        /* a replacement is not in the map (MappedNodeId 0) until the map
         * is updated: "assigned", as by AssignNodeId */
        if (o->kind == LSS_OUTCOME_ASSIGNED || o->kind == LSS_OUTCOME_POOL || o->kind == LSS_OUTCOME_REPLACED) {
                d->assigned = true;
                d->pooled = o->kind == LSS_OUTCOME_POOL;
        }
        d->blocked = o->kind == LSS_OUTCOME_CONFLICT;
        d->missing = missing;
        /* what it holds beyond what it answers to: only an assignment or its
         * verification says it (a failure that kept nothing keeps what was) */
        if (o->kind == LSS_OUTCOME_ASSIGNED || o->kind == LSS_OUTCOME_POOL || o->kind == LSS_OUTCOME_REPLACED ||
            o->kind == LSS_OUTCOME_UNCHANGED) {
                /* "unchanged" is what Inquire Node-ID says, which is the
                 * pending node-ID of a device that has none in effect (Lely):
                 * pending until it is heard there */
                d->pending_reset = o->pending_reset || (o->kind == LSS_OUTCOME_UNCHANGED && d->pending_reset &&
                                                        !lssd_heard_taken(e->heard, node_id, NULL));
                d->kept_node_id = 0;
        } else if (o->kind == LSS_OUTCOME_FAILED && o->kept_node_id) {
                d->pending_reset = false;
                d->kept_node_id = o->kept_node_id;
        }
        if (!missing) {
                d->last_seen = now_realtime;
                d->changed |= LSSD_DEVICE_CHANGED_LAST_SEEN;
        }
}

/* An identity for people; a map entry's without a revision has "-" there. */
static const char *identity_format(const lss_identity *id, bool revision_known, char *buf, size_t size) {
        if (revision_known)
                return lssd_identity_format(id, buf, size);
        snprintf(buf, size, "%08x:%08x:-:%08x", id->vendor, id->product, id->serial);
        return buf;
}

/* What an outcome needs said beyond its kind ("" when nothing): the
 * journal line and the reply's detail. */
static void outcome_detail(const lss_outcome *o, char *buf, size_t size) {
        char old[40], stored[80] = "";
        if (o->not_stored)
                snprintf(stored, sizeof(stored), "not stored (device cannot store: %s)", lss_store_error_name(o->err));
        if (o->pending_reset)
                snprintf(stored + strlen(stored), sizeof(stored) - strlen(stored), "%s%s", stored[0] ? ", " : "",
                         LSSD_PENDING_RESET_TEXT);
        if (o->kind == LSS_OUTCOME_REPLACED)
                snprintf(buf, size, "%s %s (missing)%s%s", o->dry ? "would replace" : "replaced",
                         identity_format(&o->replaced, o->replaced_revision_known, old, sizeof(old)),
                         stored[0] ? ", " : "", stored);
        else
                snprintf(buf, size, "%s", stored[0] ? stored : o->message);
}

static bool outcome_changed(const lss_outcome *o) {
        return (o->kind == LSS_OUTCOME_ASSIGNED || o->kind == LSS_OUTCOME_POOL || o->kind == LSS_OUTCOME_REPLACED) &&
               !o->dry;
}

/* The reply's and the journal's name: a dry run's changes are "would-..." */
static const char *outcome_name(const lss_outcome *o) {
        if (o->dry)
                return o->kind == LSS_OUTCOME_POOL ? "would-pool" :
                       o->kind == LSS_OUTCOME_REPLACED ? "would-replace" : "would-assign";
        return lss_outcome_name(o->kind);
}

static void autoassign_log_one(lssd_job_env *e, const lssd_job *j, const lss_outcome *o) {
        char ident[40], detail[200];
        int priority = LOG_INFO;

        /* the map's identity without a revision: not 0 */
        identity_format(&o->id, outcome_revision_known(j, o), ident, sizeof(ident));
        switch (o->kind) {
        case LSS_OUTCOME_ASSIGNED:
        case LSS_OUTCOME_POOL:
        case LSS_OUTCOME_REPLACED:
                priority = o->pending_reset ? LOG_WARNING : LOG_NOTICE;
                break;
        case LSS_OUTCOME_MISSING:
        case LSS_OUTCOME_CONFLICT:
        case LSS_OUTCOME_FAILED:
                priority = LOG_WARNING;
                break;
        default:
                break;
        }
        outcome_detail(o, detail, sizeof(detail));
        const char *sep = !detail[0]                                                            ? ""
                          : (o->not_stored || o->pending_reset) && o->kind != LSS_OUTCOME_REPLACED ? ", "
                                                                                                   : ": ";
        const lss_map_entry *m = outcome_map_entry(j, o);
        if (o->kind == LSS_OUTCOME_MISSING) /* it has no node-ID here: the map's says which device */
                lssd_log_device(priority, e->ifname, &o->id, o->new_node_id,
                                "%s: AutoAssign: device %s missing, map node-ID %u%s%s", e->ifname, ident,
                                m ? m->node_id : 0u, sep, detail);
        else
                lssd_log_device(priority, e->ifname, &o->id, o->new_node_id,
                                "%s: AutoAssign: device %s %s, node-ID %u -> %u%s%s", e->ifname, ident,
                                outcome_name(o), o->old_node_id, o->new_node_id, sep, detail);
        if (o->kind == LSS_OUTCOME_REPLACED && !o->dry) {
                char old[40];
                lssd_log_device(LOG_NOTICE, e->ifname, &o->id, o->new_node_id,
                                "%s: %s replaced %s (missing) at node-ID %u: update the map entry", e->ifname, ident,
                                identity_format(&o->replaced, o->replaced_revision_known, old, sizeof(old)),
                                o->new_node_id);
        }
}

/* The reply: one outcome per device, then the verdict. */
typedef struct aa_reply {
        const lss_outcome *out;
        size_t n;
        const char *result;
} aa_reply;

static int fill_outcomes(sd_bus_message *reply, const void *userdata) {
        const aa_reply *a = userdata;
        int k = sd_bus_message_open_container(reply, 'a', "(uuuuyyss)");
        for (size_t i = 0; k >= 0 && i < a->n; i++) {
                const lss_outcome *o = &a->out[i];
                char detail[440];
                outcome_detail(o, detail, sizeof(detail));
                k = sd_bus_message_append(reply, "(uuuuyyss)", o->id.vendor, o->id.product, o->id.revision,
                                          o->id.serial, o->old_node_id, o->new_node_id, outcome_name(o), detail);
        }
        if (k >= 0)
                k = sd_bus_message_close_container(reply);
        return k < 0 ? k : sd_bus_message_append(reply, "s", a->result);
}

int lssd_run_autoassign(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        size_t n = 0, count[LSS_OUTCOME_FAILED + 1] = { 0 };
        const lss_outcome *out;
        sd_bus *bus = e->dbus;
        uint64_t now_realtime = lssd_realtime_us();

        if (!r) {
                e->pass_started_us = now_realtime;
                j->plan.unstored = lssd_unstored_table(&e->unstored);
                lssd_taken_check(e, false);
                lssd_run_expect_finds(e);
                int k = lss_master_autoassign(e->engine, &j->plan, lssd_job_env_now(e));
                return k < 0 ? lssd_job_start_failed(e, j, k) : 1;
        }
        if (r->status == LSS_OK)
                lssd_unstored_forget(&e->unstored);

        const lss_master_stats *st = lss_master_get_stats(e->engine);
        if (st->patient_wait_us)
                log_notice("%s: AutoAssign: mapped devices were not found at first: looked for them again with "
                           "waits of %u ms (the configured LSS timeout is %u ms)", e->ifname,
                           st->patient_wait_us / 1000, e->config->lss_timeout_ms);
        out = lss_master_outcomes(e->engine, &n);
        for (size_t i = 0; i < n; i++) {
                /* what a dry run would change did not change: the device is
                 * where it was found */
                lss_outcome seen = out[i];
                if (seen.dry) {
                        seen.kind = LSS_OUTCOME_UNCHANGED;
                        seen.new_node_id = seen.old_node_id;
                        seen.dry = false;
                }
                autoassign_publish_one(e, j, &seen, now_realtime);
                autoassign_log_one(e, j, &out[i]);
                if ((unsigned) out[i].kind <= LSS_OUTCOME_FAILED)
                        count[out[i].kind]++;
        }
        lssd_devices_refresh(e->devices);

        if (bus)
                for (size_t i = 0; i < n; i++) {
                        const lss_outcome *o = &out[i];
                        lssd_device *d = lssd_devices_find(e->devices, &o->id);
                        if (outcome_changed(o) && d)
                                (void) sd_bus_emit_signal(bus, e->path, LSSD_BUS_IFACE,
                                                          LSSD_SIGNAL_NODE_ID_ASSIGNED, "oyy", d->path,
                                                          o->old_node_id, o->new_node_id);
                        else if (o->kind == LSS_OUTCOME_UNKNOWN)
                                (void) sd_bus_emit_signal(bus, e->path, LSSD_BUS_IFACE, LSSD_SIGNAL_UNKNOWN_DEVICE,
                                                          "uuuu", o->id.vendor, o->id.product, o->id.revision,
                                                          o->id.serial);
                        if (o->kind == LSS_OUTCOME_REPLACED && !o->dry)
                                (void) sd_bus_emit_signal(bus, e->path, LSSD_BUS_IFACE, LSSD_SIGNAL_DEVICE_REPLACED,
                                                          "(uuuu)(uuuu)y",
                                                          o->replaced.vendor, o->replaced.product,
                                                          o->replaced.revision, o->replaced.serial, o->id.vendor,
                                                          o->id.product, o->id.revision, o->id.serial, o->new_node_id);
                }

        /* a dry run is not the bus's last pass */
        lssd_pass_record dry_rec, *rec = j->plan.dry_run ? &dry_rec : &e->last_pass;
        *rec = (lssd_pass_record) { .started_us = e->pass_started_us, .boot = e->boot_pending,
                                    .duration_us = now_realtime > e->pass_started_us ?
                                                           now_realtime - e->pass_started_us : 0 };
        for (size_t i = 0; i <= LSS_OUTCOME_FAILED; i++)
                rec->counts[i] = (uint32_t) count[i];
        /* the bus matches the map only when every mapped device has its node-ID */
        const char *verdict = r->status != LSS_OK ? lssd_status_to_result(r->status)
                              : count[LSS_OUTCOME_MISSING] + count[LSS_OUTCOME_CONFLICT] + count[LSS_OUTCOME_FAILED] > 0
                                      ? "partial"
                                      : "done";
        snprintf(rec->result, sizeof(rec->result), "%s", verdict);
        if (!j->plan.dry_run)
                e->ops->last_pass_changed(e->userdata);

        snprintf(j->summary, sizeof(j->summary),
                 "%s: %zu %sassigned, %zu from the pool, %zu replaced, %zu unchanged, %zu unknown, %zu missing, "
                 "%zu conflicts, %zu failed", e->ifname, count[LSS_OUTCOME_ASSIGNED], j->plan.dry_run ? "would be " : "",
                 count[LSS_OUTCOME_POOL], count[LSS_OUTCOME_REPLACED],
                 count[LSS_OUTCOME_UNCHANGED], count[LSS_OUTCOME_UNKNOWN], count[LSS_OUTCOME_MISSING],
                 count[LSS_OUTCOME_CONFLICT], count[LSS_OUTCOME_FAILED]);

        if (r->status != LSS_OK) {
                /* the pass as a whole broke off (bus down, cancelled): what it did is published above */
                sd_bus_error err = SD_BUS_ERROR_NULL;
                lssd_error_from_result(&err, r, LSS_SERVICE_NONE, "AutoAssign: ");
                log_warning("%s: %s (%s)", e->ifname, err.message, j->summary);
                lssd_job_reply_error(j, &err);
                sd_bus_error_free(&err);
                j->result = lssd_status_to_result(r->status);
                return 0;
        }

        log_notice("AutoAssign%s on %s", j->plan.dry_run ? " (dry run: nothing was sent but discovery)" : "",
                   j->summary);
        j->result = verdict;

        const aa_reply a = { .out = out, .n = n, .result = j->result };
        lssd_job_reply_done(e, j, "AutoAssign", fill_outcomes, &a);
        return 0;
}
