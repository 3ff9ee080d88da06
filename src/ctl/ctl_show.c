/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* status and list: what lssd knows, for people (tables) and scripts (--json). */
#include <errno.h>
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "ctl/ctl.h"
#include "ctl/ctl_errors.h"
#include "ctl/ctl_json.h"
#include "ctl/ctl_objects.h"
#include "ctl/ctl_show.h"
#include "ctl/ctl_table.h"

static const char *const device_states[] = {
        "assigned", "pool", "pending-reset", "configured", "non-configured", "mismatch", "conflict", "missing",
};
#define N_DEVICE_STATES (sizeof(device_states) / sizeof(device_states[0]))

static const char *ctl_device_state_color(const char *state) {
        if (!state)
                return NULL;
        if (strcmp(state, "assigned") == 0 || strcmp(state, "pool") == 0)
                return CTL_ANSI_GREEN;
        if (strcmp(state, "non-configured") == 0 || strcmp(state, "pending-reset") == 0)
                return CTL_ANSI_YELLOW;
        if (strcmp(state, "mismatch") == 0 || strcmp(state, "conflict") == 0)
                return CTL_ANSI_RED;
        if (strcmp(state, "missing") == 0)
                return CTL_ANSI_GREY;
        return NULL;
}

static const char *bus_state_color(const char *state) {
        if (!state)
                return NULL;
        if (strcmp(state, "idle") == 0)
                return CTL_ANSI_GREEN;
        if (strcmp(state, "busy") == 0 || strcmp(state, "error-passive") == 0)
                return CTL_ANSI_YELLOW;
        return CTL_ANSI_RED;
}

static void ctl_format_time(uint64_t usec, char *buf, size_t size) {
        struct tm tm;
        time_t t = (time_t) (usec / 1000000);

        if (usec == 0 || !localtime_r(&t, &tm) || strftime(buf, size, "%Y-%m-%d %H:%M:%S", &tm) == 0)
                snprintf(buf, size, "never");
}

/* the --bus one must be served */
static int check_bus_filter(ctl_context *c, const ctl_objects *o) {
        if (!c->bus_name)
                return 0;
        for (size_t i = 0; i < o->n_buses; i++)
                if (o->buses[i].ifname && strcmp(o->buses[i].ifname, c->bus_name) == 0)
                        return 0;
        return ctl_fail(c, CTL_EXIT_NOT_FOUND, -ENXIO, "lssd does not serve interface '%s'.", c->bus_name);
}

static bool bus_wanted(const ctl_context *c, const char *ifname) {
        return !c->bus_name || (ifname && strcmp(ifname, c->bus_name) == 0);
}

static void count_states(const ctl_objects *o, const char *ifname, size_t counts[N_DEVICE_STATES + 1],
                         size_t *total) {
        memset(counts, 0, sizeof(size_t) * (N_DEVICE_STATES + 1));
        *total = 0;
        for (size_t i = 0; i < o->n_devices; i++) {
                const ctl_device_info *d = &o->devices[i];
                if (!d->ifname || strcmp(d->ifname, ifname) != 0)
                        continue;
                size_t k = 0;
                while (k < N_DEVICE_STATES && (!d->state || strcmp(d->state, device_states[k]) != 0))
                        k++;
                counts[k]++; /* N_DEVICE_STATES: a state this lssctl does not know */
                (*total)++;
        }
}

static void status_json(ctl_context *c, const ctl_objects *o) {
        ctl_json j;

        ctl_json_init(&j, stdout);
        ctl_json_object_begin(&j);
        ctl_json_key(&j, "version");
        ctl_json_string(&j, o->version);
        ctl_json_key(&j, "buses");
        ctl_json_array_begin(&j);
        for (size_t i = 0; i < o->n_buses; i++) {
                const ctl_bus_info *b = &o->buses[i];
                size_t counts[N_DEVICE_STATES + 1], total;

                if (!bus_wanted(c, b->ifname))
                        continue;
                count_states(o, b->ifname, counts, &total);
                ctl_json_object_begin(&j);
                ctl_json_key(&j, "interface");
                ctl_json_string(&j, b->ifname);
                ctl_json_key(&j, "state");
                ctl_json_string(&j, b->state);
                ctl_json_key(&j, "bitrate");
                ctl_json_uint(&j, b->bitrate);
                ctl_json_key(&j, "job");
                ctl_json_string(&j, b->job);
                ctl_json_key(&j, "progress");
                ctl_json_double(&j, b->progress);
                ctl_json_key(&j, "queue_length");
                ctl_json_uint(&j, b->queue_length);
                ctl_json_key(&j, "devices");
                ctl_json_uint(&j, total);
                ctl_json_key(&j, "device_states");
                ctl_json_object_begin(&j);
                for (size_t k = 0; k < N_DEVICE_STATES; k++) {
                        ctl_json_key(&j, device_states[k]);
                        ctl_json_uint(&j, counts[k]);
                }
                ctl_json_object_end(&j);
                ctl_json_key(&j, "last_pass");
                if (b->pass_started) {
                        ctl_json_object_begin(&j);
                        ctl_json_key(&j, "started");
                        ctl_json_uint(&j, b->pass_started);
                        ctl_json_key(&j, "duration");
                        ctl_json_uint(&j, b->pass_duration);
                        ctl_json_key(&j, "kind");
                        ctl_json_string(&j, b->pass_kind);
                        ctl_json_key(&j, "result");
                        ctl_json_string(&j, b->pass_result);
                        ctl_json_object_end(&j);
                } else
                        ctl_json_null(&j);
                ctl_json_key(&j, "foreign_master");
                if (b->foreign_since) {
                        ctl_json_object_begin(&j);
                        ctl_json_key(&j, "active");
                        ctl_json_bool(&j, b->foreign_active);
                        ctl_json_key(&j, "since");
                        ctl_json_uint(&j, b->foreign_since);
                        ctl_json_key(&j, "last");
                        ctl_json_uint(&j, b->foreign_last);
                        ctl_json_key(&j, "frame");
                        ctl_json_string(&j, b->foreign_frame);
                        ctl_json_object_end(&j);
                } else
                        ctl_json_null(&j);
                ctl_json_object_end(&j);
        }
        ctl_json_array_end(&j);
        ctl_json_object_end(&j);
        ctl_json_finish(&j);
}

static void field(const ctl_context *c, const char *name) {
        printf("%s%13s:%s ", c->colors ? CTL_ANSI_BOLD : "", name, c->colors ? CTL_ANSI_NORMAL : "");
}

static void colored(const ctl_context *c, const char *color, const char *text) {
        if (c->colors && color)
                printf("%s%s%s", color, text, CTL_ANSI_NORMAL);
        else
                fputs(text, stdout);
}

static void status_text(ctl_context *c, const ctl_objects *o) {
        field(c, "Version");
        printf("%s\n", o->version ? o->version : "?");
        if (o->n_buses == 0) {
                field(c, "Buses");
                printf("none\n");
        }
        for (size_t i = 0; i < o->n_buses; i++) {
                const ctl_bus_info *b = &o->buses[i];
                size_t counts[N_DEVICE_STATES + 1], total;

                if (!bus_wanted(c, b->ifname))
                        continue;
                count_states(o, b->ifname, counts, &total);
                putchar('\n');
                field(c, "Bus");
                printf("%s\n", b->ifname ? b->ifname : "?");
                field(c, "State");
                colored(c, bus_state_color(b->state), b->state ? b->state : "?");
                putchar('\n');
                field(c, "Bitrate");
                if (b->bitrate % 1000 == 0)
                        printf("%" PRIu32 " kbit/s\n", b->bitrate / 1000);
                else
                        printf("%" PRIu32 " bit/s\n", b->bitrate);
                field(c, "Job");
                if (b->job && *b->job)
                        printf("%s (%.0f%%)\n", b->job, b->progress * 100);
                else
                        printf("none\n");
                field(c, "Queue");
                printf("%" PRIu32 " waiting\n", b->queue_length);
                field(c, "Devices");
                printf("%zu", total);
                const char *sep = " (";
                for (size_t k = 0; k < N_DEVICE_STATES; k++) {
                        if (!counts[k])
                                continue;
                        printf("%s%zu ", sep, counts[k]);
                        colored(c, ctl_device_state_color(device_states[k]), device_states[k]);
                        sep = ", ";
                }
                if (counts[N_DEVICE_STATES]) {
                        printf("%s%zu other", sep, counts[N_DEVICE_STATES]);
                        sep = ", ";
                }
                printf("%s\n", total ? ")" : "");
                field(c, "Last pass");
                if (b->pass_started) {
                        char when[32];
                        time_t t = (time_t) (b->pass_started / 1000000u);
                        struct tm tm;
                        strftime(when, sizeof(when), "%Y-%m-%d %H:%M:%S", localtime_r(&t, &tm));
                        printf("%s, %s, %.1f s: %s%s%s\n", b->pass_kind, when, (double) b->pass_duration / 1e6,
                               b->pass_result, *b->pass_counts ? ", " : "", b->pass_counts);
                } else
                        printf("none since lssd started\n");
                if (b->foreign_since) {
                        /* another LSS master: the line only once one was heard */
                        char last[32], since[32];
                        ctl_format_time(b->foreign_last, last, sizeof(last));
                        ctl_format_time(b->foreign_since, since, sizeof(since));
                        field(c, "Other master");
                        if (b->foreign_active) {
                                colored(c, CTL_ANSI_RED, "another LSS master active");
                                printf(", last heard %s.%03u: %s (since %s); LSS jobs are refused until it is quiet\n",
                                       last, (unsigned) (b->foreign_last % 1000000u / 1000u), b->foreign_frame, since);
                        } else
                                printf("none active; another LSS master was last heard %s.%03u: %s\n", last,
                                       (unsigned) (b->foreign_last % 1000000u / 1000u), b->foreign_frame);
                }
        }
}

int verb_status(ctl_context *c) {
        ctl_objects o;
        int r;

        r = ctl_objects_load(c, &o);
        if (r < 0)
                return r;
        r = check_bus_filter(c, &o);
        if (r >= 0) {
                if (c->json)
                        status_json(c, &o);
                else
                        status_text(c, &o);
        }
        ctl_objects_done(&o);
        return r;
}

void ctl_json_identity(ctl_json *j, const uint32_t id[4]) {
        static const char *const keys[4] = { "vendor", "product", "revision", "serial" };
        for (size_t i = 0; i < 4; i++) {
                ctl_json_key(j, keys[i]);
                ctl_json_uint(j, id[i]);
        }
}

void ctl_table_identity_full(ctl_table *t, const uint32_t id[4], bool revision_known) {
        for (size_t i = 0; i < 4; i++)
                if (i == 2 && !revision_known)
                        ctl_table_add(t, NULL, "-");
                else
                        ctl_table_add(t, NULL, "0x%08" PRIx32, id[i]);
}

static void list_json(ctl_context *c, const ctl_objects *o) {
        ctl_json j;

        ctl_json_init(&j, stdout);
        ctl_json_array_begin(&j);
        for (size_t i = 0; i < o->n_devices; i++) {
                const ctl_device_info *d = &o->devices[i];
                if (!bus_wanted(c, d->ifname))
                        continue;
                ctl_json_object_begin(&j);
                ctl_json_key(&j, "bus");
                ctl_json_string(&j, d->ifname);
                ctl_json_identity(&j, d->id);
                ctl_json_key(&j, "revision_known");
                ctl_json_bool(&j, !d->revision_unknown);
                ctl_json_key(&j, "node_id");
                ctl_json_uint(&j, d->node_id);
                ctl_json_key(&j, "mapped_node_id");
                ctl_json_uint(&j, d->mapped_node_id);
                ctl_json_key(&j, "state");
                ctl_json_string(&j, d->state);
                ctl_json_key(&j, "last_seen");
                ctl_json_uint(&j, d->last_seen);
                ctl_json_key(&j, "path");
                ctl_json_string(&j, d->path);
                ctl_json_object_end(&j);
        }
        ctl_json_array_end(&j);
        ctl_json_finish(&j);
}

static int list_text(ctl_context *c, const ctl_objects *o) {
        static const char *const columns[] = {
                "BUS", "VENDOR", "PRODUCT", "REVISION", "SERIAL", ">NODE", ">MAPPED", "STATE", "LAST SEEN",
        };
        ctl_table *t;
        int r;

        r = ctl_table_new(&t, sizeof(columns) / sizeof(columns[0]), columns);
        if (r < 0)
                return ctl_fail(c, CTL_EXIT_FAILURE, r, "Out of memory.");
        for (size_t i = 0; i < o->n_devices; i++) {
                const ctl_device_info *d = &o->devices[i];
                char when[64];

                if (!bus_wanted(c, d->ifname))
                        continue;
                ctl_format_time(d->last_seen, when, sizeof(when));
                ctl_table_add(t, NULL, "%s", d->ifname);
                ctl_table_identity_full(t, d->id, !d->revision_unknown);
                if (d->node_id == 0xFF)
                        ctl_table_add(t, NULL, "-");
                else
                        ctl_table_add(t, NULL, "%u", d->node_id);
                if (d->mapped_node_id == 0)
                        ctl_table_add(t, NULL, "-");
                else
                        ctl_table_add(t, NULL, "%u", d->mapped_node_id);
                ctl_table_add(t, ctl_device_state_color(d->state), "%s", d->state ? d->state : "?");
                ctl_table_add(t, NULL, "%s", when);
        }
        size_t rows = ctl_table_rows(t);
        if (rows > 0)
                ctl_table_print(t, stdout, !c->no_legend, c->colors);
        if (!c->no_legend) {
                if (rows > 0)
                        putchar('\n');
                printf("%zu device%s listed.%s\n", rows, rows == 1 ? "" : "s",
                       rows == 0 ? " Run 'lssctl scan' to look for devices." : "");
        }
        ctl_table_free(t);
        return 0;
}

int verb_list(ctl_context *c) {
        ctl_objects o;
        int r;

        r = ctl_objects_load(c, &o);
        if (r < 0)
                return r;
        r = check_bus_filter(c, &o);
        if (r >= 0) {
                if (c->json)
                        list_json(c, &o);
                else
                        r = list_text(c, &o);
        }
        ctl_objects_done(&o);
        return r;
}
