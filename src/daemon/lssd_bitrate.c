/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "can/rtnl_watch.h"
#include "daemon/lssd_auth.h"
#include "daemon/lssd_bitrate.h"
#include "daemon/lssd_bitrate_host.h"
#include "daemon/lssd_errors.h"
#include "daemon/lssd_jobs.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_options.h"
#include "daemon/lssd_vtables.h"

/* Link events this long after our own retune are taken for it. */
#define RETUNE_LINK_GRACE_US (5u * 1000000u)

typedef struct bitrate_options {
        bool store, skip_missing;
} bitrate_options;

static const lssd_option bitrate_table[] = {
        LSSD_OPTION("store", 'b', bitrate_options, store),
        LSSD_OPTION("skip_missing", 'b', bitrate_options, skip_missing),
        LSSD_OPTION_END,
};

int lssd_bitrate_method(lssd_bus *b, sd_bus_message *m, uint32_t bitrate, uint16_t switch_delay_ms,
                        sd_bus_error *error) {
        bitrate_options o = { .store = b->config->store };
        lssd_job *j;
        int r;

        r = lssd_options_read(m, "options", bitrate_table, &o, error);
        if (r < 0)
                return r;
        r = lssd_auth_check(&b->ctx->auth, m, error);
        if (r < 0)
                return r;
        /* changing a whole network's rate is opt-in per bus, and on a real
         * controller it needs CAP_NET_ADMIN, which only that opt-in grants */
        if (!b->config->bitrate_change)
                return sd_bus_error_setf(error, LSSD_ERROR_NOT_SUPPORTED,
                                         "Bit-rate changes are not enabled for %s: set bitrate_change = true for "
                                         "this bus in lssd.conf (see lssd(8) for what to check first)",
                                         b->ifname);
        /* already there: nothing to send */
        if (bitrate == lssd_bus_bitrate(b)) {
                log_info("%s: SetBitrate %u bit/s: the bus runs at that rate already", b->ifname, bitrate);
                return sd_bus_reply_method_return(m, "a(uuuus)", 0);
        }

        r = lssd_job_new(LSSD_JOB_SET_BITRATE, m, &j);
        if (r < 0)
                return r;
        j->bitrate = bitrate;
        j->switch_delay_ms = switch_delay_ms;
        j->bitrate_store = o.store;
        j->bitrate_skip_missing = o.skip_missing;
        /* configured devices are only found by slowscan of known vendor/product pairs */
        for (size_t i = 0; r >= 0 && i < b->config->n_devices; i++)
                r = lssd_job_add_pair(j, b->config->devices[i].identity.vendor, b->config->devices[i].identity.product);
        for (lssd_device *d = b->devices; r >= 0 && d; d = d->next)
                r = lssd_job_add_pair(j, d->id.vendor, d->id.product);
        if (r >= 0)
                r = lssd_bus_check_available(b, sd_bus_message_get_sender(m), false, error);
        if (r >= 0)
                r = lssd_bus_submit(b, j, error);
        if (r < 0) {
                lssd_job_free(j);
                return r;
        }
        return 1; /* the job answers */
}

/* ---- the job ---- */

static void reply_error(lssd_job *j, const sd_bus_error *e) {
        if (!j->request)
                return;
        int r = sd_bus_reply_method_error(j->request, e);
        if (r < 0)
                log_debug("Failed to send error reply to %s: %s", j->sender ? j->sender : "?", strerror(-r));
}

static int fail(lssd_bus *b, lssd_job *j, const char *name, const char *result, const char *fmt, ...)
        __attribute__((format(printf, 5, 6)));

static int fail(lssd_bus *b, lssd_job *j, const char *name, const char *result, const char *fmt, ...) {
        sd_bus_error e = SD_BUS_ERROR_NULL;
        char text[1024];
        va_list ap;

        va_start(ap, fmt);
        vsnprintf(text, sizeof(text), fmt, ap);
        va_end(ap);
        log_warning("%s: SetBitrate %u bit/s: %s", b->ifname, j->bitrate, text);
        sd_bus_error_setf(&e, name, "%s", text);
        reply_error(j, &e);
        sd_bus_error_free(&e);
        j->result = result;
        return 0;
}

static int start_failed(lssd_bus *b, lssd_job *j, int r) {
        return fail(b, j, SD_BUS_ERROR_FAILED, "failed", "could not start: %s", strerror(-r));
}

static int scan_start_stage(lssd_bus *b, lssd_job *j) {
        int k = lssd_scan_stage_start(b, j);
        return k < 0 ? start_failed(b, j, k) : 1;
}

static bool in_list(const lss_bitrate_device *d, size_t n, const lss_identity *id) {
        for (size_t i = 0; i < n; i++)
                if (lss_identity_equal(&d[i].id, id))
                        return true;
        return false;
}

static int add_device(lssd_job *j, const lss_identity *id, size_t *cap) {
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
        j->br_devices[j->n_br_devices++] = (lss_bitrate_device) { .id = *id };
        return 0;
}

/* Every device on the bus: found now, in the map, or seen before. A device
 * not found now still gets the selective switch (configured devices of
 * stacks without identify services are found no other way) unless
 * skip_missing; a mapped one without revision cannot be addressed at all. */
static int collect_devices(lssd_bus *b, lssd_job *j, char *unaddressable, size_t size) {
        size_t cap = 0, n = 0;
        int r = 0;

        unaddressable[0] = 0;
        for (size_t i = 0; r >= 0 && i < j->n_found; i++)
                r = add_device(j, &j->found[i].id, &cap);
        if (j->bitrate_skip_missing || r < 0)
                return r;
        for (lssd_device *d = b->devices; r >= 0 && d; d = d->next)
                if (!d->missing)
                        r = add_device(j, &d->id, &cap);
        for (size_t i = 0; r >= 0 && i < b->config->n_devices; i++) {
                const lssd_device_config *c = &b->config->devices[i];
                bool found = false;
                if (c->has_revision) {
                        r = add_device(j, &c->identity, &cap);
                        continue;
                }
                for (size_t k = 0; k < j->n_br_devices && !found; k++)
                        found = lssd_device_config_matches(c, &j->br_devices[k].id);
                if (!found && n + 40 < size)
                        n += (size_t) snprintf(unaddressable + n, size - n, "%s%08x:%08x:*:%08x", n ? ", " : "",
                                               c->identity.vendor, c->identity.product, c->identity.serial);
        }
        return r;
}

static const char *retune_text(lssd_bus *b, const lssd_job *j, char *buf, size_t size) {
        switch (lss_master_retune_state(b->engine)) {
        case LSS_RETUNE_DONE:
                snprintf(buf, size, "host interface %s retuned to %u bit/s", b->ifname, j->bitrate);
                break;
        case LSS_RETUNE_SKIPPED:
                snprintf(buf, size, "host interface %s not retuned: skipped, a virtual interface has no bit timing",
                         b->ifname);
                break;
        case LSS_RETUNE_FAILED:
                snprintf(buf, size, "host interface %s could NOT be retuned (%s): it still runs at the old rate",
                         b->ifname, j->retune_error ? strerror(j->retune_error) : "not allowed");
                break;
        case LSS_RETUNE_TIMEOUT:
                snprintf(buf, size, "host interface %s was not retuned in time", b->ifname);
                break;
        default:
                snprintf(buf, size, "host interface %s untouched", b->ifname);
                break;
        }
        return buf;
}

static void log_outcomes(lssd_bus *b, const lssd_job *j) {
        uint64_t now_realtime = lssd_realtime_us();

        for (size_t i = 0; i < j->n_br_devices; i++) {
                const lss_bitrate_device *d = &j->br_devices[i];
                lssd_device *dev = lssd_bus_find_device(b, &d->id);
                bool good = d->outcome == LSS_BITRATE_SWITCHED || d->outcome == LSS_BITRATE_STORED;
                bool bad = d->outcome == LSS_BITRATE_LOST || d->outcome == LSS_BITRATE_UNREACHABLE ||
                           d->outcome == LSS_BITRATE_REFUSED || d->outcome == LSS_BITRATE_SILENT ||
                           d->outcome == LSS_BITRATE_STORE_FAILED || d->outcome == LSS_BITRATE_CONFIGURED;
                char ident[40], codes[48] = "";

                if (d->outcome == LSS_BITRATE_REFUSED || (d->outcome == LSS_BITRATE_STORE_FAILED && d->err))
                        snprintf(codes, sizeof(codes), " (error %u, spec %u)", d->err, d->spec);
                lssd_log_device(bad ? LOG_WARNING : good ? LOG_NOTICE : LOG_INFO, b->ifname, &d->id,
                                dev ? dev->node_id : 0, "%s: SetBitrate %u bit/s: device %s %s%s", b->ifname,
                                j->bitrate, lssd_identity_format(&d->id, ident, sizeof(ident)),
                                lss_bitrate_outcome_name(d->outcome), codes);
                if (good && dev) {
                        dev->last_seen = now_realtime;
                        dev->changed |= LSSD_DEVICE_CHANGED_LAST_SEEN;
                }
        }
        lssd_bus_refresh_devices(b);
}

/* The reply: every device switched, with its outcome ("stored", "switched"). */
static int reply_devices(const lssd_job *j) {
        sd_bus_message *reply = NULL;
        int k = sd_bus_message_new_method_return(j->request, &reply);
        if (k >= 0)
                k = sd_bus_message_open_container(reply, 'a', "(uuuus)");
        for (size_t i = 0; k >= 0 && i < j->n_br_devices; i++) {
                const lss_bitrate_device *d = &j->br_devices[i];
                k = sd_bus_message_append(reply, "(uuuus)", d->id.vendor, d->id.product, d->id.revision,
                                          d->id.serial, lss_bitrate_outcome_name(d->outcome));
        }
        if (k >= 0)
                k = sd_bus_message_close_container(reply);
        if (k >= 0)
                k = sd_bus_send(NULL, reply, NULL);
        sd_bus_message_unref(reply);
        return k;
}

static int finish(lssd_bus *b, lssd_job *j, const lss_result *r) {
        enum lss_retune rt = lss_master_retune_state(b->engine);
        char host[160];

        log_outcomes(b, j);
        retune_text(b, j, host, sizeof(host));
        log_notice("%s: SetBitrate %u bit/s: %s", b->ifname, j->bitrate, host);
        /* the master runs at the new rate once the activation went out and
         * the host followed (or has no rate): so does everything lssd says */
        if (rt == LSS_RETUNE_DONE || rt == LSS_RETUNE_SKIPPED)
                lssd_bus_set_bitrate(b, j->bitrate);

        if (r->status == LSS_OK) {
                log_notice("%s: SetBitrate: %zu device%s now at %u bit/s%s", b->ifname, j->n_br_devices,
                           j->n_br_devices == 1 ? "" : "s", j->bitrate, j->bitrate_store ? ", stored" : "");
                j->result = "done";
                if (j->request) {
                        int k = reply_devices(j);
                        if (k < 0)
                                log_debug("Failed to send reply to %s: %s", j->sender ? j->sender : "?",
                                          strerror(-k));
                }
                return 0;
        }
        /* the host did not follow: that, not a conflict, is the cause */
        if (r->status == LSS_E_INCOMPLETE && (rt == LSS_RETUNE_FAILED || rt == LSS_RETUNE_TIMEOUT))
                return fail(b, j, lssd_bitrate_retune_error(rt == LSS_RETUNE_FAILED ? j->retune_error : ETIMEDOUT),
                            "partial", "%s; %s", r->message, host);
        if (r->status == LSS_E_INCOMPLETE)
                return fail(b, j, LSSD_ERROR_CONFLICT, "partial", "%s; %s", r->message, host);
        if (r->status == LSS_E_REJECTED && rt != LSS_RETUNE_NONE)
                /* switched; only the store failed */
                return fail(b, j, LSSD_ERROR_REJECTED, "partial", "%s; %s", r->message, host);
        /* nothing was activated */
        return fail(b, j, lssd_status_to_error_name(r->status), lssd_status_to_result(r->status),
                    "%s; nothing was activated, the bus stays at %u bit/s", r->message[0] ? r->message :
                    lssd_status_to_result(r->status), lssd_bus_bitrate(b));
}

int lssd_bitrate_run(lssd_bus *b, lssd_job *j, const lss_result *r) {
        char missing[512];
        int k;

        if (!r) {
                /* whether the host can follow, before the first frame */
                lssd_bitrate_refusal no;
                if (lssd_bitrate_check_host(b, j->bitrate, &no) < 0)
                        return fail(b, j, no.error, no.result, "%s", no.text);
                j->n_stages = (unsigned) j->n_pairs + 2;
                log_info("%s: SetBitrate %u -> %u bit/s, switch delay %u ms%s: scanning", b->ifname,
                         lssd_bus_bitrate(b), j->bitrate, j->switch_delay_ms, j->bitrate_store ? ", store" : "");
                return scan_start_stage(b, j);
        }

        if (j->stage <= j->n_pairs) {
                for (size_t i = 0; i < r->n_devices; i++)
                        if (lssd_job_add_found(j, &r->devices[i]) < 0)
                                return start_failed(b, j, -ENOMEM);
                if (r->status != LSS_OK)
                        return fail(b, j, lssd_status_to_error_name(r->status), lssd_status_to_result(r->status),
                                    "the scan did not finish (%s): nothing changed",
                                    r->message[0] ? r->message : lssd_status_to_result(r->status));
                if (++j->stage <= j->n_pairs)
                        return scan_start_stage(b, j);

                k = collect_devices(b, j, missing, sizeof(missing));
                if (k < 0)
                        return start_failed(b, j, k);
                if (missing[0])
                        return fail(b, j, LSSD_ERROR_NOT_FOUND, "not-found",
                                    "mapped device%s not found by the scan, and without a revision in the map it "
                                    "cannot be addressed: %s; nothing changed (option skip_missing=true leaves "
                                    "devices the scan does not find out)", strchr(missing, ',') ? "s" : "",
                                    missing);
                if (j->n_br_devices == 0)
                        return fail(b, j, LSSD_ERROR_NOT_FOUND, "not-found",
                                    "no LSS device on %s: nothing to switch, nothing changed", b->ifname);

                lss_bitrate_params p = {
                        .bitrate = j->bitrate,
                        .old_bitrate = lssd_bus_bitrate(b),
                        .delay_ms = j->switch_delay_ms,
                        .store = j->bitrate_store,
                        .devices = j->br_devices,
                        .n_devices = j->n_br_devices,
                };
                log_info("%s: SetBitrate: %zu device%s to switch", b->ifname, j->n_br_devices,
                         j->n_br_devices == 1 ? "" : "s");
                k = lss_master_set_bitrate(b->engine, &p, lssd_bus_now(b));
                return k < 0 ? start_failed(b, j, k) : 1;
        }
        return finish(b, j, r);
}

/* ---- the host interface ---- */

bool lssd_bitrate_retune(lssd_bus *b) {
        lssd_job *j = b->job;
        enum lss_retune how = LSS_RETUNE_FAILED;
        uint32_t rate;
        uint64_t deadline, now, done;
        bool reopened = false;
        int r;

        if (!lss_master_retune_wanted(b->engine, &rate, &deadline))
                return false;
        now = lssd_bus_now(b);
        if (!j || j->type != LSSD_JOB_SET_BITRATE || !b->config->bitrate_change) {
                if (j)
                        j->retune_error = EPERM;
        } else if (b->sim) {
                lssd_simbus_set_bitrate(b->sim, rate);
                how = LSS_RETUNE_DONE;
        } else if (b->link_virtual) {
                how = LSS_RETUNE_SKIPPED;
        } else {
                j->retune_until = now + RETUNE_LINK_GRACE_US;
                r = rtnl_set_can_bitrate(NULL, b->ifname, rate);
                if (r == 0) {
                        how = LSS_RETUNE_DONE;
                        /* the old socket carries a pending ENETDOWN from the link going down */
                        if (b->port) {
                                r = socketcan_port_reopen(b->port);
                                if (r < 0)
                                        log_warning("%s: re-opening after the retune failed: %s", b->ifname,
                                                    strerror(-r));
                                reopened = true;
                        }
                } else if (r == -EOPNOTSUPP) {
                        how = LSS_RETUNE_SKIPPED;
                } else {
                        j->retune_error = -r;
                        log_error("%s: retuning the interface to %u bit/s failed: %s%s", b->ifname, rate,
                                  strerror(-r), r == -EPERM ? " (lssd needs CAP_NET_ADMIN for bit-rate changes: "
                                                              "see the lssd-bitrate.conf drop-in)" : "");
                }
        }
        done = lssd_bus_now(b);
        if (how == LSS_RETUNE_DONE && done > deadline)
                log_warning("%s: the interface was retuned %llu us after the slaves switched", b->ifname,
                            (unsigned long long) (done - deadline));
        log_info("%s: SetBitrate: host interface retune: %s (%llu us)", b->ifname, lss_retune_name(how),
                 (unsigned long long) (done - now));
        lss_master_retune_done(b->engine, how, done);
        return reopened;
}

bool lssd_bitrate_retuning(lssd_bus *b) {
        const lssd_job *j = b->job;
        return j && j->type == LSSD_JOB_SET_BITRATE && j->retune_until > lssd_bus_now(b);
}

bool lssd_bitrate_uncancellable(lssd_bus *b) {
        const lssd_job *j = b->job;
        return b->engine_running && j && j->type == LSSD_JOB_SET_BITRATE && j->stage > j->n_pairs;
}
