/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_errors.h"
#include "daemon/lssd_job_reply.h"
#include "daemon/lssd_run.h"
#include "daemon/lssd_log.h"

/* ---- Scan: the stages of lssd_run_discover.c (fastscan enumeration,
 * slowscan per vendor/product pair, with option sdo SDO discovery of 1018h
 * at every node-ID and the confirmation through LSS of what only SDO
 * found), then the devices published ---- */

static int scan_start_stage(lssd_job_env *e, lssd_job *j) {
        int k = lssd_discover_start(e, j);
        return k < 0 ? lssd_job_start_failed(e, j, k) : 1;
}

/* The stage ended (or the job): its time counts for its part. */
static void scan_part_end(lssd_job_env *e, lssd_job *j) {
        uint64_t now = lssd_job_env_now(e);
        j->part_us[lssd_discover_part(j)] += now - j->part_started;
        j->part_started = now;
}

static int compare_devices(const void *a, const void *b) {
        const lssd_scan_find *x = a, *y = b;
        return lss_identity_compare(&x->dev.id, &y->dev.id);
}

static bool scan_covers(const lssd_job *j, const lssd_device *d) {
        /* every non-configured slave answers the fastscan */
        if (d->node_id == LSS_NODE_ID_UNCONFIGURED)
                return true;
        for (size_t i = 0; i < j->n_pairs; i++)
                if (j->pairs[i].vendor == d->id.vendor && j->pairs[i].product == d->id.product)
                        return true;
        return false;
}

/* The device object of a device the scan found, brought up to date
 * (created when new); NULL when it could not be recorded. */
static lssd_device *scan_record(lssd_job_env *e, const lss_device *f, unsigned by, uint64_t now_realtime) {
        lssd_device *d = NULL;
        char ident[40];
        int k = lssd_devices_get(e->devices, &f->id, true, f->node_id, lssd_realtime_us(), &d);
        if (k < 0) {
                log_error("%s: failed to record device %s: %s", e->ifname,
                          lssd_identity_format(&f->id, ident, sizeof(ident)), strerror(-k));
                return NULL;
        }
        lssd_heard_owner(e->heard, f->node_id, &f->id);
        if (d->node_id != f->node_id) {
                d->node_id = f->node_id;
                d->assigned = false;
                d->changed |= LSSD_DEVICE_CHANGED_NODE_ID;
        }
        if (d->found_by != by) {
                d->found_by = (uint8_t) by;
                d->changed |= LSSD_DEVICE_CHANGED_FOUND_BY;
        }
        d->missing = false;
        d->last_seen = now_realtime;
        d->changed |= LSSD_DEVICE_CHANGED_LAST_SEEN;
        return d;
}

static bool scan_announced(const lssd_job *j, const lss_identity *id) {
        for (size_t i = 0; i < j->n_announced; i++)
                if (lss_identity_equal(&j->announced[i], id))
                        return true;
        return false;
}

/* DeviceFound, and UnknownDevice when the map does not know it: once per
 * device and job. */
static void scan_announce(lssd_job_env *e, lssd_job *j, const lss_device *f, const lssd_device *d) {
        sd_bus *bus = e->dbus;
        lss_identity *a = realloc(j->announced, (j->n_announced + 1) * sizeof(*a));
        if (a) {
                j->announced = a;
                j->announced[j->n_announced++] = f->id;
        }
        if (!bus)
                return;
        if (d)
                (void) sd_bus_emit_signal(bus, e->path, LSSD_BUS_IFACE, LSSD_SIGNAL_DEVICE_FOUND, "o", d->path);
        if (!lssconf_lookup_device(e->config, &f->id))
                (void) sd_bus_emit_signal(bus, e->path, LSSD_BUS_IFACE, LSSD_SIGNAL_UNKNOWN_DEVICE, "uuuu",
                                          f->id.vendor, f->id.product, f->id.revision, f->id.serial);
}

void lssd_scan_found(lssd_job_env *e, lssd_job *j, const lss_device *f) {
        if (scan_announced(j, &f->id))
                return; /* by an earlier stage: the end brings its node-ID up to date */
        /* the confirmation stage confirms what SDO found */
        unsigned by = LSSD_FOUND_LSS | (j->scan_sdo && j->stage == lssd_discover_confirm_stage(j) ? LSSD_FOUND_SDO : 0);
        lssd_device *d = scan_record(e, f, by, lssd_realtime_us());
        if (!d)
                return; /* tried again at the end */
        lssd_devices_refresh(e->devices);
        scan_announce(e, j, f, d);
}

/* A map entry no known device matches was never seen: a complete Scan asks
 * for every map entry's vendor and product (and every non-configured
 * slave), so it is missing. Published as AutoAssign publishes it (LastSeen
 * 0, no revision when the map has none), so that the absence shows, in
 * lssctl list and in the map lssctl scan --as-config prints, also where no
 * AutoAssign ran. */
static void scan_publish_map_missing(lssd_job_env *e) {
        for (size_t i = 0; e->config && i < e->config->n_devices; i++) {
                const lssconf_device *c = &e->config->devices[i];
                bool known = false;
                for (const lssd_device *d = e->devices->head; d && !known; d = d->next)
                        known = lss_identity_matches(&c->identity, c->has_revision, &d->id);
                if (known)
                        continue;
                lssd_device *d = NULL;
                char ident[40];
                int k = lssd_devices_get(e->devices, &c->identity, c->has_revision, LSS_NODE_ID_UNCONFIGURED, 0, &d);
                if (k < 0)
                        log_error("%s: failed to record missing device %s: %s", e->ifname,
                                  lssd_identity_format(&c->identity, ident, sizeof(ident)), strerror(-k));
                else
                        d->missing = true;
        }
}

static void scan_publish(lssd_job_env *e, lssd_job *j, uint64_t now_realtime) {
        /* who was not found although the scan would have */
        if (!j->scan_incomplete)
                for (lssd_device *d = e->devices->head; d; d = d->next) {
                        bool found = false;
                        for (size_t i = 0; i < j->n_found && !found; i++)
                                found = lss_identity_equal(&j->found[i].dev.id, &d->id);
                        if (!found && !d->missing && scan_covers(j, d))
                                d->missing = true;
                }

        /* Devices announced when they were found are up to date, unless a
         * later stage read another node-ID or found them another way too;
         * the others are recorded now. */
        for (size_t i = 0; i < j->n_found; i++) {
                const lss_device *f = &j->found[i].dev;
                const lssd_device *d = lssd_devices_find(e->devices, &f->id);
                if (!scan_announced(j, &f->id) || !d || d->node_id != f->node_id || d->found_by != j->found[i].by)
                        (void) scan_record(e, f, j->found[i].by, now_realtime);
        }
        if (!j->scan_incomplete)
                scan_publish_map_missing(e);
        lssd_devices_refresh(e->devices);

        for (size_t i = 0; i < j->n_found; i++) {
                const lss_device *f = &j->found[i].dev;
                if (!scan_announced(j, &f->id))
                        scan_announce(e, j, f, lssd_devices_find(e->devices, &f->id));
        }
}

/* The notes of the reply that every Scan of its kind has: what it did not
 * look for, and the devices SDO found that LSS cannot address (the notes of
 * node-IDs it could not identify were added by the SDO stage). */
static void scan_notes(lssd_job *j) {
        char text[320];
        if (!j->scan_sdo) {
                size_t n = (size_t) snprintf(text, sizeof(text), "configured devices of vendor/product pairs "
                                             "not scanned were not looked for (option sdo = false, lssctl scan "
                                             "--no-sdo); scanned:");
                for (size_t i = 0; i < j->n_pairs && n < sizeof(text); i++)
                        n += (size_t) snprintf(text + n, sizeof(text) - n, " %08x:%08x", j->pairs[i].vendor,
                                               j->pairs[i].product);
                if (j->n_pairs == 0 && n < sizeof(text))
                        snprintf(text + n, sizeof(text) - n, " none");
        } else
                snprintf(text, sizeof(text), "configured devices in NMT Stopped that send no heartbeat were not "
                         "looked for: they do not answer SDO; AutoAssign with nmt_stop, or Scan with their "
                         "vendor/product, finds them");
        (void) lssd_job_add_note(j, text);
        for (size_t i = 0; i < j->n_found; i++) {
                char ident[40];
                if (j->found[i].by != LSSD_FOUND_SDO)
                        continue;
                snprintf(text, sizeof(text), "node %u: %s answered SDO (1018h) but not the LSS selective "
                         "switch: lssd cannot give it a node-ID", j->found[i].dev.node_id,
                         lssd_identity_format(&j->found[i].dev.id, ident, sizeof(ident)));
                (void) lssd_job_add_note(j, text);
        }
}

static void scan_log(lssd_job_env *e, lssd_job *j) {
        char line[900];
        size_t n = 0;
        n += (size_t) snprintf(line, sizeof(line), "%s: Scan: %zu device%s", e->ifname, j->n_found,
                               j->n_found == 1 ? "" : "s");
        for (size_t i = 0; i < j->n_found && n < sizeof(line); i++) {
                char ident[40];
                const lss_device *d = &j->found[i].dev;
                lssd_identity_format(&d->id, ident, sizeof(ident));
                if (d->node_id == LSS_NODE_ID_UNCONFIGURED)
                        n += (size_t) snprintf(line + n, sizeof(line) - n, "%s %s non-configured", i ? "," : ":",
                                               ident);
                else
                        n += (size_t) snprintf(line + n, sizeof(line) - n, "%s %s node %u%s", i ? "," : ":", ident,
                                               d->node_id, j->found[i].by & LSSD_FOUND_LSS ? "" : " (SDO only)");
        }
        log_info("%s", line);
        for (size_t i = 0; i < j->n_found; i++) {
                char ident[40];
                const lss_device *d = &j->found[i].dev;
                lssd_identity_format(&d->id, ident, sizeof(ident));
                lssd_log_device(LOG_DEBUG, e->ifname, &d->id, d->node_id, "%s: found %s node %u%s%s", e->ifname,
                                ident, d->node_id, j->found[i].by & LSSD_FOUND_LSS ? " by LSS" : "",
                                j->found[i].by & LSSD_FOUND_SDO ? " by SDO" : "");
                if (!(j->found[i].by & LSSD_FOUND_LSS))
                        lssd_log_device(LOG_NOTICE, e->ifname, &d->id, d->node_id,
                                        "%s: Scan: %s answers SDO at node %u but not LSS (selective switch): "
                                        "reported as SDO found it, not confirmed", e->ifname, ident, d->node_id);
                if (d->aside_node_id)
                        lssd_log_device(LOG_INFO, e->ifname, &d->id, d->node_id,
                                        "%s: Scan set %s aside: it answers Fastscan in configuration state (as "
                                        "CANopenNode's LSS slave does), so it took the volatile node-ID %u while the "
                                        "Scan went on, then 255 back (NMT Reset Communication of node %u); node-ID "
                                        "now %u", e->ifname, ident, d->aside_node_id, d->aside_node_id, d->node_id);
        }
}

/* Scan's answer: every device found, sorted, and the notes. */
static int fill_scan(sd_bus_message *reply, const void *userdata) {
        const lssd_job *j = userdata;
        int k = sd_bus_message_open_container(reply, 'a', "(uuuuy)");
        for (size_t i = 0; k >= 0 && i < j->n_found; i++) {
                const lss_device *f = &j->found[i].dev;
                k = sd_bus_message_append(reply, "(uuuuy)", f->id.vendor, f->id.product, f->id.revision, f->id.serial,
                                          f->node_id);
        }
        if (k >= 0)
                k = sd_bus_message_close_container(reply);
        if (k >= 0)
                k = sd_bus_message_open_container(reply, 'a', "s");
        for (size_t i = 0; k >= 0 && i < j->n_notes; i++)
                k = sd_bus_message_append(reply, "s", j->notes[i]);
        return k < 0 ? k : sd_bus_message_close_container(reply);
}

int lssd_run_scan(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        if (!r) {
                j->n_stages = lssd_discover_n_stages(j);
                j->expected_finds = lssd_run_expected_finds(e);
                j->part_started = lssd_job_env_now(e);
                return scan_start_stage(e, j);
        }

        if (lssd_discover_take(e, j, r) < 0) {
                log_error("%s: Scan: out of memory for the devices found", e->ifname);
                j->scan_incomplete = true;
        }

        if (r->status != LSS_OK) {
                sd_bus_error err = SD_BUS_ERROR_NULL;
                j->scan_incomplete = true;
                scan_publish(e, j, lssd_realtime_us());
                lssd_error_from_result(&err, r, LSS_SERVICE_NONE, "Scan: ");
                log_warning("%s: %s", e->ifname, err.message);
                lssd_job_reply_error(j, &err);
                sd_bus_error_free(&err);
                j->result = lssd_status_to_result(r->status);
                return 0;
        }

        scan_part_end(e, j);
        if (lssd_discover_more(j)) {
                j->stage++;
                return scan_start_stage(e, j);
        }
        if (j->scan_sdo && !j->scan_incomplete)
                memcpy(e->scan_part_us, j->part_us, sizeof(e->scan_part_us));

        if (j->n_found > 1) /* found is NULL when nothing was found, and qsort's pointer is nonnull */
                qsort(j->found, j->n_found, sizeof(*j->found), compare_devices);
        scan_publish(e, j, lssd_realtime_us());
        scan_log(e, j);
        scan_notes(j);
        j->result = "done";
        lssd_job_reply_done(e, j, "Scan", fill_scan, j);
        return 0;
}
