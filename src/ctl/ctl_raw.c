/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* raw: single CiA 305 services for experts. The bus is acquired for the
 * whole command and released at its end, whatever happened (lssd then
 * switches every slave back to waiting). */
#include <errno.h>
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>

#include "ctl/ctl.h"
#include "ctl/ctl_errors.h"
#include "ctl/ctl_job.h"
#include "ctl/ctl_json.h"
#include "ctl/ctl_parse.h"

typedef enum arg_kind {
        ARG_NONE,
        ARG_MODE,       /* y: waiting|configuration|0|1 */
        ARG_IDENTITY,   /* uuuu from VENDOR:PRODUCT:REVISION:SERIAL */
        ARG_BYTE,       /* y */
        ARG_TWO_BYTES,  /* yy */
        ARG_WORD,       /* q */
        ARG_RANGES,     /* uuuuuu */
        ARG_KNOWN,      /* a{sv} from KEY=VALUE words */
} arg_kind;

typedef enum result_kind {
        RES_NONE,
        RES_FOUND,      /* b */
        RES_NODE_ID,    /* y */
        RES_IDENTITY,   /* (uuuu) */
} result_kind;

typedef struct service {
        const char *name;       /* lssctl's name */
        const char *method;     /* the Bus method */
        arg_kind arg;
        result_kind result;
} service;

static const service services[] = {
        { "switch-global", "SwitchModeGlobal", ARG_MODE, RES_NONE },
        { "switch-selective", "SwitchModeSelective", ARG_IDENTITY, RES_FOUND },
        { "configure-node-id", "ConfigureNodeId", ARG_BYTE, RES_NONE },
        { "configure-bit-timing", "ConfigureBitTiming", ARG_TWO_BYTES, RES_NONE },
        { "activate-bit-timing", "ActivateBitTiming", ARG_WORD, RES_NONE },
        { "store", "StoreConfiguration", ARG_NONE, RES_NONE },
        { "inquire-identity", "InquireIdentity", ARG_NONE, RES_IDENTITY },
        { "inquire-node-id", "InquireNodeId", ARG_NONE, RES_NODE_ID },
        { "identify-remote", "IdentifyRemoteSlaves", ARG_RANGES, RES_FOUND },
        { "identify-non-configured", "IdentifyNonConfigured", ARG_NONE, RES_FOUND },
        { "fastscan", "Fastscan", ARG_KNOWN, RES_IDENTITY },
};

typedef struct step {
        const service *s;
        uint32_t v[6];
        size_t n_known;
        const char *known_keys[4];
        uint32_t known_values[4];
} step;

static const service *find_service(const char *name) {
        for (size_t i = 0; i < sizeof(services) / sizeof(services[0]); i++)
                if (strcmp(services[i].name, name) == 0 || strcmp(services[i].method, name) == 0)
                        return &services[i];
        return NULL;
}

static int number_in(ctl_context *c, const char *what, const char *s, uint32_t max, uint32_t *ret) {
        if (ctl_parse_u32(s, ret) < 0 || *ret > max)
                return ctl_usage(c, "Invalid %s '%s': 0..%" PRIu32 ".", what, s, max);
        return 0;
}

/* the words of one step; returns how many arguments it took */
static int parse_step(ctl_context *c, char **args, int n, step *st) {
        static const char *const known[4] = { "vendor", "product", "revision", "serial" };
        const service *s = find_service(args[0]);
        int need = 0, r;

        if (!s)
                return ctl_usage(c, "Unknown raw service '%s'.", args[0]);
        *st = (step) { .s = s };
        switch (s->arg) {
        case ARG_NONE: need = 0; break;
        case ARG_MODE: case ARG_IDENTITY: case ARG_BYTE: case ARG_WORD: need = 1; break;
        case ARG_TWO_BYTES: need = 2; break;
        case ARG_RANGES: need = 6; break;
        case ARG_KNOWN: need = 0; break;
        }
        if (n - 1 < need)
                return ctl_usage(c, "Raw service '%s' needs %d argument%s.", s->name, need, need == 1 ? "" : "s");

        switch (s->arg) {
        case ARG_MODE:
                if (strcmp(args[1], "waiting") == 0 || strcmp(args[1], "0") == 0)
                        st->v[0] = 0;
                else if (strcmp(args[1], "configuration") == 0 || strcmp(args[1], "1") == 0)
                        st->v[0] = 1;
                else
                        return ctl_usage(c, "Invalid mode '%s': waiting or configuration.", args[1]);
                break;
        case ARG_IDENTITY:
                if (ctl_parse_identity(args[1], st->v) < 0)
                        return ctl_usage(c, "Invalid identity '%s': VENDOR:PRODUCT:REVISION:SERIAL.", args[1]);
                break;
        case ARG_BYTE:
                r = number_in(c, "node-ID", args[1], 255, &st->v[0]);
                if (r < 0)
                        return r;
                break;
        case ARG_TWO_BYTES:
                for (int i = 0; i < 2; i++) {
                        r = number_in(c, i == 0 ? "bit timing table" : "bit timing index", args[1 + i], 255,
                                      &st->v[i]);
                        if (r < 0)
                                return r;
                }
                break;
        case ARG_WORD:
                r = number_in(c, "delay", args[1], 65535, &st->v[0]);
                if (r < 0)
                        return r;
                break;
        case ARG_RANGES:
                for (int i = 0; i < 6; i++) {
                        r = number_in(c, "number", args[1 + i], UINT32_MAX, &st->v[i]);
                        if (r < 0)
                                return r;
                }
                break;
        case ARG_KNOWN:
                /* KEY=VALUE words, as many as follow */
                while (1 + need < n && strchr(args[1 + need], '=')) {
                        const char *w = args[1 + need];
                        size_t k = 0;
                        while (k < 4 && !(strncmp(w, known[k], strlen(known[k])) == 0 && w[strlen(known[k])] == '='))
                                k++;
                        if (k == 4)
                                return ctl_usage(c, "Invalid fastscan field '%s': vendor=, product=, revision= or "
                                                 "serial=.", w);
                        r = number_in(c, known[k], w + strlen(known[k]) + 1, UINT32_MAX,
                                      &st->known_values[st->n_known]);
                        if (r < 0)
                                return r;
                        for (size_t i = 0; i < st->n_known; i++)
                                if (st->known_keys[i] == known[k])
                                        return ctl_usage(c, "Fastscan field '%s' given twice.", known[k]);
                        st->known_keys[st->n_known++] = known[k];
                        need++;
                }
                break;
        case ARG_NONE:
                break;
        }
        return 1 + need;
}

static int build(sd_bus *bus, const char *path, const step *st, sd_bus_message **ret) {
        sd_bus_message *m = NULL;
        int r;

        r = sd_bus_message_new_method_call(bus, &m, LSSD_BUS_NAME, path, LSSD_BUS_IFACE, st->s->method);
        if (r < 0)
                return r;
        switch (st->s->arg) {
        case ARG_MODE: case ARG_BYTE:
                r = sd_bus_message_append(m, "y", (uint8_t) st->v[0]);
                break;
        case ARG_TWO_BYTES:
                r = sd_bus_message_append(m, "yy", (uint8_t) st->v[0], (uint8_t) st->v[1]);
                break;
        case ARG_WORD:
                r = sd_bus_message_append(m, "q", (uint16_t) st->v[0]);
                break;
        case ARG_IDENTITY:
                r = sd_bus_message_append(m, "uuuu", st->v[0], st->v[1], st->v[2], st->v[3]);
                break;
        case ARG_RANGES:
                r = sd_bus_message_append(m, "uuuuuu", st->v[0], st->v[1], st->v[2], st->v[3], st->v[4], st->v[5]);
                break;
        case ARG_KNOWN:
                r = sd_bus_message_open_container(m, 'a', "{sv}");
                for (size_t i = 0; r >= 0 && i < st->n_known; i++)
                        r = sd_bus_message_append(m, "{sv}", st->known_keys[i], "u", st->known_values[i]);
                if (r >= 0)
                        r = sd_bus_message_close_container(m);
                break;
        case ARG_NONE:
                break;
        }
        if (r < 0) {
                sd_bus_message_unref(m);
                return r;
        }
        *ret = m;
        return 0;
}

static int show_result(ctl_context *c, ctl_json *j, const step *st, sd_bus_message *reply) {
        uint32_t id[4];
        uint8_t node_id;
        int found, r = 0;

        if (c->json) {
                ctl_json_object_begin(j);
                ctl_json_key(j, "service");
                ctl_json_string(j, st->s->method);
                ctl_json_key(j, "result");
        } else
                printf("%s: ", st->s->name);

        switch (st->s->result) {
        case RES_NONE:
                if (c->json)
                        ctl_json_null(j);
                else
                        printf("done\n");
                /* CiA 305: 255 is the pending node-ID only */
                if (!c->json && strcmp(st->s->method, "ConfigureNodeId") == 0 && st->v[0] == 0xFF)
                        fprintf(stderr, "lssctl: note: node-ID 255 is pending: a configured device keeps its "
                                "node-ID until it is reset or power-cycled ('lssctl unassign --reset' does it all)\n");
                break;
        case RES_FOUND:
                r = sd_bus_message_read(reply, "b", &found);
                if (r < 0)
                        break;
                if (c->json)
                        ctl_json_bool(j, found);
                else
                        printf("%s\n", found ? "answered" : "no answer");
                break;
        case RES_NODE_ID:
                r = sd_bus_message_read(reply, "y", &node_id);
                if (r < 0)
                        break;
                if (c->json)
                        ctl_json_uint(j, node_id);
                else if (node_id == 0xFF)
                        printf("255 (non-configured)\n");
                else
                        printf("%u\n", node_id);
                break;
        case RES_IDENTITY:
                r = sd_bus_message_read(reply, "(uuuu)", &id[0], &id[1], &id[2], &id[3]);
                if (r < 0)
                        break;
                if (c->json) {
                        static const char *const keys[4] = { "vendor", "product", "revision", "serial" };
                        ctl_json_object_begin(j);
                        for (size_t i = 0; i < 4; i++) {
                                ctl_json_key(j, keys[i]);
                                ctl_json_uint(j, id[i]);
                        }
                        ctl_json_object_end(j);
                } else
                        printf("0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 "\n", id[0], id[1],
                               id[2], id[3]);
                break;
        }
        if (c->json)
                ctl_json_object_end(j);
        if (r < 0)
                return ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to parse lssd's answer: %s", strerror(-r));
        return 0;
}

/* a call of the runner that needs no result */
static int simple_call(ctl_context *c, ctl_runner *run, const char *path, const char *ifname, const char *method,
                       sd_bus_error *error) {
        sd_bus_message *m = NULL, *reply = NULL;
        int r = sd_bus_message_new_method_call(c->bus, &m, LSSD_BUS_NAME, path, LSSD_BUS_IFACE, method);
        if (r < 0)
                return r;
        r = ctl_runner_call(run, m, path, ifname, method, &reply, error);
        sd_bus_message_unref(reply);
        sd_bus_message_unref(m);
        return r;
}

int verb_raw(ctl_context *c) {
        sd_bus_error error = SD_BUS_ERROR_NULL;
        char *path = NULL, *ifname = NULL;
        ctl_runner *run = NULL;
        step *steps = NULL;
        size_t n_steps = 0;
        bool acquired = false;
        ctl_json j;
        int r;

        steps = calloc(c->n_args, sizeof(step));
        if (!steps)
                return ctl_fail(c, CTL_EXIT_FAILURE, -ENOMEM, "Out of memory.");
        for (int i = 0; i < c->n_args;) {
                r = parse_step(c, c->args + i, c->n_args - i, &steps[n_steps]);
                if (r < 0)
                        goto finish;
                n_steps++;
                i += r;
        }

        r = ctl_pick_bus(c, &path, &ifname);
        if (r < 0)
                goto finish;
        /* no bar: raw services are short; ^C still stops between them */
        r = ctl_runner_new(c, false, &run);
        if (r < 0) {
                r = ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to set up the event loop: %s", strerror(-r));
                goto finish;
        }
        r = simple_call(c, run, path, ifname, "Acquire", &error);
        if (r < 0) {
                r = r == -EINTR ? ctl_fail(c, CTL_EXIT_INTERRUPTED, r, "Interrupted.")
                                : ctl_bus_fail(c, &error, r, "Failed to acquire the bus");
                goto finish;
        }
        acquired = true;

        ctl_json_init(&j, stdout);
        if (c->json)
                ctl_json_array_begin(&j);
        for (size_t i = 0; i < n_steps; i++) {
                sd_bus_message *m = NULL, *reply = NULL;

                r = build(c->bus, path, &steps[i], &m);
                if (r < 0) {
                        r = ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to build the call: %s", strerror(-r));
                        break;
                }
                r = ctl_runner_call(run, m, path, ifname, steps[i].s->method, &reply, &error);
                sd_bus_message_unref(m);
                if (r == -EINTR) {
                        r = ctl_fail(c, CTL_EXIT_INTERRUPTED, r, "Interrupted at '%s'.", steps[i].s->name);
                        break;
                }
                if (r < 0) {
                        char what[96];
                        snprintf(what, sizeof(what), "%s failed", steps[i].s->name);
                        r = ctl_bus_fail(c, &error, r, what);
                        break;
                }
                r = show_result(c, &j, &steps[i], reply);
                sd_bus_message_unref(reply);
                if (r < 0)
                        break;
        }
        if (c->json) {
                ctl_json_array_end(&j);
                ctl_json_finish(&j);
        }
        fflush(stdout);

finish:
        if (acquired) {
                /* always, also after a failure or ^C: a fresh loop-free call */
                sd_bus_error release_error = SD_BUS_ERROR_NULL;
                int k = sd_bus_call_method(c->bus, LSSD_BUS_NAME, path, LSSD_BUS_IFACE, "Release", &release_error,
                                           NULL, NULL);
                if (k < 0 && r >= 0)
                        r = ctl_bus_fail(c, &release_error, k, "Failed to release the bus");
                sd_bus_error_free(&release_error);
        }
        ctl_runner_free(run);
        sd_bus_error_free(&error);
        free(steps);
        free(path);
        free(ifname);
        return r;
}
