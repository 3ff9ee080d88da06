/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The verbs that start jobs on a bus (scan, auto-assign, assign, unassign,
 * set-bitrate) and reload. */
#include <errno.h>
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "ctl/ctl.h"
#include "ctl/ctl_dcf.h"
#include "ctl/ctl_errors.h"
#include "ctl/ctl_job.h"
#include "ctl/ctl_json.h"
#include "ctl/ctl_map_entry.h"
#include "ctl/ctl_objects.h"
#include "ctl/ctl_parse.h"
#include "ctl/ctl_show.h"
#include "ctl/ctl_table.h"
#include "lss/lss_proto.h"

#define DEFAULT_SWITCH_DELAY_MS 100

typedef struct found {
        const char *ifname;
        uint32_t id[4];
        uint8_t old_id, new_id;   /* scan: new_id is the node-ID */
        char *outcome, *detail;   /* auto-assign */
        bool revision_unknown;    /* a missing device from a map entry without revision */
        bool by_lss, by_sdo;      /* scan: the device's FoundBy */
        bool kept;                /* scan --as-config: in the map, not found by this scan, or found
                                   * non-configured (then non_configured): at the map's node-ID */
        bool non_configured;
        uint8_t mapped;           /* scan --as-config: the map's node-ID, 0: not in the map */
} found;

typedef struct results {
        found *v;
        size_t n;
        bool partial;             /* auto-assign: some bus does not match its map */
        char **notes;             /* scan: "<ifname>: <note>", what lssd did not look for or identify */
        size_t n_notes;
        size_t n_map_missing;     /* scan: the map's devices it did not find (Device objects "missing") */
} results;

static int results_add_note(results *res, const char *ifname, const char *note) {
        char **v = realloc(res->notes, (res->n_notes + 1) * sizeof(*v));
        if (!v)
                return -ENOMEM;
        res->notes = v;
        if (asprintf(&res->notes[res->n_notes], "%s: %s", ifname, note) < 0)
                return -ENOMEM;
        res->n_notes++;
        return 0;
}

static int results_add(results *res, const char *ifname, const uint32_t id[4], uint8_t old_id, uint8_t new_id,
                       const char *outcome, const char *detail) {
        found *v = realloc(res->v, (res->n + 1) * sizeof(*v));
        if (!v)
                return -ENOMEM;
        res->v = v;
        found *f = &res->v[res->n++];
        *f = (found) { ifname, { id[0], id[1], id[2], id[3] }, old_id, new_id, NULL, NULL };
        if (outcome && (!(f->outcome = strdup(outcome)) || !(f->detail = strdup(detail))))
                return -ENOMEM;
        return 0;
}

static void results_free(results *res) {
        for (size_t i = 0; i < res->n; i++) {
                free(res->v[i].outcome);
                free(res->v[i].detail);
        }
        free(res->v);
        for (size_t i = 0; i < res->n_notes; i++)
                free(res->notes[i]);
        free(res->notes);
}

/* auto-assign outcomes that leave the bus unlike its map */
static bool outcome_is_problem(const char *outcome) {
        return strcmp(outcome, "missing") == 0 || strcmp(outcome, "conflict") == 0 || strcmp(outcome, "failed") == 0;
}

static bool outcome_is_change(const char *outcome) {
        return strcmp(outcome, "assigned") == 0 || strcmp(outcome, "pool") == 0 || strcmp(outcome, "replaced") == 0 ||
               strncmp(outcome, "would-", strlen("would-")) == 0;
}

/* after ^C: the job was cancelled (or still queued), lssctl exits 130 */
static int interrupted(ctl_context *c, const char *what, const char *ifname) {
        return ctl_fail(c, CTL_EXIT_INTERRUPTED, -EINTR, "%s on %s interrupted.", what, ifname);
}

/* a job call: message prepared by `build`, run with progress and ^C */
static int run_job(ctl_context *c, ctl_runner *run, sd_bus_message *m, const char *path, const char *ifname,
                   const char *job, const char *what, sd_bus_message **ret_reply) {
        sd_bus_error error = SD_BUS_ERROR_NULL;
        int r;

        r = ctl_runner_call(run, m, path, ifname, job, ret_reply, &error);
        if (r == -EINTR)
                r = interrupted(c, what, ifname);
        else if (r < 0) {
                char *msg;
                if (asprintf(&msg, "%s on %s failed", what, ifname) < 0)
                        msg = NULL;
                r = ctl_bus_fail(c, &error, r, msg ? msg : what);
                free(msg);
        }
        sd_bus_error_free(&error);
        return r;
}

/* run_job() with its own event loop, for a single-bus job whose reply carries nothing */
static int run_built_job(ctl_context *c, sd_bus_message *m, const char *path, const char *ifname, const char *job,
                         const char *what) {
        sd_bus_message *reply = NULL;
        ctl_runner *run = NULL;
        int r = ctl_runner_new(c, c->stderr_tty, &run);
        if (r < 0)
                return ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to set up the event loop: %s", strerror(-r));
        r = run_job(c, run, m, path, ifname, job, what, &reply);
        sd_bus_message_unref(reply);
        ctl_runner_free(run);
        return r;
}

static int append_bool_option(sd_bus_message *m, const char *key, bool value) {
        return sd_bus_message_append(m, "{sv}", key, "b", value);
}

/* auto-assign: the count of each outcome, and each problem on stderr */
static void print_outcome_summary(const results *res, bool dry_run) {
        static const char *const kinds[] = { "assigned", "pool", "replaced", "unchanged", "unknown", "missing",
                                             "conflict", "failed" };
        /* node-IDs given (assigned, pool); replacements are counted apart */
        size_t changed = 0;
        for (size_t i = 0; i < res->n; i++)
                changed += outcome_is_change(res->v[i].outcome) && strcmp(res->v[i].outcome, "replaced") != 0 &&
                           strcmp(res->v[i].outcome, "would-replace") != 0;
        if (dry_run)
                printf("Dry run, nothing was configured: %zu node-ID%s would be assigned", changed,
                       changed == 1 ? "" : "s");
        else
                printf("%zu node-ID%s assigned", changed, changed == 1 ? "" : "s");
        for (size_t k = 2; k < sizeof(kinds) / sizeof(kinds[0]); k++) {
                size_t n = 0;
                for (size_t i = 0; i < res->n; i++)
                        n += strcmp(res->v[i].outcome, kinds[k]) == 0 ||
                             (strcmp(kinds[k], "replaced") == 0 && strcmp(res->v[i].outcome, "would-replace") == 0);
                if (n > 0)
                        printf(", %zu %s%s", n, dry_run && strcmp(kinds[k], "replaced") == 0 ? "would be " : "",
                               kinds[k]);
        }
        printf(".\n");
}

static void print_problems(const results *res) {
        for (size_t i = 0; i < res->n; i++) {
                const found *f = &res->v[i];
                char revision[16] = "-";
                if (!outcome_is_problem(f->outcome))
                        continue;
                if (!f->revision_unknown)
                        snprintf(revision, sizeof(revision), "0x%08" PRIx32, f->id[2]);
                fprintf(stderr, "lssctl: %s: device 0x%08" PRIx32 ":0x%08" PRIx32 ":%s:0x%08" PRIx32 " %s%s%s\n",
                        f->ifname, f->id[0], f->id[1], revision, f->id[3], f->outcome, f->detail[0] ? ": " : "",
                        f->detail);
        }
}

/* A map printed from a scan keeps the map's devices the scan did not find
 * (switched off, unplugged for service): written over lssd.conf, it would
 * otherwise drop them from the map without a word. */
static int add_map_devices_not_found(results *res, const ctl_objects *o, char **ifnames, size_t n) {
        for (size_t k = 0; k < o->n_devices; k++) {
                const ctl_device_info *d = &o->devices[k];
                size_t b = 0;
                bool seen = false;
                if (d->mapped_node_id < 1 || d->mapped_node_id > 127)
                        continue;
                while (b < n && strcmp(ifnames[b], d->ifname) != 0)
                        b++;
                for (size_t i = 0; i < res->n && !seen; i++)
                        seen = strcmp(res->v[i].ifname, d->ifname) == 0 &&
                               memcmp(res->v[i].id, d->id, sizeof(d->id)) == 0;
                if (b == n || seen)
                        continue;
                if (results_add(res, ifnames[b], d->id, 0xFF, d->mapped_node_id, NULL, NULL) < 0)
                        return -ENOMEM;
                res->v[res->n - 1].kept = true;
                res->v[res->n - 1].revision_unknown = d->revision_unknown;
        }
        return 0;
}

/* found by SDO alone: it did not answer LSS, so lssd cannot give it a node-ID */
static bool sdo_only(const found *f) {
        return f->by_sdo && !f->by_lss;
}

/* --as-config: a device of the map found non-configured goes in at the
 * map's node-ID (AutoAssign gives it that), as one not found does: as the
 * bus is, it would lose its entry. */
static void keep_non_configured(found *f) {
        if (f->new_id != 0xFF || f->mapped < 1 || f->mapped > 127 || sdo_only(f))
                return;
        f->new_id = f->mapped;
        f->kept = f->non_configured = true;
}

/* What the replies do not carry, from the Device objects: auto-assign's
 * reply gives a missing device the map's identity, whose revision is 0 when
 * the map has none (RevisionKnown); scan's does not say how each device
 * was found (FoundBy), nor which devices of the map it did not find (for
 * --as-config, which fails without them rather than print a map short of
 * them; the table goes without the rest). */
static int annotate_from_objects(ctl_context *c, results *res, bool scan, char **ifnames, size_t n_buses) {
        bool keep_map = scan && c->as_config;
        bool any = scan;
        for (size_t i = 0; i < res->n && !any; i++)
                any = strcmp(res->v[i].outcome, "missing") == 0;
        ctl_objects o = { 0 };
        if (!any)
                return 0;
        int r = ctl_objects_load(c, &o);
        if (r < 0)
                return keep_map ? r : 0;
        for (size_t i = 0; i < res->n; i++)
                for (size_t k = 0; k < o.n_devices; k++) {
                        const ctl_device_info *d = &o.devices[k];
                        if (strcmp(d->ifname, res->v[i].ifname) != 0 ||
                            memcmp(d->id, res->v[i].id, sizeof(res->v[i].id)) != 0)
                                continue;
                        if (scan) {
                                res->v[i].by_lss = d->found_lss;
                                res->v[i].by_sdo = d->found_sdo;
                                res->v[i].mapped = d->mapped_node_id;
                                if (keep_map)
                                        keep_non_configured(&res->v[i]);
                        } else if (strcmp(res->v[i].outcome, "missing") == 0)
                                res->v[i].revision_unknown = d->revision_unknown;
                }
        for (size_t k = 0; scan && k < o.n_devices; k++)
                for (size_t b = 0; b < n_buses; b++)
                        res->n_map_missing += strcmp(o.devices[k].ifname, ifnames[b]) == 0 &&
                                              o.devices[k].mapped_node_id != 0 &&
                                              strcmp(o.devices[k].state, "missing") == 0;
        r = keep_map ? add_map_devices_not_found(res, &o, ifnames, n_buses) : 0;
        ctl_objects_done(&o);
        if (r < 0)
                return ctl_fail(c, CTL_EXIT_FAILURE, r, "Out of memory.");
        return 0;
}

/* FoundBy as the table shows it: "lss,sdo", "lss", "sdo" or "-" */
static const char *found_by_text(const found *f) {
        return f->by_lss && f->by_sdo ? LSSD_FOUND_BY_LSS "," LSSD_FOUND_BY_SDO
                : f->by_lss ? LSSD_FOUND_BY_LSS : f->by_sdo ? LSSD_FOUND_BY_SDO : "-";
}

/* scan: the count, and lssd's notes: what the scan did not look for or
 * could not identify */
static void print_scan_legend(const results *res) {
        size_t only = 0;
        for (size_t i = 0; i < res->n; i++)
                only += sdo_only(&res->v[i]);
        printf("%zu device%s found", res->n, res->n == 1 ? "" : "s");
        if (only > 0)
                printf(", %zu by SDO only (no LSS answer: lssd cannot assign %s)", only, only == 1 ? "it" : "them");
        printf(".\n");
        if (res->n_map_missing > 0)
                printf("%zu device%s of the map not found (missing): 'lssctl list' shows %s.\n", res->n_map_missing,
                       res->n_map_missing == 1 ? "" : "s", res->n_map_missing == 1 ? "it" : "them");
        for (size_t i = 0; i < res->n_notes; i++)
                printf("Note: %s.\n", res->notes[i]);
}

static void print_results(ctl_context *c, const results *res, bool assignments) {
        if (assignments)
                print_problems(res);
        if (assignments && c->quiet && !c->json)
                return;
        if (c->json) {
                ctl_json j;
                ctl_json_init(&j, stdout);
                ctl_json_array_begin(&j);
                for (size_t i = 0; i < res->n; i++) {
                        ctl_json_object_begin(&j);
                        ctl_json_key(&j, "bus");
                        ctl_json_string(&j, res->v[i].ifname);
                        ctl_json_identity(&j, res->v[i].id);
                        if (assignments) {
                                ctl_json_key(&j, "revision_known");
                                ctl_json_bool(&j, !res->v[i].revision_unknown);
                                ctl_json_key(&j, "old_node_id");
                                ctl_json_uint(&j, res->v[i].old_id);
                                ctl_json_key(&j, "new_node_id");
                        } else
                                ctl_json_key(&j, "node_id");
                        ctl_json_uint(&j, res->v[i].new_id);
                        if (assignments) {
                                ctl_json_key(&j, "outcome");
                                ctl_json_string(&j, res->v[i].outcome);
                                ctl_json_key(&j, "detail");
                                ctl_json_string(&j, res->v[i].detail);
                        } else {
                                ctl_json_key(&j, "found_by");
                                ctl_json_array_begin(&j);
                                if (res->v[i].by_lss)
                                        ctl_json_string(&j, LSSD_FOUND_BY_LSS);
                                if (res->v[i].by_sdo)
                                        ctl_json_string(&j, LSSD_FOUND_BY_SDO);
                                ctl_json_array_end(&j);
                        }
                        ctl_json_object_end(&j);
                }
                ctl_json_array_end(&j);
                ctl_json_finish(&j);
                return;
        }

        static const char *const scan_columns[] = { "BUS", "VENDOR", "PRODUCT", "REVISION", "SERIAL", ">NODE",
                                                    "FOUND-BY" };
        static const char *const assign_columns[] = { "BUS", "VENDOR", "PRODUCT", "REVISION", "SERIAL", ">OLD",
                                                      ">NEW", "OUTCOME" };
        ctl_table *t;
        if (ctl_table_new(&t, assignments ? 8 : 7, assignments ? assign_columns : scan_columns) < 0)
                return;
        for (size_t i = 0; i < res->n; i++) {
                const found *f = &res->v[i];
                bool missing = assignments && strcmp(f->outcome, "missing") == 0;
                ctl_table_add(t, NULL, "%s", f->ifname);
                ctl_table_identity_full(t, f->id, !f->revision_unknown);
                if (missing || (assignments && f->old_id == 0xFF))
                        ctl_table_add(t, NULL, "-");
                else if (assignments)
                        ctl_table_add(t, NULL, "%u", f->old_id);
                if (missing || f->new_id == 0xFF)
                        ctl_table_add(t, CTL_ANSI_YELLOW, "-");
                else
                        ctl_table_add(t, NULL, "%u", f->new_id);
                if (assignments)
                        ctl_table_add(t, outcome_is_problem(f->outcome) ? CTL_ANSI_RED : NULL, "%s%s%s", f->outcome,
                                      f->detail[0] ? ", " : "", f->detail);
                else
                        ctl_table_add(t, sdo_only(f) ? CTL_ANSI_YELLOW : NULL, "%s", found_by_text(f));
        }
        if (res->n > 0)
                ctl_table_print(t, stdout, !c->no_legend, c->colors);
        for (size_t i = 0; assignments && i < res->n; i++)
                ctl_print_replacement(res->v[i].ifname, res->v[i].id, res->v[i].new_id, res->v[i].outcome,
                                      res->v[i].detail);
        if (!c->no_legend) {
                if (res->n > 0)
                        putchar('\n');
                if (assignments)
                        print_outcome_summary(res, c->dry_run);
                else
                        print_scan_legend(res);
        }
        ctl_table_free(t);
}

/* scan --as-config: one device of a map line, 0x%08x as lssd.conf(5) shows them */
static void print_map_entry(const found *f, bool active, bool comma) {
        ctl_print_map_entry(f->id, !f->revision_unknown, f->new_id, active, comma);
}

/* a device of the map found at another node-ID than the map's */
static bool map_moved(const found *f) {
        return f->mapped >= 1 && f->mapped <= 127 && f->mapped != f->new_id;
}

static int compare_by_node_id(const void *a, const void *b) {
        const found *x = *(const found *const *) a, *y = *(const found *const *) b;
        if (x->new_id != y->new_id)
                return x->new_id < y->new_id ? -1 : 1;
        return memcmp(x->id, y->id, sizeof(x->id));
}

/* Which devices can be map entries (calloc'ed, NULL when out of memory):
 * a device found is when its node-ID is 1..127, it answers LSS and no
 * other device found on its bus has that node-ID; one kept from the map
 * when no device found has its node-ID. */
static bool *mappable(const results *res) {
        bool *ok = calloc(res->n ? res->n : 1, sizeof(*ok));
        for (size_t i = 0; ok && i < res->n; i++) {
                const found *f = &res->v[i];
                ok[i] = f->new_id >= 1 && f->new_id <= 127 && !sdo_only(f);
                for (size_t k = 0; k < res->n && ok[i]; k++)
                        if (k != i && res->v[k].new_id == f->new_id && strcmp(res->v[k].ifname, f->ifname) == 0 &&
                            (f->kept || !res->v[k].kept))
                                ok[i] = false;
        }
        return ok;
}

/* The bus's Bitrate as lssd publishes it, 0 when it does not say a CiA 301 one. */
static uint32_t bus_bitrate(ctl_context *c, const char *path) {
        uint32_t bitrate = 0;
        if (sd_bus_get_property_trivial(c->bus, LSSD_BUS_NAME, path, LSSD_BUS_IFACE, "Bitrate", NULL, 'u', &bitrate) < 0 ||
            lss_bit_timing_index(bitrate) < 0)
                return 0;
        return bitrate;
}

/* The found devices as the buses list of lssd.conf(5): each configured
 * device a map entry at its node-ID, and the map's devices not found at
 * theirs; what cannot be one commented out. */
static int print_config(ctl_context *c, const results *res, char **paths, char **ifnames, size_t n) {
        const found **v = calloc(res->n ? res->n : 1, sizeof(*v));
        bool *ok = mappable(res);
        size_t mapped = 0, kept = 0, waiting = 0, left_out = 0, moved = 0;
        char when[64] = "";
        time_t now = time(NULL);
        struct tm tm;

        if (!v || !ok) {
                free(v);
                free(ok);
                return ctl_fail(c, CTL_EXIT_FAILURE, -ENOMEM, "Out of memory.");
        }
        for (size_t i = 0; i < res->n; i++) {
                const found *f = &res->v[i];
                mapped += ok[i] && !f->kept;
                kept += ok[i] && f->kept && !f->non_configured;
                waiting += ok[i] && f->non_configured;
                left_out += !ok[i];
                moved += ok[i] && !f->kept && map_moved(f);
        }
        if (gmtime_r(&now, &tm))
                strftime(when, sizeof(when), "%Y-%m-%d %H:%M:%S UTC", &tm);

        printf("# lssd.conf(5) buses as found by 'lssctl scan --as-config', %s, lssctl %s:\n", when, LSSCTL_VERSION);
        printf("# %zu device%s mapped at %s current node-ID%s", mapped, mapped == 1 ? "" : "s",
               mapped == 1 ? "its" : "their", mapped == 1 ? "" : "s");
        if (moved > 0)
                printf(" (%zu of them not at the map's node-ID: see there)", moved);
        if (kept > 0)
                printf(", %zu kept from the map (not found)", kept);
        if (waiting > 0)
                printf(", %zu non-configured at the map's node-ID%s", waiting, waiting == 1 ? "" : "s");
        if (left_out > 0)
                printf(", %zu commented out (see there)", left_out);
        printf(", on");
        for (size_t b = 0; b < n; b++)
                printf("%s %s", b == 0 ? "" : ",", ifnames[b]);
        printf(".\n"
               "# It replaces the buses = ( ... ); of lssd's configuration file (lssd.conf(5):\n"
               "# /etc/lssd/lssd.conf unless lssd runs with --config), or extends it by\n"
               "# the groups of the buses not there yet; the global settings there stay.\n"
               "# Bus settings lssd does not publish (store, unknown, pool, nmt_stop,\n"
               "# bitrate_change, vendor, product) are not here: copy them from the old file.\n"
               "# Check the file with 'lssd --check-config FILE', then 'lssctl reload'.\n"
               "buses = (\n");
        for (size_t b = 0; b < n; b++) {
                size_t nv = 0, last = SIZE_MAX;
                uint32_t bitrate = bus_bitrate(c, paths[b]);

                for (size_t i = 0; i < res->n; i++)
                        if (strcmp(res->v[i].ifname, ifnames[b]) == 0)
                                v[nv++] = &res->v[i];
                qsort(v, nv, sizeof(*v), compare_by_node_id);
                for (size_t i = 0; i < nv; i++)
                        if (ok[v[i] - res->v])
                                last = i;

                printf("  {\n    interface = \"%s\";\n", ifnames[b]);
                if (bitrate > 0)
                        printf("    bitrate = %" PRIu32 ";\n", bitrate);
                else
                        printf("    # bitrate = ...;  lssd did not say this bus's bit rate: give it\n");
                printf("    auto_assign = true;   # at start, every device below gets its node-ID\n"
                       "    devices = (\n");
                for (size_t i = 0; i < nv; i++) {
                        const found *f = v[i];
                        if (ok[f - res->v]) {
                                print_map_entry(f, true, i < last);
                                if (f->non_configured)
                                        printf("  # non-configured now: at the map's node-ID, which AutoAssign "
                                               "gives it");
                                else if (f->kept)
                                        printf("  # in the map, not found by this scan: kept (delete the line if "
                                               "the device is gone)");
                                else if (map_moved(f))
                                        printf("  # the map has node-ID %u: this is the node-ID it has now", f->mapped);
                                putchar('\n');
                                continue;
                        }
                        print_map_entry(f, false, false);
                        if (f->non_configured)
                                printf("  # non-configured now; the map's node-ID %u is another device's now\n",
                                       f->new_id);
                        else if (f->kept)
                                printf("  # in the map, not found by this scan; node-ID %u is another device's now\n",
                                       f->new_id);
                        else if (sdo_only(f))
                                printf("  # found by SDO only: it does not answer LSS, so lssd cannot give it a "
                                       "node-ID\n");
                        else if (f->new_id == 0xFF)
                                printf("  # non-configured (node-ID 255): give it a node-ID, then scan again\n");
                        else if (f->new_id >= 1 && f->new_id <= 127) {
                                printf("  # WARNING: node-ID %u is answered by two devices; should not happen: "
                                       "give one another node-ID, then scan again\n", f->new_id);
                                fprintf(stderr, "lssctl: %s: node-ID %u is answered by two devices, both commented "
                                        "out: device 0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32
                                        ".\n", f->ifname, f->new_id, f->id[0], f->id[1], f->id[2], f->id[3]);
                        } else
                                printf("  # node-ID %u is not one a map takes (1..127)\n", f->new_id);
                }
                printf("    );\n  }%s\n", b + 1 < n ? "," : "");
        }
        printf(");\n");
        free(ok);
        free(v);
        return 0;
}

/* scan --as-dcf: a DCF fragment for each device --as-config would map at
 * its node-ID; the others found are named, with why not. */
static int write_dcfs(ctl_context *c, const results *res, char **paths, char **ifnames, size_t n) {
        ctl_dcf_device *v = calloc(res->n ? res->n : 1, sizeof(*v));
        uint32_t *bitrate = calloc(n ? n : 1, sizeof(*bitrate));
        bool *ok = mappable(res);
        size_t k = 0;
        int r = 0;

        if (!v || !bitrate || !ok) {
                r = ctl_fail(c, CTL_EXIT_FAILURE, -ENOMEM, "Out of memory.");
                goto finish;
        }
        for (size_t b = 0; b < n; b++)
                bitrate[b] = bus_bitrate(c, paths[b]);
        for (size_t b = 0; b < n; b++)
                for (uint8_t node = 1; node <= 127; node++)
                        for (size_t i = 0; i < res->n; i++) {
                                const found *f = &res->v[i];
                                if (!ok[i] || f->kept || f->new_id != node || strcmp(f->ifname, ifnames[b]) != 0)
                                        continue;
                                v[k++] = (ctl_dcf_device) { f->ifname, { f->id[0], f->id[1], f->id[2], f->id[3] },
                                                            f->new_id, bitrate[b] };
                        }
        r = ctl_write_dcfs(c, c->as_dcf, v, k);
        if (r < 0)
                goto finish;
        for (size_t i = 0; i < res->n; i++) {
                const found *f = &res->v[i];
                if (ok[i] || f->kept)
                        continue;
                printf("%s: device 0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 " not written: ",
                       f->ifname, f->id[0], f->id[1], f->id[2], f->id[3]);
                if (sdo_only(f))
                        printf("found by SDO only, it does not answer LSS\n");
                else if (f->new_id == 0xFF)
                        printf("non-configured (node-ID 255)\n");
                else if (f->new_id >= 1 && f->new_id <= 127)
                        printf("node-ID %u is answered by two devices\n", f->new_id);
                else
                        printf("node-ID %u is not 1..127\n", f->new_id);
        }
        printf("%zu DCF%s written to %s.\n", k, k == 1 ? "" : "s", c->as_dcf);
finish:
        free(ok);
        free(bitrate);
        free(v);
        return r;
}

/* scan and auto-assign: the same shape, on every bus (or the --bus one) */
static int scan_like(ctl_context *c, bool assign) {
        const char *method = assign ? "AutoAssign" : "Scan";
        const char *what = assign ? "Auto-assignment" : "Scan";
        char **paths = NULL, **ifnames = NULL;
        ctl_runner *run = NULL;
        results res = { 0 };
        size_t n = 0;
        int r;

        r = ctl_buses(c, &paths, &ifnames, &n);
        if (r < 0)
                return r;
        if (n == 0) {
                r = ctl_fail(c, CTL_EXIT_NOT_FOUND, -ENXIO, "lssd serves no bus.");
                goto finish;
        }
        r = ctl_runner_new(c, c->stderr_tty, &run);
        if (r < 0) {
                r = ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to set up the event loop: %s", strerror(-r));
                goto finish;
        }

        for (size_t i = 0; i < n; i++) {
                sd_bus_message *m = NULL, *reply = NULL;

                r = sd_bus_message_new_method_call(c->bus, &m, LSSD_BUS_NAME, paths[i], LSSD_BUS_IFACE, method);
                if (r >= 0)
                        r = sd_bus_message_open_container(m, 'a', "{sv}");
                if (r >= 0 && assign && c->no_store)
                        r = append_bool_option(m, "store", false);
                if (r >= 0 && assign && c->dry_run)
                        r = append_bool_option(m, "dry_run", true);
                if (r >= 0 && !assign && c->no_sdo)
                        r = append_bool_option(m, LSSD_SCAN_OPTION_SDO, false);
                if (r >= 0 && !assign && c->has_vendor) {
                        r = sd_bus_message_append(m, "{sv}", "vendor", "u", c->vendor);
                        if (r >= 0)
                                r = sd_bus_message_append(m, "{sv}", "product", "u", c->product);
                }
                if (r >= 0)
                        r = sd_bus_message_close_container(m);
                if (r < 0) {
                        sd_bus_message_unref(m);
                        r = ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to build the call: %s", strerror(-r));
                        goto finish;
                }
                r = run_job(c, run, m, paths[i], ifnames[i], method, what, &reply);
                sd_bus_message_unref(m);
                if (r < 0)
                        goto finish;

                r = sd_bus_message_enter_container(reply, 'a', assign ? "(uuuuyyss)" : "(uuuuy)");
                while (r > 0) {
                        uint32_t id[4];
                        uint8_t a = 0xFF, b = 0xFF;
                        const char *outcome = NULL, *detail = NULL;
                        r = assign ? sd_bus_message_read(reply, "(uuuuyyss)", &id[0], &id[1], &id[2], &id[3], &a, &b,
                                                         &outcome, &detail)
                                   : sd_bus_message_read(reply, "(uuuuy)", &id[0], &id[1], &id[2], &id[3], &b);
                        if (r > 0 && results_add(&res, ifnames[i], id, a, b, outcome, detail) < 0)
                                r = -ENOMEM;
                }
                if (r >= 0 && assign) {
                        const char *result = NULL;
                        r = sd_bus_message_exit_container(reply);
                        if (r >= 0)
                                r = sd_bus_message_read(reply, "s", &result);
                        if (r >= 0 && strcmp(result, "done") != 0)
                                res.partial = true;
                } else if (r >= 0) {
                        r = sd_bus_message_exit_container(reply);
                        if (r >= 0)
                                r = sd_bus_message_enter_container(reply, 'a', "s");
                        while (r > 0) {
                                const char *note;
                                r = sd_bus_message_read(reply, "s", &note);
                                if (r > 0 && results_add_note(&res, ifnames[i], note) < 0)
                                        r = -ENOMEM;
                        }
                }
                sd_bus_message_unref(reply);
                if (r < 0) {
                        r = ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to parse lssd's answer: %s", strerror(-r));
                        goto finish;
                }
        }
        r = annotate_from_objects(c, &res, !assign, ifnames, n);
        if (r < 0)
                goto finish;
        if (c->as_config)
                r = print_config(c, &res, paths, ifnames, n);
        else if (c->as_dcf)
                r = write_dcfs(c, &res, paths, ifnames, n);
        else
                print_results(c, &res, assign);
        if (r < 0)
                goto finish;
        if (res.partial) {
                size_t bad = 0;
                for (size_t i = 0; i < res.n; i++)
                        bad += outcome_is_problem(res.v[i].outcome);
                r = ctl_fail(c, CTL_EXIT_PARTIAL, -EAGAIN, "The bus %s the map: %zu mapped device%s "
                             "missing, in conflict or failed.", c->dry_run ? "would still not match" : "does not match",
                             bad, bad == 1 ? "" : "s");
        }
finish:
        ctl_runner_free(run);
        ctl_strv_free(paths, n);
        ctl_strv_free(ifnames, n);
        results_free(&res);
        return r;
}

int verb_scan(ctl_context *c) {
        return scan_like(c, false);
}

int verb_auto_assign(ctl_context *c) {
        return scan_like(c, true);
}

/* A bare serial: the one known device with it (on the --bus bus). */
static int resolve_serial(ctl_context *c, uint32_t serial, uint32_t id[4], char **ret_ifname) {
        ctl_objects o;
        const ctl_device_info *hit = NULL;
        size_t hits = 0;
        int r;

        r = ctl_objects_load(c, &o);
        if (r < 0)
                return r;
        for (size_t i = 0; i < o.n_devices; i++) {
                const ctl_device_info *d = &o.devices[i];
                if (d->id[3] != serial || (c->bus_name && (!d->ifname || strcmp(d->ifname, c->bus_name) != 0)))
                        continue;
                hits++;
                if (!hit)
                        hit = d;
        }
        if (hits == 0)
                r = ctl_fail(c, CTL_EXIT_NOT_FOUND, -ENXIO,
                             "No known device has serial number 0x%08" PRIx32 "%s%s. Run 'lssctl scan' first, or "
                             "give the whole identity VENDOR:PRODUCT:REVISION:SERIAL.",
                             serial, c->bus_name ? " on " : "", c->bus_name ? c->bus_name : "");
        else if (hits > 1) {
                fprintf(stderr, "lssctl: Serial number 0x%08" PRIx32 " is ambiguous, %zu known devices have it:\n",
                        serial, hits);
                for (size_t i = 0; i < o.n_devices; i++) {
                        const ctl_device_info *d = &o.devices[i];
                        if (d->id[3] == serial &&
                            (!c->bus_name || (d->ifname && strcmp(d->ifname, c->bus_name) == 0)))
                                fprintf(stderr, "        0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32
                                        " on %s\n", d->id[0], d->id[1], d->id[2], d->id[3], d->ifname);
                }
                r = ctl_usage(c, "Give the whole identity VENDOR:PRODUCT:REVISION:SERIAL%s.",
                              c->bus_name ? "" : " (and --bus IFACE)");
        } else {
                memcpy(id, hit->id, sizeof(hit->id));
                *ret_ifname = strdup(hit->ifname);
                r = *ret_ifname ? 0 : -ENOMEM;
        }
        ctl_objects_done(&o);
        return r;
}

/* A whole identity without --bus: the only bus, or the one that knows it. */
static int bus_of_identity(ctl_context *c, const uint32_t id[4], char **ret_ifname) {
        ctl_objects o;
        const char *ifname = NULL;
        size_t n = 0;
        int r;

        r = ctl_objects_load(c, &o);
        if (r < 0)
                return r;
        if (o.n_buses == 1)
                ifname = o.buses[0].ifname;
        else
                for (size_t i = 0; i < o.n_devices; i++)
                        if (memcmp(o.devices[i].id, id, sizeof(o.devices[i].id)) == 0) {
                                ifname = o.devices[i].ifname;
                                n++;
                        }
        if (o.n_buses == 0)
                r = ctl_fail(c, CTL_EXIT_NOT_FOUND, -ENXIO, "lssd serves no bus.");
        else if (!ifname || n > 1)
                r = ctl_usage(c, "lssd serves %zu buses and %s: say which one with --bus IFACE.", o.n_buses,
                              n > 1 ? "several know this identity" : "none knows this identity");
        else {
                *ret_ifname = strdup(ifname);
                r = *ret_ifname ? 0 : -ENOMEM;
        }
        ctl_objects_done(&o);
        return r;
}

/* A device's node-ID and map entry as lssd knows them: 0 when unknown. */
static void device_node_ids(ctl_context *c, const char *ifname, const uint32_t id[4], uint8_t *ret_node_id,
                            uint8_t *ret_mapped) {
        ctl_objects o;
        *ret_node_id = *ret_mapped = 0;
        if (ctl_objects_load(c, &o) < 0)
                return;
        for (size_t i = 0; i < o.n_devices; i++) {
                const ctl_device_info *d = &o.devices[i];
                if (d->ifname && strcmp(d->ifname, ifname) == 0 && memcmp(d->id, id, sizeof(d->id)) == 0) {
                        *ret_node_id = d->node_id;
                        *ret_mapped = d->mapped_node_id;
                }
        }
        ctl_objects_done(&o);
}

/* assign, unassign --json: the object begins with the bus and the identity */
static void json_device_begin(ctl_json *j, const char *ifname, const uint32_t id[4]) {
        static const char *const keys[4] = { "vendor", "product", "revision", "serial" };
        ctl_json_init(j, stdout);
        ctl_json_object_begin(j);
        ctl_json_key(j, "bus");
        ctl_json_string(j, ifname);
        for (size_t i = 0; i < 4; i++) {
                ctl_json_key(j, keys[i]);
                ctl_json_uint(j, id[i]);
        }
}

/* ... and ends with the warning (null when none) */
static void json_device_end(ctl_json *j, const char *warning) {
        ctl_json_key(j, "warning");
        if (warning[0])
                ctl_json_string(j, warning);
        else
                ctl_json_null(j);
        ctl_json_object_end(j);
        ctl_json_finish(j);
}

/* assign: what was done, and a warning when the map says otherwise */
static void report_assignment(ctl_context *c, const char *ifname, const uint32_t id[4], uint8_t old_id,
                              uint8_t node_id) {
        uint8_t now_id, mapped;
        device_node_ids(c, ifname, id, &now_id, &mapped);
        char warning[160] = "";
        if (mapped != 0 && mapped != node_id)
                snprintf(warning, sizeof(warning), "the map gives this device node-ID %u: the next auto-assign "
                         "pass (also the one at boot) puts %u back", mapped, mapped);
        bool changed = old_id != node_id;
        bool stored = changed && !c->no_store;

        if (c->json) {
                ctl_json j;
                json_device_begin(&j, ifname, id);
                ctl_json_key(&j, "old");
                if (old_id)
                        ctl_json_uint(&j, old_id);
                else
                        ctl_json_null(&j);
                ctl_json_key(&j, "new");
                ctl_json_uint(&j, node_id);
                ctl_json_key(&j, "stored");
                ctl_json_bool(&j, stored);
                json_device_end(&j, warning);
        } else if (!c->quiet) {
                char from[16] = "?";
                if (old_id)
                        snprintf(from, sizeof(from), "%u", old_id);
                printf("%s: device 0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 ": ", ifname, id[0],
                       id[1], id[2], id[3]);
                if (!changed)
                        printf("node-ID %u already, nothing changed.\n", node_id);
                else
                        printf("node-ID %s -> %u%s.\n", from, node_id, stored ? ", stored" : ", not stored");
        }
        if (warning[0])
                fprintf(stderr, "lssctl: warning: %s\n", warning);
}

/* The device argument of assign and unassign: SERIAL (a known device) or
 * VENDOR:PRODUCT:REVISION:SERIAL; its bus's name and object path. */
static int resolve_device(ctl_context *c, const char *arg, uint32_t id[4], char **ret_ifname, char **ret_path) {
        char *ifname = NULL;
        int r;

        r = ctl_parse_identity(arg, id);
        if (r == -ENOENT) {
                uint32_t serial;
                if (ctl_parse_u32(arg, &serial) < 0)
                        return ctl_usage(c, "Invalid serial number '%s'.", arg);
                r = resolve_serial(c, serial, id, &ifname);
        } else if (r < 0)
                return ctl_usage(c, "Invalid identity '%s': VENDOR:PRODUCT:REVISION:SERIAL.", arg);
        else if (c->bus_name) {
                ifname = strdup(c->bus_name);
                r = ifname ? 0 : -ENOMEM;
        } else
                r = bus_of_identity(c, id, &ifname);
        if (r < 0) {
                free(ifname);
                return r;
        }

        /* the path through lssd, which also says whether it serves that bus */
        const char *saved = c->bus_name;
        char **paths = NULL, **names = NULL;
        size_t n = 0;
        c->bus_name = ifname;
        r = ctl_buses(c, &paths, &names, &n);
        c->bus_name = saved;
        if (r < 0) {
                free(ifname);
                return r;
        }
        *ret_path = paths[0];
        paths[0] = NULL;
        ctl_strv_free(paths, n);
        ctl_strv_free(names, n);
        *ret_ifname = ifname;
        return 0;
}

int verb_assign(ctl_context *c) {
        sd_bus_message *m = NULL;
        char *ifname = NULL, *path = NULL;
        uint32_t id[4];
        uint8_t node_id;
        int r;

        if (ctl_parse_node_id(c->args[1], &node_id) < 0)
                return ctl_usage(c, "Invalid node-ID '%s': 1..127.", c->args[1]);
        r = resolve_device(c, c->args[0], id, &ifname, &path);
        if (r < 0)
                goto finish;

        r = sd_bus_message_new_method_call(c->bus, &m, LSSD_BUS_NAME, path, LSSD_BUS_IFACE, "AssignNodeId");
        if (r >= 0)
                r = sd_bus_message_append(m, "uuuuy", id[0], id[1], id[2], id[3], node_id);
        if (r >= 0)
                r = sd_bus_message_open_container(m, 'a', "{sv}");
        if (r >= 0 && c->no_store)
                r = append_bool_option(m, "store", false);
        if (r >= 0 && c->no_verify)
                r = append_bool_option(m, "verify", false);
        if (r >= 0 && c->force)
                r = append_bool_option(m, "force", true);
        if (r >= 0)
                r = sd_bus_message_close_container(m);
        if (r < 0) {
                r = ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to build the call: %s", strerror(-r));
                goto finish;
        }
        uint8_t old_id, mapped;
        device_node_ids(c, ifname, id, &old_id, &mapped);
        r = run_built_job(c, m, path, ifname, "AssignNodeId", "Assignment");
        if (r >= 0)
                report_assignment(c, ifname, id, old_id, node_id);
finish:
        sd_bus_message_unref(m);
        free(path);
        free(ifname);
        return r;
}

/* unassign: lssd's account of what happened, and what remains */
static int report_unassignment(ctl_context *c, sd_bus_message *reply, const char *ifname, const uint32_t id[4]) {
        uint8_t old_id;
        int stored, in_effect;
        const char *message, *warning;
        int r = sd_bus_message_read(reply, "ybbss", &old_id, &stored, &in_effect, &message, &warning);
        if (r < 0)
                return ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to parse lssd's answer: %s", strerror(-r));

        if (c->json) {
                ctl_json j;
                json_device_begin(&j, ifname, id);
                ctl_json_key(&j, "old");
                ctl_json_uint(&j, old_id);
                ctl_json_key(&j, "stored");
                ctl_json_bool(&j, stored);
                ctl_json_key(&j, "in_effect");
                ctl_json_bool(&j, in_effect);
                ctl_json_key(&j, "message");
                ctl_json_string(&j, message);
                json_device_end(&j, warning);
        } else if (!c->quiet)
                printf("%s: device 0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 ": %s.\n", ifname,
                       id[0], id[1], id[2], id[3], message);
        if (warning[0] && !c->json)
                fprintf(stderr, "lssctl: warning: %s\n", warning);
        return 0;
}

int verb_unassign(ctl_context *c) {
        sd_bus_message *m = NULL, *reply = NULL;
        char *ifname = NULL, *path = NULL;
        ctl_runner *run = NULL;
        uint32_t id[4];
        int r;

        r = resolve_device(c, c->args[0], id, &ifname, &path);
        if (r < 0)
                goto finish;

        r = sd_bus_message_new_method_call(c->bus, &m, LSSD_BUS_NAME, path, LSSD_BUS_IFACE, "UnassignNodeId");
        if (r >= 0)
                r = sd_bus_message_append(m, "uuuu", id[0], id[1], id[2], id[3]);
        if (r >= 0)
                r = sd_bus_message_open_container(m, 'a', "{sv}");
        if (r >= 0 && c->no_store)
                r = append_bool_option(m, "store", false);
        if (r >= 0 && c->reset)
                r = append_bool_option(m, "reset", true);
        if (r >= 0)
                r = sd_bus_message_close_container(m);
        if (r < 0) {
                r = ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to build the call: %s", strerror(-r));
                goto finish;
        }
        r = ctl_runner_new(c, c->stderr_tty, &run);
        if (r < 0) {
                r = ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to set up the event loop: %s", strerror(-r));
                goto finish;
        }
        r = run_job(c, run, m, path, ifname, "UnassignNodeId", "Unassignment", &reply);
        if (r >= 0)
                r = report_unassignment(c, reply, ifname, id);
finish:
        sd_bus_message_unref(reply);
        sd_bus_message_unref(m);
        ctl_runner_free(run);
        free(path);
        free(ifname);
        return r;
}

/* set-bitrate: a line per device switched, then the interface */
static int report_bitrate(ctl_context *c, sd_bus_message *reply, const char *ifname, uint32_t before,
                          uint32_t bitrate) {
        uint32_t id[4];
        const char *outcome;
        size_t n = 0;
        int r = sd_bus_message_enter_container(reply, 'a', "(uuuus)");
        while (r >= 0) {
                r = sd_bus_message_read(reply, "(uuuus)", &id[0], &id[1], &id[2], &id[3], &outcome);
                if (r <= 0)
                        break;
                n++;
                if (!c->quiet)
                        printf("%s: device 0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32
                               ": %" PRIu32 " -> %" PRIu32 " bit/s, %s.\n", ifname, id[0], id[1], id[2], id[3],
                               before, bitrate, strcmp(outcome, "stored") == 0 ? "stored" : "not stored");
        }
        if (r < 0)
                return ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to parse lssd's answer: %s", strerror(-r));
        if (c->quiet)
                return 0;
        if (n == 0 && before == bitrate)
                printf("%s: the network runs at %" PRIu32 " bit/s already, nothing changed.\n", ifname, bitrate);
        else
                printf("%s: the interface and %zu device%s switched from %" PRIu32 " to %" PRIu32 " bit/s.\n",
                       ifname, n, n == 1 ? "" : "s", before, bitrate);
        return 0;
}

int verb_set_bitrate(ctl_context *c) {
        sd_bus_message *m = NULL;
        char *path = NULL, *ifname = NULL;
        uint32_t bitrate;
        int r;

        r = ctl_parse_bitrate(c->args[0], &bitrate);
        if (r < 0)
                return ctl_usage(c, "Invalid bit rate '%s': one of 1000000 800000 500000 250000 125000 100000 "
                                 "50000 20000 10000 (or 1M, 500k, ...).", c->args[0]);
        r = ctl_pick_bus(c, &path, &ifname);
        if (r < 0)
                return r;
        r = sd_bus_message_new_method_call(c->bus, &m, LSSD_BUS_NAME, path, LSSD_BUS_IFACE, "SetBitrate");
        if (r >= 0)
                r = sd_bus_message_append(m, "uq", bitrate,
                                          (uint16_t) (c->has_delay ? c->delay_ms : DEFAULT_SWITCH_DELAY_MS));
        if (r >= 0)
                r = sd_bus_message_open_container(m, 'a', "{sv}");
        if (r >= 0 && c->no_store)
                r = append_bool_option(m, "store", false);
        if (r >= 0 && c->skip_missing)
                r = append_bool_option(m, "skip_missing", true);
        if (r >= 0 && c->global)
                r = append_bool_option(m, LSSD_BITRATE_OPTION_GLOBAL, true);
        if (r >= 0)
                r = sd_bus_message_close_container(m);
        if (r < 0) {
                r = ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to build the call: %s", strerror(-r));
                goto finish;
        }
        uint32_t before = 0;
        (void) sd_bus_get_property_trivial(c->bus, LSSD_BUS_NAME, path, LSSD_BUS_IFACE, "Bitrate", NULL, 'u', &before);
        ctl_runner *run = NULL;
        sd_bus_message *reply = NULL;
        r = ctl_runner_new(c, c->stderr_tty, &run);
        if (r < 0) {
                r = ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to set up the event loop: %s", strerror(-r));
                goto finish;
        }
        r = run_job(c, run, m, path, ifname, "SetBitrate", "Bit rate change", &reply);
        if (r >= 0)
                r = report_bitrate(c, reply, ifname, before, bitrate);
        sd_bus_message_unref(reply);
        ctl_runner_free(run);
finish:
        sd_bus_message_unref(m);
        free(path);
        free(ifname);
        return r;
}

int verb_reload(ctl_context *c) {
        sd_bus_error error = SD_BUS_ERROR_NULL;
        int r;

        r = ctl_connect(c);
        if (r < 0)
                return r;
        r = sd_bus_call_method(c->bus, LSSD_BUS_NAME, LSSD_MANAGER_PATH, LSSD_MANAGER_IFACE, "ReloadConfig", &error,
                               NULL, NULL);
        if (r < 0)
                r = ctl_bus_fail(c, &error, r, "Failed to reload the configuration");
        else if (!c->quiet)
                printf("lssd read its configuration again.\n");
        sd_bus_error_free(&error);
        return r;
}
