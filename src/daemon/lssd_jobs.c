/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_errors.h"
#include "daemon/lssd_jobs.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_path.h"
#include "daemon/lssd_taken.h"
#include "lss/lss_autoassign.h"

/* Failing to send a reply only means the caller is gone: log it and go on. */
static void reply_error(lssd_job *j, const sd_bus_error *e) {
        if (!j->request)
                return;
        int r = sd_bus_reply_method_error(j->request, e);
        if (r < 0)
                log_debug("Failed to send error reply to %s: %s", j->sender ? j->sender : "?", strerror(-r));
}

static void reply_message(lssd_job *j, sd_bus_message *reply) {
        int r = sd_bus_message_send(reply);
        if (r < 0)
                log_debug("Failed to send reply to %s: %s", j->sender ? j->sender : "?", strerror(-r));
}

static void reply_empty(lssd_job *j) {
        if (!j->request)
                return;
        int r = sd_bus_reply_method_return(j->request, NULL);
        if (r < 0)
                log_debug("Failed to send reply to %s: %s", j->sender ? j->sender : "?", strerror(-r));
}

void lssd_job_abort(lssd_job *j, const char *error_name, const char *message) {
        sd_bus_error err = SD_BUS_ERROR_NULL;
        sd_bus_error_set(&err, error_name, message);
        reply_error(j, &err);
        sd_bus_error_free(&err);
        j->result = error_name && strcmp(error_name, LSSD_ERROR_CANCELLED) == 0 ? "cancelled" : "failed";
}

/* An engine operation that could not even start (a bug, or out of memory). */
static int job_start_failed(lssd_job_env *e, lssd_job *j, int r) {
        sd_bus_error err = SD_BUS_ERROR_NULL;
        log_error("%s: failed to start %s: %s", e->ifname, lssd_job_name(j), strerror(-r));
        sd_bus_error_set_errno(&err, r);
        reply_error(j, &err);
        sd_bus_error_free(&err);
        j->result = "failed";
        return 0;
}

/* ---- Reset: switch-global waiting ---- */

int lssd_run_reset(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        if (!r) {
                int k = lss_master_switch_global(e->engine, LSS_MODE_WAITING, lssd_job_env_now(e));
                if (k >= 0) {
                        lss_timing_config tc;
                        lss_timing_config_default(&tc);
                        e->unstored_until = lssd_job_env_now(e) + tc.bootup_timeout_us;
                }
                return k < 0 ? job_start_failed(e, j, k) : 1;
        }
        j->result = lssd_status_to_result(r->status);
        if (r->status != LSS_OK)
                log_warning("%s: could not switch the slaves to waiting: %s", e->ifname,
                            r->message[0] ? r->message : lssd_status_to_result(r->status));
        else
                log_debug("%s: all slaves switched to waiting", e->ifname);
        return 0;
}

/* ---- raw services of the holder ---- */

static bool sender_holds(lssd_job_env *e, const lssd_job *j) {
        const char *holder = e->ops->holder(e->userdata);
        return holder && j->sender && strcmp(holder, j->sender) == 0;
}

int lssd_run_raw(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        const lssd_raw_step *s = &j->steps[0];
        char what[96];

        if (!r) {
                /* queued while held, but the holder let go before its turn */
                if (!sender_holds(e, j)) {
                        lssd_job_abort(j, LSSD_ERROR_CANCELLED, "The bus was released before this call ran");
                        return 0;
                }
                lssd_taken_check(e, true);
                int k = lssd_raw_step_start(s, e->engine, lssd_job_env_now(e));
                return k < 0 ? job_start_failed(e, j, k) : 1;
        }

        lssd_raw_step_describe(s, what, sizeof(what));
        if (!lssd_raw_step_succeeded(s, r)) {
                sd_bus_error err = SD_BUS_ERROR_NULL;
                if (r->in_use)
                        lssd_taken_error(e, &err, s->node_id, NULL, NULL);
                else
                        lssd_raw_step_error(s, r, NULL, &err);
                log_info("%s: %s by %s: %s", e->ifname, what, j->sender ? j->sender : "?", err.message);
                reply_error(j, &err);
                sd_bus_error_free(&err);
                j->result = lssd_status_to_result(r->status);
                return 0;
        }

        log_info("%s: %s by %s: done", e->ifname, what, j->sender ? j->sender : "?");
        j->result = "done";
        if (!j->request)
                return 0;
        sd_bus_message *reply = NULL;
        int k = sd_bus_message_new_method_return(j->request, &reply);
        if (k >= 0)
                k = lssd_raw_step_append_result(s, r, reply, false);
        if (k >= 0)
                reply_message(j, reply);
        else
                log_error("%s: failed to build the reply of %s: %s", e->ifname, what, strerror(-k));
        sd_bus_message_unref(reply);
        return 0;
}

/* ---- Execute: steps, then always switch-global waiting ---- */

static int execute_start_stage(lssd_job_env *e, lssd_job *j) {
        uint64_t now = lssd_job_env_now(e);
        int k;
        if (j->stage < j->n_steps) {
                lssd_taken_check(e, true);
                k = lssd_raw_step_start(&j->steps[j->stage], e->engine, now);
        } else
                k = lss_master_switch_global(e->engine, LSS_MODE_WAITING, now);
        return k < 0 ? job_start_failed(e, j, k) : 1;
}

int lssd_run_execute(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        int k;

        if (!r) {
                j->n_stages = (unsigned) j->n_steps + 1;
                if (j->request) {
                        k = sd_bus_message_new_method_return(j->request, &j->reply);
                        if (k >= 0)
                                k = sd_bus_message_open_container(j->reply, 'a', "v");
                        if (k < 0)
                                return job_start_failed(e, j, k);
                }
                return execute_start_stage(e, j);
        }

        if (j->stage < j->n_steps) {
                const lssd_raw_step *s = &j->steps[j->stage];
                if (lssd_raw_step_succeeded(s, r)) {
                        if (j->reply) {
                                k = lssd_raw_step_append_result(s, r, j->reply, true);
                                if (k < 0)
                                        sd_bus_error_set_errno(&j->error, k);
                        }
                        j->stage++;
                } else {
                        char prefix[64];
                        snprintf(prefix, sizeof(prefix), "steps[%u] (%s): ", j->stage,
                                 lssd_raw_op_to_string(s->op));
                        if (r->in_use)
                                lssd_taken_error(e, &j->error, s->node_id, NULL, prefix);
                        else
                                lssd_raw_step_error(s, r, prefix, &j->error);
                        j->result = lssd_status_to_result(r->status);
                        j->stage = (unsigned) j->n_steps; /* straight to the final switch */
                }
                if (sd_bus_error_is_set(&j->error))
                        j->stage = (unsigned) j->n_steps;
                return execute_start_stage(e, j);
        }

        /* the final switch to waiting is done */
        if (!sd_bus_error_is_set(&j->error) && r->status != LSS_OK) {
                lssd_error_from_result(&j->error, r, LSS_SERVICE_NONE,
                                       "Switching the slaves back to waiting failed: ");
                j->result = lssd_status_to_result(r->status);
        }

        if (sd_bus_error_is_set(&j->error)) {
                log_info("%s: Execute (%zu steps) by %s failed: %s", e->ifname, j->n_steps,
                         j->sender ? j->sender : "?", j->error.message);
                reply_error(j, &j->error);
                if (!j->result)
                        j->result = "failed";
                return 0;
        }

        log_info("%s: Execute (%zu steps) by %s: done", e->ifname, j->n_steps, j->sender ? j->sender : "?");
        j->result = "done";
        if (j->reply) {
                k = sd_bus_message_close_container(j->reply);
                if (k >= 0)
                        reply_message(j, j->reply);
                else
                        log_error("%s: failed to build the reply of Execute: %s", e->ifname, strerror(-k));
        }
        return 0;
}

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
                return k < 0 ? job_start_failed(e, j, k) : 1;
        }

        if (r->status != LSS_OK) {
                sd_bus_error err = SD_BUS_ERROR_NULL;
                if (r->in_use)
                        lssd_taken_error(e, &err, j->node_id, &j->identity, NULL);
                else
                        lssd_error_from_result(&err, r, r->failed_service, NULL);
                lssd_log_device(LOG_WARNING, e->ifname, &j->identity, j->node_id,
                                "%s: AssignNodeId %s -> node %u failed: %s", e->ifname, ident, j->node_id,
                                err.message);
                reply_error(j, &err);
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
                d->last_seen = lssd_realtime_us();
                d->changed |= LSSD_DEVICE_CHANGED_LAST_SEEN;
                lssd_devices_refresh(e->devices);
                if (r->changed && e->dbus)
                        (void) sd_bus_emit_signal(e->dbus, e->path, LSSD_BUS_IFACE, "NodeIdAssigned", "oyy",
                                                  d->path, old, j->node_id);
        } else
                log_error("%s: failed to record device %s: %s", e->ifname, ident, strerror(-k));

        char stored[80] = "";
        if (r->not_stored)
                snprintf(stored, sizeof(stored), ", not stored (device cannot store: %s)",
                         lss_store_error_name(r->err));
        else if (r->changed && j->assign.store)
                snprintf(stored, sizeof(stored), ", stored");
        lssd_log_device(LOG_NOTICE, e->ifname, &j->identity, j->node_id, "%s: device %s: node-ID %u -> %u%s%s",
                        e->ifname, ident, r->node_id, j->node_id, r->changed ? "" : " (already set)", stored);
        j->result = "done";
        reply_empty(j);
        return 0;
}

/* ---- UnassignNodeId: back to non-configured ---- */

static void append_sentence(char *buf, size_t size, const char *text) {
        size_t n = strlen(buf);
        if (n < size)
                snprintf(buf + n, size - n, "%s%s", n ? "; " : "", text);
}

int lssd_run_unassign(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        char ident[40];
        lssd_identity_format(&j->identity, ident, sizeof(ident));

        if (!r) {
                unsigned flags = (j->unassign.store ? LSS_UNASSIGN_STORE : 0u) |
                                 (j->unassign.reset ? LSS_UNASSIGN_RESET : 0u);
                int k = lss_master_unassign(e->engine, &j->identity, flags, lssd_job_env_now(e));
                return k < 0 ? job_start_failed(e, j, k) : 1;
        }

        uint8_t old = r->node_id;
        if (r->status != LSS_OK) {
                sd_bus_error err = SD_BUS_ERROR_NULL;
                lssd_error_from_result(&err, r, r->failed_service, NULL);
                lssd_log_device(LOG_WARNING, e->ifname, &j->identity, old, "%s: UnassignNodeId %s failed: %s",
                                e->ifname, ident, err.message);
                reply_error(j, &err);
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
                d->blocked = false;
                d->missing = false;
                d->last_seen = lssd_realtime_us();
                d->changed |= LSSD_DEVICE_CHANGED_LAST_SEEN;
                lssd_devices_refresh(e->devices);
                if (r->in_effect && old != LSS_NODE_ID_UNCONFIGURED && e->dbus)
                        (void) sd_bus_emit_signal(e->dbus, e->path, LSSD_BUS_IFACE, "NodeIdAssigned", "oyy",
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
        if (!j->request)
                return 0;
        sd_bus_message *reply = NULL;
        k = sd_bus_message_new_method_return(j->request, &reply);
        if (k >= 0)
                k = sd_bus_message_append(reply, "ybbss", old, r->stored, r->in_effect, message, warning);
        if (k >= 0)
                reply_message(j, reply);
        else
                log_error("%s: failed to build the reply of UnassignNodeId: %s", e->ifname, strerror(-k));
        sd_bus_message_unref(reply);
        return 0;
}

/* ---- Scan: fastscan enumeration, then slowscan per vendor/product pair ---- */

/* What an enumeration will likely find: the non-configured devices seen
 * before (the first scan of a bus cannot know: its progress assumes as many
 * again as found so far). */
static void expect_finds(lssd_job_env *e) {
        unsigned n = 0;
        for (const lssd_device *d = e->devices->head; d; d = d->next)
                n += !d->missing && d->node_id == LSS_NODE_ID_UNCONFIGURED;
        lss_master_set_expected_finds(e->engine, n);
}

int lssd_scan_stage_start(lssd_job_env *e, const lssd_job *j) {
        uint64_t now = lssd_job_env_now(e);
        if (j->stage == 0) {
                expect_finds(e);
                return lss_master_enumerate(e->engine, NULL, now);
        }
        const lssd_vendor_product *p = &j->pairs[j->stage - 1];
        lss_identify_range range = {
                .vendor = p->vendor, .product = p->product,
                .rev_lo = 0, .rev_hi = UINT32_MAX,
                .serial_lo = 0, .serial_hi = UINT32_MAX,
        };
        return lss_master_slowscan(e->engine, &range, now);
}

static int scan_start_stage(lssd_job_env *e, lssd_job *j) {
        int k = lssd_scan_stage_start(e, j);
        return k < 0 ? job_start_failed(e, j, k) : 1;
}

static int compare_devices(const void *a, const void *b) {
        const lss_device *x = a, *y = b;
        return lss_identity_compare(&x->id, &y->id);
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
static lssd_device *scan_record(lssd_job_env *e, const lss_device *f, uint64_t now_realtime) {
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
                (void) sd_bus_emit_signal(bus, e->path, LSSD_BUS_IFACE, "DeviceFound", "o", d->path);
        if (!lssd_config_lookup_device(e->config, &f->id))
                (void) sd_bus_emit_signal(bus, e->path, LSSD_BUS_IFACE, "UnknownDevice", "uuuu", f->id.vendor,
                                          f->id.product, f->id.revision, f->id.serial);
}

void lssd_scan_found(lssd_job_env *e, lssd_job *j, const lss_device *f) {
        if (scan_announced(j, &f->id))
                return; /* by an earlier stage: the end brings its node-ID up to date */
        lssd_device *d = scan_record(e, f, lssd_realtime_us());
        if (!d)
                return; /* tried again at the end */
        lssd_devices_refresh(e->devices);
        scan_announce(e, j, f, d);
}

static void scan_publish(lssd_job_env *e, lssd_job *j, uint64_t now_realtime) {
        /* who was not found although the scan would have */
        if (!j->scan_incomplete)
                for (lssd_device *d = e->devices->head; d; d = d->next) {
                        bool found = false;
                        for (size_t i = 0; i < j->n_found && !found; i++)
                                found = lss_identity_equal(&j->found[i].id, &d->id);
                        if (!found && !d->missing && scan_covers(j, d))
                                d->missing = true;
                }

        /* Devices announced when they were found are up to date, unless a
         * later stage read another node-ID; the others are recorded now. */
        for (size_t i = 0; i < j->n_found; i++) {
                const lss_device *f = &j->found[i];
                const lssd_device *d = lssd_devices_find(e->devices, &f->id);
                if (!scan_announced(j, &f->id) || !d || d->node_id != f->node_id)
                        (void) scan_record(e, f, now_realtime);
        }
        lssd_devices_refresh(e->devices);

        for (size_t i = 0; i < j->n_found; i++) {
                const lss_device *f = &j->found[i];
                if (!scan_announced(j, &f->id))
                        scan_announce(e, j, f, lssd_devices_find(e->devices, &f->id));
        }
}

static void scan_log(lssd_job_env *e, lssd_job *j) {
        char line[900];
        size_t n = 0;
        n += (size_t) snprintf(line, sizeof(line), "%s: Scan: %zu device%s", e->ifname, j->n_found,
                               j->n_found == 1 ? "" : "s");
        for (size_t i = 0; i < j->n_found && n < sizeof(line); i++) {
                char ident[40];
                lssd_identity_format(&j->found[i].id, ident, sizeof(ident));
                if (j->found[i].node_id == LSS_NODE_ID_UNCONFIGURED)
                        n += (size_t) snprintf(line + n, sizeof(line) - n, "%s %s non-configured", i ? "," : ":",
                                               ident);
                else
                        n += (size_t) snprintf(line + n, sizeof(line) - n, "%s %s node %u", i ? "," : ":", ident,
                                               j->found[i].node_id);
        }
        log_info("%s", line);
        for (size_t i = 0; i < j->n_found; i++) {
                char ident[40];
                const lss_device *d = &j->found[i];
                lssd_identity_format(&d->id, ident, sizeof(ident));
                lssd_log_device(LOG_DEBUG, e->ifname, &d->id, d->node_id, "%s: found %s node %u", e->ifname, ident,
                                d->node_id);
                if (d->aside_node_id)
                        lssd_log_device(LOG_INFO, e->ifname, &d->id, d->node_id,
                                        "%s: Scan set %s aside with the volatile node-ID %u while it went on, then "
                                        "gave it 255 back (NMT Reset Communication of node %u); node-ID now %u",
                                        e->ifname, ident, d->aside_node_id, d->aside_node_id, d->node_id);
        }
}

int lssd_run_scan(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        if (!r) {
                j->n_stages = (unsigned) j->n_pairs + 1;
                return scan_start_stage(e, j);
        }

        for (size_t i = 0; i < r->n_devices; i++)
                if (lssd_job_add_found(j, &r->devices[i]) < 0) {
                        j->scan_incomplete = true;
                        break;
                }

        if (r->status != LSS_OK) {
                sd_bus_error err = SD_BUS_ERROR_NULL;
                j->scan_incomplete = true;
                scan_publish(e, j, lssd_realtime_us());
                lssd_error_from_result(&err, r, LSS_SERVICE_NONE, "Scan: ");
                log_warning("%s: %s", e->ifname, err.message);
                reply_error(j, &err);
                sd_bus_error_free(&err);
                j->result = lssd_status_to_result(r->status);
                return 0;
        }

        if (++j->stage <= j->n_pairs)
                return scan_start_stage(e, j);

        if (j->n_found > 1) /* found is NULL when nothing was found, and qsort's pointer is nonnull */
                qsort(j->found, j->n_found, sizeof(*j->found), compare_devices);
        scan_publish(e, j, lssd_realtime_us());
        scan_log(e, j);
        j->result = "done";

        if (!j->request)
                return 0;
        sd_bus_message *reply = NULL;
        int k = sd_bus_message_new_method_return(j->request, &reply);
        if (k >= 0)
                k = sd_bus_message_open_container(reply, 'a', "(uuuuy)");
        for (size_t i = 0; k >= 0 && i < j->n_found; i++) {
                const lss_device *f = &j->found[i];
                k = sd_bus_message_append(reply, "(uuuuy)", f->id.vendor, f->id.product, f->id.revision, f->id.serial,
                                          f->node_id);
        }
        if (k >= 0)
                k = sd_bus_message_close_container(reply);
        if (k >= 0)
                reply_message(j, reply);
        else
                log_error("%s: failed to build the reply of Scan: %s", e->ifname, strerror(-k));
        sd_bus_message_unref(reply);
        return 0;
}

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

/* A missing device's identity is the map's: without a revision there, its
 * revision (0) is not known. */
static bool outcome_revision_known(const lssd_job *j, const lss_outcome *o) {
        if (o->kind != LSS_OUTCOME_MISSING)
                return true;
        for (size_t i = 0; i < j->plan.n_map; i++)
                if (lss_map_entry_matches(&j->plan.map[i], &o->id))
                        return j->plan.map[i].revision_known;
        return true;
}

/* Brings the Device object of one outcome up to date. */
static void autoassign_publish_one(lssd_job_env *e, const lssd_job *j, const lss_outcome *o, uint64_t now_realtime) {
        bool missing = o->kind == LSS_OUTCOME_MISSING;
        uint8_t node_id = o->new_node_id != 0 ? o->new_node_id : LSS_NODE_ID_UNCONFIGURED;
        lssd_device *d = NULL;
        char ident[40];

        if (missing && autoassign_mark_missing(e, j, o))
                return;
        int k = lssd_devices_get(e->devices, &o->id, outcome_revision_known(j, o), node_id, lssd_realtime_us(), &d);
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
        if (o->kind == LSS_OUTCOME_ASSIGNED || o->kind == LSS_OUTCOME_POOL) {
                d->assigned = true;
                d->pooled = o->kind == LSS_OUTCOME_POOL;
        }
        d->blocked = o->kind == LSS_OUTCOME_CONFLICT;
        d->missing = missing;
        if (!missing) {
                d->last_seen = now_realtime;
                d->changed |= LSSD_DEVICE_CHANGED_LAST_SEEN;
        }
}

/* What an outcome needs said beyond its kind ("" when nothing): the
 * journal line and the reply's detail. */
static void outcome_detail(const lss_outcome *o, char *buf, size_t size) {
        buf[0] = '\0';
        if (o->not_stored)
                snprintf(buf, size, "not stored (device cannot store: %s)", lss_store_error_name(o->err));
        else if (o->message[0])
                snprintf(buf, size, "%s", o->message);
}

static bool outcome_changed(const lss_outcome *o) {
        return (o->kind == LSS_OUTCOME_ASSIGNED || o->kind == LSS_OUTCOME_POOL) && !o->dry;
}

/* The reply's and the journal's name: a dry run's changes are "would-..." */
static const char *outcome_name(const lss_outcome *o) {
        if (o->dry)
                return o->kind == LSS_OUTCOME_POOL ? "would-pool" : "would-assign";
        return lss_outcome_name(o->kind);
}

static void autoassign_log_one(lssd_job_env *e, const lssd_job *j, const lss_outcome *o) {
        char ident[40], detail[200];
        int priority = LOG_INFO;

        if (outcome_revision_known(j, o))
                lssd_identity_format(&o->id, ident, sizeof(ident));
        else /* the map's identity without a revision: not 0 */
                snprintf(ident, sizeof(ident), "%08x:%08x:-:%08x", o->id.vendor, o->id.product, o->id.serial);
        switch (o->kind) {
        case LSS_OUTCOME_ASSIGNED:
        case LSS_OUTCOME_POOL:
                priority = LOG_NOTICE;
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
        lssd_log_device(priority, e->ifname, &o->id, o->new_node_id, "%s: AutoAssign: device %s %s, node-ID %u -> %u%s%s",
                        e->ifname, ident, outcome_name(o), o->old_node_id, o->new_node_id,
                        !detail[0] ? "" : o->not_stored ? ", " : ": ", detail);
}

int lssd_run_autoassign(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        size_t n = 0, count[LSS_OUTCOME_FAILED + 1] = { 0 };
        const lss_outcome *out;
        sd_bus *bus = e->dbus;
        uint64_t now_realtime = lssd_realtime_us();

        if (!r) {
                e->pass_started_us = now_realtime;
                j->plan.unstored = e->unstored;
                lssd_taken_check(e, false);
                expect_finds(e);
                int k = lss_master_autoassign(e->engine, &j->plan, lssd_job_env_now(e));
                return k < 0 ? job_start_failed(e, j, k) : 1;
        }
        if (r->status == LSS_OK)
                memset(e->unstored, 0, sizeof(e->unstored));

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
                                (void) sd_bus_emit_signal(bus, e->path, LSSD_BUS_IFACE, "NodeIdAssigned", "oyy",
                                                          d->path, o->old_node_id, o->new_node_id);
                        else if (o->kind == LSS_OUTCOME_UNKNOWN)
                                (void) sd_bus_emit_signal(bus, e->path, LSSD_BUS_IFACE, "UnknownDevice", "uuuu",
                                                          o->id.vendor, o->id.product, o->id.revision, o->id.serial);
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
                 "%s: %zu %sassigned, %zu from the pool, %zu unchanged, %zu unknown, %zu missing, %zu conflicts, "
                 "%zu failed", e->ifname, count[LSS_OUTCOME_ASSIGNED], j->plan.dry_run ? "would be " : "",
                 count[LSS_OUTCOME_POOL],
                 count[LSS_OUTCOME_UNCHANGED], count[LSS_OUTCOME_UNKNOWN], count[LSS_OUTCOME_MISSING],
                 count[LSS_OUTCOME_CONFLICT], count[LSS_OUTCOME_FAILED]);

        if (r->status != LSS_OK) {
                /* the pass as a whole broke off (bus down, cancelled): what it did is published above */
                sd_bus_error err = SD_BUS_ERROR_NULL;
                lssd_error_from_result(&err, r, LSS_SERVICE_NONE, "AutoAssign: ");
                log_warning("%s: %s (%s)", e->ifname, err.message, j->summary);
                reply_error(j, &err);
                sd_bus_error_free(&err);
                j->result = lssd_status_to_result(r->status);
                return 0;
        }

        log_notice("AutoAssign%s on %s", j->plan.dry_run ? " (dry run: nothing was sent but discovery)" : "",
                   j->summary);
        j->result = verdict;

        if (!j->request)
                return 0;
        sd_bus_message *reply = NULL;
        int k = sd_bus_message_new_method_return(j->request, &reply);
        if (k >= 0)
                k = sd_bus_message_open_container(reply, 'a', "(uuuuyyss)");
        for (size_t i = 0; k >= 0 && i < n; i++) {
                const lss_outcome *o = &out[i];
                char detail[200];
                outcome_detail(o, detail, sizeof(detail));
                k = sd_bus_message_append(reply, "(uuuuyyss)", o->id.vendor, o->id.product, o->id.revision,
                                          o->id.serial, o->old_node_id, o->new_node_id, outcome_name(o), detail);
        }
        if (k >= 0)
                k = sd_bus_message_close_container(reply);
        if (k >= 0)
                k = sd_bus_message_append(reply, "s", j->result);
        if (k >= 0)
                reply_message(j, reply);
        else
                log_error("%s: failed to build the reply of AutoAssign: %s", e->ifname, strerror(-k));
        sd_bus_message_unref(reply);
        return 0;
}
