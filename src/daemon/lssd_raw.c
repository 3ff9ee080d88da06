/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_errors.h"
#include "daemon/lssd_options.h"
#include "daemon/lssd_raw.h"
#include "daemon/lssd_validate.h"

static const struct {
        const char *name;
        const char *signature;
        const char *result;
        enum lss_service service; /* whose error codes a rejection carries */
} raw_table[_LSSD_RAW_OP_MAX] = {
        [LSSD_RAW_SWITCH_MODE_GLOBAL] = { "SwitchModeGlobal", "y", "", LSS_SERVICE_NONE },
        [LSSD_RAW_SWITCH_MODE_SELECTIVE] = { "SwitchModeSelective", "uuuu", "b", LSS_SERVICE_NONE },
        [LSSD_RAW_CONFIGURE_NODE_ID] = { "ConfigureNodeId", "y", "", LSS_SERVICE_CONFIGURE_NODE_ID },
        [LSSD_RAW_CONFIGURE_BIT_TIMING] = { "ConfigureBitTiming", "yy", "", LSS_SERVICE_CONFIGURE_BIT_TIMING },
        [LSSD_RAW_ACTIVATE_BIT_TIMING] = { "ActivateBitTiming", "q", "", LSS_SERVICE_NONE },
        [LSSD_RAW_STORE_CONFIGURATION] = { "StoreConfiguration", "", "", LSS_SERVICE_STORE },
        [LSSD_RAW_INQUIRE_IDENTITY] = { "InquireIdentity", "", "(uuuu)", LSS_SERVICE_NONE },
        [LSSD_RAW_INQUIRE_NODE_ID] = { "InquireNodeId", "", "y", LSS_SERVICE_NONE },
        [LSSD_RAW_IDENTIFY_REMOTE_SLAVES] = { "IdentifyRemoteSlaves", "uuuuuu", "b", LSS_SERVICE_NONE },
        [LSSD_RAW_IDENTIFY_NON_CONFIGURED] = { "IdentifyNonConfigured", "", "b", LSS_SERVICE_NONE },
        [LSSD_RAW_FASTSCAN] = { "Fastscan", "a{sv}", "(uuuu)", LSS_SERVICE_NONE },
};

const char *lssd_raw_op_to_string(lssd_raw_op op) {
        return (unsigned) op < _LSSD_RAW_OP_MAX ? raw_table[op].name : NULL;
}

int lssd_raw_op_from_string(const char *name) {
        for (unsigned i = 0; name && i < _LSSD_RAW_OP_MAX; i++)
                if (strcmp(raw_table[i].name, name) == 0)
                        return (int) i;
        return -EINVAL;
}

const char *lssd_raw_op_signature(lssd_raw_op op) {
        return (unsigned) op < _LSSD_RAW_OP_MAX ? raw_table[op].signature : NULL;
}

/* `argument` is the name of the Fastscan option argument: "known" for the
 * method, "steps[i]" for Execute. */
static int read_args(sd_bus_message *m, lssd_raw_op op, const char *known_argument, lssd_raw_step *s,
                     sd_bus_error *error) {
        int r;

        *s = (lssd_raw_step) { .op = op };
        switch (op) {
        case LSSD_RAW_SWITCH_MODE_GLOBAL:
                r = sd_bus_message_read(m, "y", &s->mode);
                if (r < 0)
                        return r;
                return lssd_validate_mode("mode", s->mode, error);

        case LSSD_RAW_SWITCH_MODE_SELECTIVE:
                return sd_bus_message_read(m, "uuuu", &s->id.vendor, &s->id.product, &s->id.revision,
                                           &s->id.serial);

        case LSSD_RAW_CONFIGURE_NODE_ID:
                r = sd_bus_message_read(m, "y", &s->node_id);
                if (r < 0)
                        return r;
                return lssd_validate_raw_node_id("node_id", s->node_id, error);

        case LSSD_RAW_CONFIGURE_BIT_TIMING:
                r = sd_bus_message_read(m, "yy", &s->bit_timing.table, &s->bit_timing.index);
                if (r < 0)
                        return r;
                return lssd_validate_bit_timing(s->bit_timing.table, s->bit_timing.index, error);

        case LSSD_RAW_ACTIVATE_BIT_TIMING:
                return sd_bus_message_read(m, "q", &s->delay_ms);

        case LSSD_RAW_IDENTIFY_REMOTE_SLAVES: {
                lss_identify_range *g = &s->range;
                r = sd_bus_message_read(m, "uuuuuu", &g->vendor, &g->product, &g->rev_lo, &g->rev_hi,
                                        &g->serial_lo, &g->serial_hi);
                if (r < 0)
                        return r;
                r = lssd_validate_range("rev_lo", g->rev_lo, "rev_hi", g->rev_hi, error);
                if (r < 0)
                        return r;
                return lssd_validate_range("serial_lo", g->serial_lo, "serial_hi", g->serial_hi, error);
        }

        case LSSD_RAW_FASTSCAN: {
                lssd_fastscan_options o;
                r = lssd_fastscan_options_read(m, known_argument, &o, error);
                if (r < 0)
                        return r;
                for (unsigned i = 0; i < LSS_FIELD_COUNT; i++)
                        if (o.has[i]) {
                                lss_identity_set_field(&s->known.value, i, o.value[i]);
                                s->known.known_bits[i] = 32;
                        }
                return 0;
        }

        case LSSD_RAW_STORE_CONFIGURATION:
        case LSSD_RAW_INQUIRE_IDENTITY:
        case LSSD_RAW_INQUIRE_NODE_ID:
        case LSSD_RAW_IDENTIFY_NON_CONFIGURED:
                return 0;

        default:
                return -EINVAL;
        }
}

int lssd_raw_step_read_args(sd_bus_message *m, lssd_raw_op op, lssd_raw_step *ret, sd_bus_error *error) {
        return read_args(m, op, "known", ret, error);
}

/* Puts "prefix" in front of an error's message, keeping its name. */
static int error_prefix(sd_bus_error *error, int r, const char *prefix) {
        if (!sd_bus_error_is_set(error))
                return r;
        sd_bus_error e = SD_BUS_ERROR_NULL;
        int k = sd_bus_error_setf(&e, error->name, "%s%s", prefix, error->message ? error->message : "");
        sd_bus_error_free(error);
        sd_bus_error_move(error, &e);
        return k;
}

static int read_step(sd_bus_message *m, size_t i, lssd_raw_step *s, sd_bus_error *error) {
        const char *name, *contents;
        char type, prefix[96], argument[32];
        int r, op;

        r = sd_bus_message_read_basic(m, 's', &name);
        if (r < 0)
                return r;
        op = lssd_raw_op_from_string(name);
        if (op < 0) {
                char shown[48];
                size_t n = strlen(name);
                if (n >= sizeof(shown)) {
                        /* cut before a character, never inside one: the reply must stay valid UTF-8 */
                        n = sizeof(shown) - 1;
                        while (n > 0 && ((unsigned char) name[n] & 0xC0) == 0x80)
                                n--;
                }
                memcpy(shown, name, n);
                shown[n] = '\0';
                return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS,
                                         "steps[%zu]: unknown step '%s%s': a step is a raw method name "
                                         "(SwitchModeGlobal, SwitchModeSelective, ConfigureNodeId, ...)",
                                         i, shown, strlen(name) >= sizeof(shown) ? "..." : "");
        }
        snprintf(prefix, sizeof(prefix), "steps[%zu] (%s): ", i, name);
        snprintf(argument, sizeof(argument), "steps[%zu]", i);

        r = sd_bus_message_peek_type(m, &type, &contents);
        if (r < 0)
                return r;

        /* ConfigureNodeId also as (node_id, force) */
        if (op == LSSD_RAW_CONFIGURE_NODE_ID && contents && strcmp(contents, "(yb)") == 0) {
                int force = 0;
                *s = (lssd_raw_step) { .op = LSSD_RAW_CONFIGURE_NODE_ID };
                r = sd_bus_message_read(m, "v", "(yb)", &s->node_id, &force);
                if (r < 0)
                        return r;
                s->force = force;
                r = lssd_validate_raw_node_id("node_id", s->node_id, error);
                return r < 0 ? error_prefix(error, r, prefix) : 0;
        }

        const char *sig = raw_table[op].signature;
        if (sig[0] == '\0') { /* no argument: whatever the variant holds is ignored */
                *s = (lssd_raw_step) { .op = (lssd_raw_op) op };
                return sd_bus_message_skip(m, "v");
        }

        bool single = strlen(sig) == 1 || strcmp(sig, "a{sv}") == 0;
        char want[16];
        snprintf(want, sizeof(want), single ? "%s" : "(%s)", sig);
        if (!contents || strcmp(contents, want) != 0)
                return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS,
                                         "%sargument must be a variant of type '%s'%s, not '%s'", prefix, want,
                                         op == LSSD_RAW_CONFIGURE_NODE_ID ? " or '(yb)' (node-ID, force)" : "",
                                         contents ? contents : "?");

        r = sd_bus_message_enter_container(m, 'v', contents);
        if (r < 0)
                return r;
        if (!single) {
                r = sd_bus_message_enter_container(m, 'r', sig);
                if (r < 0)
                        return r;
        }
        r = read_args(m, (lssd_raw_op) op, argument, s, error);
        if (r < 0)
                return error_prefix(error, r, prefix);
        if (!single) {
                r = sd_bus_message_exit_container(m);
                if (r < 0)
                        return r;
        }
        return sd_bus_message_exit_container(m);
}

int lssd_execute_steps_read(sd_bus_message *m, lssd_raw_step **ret, size_t *ret_n, sd_bus_error *error) {
        lssd_raw_step *steps = NULL;
        size_t n = 0;
        int r;

        r = sd_bus_message_enter_container(m, 'a', "(sv)");
        if (r < 0)
                return r;
        for (;;) {
                r = sd_bus_message_enter_container(m, 'r', "sv");
                if (r < 0)
                        goto fail;
                if (r == 0)
                        break;
                if (n >= LSSD_EXECUTE_STEPS_MAX) {
                        r = sd_bus_error_setf(error, LSSD_ERROR_LIMITS_EXCEEDED,
                                              "Too many steps: at most %u per Execute() call",
                                              LSSD_EXECUTE_STEPS_MAX);
                        goto fail;
                }
                lssd_raw_step *a = realloc(steps, (n + 1) * sizeof(*steps));
                if (!a) {
                        r = -ENOMEM;
                        goto fail;
                }
                steps = a;
                r = read_step(m, n, &steps[n], error);
                if (r < 0)
                        goto fail;
                n++;
                r = sd_bus_message_exit_container(m);
                if (r < 0)
                        goto fail;
        }
        r = sd_bus_message_exit_container(m);
        if (r < 0)
                goto fail;
        *ret = steps;
        *ret_n = n;
        return 0;

fail:
        free(steps);
        return r;
}

int lssd_raw_step_start(const lssd_raw_step *s, lss_master *engine, uint64_t now) {
        switch (s->op) {
        case LSSD_RAW_SWITCH_MODE_GLOBAL:
                return lss_master_switch_global(engine, (enum lss_mode) s->mode, now);
        case LSSD_RAW_SWITCH_MODE_SELECTIVE:
                return lss_master_switch_selective(engine, &s->id, now);
        case LSSD_RAW_CONFIGURE_NODE_ID:
                return s->force ? lss_master_configure_node_id(engine, s->node_id, now)
                                : lss_master_configure_node_id_checked(engine, s->node_id, now);
        case LSSD_RAW_CONFIGURE_BIT_TIMING:
                return lss_master_configure_bit_timing(engine, s->bit_timing.table, s->bit_timing.index, now);
        case LSSD_RAW_ACTIVATE_BIT_TIMING:
                return lss_master_activate_bit_timing(engine, s->delay_ms, now);
        case LSSD_RAW_STORE_CONFIGURATION:
                return lss_master_store(engine, now);
        case LSSD_RAW_INQUIRE_IDENTITY:
                return lss_master_inquire_identity(engine, now);
        case LSSD_RAW_INQUIRE_NODE_ID:
                return lss_master_inquire(engine, LSS_FIELD_COUNT, now);
        case LSSD_RAW_IDENTIFY_REMOTE_SLAVES:
                return lss_master_identify_remote(engine, &s->range, now);
        case LSSD_RAW_IDENTIFY_NON_CONFIGURED:
                return lss_master_identify_non_configured(engine, now);
        case LSSD_RAW_FASTSCAN:
                return lss_master_fastscan(engine, &s->known, now);
        default:
                return -EINVAL;
        }
}

bool lssd_raw_step_succeeded(const lssd_raw_step *s, const lss_result *r) {
        if (r->status == LSS_OK)
                return true;
        /* "nobody answered" is the answer false here, not a failure */
        return s->op == LSSD_RAW_SWITCH_MODE_SELECTIVE && r->status == LSS_E_NO_RESPONSE;
}

int lssd_raw_step_append_result(const lssd_raw_step *s, const lss_result *r, sd_bus_message *reply,
                                bool as_variant) {
        const char *sig = raw_table[s->op].result;
        int k;

        if (sig[0] == '\0') {
                if (!as_variant)
                        return 0;
                return sd_bus_message_append(reply, "v", "b", 1);
        }

        if (as_variant) {
                k = sd_bus_message_open_container(reply, 'v', sig);
                if (k < 0)
                        return k;
        }

        switch (s->op) {
        case LSSD_RAW_SWITCH_MODE_SELECTIVE:
        case LSSD_RAW_IDENTIFY_REMOTE_SLAVES:
        case LSSD_RAW_IDENTIFY_NON_CONFIGURED:
                k = sd_bus_message_append(reply, "b", (int) (r->status == LSS_OK && r->found));
                break;
        case LSSD_RAW_INQUIRE_NODE_ID:
                k = sd_bus_message_append(reply, "y", r->node_id);
                break;
        case LSSD_RAW_INQUIRE_IDENTITY:
        case LSSD_RAW_FASTSCAN:
                k = sd_bus_message_append(reply, "(uuuu)", r->id.vendor, r->id.product, r->id.revision,
                                          r->id.serial);
                break;
        default:
                k = -EINVAL;
        }
        if (k < 0)
                return k;

        if (as_variant)
                return sd_bus_message_close_container(reply);
        return 0;
}

int lssd_raw_step_error(const lssd_raw_step *s, const lss_result *r, const char *prefix, sd_bus_error *error) {
        return lssd_error_from_result(error, r, raw_table[s->op].service, prefix);
}

const char *lssd_raw_step_describe(const lssd_raw_step *s, char *buf, size_t size) {
        const char *name = lssd_raw_op_to_string(s->op);
        if (!name)
                name = "?";
        switch (s->op) {
        case LSSD_RAW_SWITCH_MODE_GLOBAL:
                snprintf(buf, size, "%s(%u)", name, s->mode);
                break;
        case LSSD_RAW_SWITCH_MODE_SELECTIVE:
                snprintf(buf, size, "%s(%08x:%08x:%08x:%08x)", name, s->id.vendor, s->id.product, s->id.revision,
                         s->id.serial);
                break;
        case LSSD_RAW_CONFIGURE_NODE_ID:
                snprintf(buf, size, "%s(%u%s)", name, s->node_id, s->force ? ", force" : "");
                break;
        case LSSD_RAW_CONFIGURE_BIT_TIMING:
                snprintf(buf, size, "%s(%u, %u)", name, s->bit_timing.table, s->bit_timing.index);
                break;
        case LSSD_RAW_ACTIVATE_BIT_TIMING:
                snprintf(buf, size, "%s(%u ms)", name, s->delay_ms);
                break;
        case LSSD_RAW_IDENTIFY_REMOTE_SLAVES:
                snprintf(buf, size, "%s(%08x:%08x:%08x-%08x:%08x-%08x)", name, s->range.vendor, s->range.product,
                         s->range.rev_lo, s->range.rev_hi, s->range.serial_lo, s->range.serial_hi);
                break;
        default:
                snprintf(buf, size, "%s()", name);
        }
        return buf;
}
