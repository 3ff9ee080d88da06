/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The D-Bus argument decoding of every method with arguments, fed method
 * calls built from the input. sd-bus checks the top-level signature against
 * the vtable before a handler runs, so most calls carry the method's own
 * signature with arbitrary values (variants of any type, unknown and
 * repeated option keys, any step name); some carry a random signature.
 *
 * Input: byte 0 picks the method, byte 1 bit 0 a random signature; the rest
 * drives the value generator (0 when it runs out).
 *
 * Checks beyond "no crash, no leak": a decoder that accepts gives values
 * the daemon's own validators accept; a refusal's error is one of the two
 * the API documents for bad arguments, and it (or the errno) can be turned
 * into the error reply sd-bus would send. A reply that cannot be built would
 * make sd_bus_process() fail and the daemon drop its bus connection. */
#include <errno.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "daemon/lssd_errors.h"
#include "daemon/lssd_options.h"
#include "daemon/lssd_raw.h"
#include "daemon/lssd_validate.h"
#include "lss/lss_proto.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

typedef struct input {
        const uint8_t *p;
        size_t n;
} input;

static uint8_t next(input *in) {
        if (in->n == 0)
                return 0;
        in->n--;
        return *in->p++;
}

static uint32_t next32(input *in) {
        uint32_t v = 0;
        for (int i = 0; i < 4; i++)
                v = v << 8 | next(in);
        return v;
}

/* Words that get the decoders past their first checks. */
static const char *const words[] = {
        "vendor", "product", "revision", "serial", "store", "verify", "nmt_stop",
        "SwitchModeGlobal", "SwitchModeSelective", "ConfigureNodeId", "ConfigureBitTiming",
        "ActivateBitTiming", "StoreConfiguration", "InquireIdentity", "InquireNodeId",
        "IdentifyRemoteSlaves", "IdentifyNonConfigured", "Fastscan", "Execute",
        "vcan0", "can0", "", ".", "..", "a/b", "a:b", "0123456789abcdef", "\xc3\xa4", "\t",
};

/* Variant types the API uses, and near misses. */
static const char *const likely_types[] = {
        "b", "y", "q", "u", "s", "i", "t", "d", "(uuuu)", "(yy)", "(uuuuuu)", "(uuu)", "(y)", "a{sv}", "a{su}",
        "av", "v", "ay", "(uuuuy)", "a(sv)", "as",
};

/* Length of the one complete type at s (0 if none). */
static size_t type_len(const char *s) {
        switch (*s) {
        case 'a':
                return s[1] ? 1 + type_len(s + 1) : 0;
        case '(':
        case '{': {
                char close = *s == '(' ? ')' : '}';
                size_t i = 1;
                while (s[i] && s[i] != close) {
                        size_t l = type_len(s + i);
                        if (l == 0)
                                return 0;
                        i += l;
                }
                return s[i] == close ? i + 1 : 0;
        }
        case '\0':
                return 0;
        default:
                return 1;
        }
}

/* Appends a random complete type to buf, which holds cap characters and a
 * NUL. Containers only start with room for their content and closing. */
static void gen_type(input *in, char *buf, size_t *len, size_t cap, unsigned depth) {
        static const char basic[] = "bynqiuxtdsog";
        if (*len + 1 > cap)
                return;
        uint8_t c = next(in);
        if (*len + 6 > cap || depth > 3)
                c = c % 12;
        switch (c % 16) {
        case 12:
                buf[(*len)++] = 'v';
                break;
        case 13:
                buf[(*len)++] = 'a';
                gen_type(in, buf, len, cap, depth + 1);
                break;
        case 14: {
                buf[(*len)++] = '(';
                unsigned k = 1 + next(in) % 4;
                for (unsigned i = 0; i < k; i++)
                        gen_type(in, buf, len, cap - 1, depth + 1);
                buf[(*len)++] = ')';
                break;
        }
        case 15:
                buf[(*len)++] = 'a';
                buf[(*len)++] = '{';
                buf[(*len)++] = basic[next(in) % (sizeof(basic) - 1)];
                gen_type(in, buf, len, cap - 1, depth + 1);
                buf[(*len)++] = '}';
                break;
        default:
                buf[(*len)++] = basic[c % 12];
                break;
        }
        buf[*len] = '\0';
}

static int gen_value(sd_bus_message *m, const char *type, input *in, unsigned depth);

static int gen_string(sd_bus_message *m, char t, input *in) {
        char s[64];
        uint8_t c = next(in);
        if (t == 'o')
                return sd_bus_message_append_basic(m, 'o', c & 1 ? LSSD_ROOT_PATH : "/");
        if (t == 'g')
                return sd_bus_message_append_basic(m, 'g', c & 1 ? "a{sv}" : "u");
        if (c < 160)
                return sd_bus_message_append_basic(m, 's', words[c % (sizeof(words) / sizeof(words[0]))]);
        /* raw bytes: sd-bus refuses invalid UTF-8 and NUL, as the wire does */
        size_t n = next(in) % sizeof(s);
        for (size_t i = 0; i < n; i++)
                s[i] = (char) (next(in) | 1);
        s[n] = '\0';
        return sd_bus_message_append_basic(m, 's', s);
}

static int gen_basic(sd_bus_message *m, char t, input *in) {
        union {
                uint8_t y;
                uint16_t q;
                uint32_t u;
                uint64_t t;
                double d;
                int b;
        } v = { 0 };
        switch (t) {
        case 'b':
                v.b = next(in) & 1;
                break;
        case 'y':
                v.y = next(in);
                break;
        case 'n':
        case 'q':
                v.q = (uint16_t) (next(in) << 8 | next(in));
                break;
        case 'i':
        case 'u':
                v.u = next32(in);
                break;
        case 'x':
        case 't':
        case 'd':
                v.t = (uint64_t) next32(in) << 32 | next32(in);
                break;
        case 's':
        case 'o':
        case 'g':
                return gen_string(m, t, in);
        default:
                return -EINVAL;
        }
        return sd_bus_message_append_basic(m, t, &v);
}

static int gen_array(sd_bus_message *m, const char *elem, size_t elen, input *in, unsigned depth) {
        char e[64];
        if (elen >= sizeof(e))
                return -EINVAL;
        memcpy(e, elem, elen);
        e[elen] = '\0';
        int r = sd_bus_message_open_container(m, 'a', e);
        if (r < 0)
                return r;
        uint8_t c = next(in);
        /* mostly a few elements; sometimes past Execute()'s limit of 64 steps */
        unsigned count = c < 240 ? c % 5 : 60 + c % 10;
        if (depth > 2 && count > 4)
                count = 4;
        for (unsigned i = 0; i < count && in->n > 0; i++) {
                r = gen_value(m, e, in, depth + 1);
                if (r < 0)
                        return r;
        }
        return sd_bus_message_close_container(m);
}

/* Appends one value of the complete type at `type`. */
static int gen_value(sd_bus_message *m, const char *type, input *in, unsigned depth) {
        size_t l = type_len(type);
        char inner[64];
        int r;

        if (l == 0 || l >= sizeof(inner) || depth > 8)
                return -EINVAL;
        switch (type[0]) {
        case 'a':
                return gen_array(m, type + 1, l - 1, in, depth);
        case '(':
        case '{':
                memcpy(inner, type + 1, l - 2);
                inner[l - 2] = '\0';
                r = sd_bus_message_open_container(m, type[0] == '(' ? 'r' : 'e', inner);
                if (r < 0)
                        return r;
                for (const char *t = inner; *t; t += type_len(t)) {
                        r = gen_value(m, t, in, depth + 1);
                        if (r < 0)
                                return r;
                }
                return sd_bus_message_close_container(m);
        case 'v': {
                char vt[40];
                uint8_t c = next(in);
                if (c < 200 || depth > 4)
                        snprintf(vt, sizeof(vt), "%s", likely_types[c % (sizeof(likely_types) / sizeof(likely_types[0]))]);
                else {
                        size_t len = 0;
                        gen_type(in, vt, &len, sizeof(vt) - 1, 0);
                }
                r = sd_bus_message_open_container(m, 'v', vt);
                if (r < 0)
                        return r;
                r = gen_value(m, vt, in, depth + 1);
                if (r < 0)
                        return r;
                return sd_bus_message_close_container(m);
        }
        default:
                return gen_basic(m, type[0], in);
        }
}

/* ---- the methods ---- */

typedef enum method {
        M_GET_BUS,
        M_SCAN,
        M_AUTO_ASSIGN,
        M_ASSIGN_NODE_ID,
        M_SET_BITRATE,
        M_DEVICE_ASSIGN_NODE_ID,
        M_EXECUTE,
        M_RAW, /* + lssd_raw_op */
        _M_MAX = M_RAW + _LSSD_RAW_OP_MAX,
} method;

static const char *method_signature(method k) {
        switch (k) {
        case M_GET_BUS: return "s";
        case M_SCAN: return "a{sv}";
        case M_AUTO_ASSIGN: return "a{sv}";
        case M_ASSIGN_NODE_ID: return "uuuuya{sv}";
        case M_SET_BITRATE: return "uqa{sv}";
        case M_DEVICE_ASSIGN_NODE_ID: return "ya{sv}";
        case M_EXECUTE: return "a(sv)";
        default: return lssd_raw_op_signature((lssd_raw_op) (k - M_RAW));
        }
}

static void check(bool ok) {
        if (!ok)
                abort();
}

static bool bus_error_ok(const sd_bus_error *e) {
        return strcmp(e->name, SD_BUS_ERROR_INVALID_ARGS) == 0 || strcmp(e->name, LSSD_ERROR_LIMITS_EXCEEDED) == 0;
}

/* A raw step that was accepted is what the validators accept. */
static void check_step(const lssd_raw_step *s) {
        switch (s->op) {
        case LSSD_RAW_SWITCH_MODE_GLOBAL:
                check(s->mode <= 1);
                break;
        case LSSD_RAW_CONFIGURE_NODE_ID:
                check(lssd_validate_raw_node_id("x", s->node_id, NULL) == 0);
                break;
        case LSSD_RAW_CONFIGURE_BIT_TIMING:
                check(lssd_validate_bit_timing(s->bit_timing.table, s->bit_timing.index, NULL) == 0);
                break;
        case LSSD_RAW_IDENTIFY_REMOTE_SLAVES:
                check(s->range.rev_lo <= s->range.rev_hi && s->range.serial_lo <= s->range.serial_hi);
                break;
        case LSSD_RAW_FASTSCAN:
                for (unsigned i = 0; i < LSS_FIELD_COUNT; i++)
                        check(s->known.known_bits[i] == 0 || s->known.known_bits[i] == 32);
                break;
        default:
                check((unsigned) s->op < _LSSD_RAW_OP_MAX);
                break;
        }
}

/* The handler's decoding part, as the vtables do it. */
static int decode(sd_bus_message *m, method k, sd_bus_error *error) {
        int r;

        switch (k) {
        case M_GET_BUS: {
                const char *ifname;
                r = sd_bus_message_read(m, "s", &ifname);
                if (r < 0)
                        return r;
                r = lssd_validate_ifname("interface", ifname, error);
                if (r >= 0)
                        check(strlen(ifname) >= 1 && strlen(ifname) <= 15 && !strchr(ifname, '/'));
                return r;
        }
        case M_SCAN: {
                lssd_scan_options o;
                r = lssd_scan_options_read(m, &o, error);
                if (r >= 0)
                        check(o.has_vendor == o.has_product);
                return r;
        }
        case M_AUTO_ASSIGN: {
                lssd_autoassign_options o;
                return lssd_autoassign_options_read(m, &o, error);
        }
        case M_ASSIGN_NODE_ID:
        case M_DEVICE_ASSIGN_NODE_ID: {
                lss_identity id;
                lssd_assign_options o;
                uint8_t node_id;
                if (k == M_ASSIGN_NODE_ID)
                        r = sd_bus_message_read(m, "uuuuy", &id.vendor, &id.product, &id.revision, &id.serial,
                                                &node_id);
                else
                        r = sd_bus_message_read(m, "y", &node_id);
                if (r < 0)
                        return r;
                r = lssd_validate_node_id("node_id", node_id, error);
                if (r < 0)
                        return r;
                check(node_id >= 1 && node_id <= 127);
                return lssd_assign_options_read(m, &o, error);
        }
        case M_SET_BITRATE: {
                uint32_t bitrate;
                uint16_t delay;
                r = sd_bus_message_read(m, "uq", &bitrate, &delay);
                if (r < 0)
                        return r;
                r = lssd_validate_bitrate("bitrate", bitrate, error);
                if (r < 0)
                        return r;
                check(lss_bit_timing_index(bitrate) >= 0);
                return lssd_no_options_read(m, error);
        }
        case M_EXECUTE: {
                lssd_raw_step *steps = NULL;
                size_t n = 0;
                r = lssd_execute_steps_read(m, &steps, &n, error);
                if (r >= 0) {
                        check(n <= LSSD_EXECUTE_STEPS_MAX);
                        for (size_t i = 0; i < n; i++)
                                check_step(&steps[i]);
                        free(steps);
                }
                return r;
        }
        default: {
                lssd_raw_step s;
                lssd_raw_op op = (lssd_raw_op) (k - M_RAW);
                r = lssd_raw_step_read_args(m, op, &s, error);
                if (r >= 0) {
                        check(s.op == op);
                        check_step(&s);
                }
                return r;
        }
        }
}

/* sd-bus creates messages only on a bus that was started: a client end of a
 * socket pair nobody answers (its auth request just sits in the buffer). */
static sd_bus *fuzz_bus(void) {
        static sd_bus *bus;
        int fds[2];

        if (bus)
                return bus;
        if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0, fds) < 0)
                abort();
        if (sd_bus_new(&bus) < 0 || sd_bus_set_fd(bus, fds[0], fds[0]) < 0 || sd_bus_start(bus) < 0)
                abort();
        /* fds[1] stays open for the life of the process */
        return bus;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
        if (size < 2)
                return 0;
        method k = (method) (data[0] % _M_MAX);
        bool random_signature = (data[1] & 7) == 7;
        input in = { data + 2, size - 2 };
        sd_bus_message *m = NULL, *reply = NULL;
        sd_bus_error error = SD_BUS_ERROR_NULL;
        char sig[64];
        int r;

        if (random_signature) {
                size_t len = 0;
                unsigned n = next(&in) % 4;
                sig[0] = '\0';
                for (unsigned i = 0; i < n; i++)
                        gen_type(&in, sig, &len, sizeof(sig) - 1, 0);
        } else
                snprintf(sig, sizeof(sig), "%s", method_signature(k));

        r = sd_bus_message_new_method_call(fuzz_bus(), &m, LSSD_BUS_NAME, LSSD_BUSES_PATH "/vcan0",
                                           LSSD_BUS_IFACE, "Fuzz");
        if (r < 0)
                abort();
        for (const char *t = sig; *t; t += type_len(t)) {
                if (type_len(t) == 0 || gen_value(m, t, &in, 0) < 0)
                        goto finish; /* not a message the wire could carry */
        }
        r = sd_bus_message_seal(m, 1, 0);
        if (r < 0)
                goto finish;
        r = sd_bus_message_rewind(m, true);
        check(r >= 0);

        r = decode(m, k, &error);
        if (r >= 0)
                check(!sd_bus_error_is_set(&error));
        else if (sd_bus_error_is_set(&error)) {
                check(bus_error_ok(&error));
                check(sd_bus_message_new_method_error(m, &reply, &error) >= 0);
        } else
                check(sd_bus_message_new_method_errno(m, &reply, r, NULL) >= 0);

finish:
        sd_bus_message_unref(reply);
        sd_bus_message_unref(m);
        sd_bus_error_free(&error);
        return 0;
}
