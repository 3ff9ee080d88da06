/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_bitrate_host.h"
#include "daemon/lssd_errors.h"
#include "daemon/lssd_job_reply.h"
#include "daemon/lssd_run.h"
#include "daemon/lssd_log.h"

/* ---- the job ---- */

static int fail(lssd_job_env *e, lssd_job *j, const char *name, const char *result, const char *fmt, ...)
        __attribute__((format(printf, 5, 6)));

static int fail(lssd_job_env *e, lssd_job *j, const char *name, const char *result, const char *fmt, ...) {
        sd_bus_error err = SD_BUS_ERROR_NULL;
        char text[1024];
        va_list ap;

        va_start(ap, fmt);
        vsnprintf(text, sizeof(text), fmt, ap);
        va_end(ap);
        log_warning("%s: SetBitrate %u bit/s: %s", e->ifname, j->bitrate, text);
        sd_bus_error_setf(&err, name, "%s", text);
        lssd_job_reply_error(j, &err);
        sd_bus_error_free(&err);
        j->result = result;
        return 0;
}

static int start_failed(lssd_job_env *e, lssd_job *j, int r) {
        return fail(e, j, SD_BUS_ERROR_FAILED, "failed", "could not start: %s", strerror(-r));
}

static int discover_start(lssd_job_env *e, lssd_job *j) {
        int k = lssd_discover_start(e, j);
        return k < 0 ? start_failed(e, j, k) : 1;
}

static bool in_list(const lss_bitrate_device *d, size_t n, const lss_identity *id) {
        for (size_t i = 0; i < n; i++)
                if (lss_identity_equal(&d[i].id, id))
                        return true;
        return false;
}

static int add_device(lssd_job *j, const lss_identity *id, uint8_t node_id, bool no_select, size_t *cap) {
        if (in_list(j->br_devices, j->n_br_devices, id))
                return 0;
        if (j->n_br_devices == *cap) {
                size_t c = *cap ? *cap * 2 : 16;
                lss_bitrate_device *d = reallocarray(j->br_devices, c, sizeof(*d));
                if (!d)
                        return -ENOMEM;
                j->br_devices = d;
                *cap = c;
        }
        j->br_devices[j->n_br_devices++] = (lss_bitrate_device) { .id = *id, .node_id = node_id,
                                                                  .no_select = no_select };
        return 0;
}

/* The devices SDO found that did not answer the selective switch
 * ("v:p:r:s at node n, ..."); 0 when none. */
static size_t sdo_only(const lssd_job *j, char *buf, size_t size) {
        size_t n = 0, len = 0;
        buf[0] = 0;
        for (size_t i = 0; i < j->n_found; i++) {
                const lss_device *d = &j->found[i].dev;
                if (j->found[i].by & LSSD_FOUND_LSS)
                        continue;
                if (len + 60 < size)
                        len += (size_t) snprintf(buf + len, size - len, "%s%08x:%08x:%08x:%08x at node %u",
                                                 n ? ", " : "", d->id.vendor, d->id.product, d->id.revision,
                                                 d->id.serial, d->node_id);
                n++;
        }
        return n;
}

/* Every device on the bus: found now, in the map, or seen before. A device
 * not found now still gets the selective switch (configured devices of
 * stacks without identify services are found no other way) unless
 * skip_missing; a mapped one without revision cannot be addressed at all. */
static int collect_devices(lssd_job_env *e, lssd_job *j, char *unaddressable, size_t size) {
        size_t cap = 0, n = 0;
        int r = 0;

        unaddressable[0] = 0;
        for (size_t i = 0; r >= 0 && i < j->n_found; i++)
                r = add_device(j, &j->found[i].dev.id, j->found[i].dev.node_id,
                               !(j->found[i].by & LSSD_FOUND_LSS), &cap);
        if (j->bitrate_skip_missing || r < 0)
                return r;
        for (lssd_device *d = e->devices->head; r >= 0 && d; d = d->next)
                if (!d->missing)
                        r = add_device(j, &d->id, 0, false, &cap);
        for (size_t i = 0; r >= 0 && i < e->config->n_devices; i++) {
                const lssconf_device *c = &e->config->devices[i];
                bool found = false;
                if (c->has_revision) {
                        r = add_device(j, &c->identity, 0, false, &cap);
                        continue;
                }
                for (size_t k = 0; k < j->n_br_devices && !found; k++)
                        found = lssconf_device_matches(c, &j->br_devices[k].id);
                if (!found && n + 40 < size)
                        n += (size_t) snprintf(unaddressable + n, size - n, "%s%08x:%08x:*:%08x", n ? ", " : "",
                                               c->identity.vendor, c->identity.product, c->identity.serial);
        }
        return r;
}

static const char *retune_text(lssd_job_env *e, const lssd_job *j, char *buf, size_t size) {
        switch (lss_master_retune_state(e->engine)) {
        case LSS_RETUNE_DONE:
                snprintf(buf, size, "host interface %s retuned to %u bit/s", e->ifname, j->bitrate);
                break;
        case LSS_RETUNE_SKIPPED:
                snprintf(buf, size, "host interface %s not retuned: skipped, a virtual interface has no bit timing",
                         e->ifname);
                break;
        case LSS_RETUNE_FAILED:
                snprintf(buf, size, "host interface %s could NOT be retuned (%s): it still runs at the old rate",
                         e->ifname, j->retune_error ? strerror(j->retune_error) : "not allowed");
                break;
        case LSS_RETUNE_TIMEOUT:
                snprintf(buf, size, "host interface %s was not retuned in time", e->ifname);
                break;
        default:
                snprintf(buf, size, "host interface %s untouched", e->ifname);
                break;
        }
        return buf;
}

static void log_outcomes(lssd_job_env *e, const lssd_job *j) {
        uint64_t now_realtime = lssd_realtime_us();

        for (size_t i = 0; i < j->n_br_devices; i++) {
                const lss_bitrate_device *d = &j->br_devices[i];
                lssd_device *dev = lssd_devices_find(e->devices, &d->id);
                bool good = d->outcome == LSS_BITRATE_SWITCHED || d->outcome == LSS_BITRATE_STORED;
                bool bad = d->outcome == LSS_BITRATE_LOST || d->outcome == LSS_BITRATE_UNREACHABLE ||
                           d->outcome == LSS_BITRATE_REFUSED || d->outcome == LSS_BITRATE_SILENT ||
                           d->outcome == LSS_BITRATE_STORE_FAILED || d->outcome == LSS_BITRATE_CONFIGURED;
                char ident[40], codes[48] = "";

                if (d->outcome == LSS_BITRATE_REFUSED || (d->outcome == LSS_BITRATE_STORE_FAILED && d->err))
                        snprintf(codes, sizeof(codes), " (error %u, spec %u)", d->err, d->spec);
                lssd_log_device(bad ? LOG_WARNING : good ? LOG_NOTICE : LOG_INFO, e->ifname, &d->id,
                                dev ? dev->node_id : 0, "%s: SetBitrate %u bit/s: device %s %s%s", e->ifname,
                                j->bitrate, lssd_identity_format(&d->id, ident, sizeof(ident)),
                                lss_bitrate_outcome_name(d->outcome), codes);
                if (good && dev) {
                        dev->last_seen = now_realtime;
                        dev->changed |= LSSD_DEVICE_CHANGED_LAST_SEEN;
                }
        }
        lssd_devices_refresh(e->devices);
}

/* The reply: every device switched, with its outcome ("stored", "switched"). */
static int fill_devices(sd_bus_message *reply, const void *userdata) {
        const lssd_job *j = userdata;
        int k = sd_bus_message_open_container(reply, 'a', "(uuuus)");
        for (size_t i = 0; k >= 0 && i < j->n_br_devices; i++) {
                const lss_bitrate_device *d = &j->br_devices[i];
                k = sd_bus_message_append(reply, "(uuuus)", d->id.vendor, d->id.product, d->id.revision,
                                          d->id.serial, lss_bitrate_outcome_name(d->outcome));
        }
        return k < 0 ? k : sd_bus_message_close_container(reply);
}

/* Another master ended it (the engine's rules, lss_master.h): past the
 * activation the devices switched, the host followed, and those verified
 * before are named; before it nothing was activated, and the devices that
 * had accepted Configure Bit Timing keep that rate pending. */
static int foreign_master(lssd_job_env *e, lssd_job *j, const lss_result *r, bool activated, const char *host) {
        char ids[400] = "";
        size_t n = 0, len = 0;
        for (size_t i = 0; i < j->n_br_devices; i++) {
                const lss_bitrate_device *d = &j->br_devices[i];
                bool name = activated ? d->outcome == LSS_BITRATE_SWITCHED || d->outcome == LSS_BITRATE_STORED :
                                        d->outcome == LSS_BITRATE_CONFIGURED;
                if (!name)
                        continue;
                n++;
                if (len < sizeof(ids))
                        len += (size_t) snprintf(ids + len, sizeof(ids) - len, "%s%08x:%08x:%08x:%08x", len ? ", " : "",
                                                 d->id.vendor, d->id.product, d->id.revision, d->id.serial);
        }
        if (activated)
                return fail(e, j, LSSD_ERROR_FOREIGN_MASTER, "foreign-master",
                            "%s; Activate Bit Timing to %u bit/s had gone out: the devices switched, %zu of %zu "
                            "verified at the new rate%s%s (the others were not); %s", r->message, j->bitrate,
                            n, j->n_br_devices, n ? ": " : "", ids, host);
        return fail(e, j, LSSD_ERROR_FOREIGN_MASTER, "foreign-master",
                    "%s; nothing was activated, the bus stays at %u bit/s%s%s", r->message, lssd_job_env_bitrate(e),
                    n ? "; these took (or may have taken) Configure Bit Timing and keep that rate pending, not "
                        "configured back (a Store Configuration would make it theirs at the next power cycle: "
                        "power-cycle them): " : "",
                    ids);
}

static int finish(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        enum lss_retune rt = lss_master_retune_state(e->engine);
        char host[160];

        log_outcomes(e, j);
        if (j->bitrate_global)
                log_info("%s: SetBitrate %u bit/s: global: %u answer%s to Configure Bit Timing, %zu device%s known "
                         "(identical answers can merge on the wire: a lower bound)", e->ifname, j->bitrate,
                         lss_master_bitrate_answers(e->engine), lss_master_bitrate_answers(e->engine) == 1 ? "" : "s",
                         j->n_br_devices, j->n_br_devices == 1 ? "" : "s");
        retune_text(e, j, host, sizeof(host));
        log_notice("%s: SetBitrate %u bit/s: %s", e->ifname, j->bitrate, host);
        /* the master runs at the new rate once the activation went out and
         * the host followed (or has no rate): so does everything lssd says */
        if (rt == LSS_RETUNE_DONE || rt == LSS_RETUNE_SKIPPED)
                e->ops->set_bitrate(e->userdata, j->bitrate);

        if (r->status == LSS_OK) {
                log_notice("%s: SetBitrate: %zu device%s now at %u bit/s%s", e->ifname, j->n_br_devices,
                           j->n_br_devices == 1 ? "" : "s", j->bitrate, j->bitrate_store ? ", stored" : "");
                j->result = "done";
                lssd_job_reply_done(e, j, "SetBitrate", fill_devices, j);
                return 0;
        }
        /* the host did not follow: that, not a conflict, is the cause */
        if (r->status == LSS_E_INCOMPLETE && (rt == LSS_RETUNE_FAILED || rt == LSS_RETUNE_TIMEOUT))
                return fail(e, j, lssd_bitrate_retune_error(rt == LSS_RETUNE_FAILED ? j->retune_error : ETIMEDOUT),
                            "partial", "%s; %s", r->message, host);
        if (r->status == LSS_E_INCOMPLETE)
                return fail(e, j, LSSD_ERROR_CONFLICT, "partial", "%s; %s", r->message, host);
        if (r->status == LSS_E_REJECTED && rt != LSS_RETUNE_NONE)
                /* switched; only the store failed */
                return fail(e, j, LSSD_ERROR_REJECTED, "partial", "%s; %s", r->message, host);
        if (r->status == LSS_E_FOREIGN_MASTER)
                return foreign_master(e, j, r, rt != LSS_RETUNE_NONE, host);
        /* nothing was activated */
        return fail(e, j, lssd_status_to_error_name(r->status), lssd_status_to_result(r->status),
                    "%s; nothing was activated, the bus stays at %u bit/s", r->message[0] ? r->message :
                    lssd_status_to_result(r->status), lssd_job_env_bitrate(e));
}

/* The discovery is over: every device it found, mapped or known is
 * switched by the engine's procedure (one by one, or global). */
static int start_bitrate(lssd_job_env *e, lssd_job *j) {
        char missing[512];
        int k;
        size_t n = sdo_only(j, missing, sizeof(missing));
        if (n > 0 && !j->bitrate_global)
                /* one by one it would be left at the old rate, cut off */
                return fail(e, j, LSSD_ERROR_NOT_SUPPORTED, "not-supported",
                            "device%s %s answer%s SDO (1018h) but not the LSS selective switch: %s cannot be "
                            "switched one by one and would be left at the old rate; nothing changed (option "
                            LSSD_BITRATE_OPTION_GLOBAL "=true, lssctl set-bitrate --global, switches all devices at "
                            "once by CiA 305's global procedure, see lssd(8))", n == 1 ? "" : "s", missing, n == 1 ? "s" : "",
                            n == 1 ? "it" : "they");
        k = collect_devices(e, j, missing, sizeof(missing));
        if (k < 0)
                return start_failed(e, j, k);
        if (missing[0])
                return fail(e, j, LSSD_ERROR_NOT_FOUND, "not-found",
                            "mapped device%s not found by the scan, and without a revision in the map it "
                            "cannot be addressed: %s; nothing changed (option skip_missing=true, lssctl set-bitrate "
                            "--skip-missing, leaves devices the scan does not find out)", strchr(missing, ',') ? "s" : "",
                            missing);
        if (j->n_br_devices == 0)
                return fail(e, j, LSSD_ERROR_NOT_FOUND, "not-found",
                            "no device found on %s: nothing to switch, nothing changed", e->ifname);

        lss_bitrate_params p = {
                .bitrate = j->bitrate,
                .old_bitrate = lssd_job_env_bitrate(e),
                .delay_ms = j->switch_delay_ms,
                .store = j->bitrate_store,
                .devices = j->br_devices,
                .n_devices = j->n_br_devices,
                .global = j->bitrate_global,
        };
        log_info("%s: SetBitrate: %zu device%s to switch%s", e->ifname, j->n_br_devices,
                 j->n_br_devices == 1 ? "" : "s", j->bitrate_global ? ", all at once (global)" : "");
        j->br_started = true;
        j->stage = j->n_stages - 1;
        k = lss_master_set_bitrate(e->engine, &p, lssd_job_env_now(e));
        return k < 0 ? start_failed(e, j, k) : 1;
}

int lssd_run_bitrate(lssd_job_env *e, lssd_job *j, const lss_result *r) {
        if (!r) {
                /* whether the host can follow, before the first frame */
                lssd_bitrate_refusal no;
                lssd_host_link host;
                e->ops->host_link(e->userdata, &host);
                if (lssd_bitrate_check_host(&host, j->bitrate, &no) < 0)
                        return fail(e, j, no.error, no.result, "%s", no.text);
                /* the stages of Scan, SDO and its confirmation included */
                j->scan_sdo = true;
                j->n_stages = lssd_discover_n_stages(j) + 1;
                log_info("%s: SetBitrate %u -> %u bit/s, switch delay %u ms%s%s: scanning", e->ifname,
                         lssd_job_env_bitrate(e), j->bitrate, j->switch_delay_ms, j->bitrate_store ? ", store" : "",
                         j->bitrate_global ? ", global" : "");
                return discover_start(e, j);
        }

        if (!j->br_started) {
                if (lssd_discover_take(e, j, r) < 0)
                        return start_failed(e, j, -ENOMEM);
                if (r->status != LSS_OK)
                        return fail(e, j, lssd_status_to_error_name(r->status), lssd_status_to_result(r->status),
                                    "the scan did not finish (%s): nothing changed",
                                    r->message[0] ? r->message : lssd_status_to_result(r->status));
                if (lssd_discover_more(j)) {
                        j->stage++;
                        return discover_start(e, j);
                }
                return start_bitrate(e, j);
        }
        return finish(e, j, r);
}
