/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The loader: reads the file, lets libconfig parse it, walks the tree into
 * plain structs, checking every key's type and range on the way. It keeps
 * going after an error so that one run reports every problem. */
#include <errno.h>
#include <inttypes.h>
#include <libconfig.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config/lssconf.h"
#include "config/lssconf_check.h"
#include "config/lssconf_dcf.h"
#include "config/lssconf_prescan.h"
#include "config/lssconf_read.h"

typedef struct loader {
        const char *name;
        const char *dir;  /* the file's folder, for relative `dcf` patterns; NULL: no file is read */
        lssconf_diag *diag;
        int oom; /* -ENOMEM once an allocation failed */
} loader;

static const char *const root_keys[] = { "lss_timeout_ms", "lss_timing", "boot_ready_limit_s", "foreign_master_quiet_s",
                                         "buses", NULL };
static const char *const bus_keys[] = {
        "interface", "bitrate", "auto_assign", "store", "unknown", "pool", "nmt_stop", "replace", "reset_after_pass",
        "lss_timeout_ms", "lss_timing", "foreign_master_quiet_s", "vendor", "product", "bitrate_change", "devices",
        "dcf", NULL
};
static const char *const device_keys[] = { "vendor", "product", "revision", "serial", "node_id", NULL };

/* ---- messages ---- */

static size_t path_append(const config_setting_t *s, char *buf, size_t size) {
        const config_setting_t *parent = config_setting_parent(s);
        if (!parent)
                return 0; /* the root has no name */

        size_t n = path_append(parent, buf, size);
        int k;
        if (config_setting_name(s))
                k = snprintf(buf + n, size - n, "%s%s", n ? "." : "", config_setting_name(s));
        else
                k = snprintf(buf + n, size - n, "[%d]", config_setting_index(s));
        if (k < 0)
                return n;
        return n + (size_t) k < size ? n + (size_t) k : size - 1;
}

/* "buses[0].devices[2].node_id" */
static const char *setting_path(const config_setting_t *s, char *buf, size_t size) {
        buf[0] = '\0';
        path_append(s, buf, size);
        return buf;
}

static unsigned setting_line(const config_setting_t *s) {
        return config_setting_source_line(s);
}

__attribute__((format(printf, 4, 5)))
static void report(loader *l, lssconf_diag_severity severity, const config_setting_t *s, const char *format, ...) {
        char path[256], *text;
        va_list ap;
        int r;

        va_start(ap, format);
        r = vasprintf(&text, format, ap);
        va_end(ap);
        if (r < 0) {
                l->oom = -ENOMEM;
                return;
        }
        lssconf_diag_add(l->diag, severity, "%s:%u: %s: %s", l->name, setting_line(s),
                      setting_path(s, path, sizeof(path)), text);
        free(text);
}

#define error_at(l, s, ...) report(l, LSSCONF_DIAG_ERROR, s, __VA_ARGS__)
#define warning_at(l, s, ...) report(l, LSSCONF_DIAG_WARNING, s, __VA_ARGS__)

/* A string from the file, quoted for a message: printable and bounded. */
static const char *quote(const char *s, char *buf, size_t size) {
        size_t n = 0;
        buf[n++] = '"';
        for (; *s && n + 8 < size; s++) {
                unsigned char c = (unsigned char) *s;
                if (c == '"' || c == '\\') {
                        buf[n++] = '\\';
                        buf[n++] = (char) c;
                } else if (c < ' ' || c >= 0x7F)
                        n += (size_t) snprintf(buf + n, size - n, "\\x%02x", c);
                else
                        buf[n++] = (char) c;
        }
        if (*s) {
                memcpy(buf + n, "...", 3);
                n += 3;
        }
        buf[n++] = '"';
        buf[n] = '\0';
        return buf;
}

static const char *type_name(const config_setting_t *s) {
        switch (config_setting_type(s)) {
        case CONFIG_TYPE_GROUP:  return "a group { }";
        case CONFIG_TYPE_INT:
        case CONFIG_TYPE_INT64:  return "an integer";
        case CONFIG_TYPE_FLOAT:  return "a float";
        case CONFIG_TYPE_STRING: return "a string";
        case CONFIG_TYPE_BOOL:   return "a boolean";
        case CONFIG_TYPE_ARRAY:  return "an array [ ]";
        case CONFIG_TYPE_LIST:   return "a list ( )";
        default:                 return "nothing";
        }
}

static void warn_unknown_keys(loader *l, const config_setting_t *group, const char *const *keys) {
        for (int i = 0; i < config_setting_length(group); i++) {
                const config_setting_t *s = config_setting_get_elem(group, (unsigned) i);
                const char *name = config_setting_name(s);
                bool known = false;
                for (const char *const *k = keys; *k && !known; k++)
                        known = strcmp(*k, name) == 0;
                if (!known)
                        warning_at(l, s, "unknown key, ignored");
        }
}

/* ---- typed values; each returns 1 when set, 0 when absent, -EINVAL ---- */

/* libconfig 1.5 keeps hex literals 0x80000000..0xFFFFFFFF as negative ints
 * marked hex: those are 32-bit patterns. A negative decimal is negative. */
static int read_integer(loader *l, const config_setting_t *s, long long *ret, bool *hex) {
        *hex = config_setting_get_format(s) == CONFIG_FORMAT_HEX;
        switch (config_setting_type(s)) {
        case CONFIG_TYPE_INT: {
                int v = config_setting_get_int(s);
                *ret = *hex && v < 0 ? (long long) (uint32_t) v : v;
                return 1;
        }
        case CONFIG_TYPE_INT64:
                *ret = config_setting_get_int64(s);
                return 1;
        default:
                error_at(l, s, "expected an integer, got %s", type_name(s));
                return -EINVAL;
        }
}

static const char *format_integer(long long v, bool hex, char *buf, size_t size) {
        if (hex)
                snprintf(buf, size, "0x%llX", (unsigned long long) v);
        else
                snprintf(buf, size, "%lld", v);
        return buf;
}

static int integer_in_range(loader *l, const config_setting_t *s, long long min, long long max,
                            bool hex_range, long long *ret) {
        char value[32];
        long long v;
        bool hex;

        if (read_integer(l, s, &v, &hex) < 0)
                return -EINVAL;
        if (v < min || v > max) {
                if (hex_range)
                        error_at(l, s, "%s is out of range 0x%llX..0x%llX", format_integer(v, hex, value, sizeof(value)),
                                 (unsigned long long) min, (unsigned long long) max);
                else
                        error_at(l, s, "%s is out of range %lld..%lld", format_integer(v, hex, value, sizeof(value)),
                                 min, max);
                return -EINVAL;
        }
        *ret = v;
        return 1;
}

static int get_integer(loader *l, const config_setting_t *group, const char *key,
                       long long min, long long max, long long *ret, const config_setting_t **where) {
        const config_setting_t *s = config_setting_get_member(group, key);
        if (where)
                *where = s;
        if (!s)
                return 0;
        return integer_in_range(l, s, min, max, false, ret);
}

/* Vendor, product, revision, serial: full 32-bit unsigned values. */
static int get_u32(loader *l, const config_setting_t *group, const char *key, uint32_t *ret) {
        const config_setting_t *s = config_setting_get_member(group, key);
        long long v;
        if (!s)
                return 0;
        int r = integer_in_range(l, s, 0, UINT32_MAX, true, &v);
        if (r > 0)
                *ret = (uint32_t) v;
        return r;
}

static int get_bool(loader *l, const config_setting_t *group, const char *key, bool *ret) {
        const config_setting_t *s = config_setting_get_member(group, key);
        if (!s)
                return 0;
        if (config_setting_type(s) != CONFIG_TYPE_BOOL) {
                error_at(l, s, "expected true or false, got %s", type_name(s));
                return -EINVAL;
        }
        *ret = config_setting_get_bool(s);
        return 1;
}

static int get_string(loader *l, const config_setting_t *group, const char *key,
                      const char **ret, const config_setting_t **where) {
        const config_setting_t *s = config_setting_get_member(group, key);
        *where = s;
        if (!s)
                return 0;
        if (config_setting_type(s) != CONFIG_TYPE_STRING) {
                error_at(l, s, "expected a string, got %s", type_name(s));
                return -EINVAL;
        }
        *ret = config_setting_get_string(s);
        return 1;
}

static int get_lss_timing(loader *l, const config_setting_t *group, lssconf_lss_timing *ret) {
        const config_setting_t *s;
        const char *v;
        char q[80];
        int r = get_string(l, group, "lss_timing", &v, &s);
        if (r <= 0)
                return r;
        int t = lssconf_lss_timing_from_string(v);
        if (t < 0) {
                error_at(l, s, "%s is not \"adaptive\" or \"fixed\"", quote(v, q, sizeof(q)));
                return -EINVAL;
        }
        *ret = (lssconf_lss_timing) t;
        return 1;
}

/* ---- devices ---- */

typedef struct bus_defaults {
        bool has_vendor, has_product;
        bool bad_vendor, bad_product; /* given but invalid: already reported */
        uint32_t vendor, product;
} bus_defaults;

static void parse_device(loader *l, const config_setting_t *g, const bus_defaults *def,
                         lssconf_device *d, lssconf_device_src *src) {
        const config_setting_t *nid;
        long long v;
        bool ok = true;
        int r;

        d->line = setting_line(g);
        if (config_setting_type(g) != CONFIG_TYPE_GROUP) {
                error_at(l, g, "expected a device entry { serial = ...; node_id = ...; }, got %s", type_name(g));
                return;
        }
        warn_unknown_keys(l, g, device_keys);

        r = get_u32(l, g, "vendor", &d->identity.vendor);
        if (r == 0) {
                if (def->has_vendor)
                        d->identity.vendor = def->vendor;
                else if (!def->bad_vendor)
                        error_at(l, g, "missing required key 'vendor' (give it here or as the bus default)");
        }
        ok = ok && (r > 0 || def->has_vendor);

        r = get_u32(l, g, "product", &d->identity.product);
        if (r == 0) {
                if (def->has_product)
                        d->identity.product = def->product;
                else if (!def->bad_product)
                        error_at(l, g, "missing required key 'product' (give it here or as the bus default)");
        }
        ok = ok && (r > 0 || def->has_product);

        r = get_u32(l, g, "revision", &d->identity.revision);
        d->has_revision = r > 0;
        ok = ok && r >= 0;

        r = get_u32(l, g, "serial", &d->identity.serial);
        if (r == 0)
                error_at(l, g, "missing required key 'serial'");
        ok = ok && r > 0;

        r = get_integer(l, g, "node_id", LSS_NODE_ID_MIN, LSS_NODE_ID_MAX, &v, &nid);
        if (r == 0)
                error_at(l, g, "missing required key 'node_id'");
        if (r > 0) {
                d->node_id = (uint8_t) v;
                src->node_id_line = setting_line(nid);
        }
        src->ok = ok && r > 0;
}

static void parse_devices(loader *l, const config_setting_t *list, const bus_defaults *def,
                          lssconf_bus *b, lssconf_bus_src *src) {
        if (config_setting_type(list) != CONFIG_TYPE_LIST) {
                error_at(l, list, "expected a list ( { ... }, ... ), got %s", type_name(list));
                return;
        }

        size_t n = (size_t) config_setting_length(list);
        if (n == 0)
                return;
        b->devices = calloc(n, sizeof(*b->devices));
        src->devices = calloc(n, sizeof(*src->devices));
        if (!b->devices || !src->devices) {
                l->oom = -ENOMEM;
                return;
        }
        b->n_devices = n;
        for (size_t i = 0; i < n; i++)
                parse_device(l, config_setting_get_elem(list, (unsigned) i), def, &b->devices[i], &src->devices[i]);
}

/* ---- DCFs ---- */

/* dcf = [ "GLOB", ... ] (or one string): the patterns, read after the bus's checks */
static void parse_dcf(loader *l, const config_setting_t *s, lssconf_bus_src *src) {
        bool one = config_setting_type(s) == CONFIG_TYPE_STRING;
        src->dcf_line = setting_line(s);
        if (!one && config_setting_type(s) != CONFIG_TYPE_ARRAY && config_setting_type(s) != CONFIG_TYPE_LIST) {
                error_at(l, s, "expected [ \"GLOB\", ... ], got %s", type_name(s));
                return;
        }
        size_t n = one ? 1 : (size_t) config_setting_length(s);
        if (n == 0)
                return;
        src->dcf = calloc(n, sizeof(*src->dcf));
        if (!src->dcf) {
                l->oom = -ENOMEM;
                return;
        }
        for (size_t i = 0; i < n; i++) {
                const config_setting_t *e = one ? s : config_setting_get_elem(s, (unsigned) i);
                if (config_setting_type(e) != CONFIG_TYPE_STRING) {
                        error_at(l, e, "expected a file name pattern \"GLOB\", got %s", type_name(e));
                        continue;
                }
                const char *v = config_setting_get_string(e);
                if (!*v) {
                        error_at(l, e, "an empty pattern names no file");
                        continue;
                }
                src->dcf[src->n_dcf++] = (lssconf_dcf_pattern) { .pattern = v, .line = setting_line(e) };
        }
}

/* ---- buses ---- */

static void parse_pool(loader *l, const config_setting_t *s, lssconf_bus *b, lssconf_bus_src *src) {
        long long v[2];
        bool ok = true;

        src->pool_line = setting_line(s);
        if (config_setting_type(s) != CONFIG_TYPE_ARRAY && config_setting_type(s) != CONFIG_TYPE_LIST) {
                error_at(l, s, "expected [ lo, hi ], got %s", type_name(s));
                return;
        }
        if (config_setting_length(s) != 2) {
                error_at(l, s, "expected two node-IDs [ lo, hi ], got %d value%s",
                         config_setting_length(s), config_setting_length(s) == 1 ? "" : "s");
                return;
        }
        for (unsigned i = 0; i < 2; i++)
                ok = integer_in_range(l, config_setting_get_elem(s, i), LSS_NODE_ID_MIN, LSS_NODE_ID_MAX,
                                      false, &v[i]) > 0 && ok;
        if (!ok)
                return;
        if (v[0] > v[1]) {
                error_at(l, s, "%lld..%lld is empty (lo > hi)", v[0], v[1]);
                return;
        }
        b->pool_lo = (uint8_t) v[0];
        b->pool_hi = (uint8_t) v[1];
        src->pool_ok = true;
}

static void parse_interface(loader *l, const config_setting_t *g, lssconf_bus *b, lssconf_bus_src *src) {
        const config_setting_t *s;
        const char *v;
        char q[80];

        int r = get_string(l, g, "interface", &v, &s);
        if (r == 0)
                error_at(l, g, "missing required key 'interface'");
        if (r <= 0)
                return;
        src->interface_line = setting_line(s);
        if (!lssconf_ifname_valid(v)) {
                error_at(l, s, "%s is not a valid interface name (1..15 characters, no '/', ':' or whitespace)",
                         quote(v, q, sizeof(q)));
                return;
        }
        strcpy(b->interface, v);
        src->interface_ok = true;
}

static void parse_bitrate(loader *l, const config_setting_t *g, lssconf_bus *b) {
        const config_setting_t *s;
        long long v;

        if (get_integer(l, g, "bitrate", 0, UINT32_MAX, &v, &s) <= 0)
                return;
        if (lss_bit_timing_index((uint32_t) v) < 0) {
                char rates[128];
                size_t n = 0;
                rates[0] = '\0';
                for (unsigned i = 0; i < 256 && n < sizeof(rates); i++) {
                        uint32_t rate = lss_bit_timing_rate((uint8_t) i);
                        if (rate == 0)
                                continue;
                        int k = snprintf(rates + n, sizeof(rates) - n, "%s%" PRIu32, n ? ", " : "", rate);
                        if (k < 0)
                                break;
                        n += (size_t) k;
                }
                error_at(l, s, "%lld bit/s is not a CiA 301 bit rate (%s)", v, rates);
                return;
        }
        b->bitrate = (uint32_t) v;
}

static void parse_unknown(loader *l, const config_setting_t *g, lssconf_bus *b, const lssconf_bus_src *src) {
        const config_setting_t *s, *pool = config_setting_get_member(g, "pool");
        const char *v;
        char q[80];

        if (get_string(l, g, "unknown", &v, &s) > 0) {
                int p = lssconf_unknown_policy_from_string(v);
                if (p < 0) {
                        error_at(l, s, "%s is not \"ignore\" or \"pool\"", quote(v, q, sizeof(q)));
                        return;
                }
                b->unknown = (lssconf_unknown_policy) p;
        }
        if (b->unknown == LSSCONF_UNKNOWN_POOL && !pool)
                error_at(l, s, "\"pool\" needs pool = [ lo, hi ] in the same bus");
        else if (b->unknown != LSSCONF_UNKNOWN_POOL && pool && src->pool_ok)
                warning_at(l, pool, "ignored unless unknown = \"pool\"");
}

static void parse_bus(loader *l, const config_setting_t *g, const lssconf *c,
                      lssconf_bus *b, lssconf_bus_src *src) {
        const config_setting_t *s;
        bus_defaults def = {};
        long long v;
        int r;

        *b = (lssconf_bus) {
                .bitrate = LSSCONF_BITRATE_DEFAULT,
                .lss_timeout_ms = c->lss_timeout_ms,
                .lss_timing = c->lss_timing,
                .foreign_master_quiet_s = c->foreign_master_quiet_s,
                .store = true,
                .unknown = LSSCONF_UNKNOWN_IGNORE,
                .line = setting_line(g),
        };
        if (config_setting_type(g) != CONFIG_TYPE_GROUP) {
                error_at(l, g, "expected a bus { interface = ...; ... }, got %s", type_name(g));
                return;
        }
        warn_unknown_keys(l, g, bus_keys);

        parse_interface(l, g, b, src);
        parse_bitrate(l, g, b);
        (void) get_bool(l, g, "auto_assign", &b->auto_assign);
        (void) get_bool(l, g, "store", &b->store);
        (void) get_bool(l, g, "nmt_stop", &b->nmt_stop);
        (void) get_bool(l, g, "replace", &b->replace);
        (void) get_bool(l, g, "reset_after_pass", &b->reset_after_pass);
        (void) get_bool(l, g, "bitrate_change", &b->bitrate_change);

        s = config_setting_get_member(g, "pool");
        if (s)
                parse_pool(l, s, b, src);
        parse_unknown(l, g, b, src);

        /* 0 = inherit the global value */
        if (get_integer(l, g, "lss_timeout_ms", 0, LSSCONF_LSS_TIMEOUT_MS_MAX, &v, NULL) > 0 && v > 0)
                b->lss_timeout_ms = (uint32_t) v;
        (void) get_lss_timing(l, g, &b->lss_timing);
        if (get_integer(l, g, "foreign_master_quiet_s", 0, LSSCONF_FOREIGN_MASTER_QUIET_S_MAX, &v, NULL) > 0 && v > 0)
                b->foreign_master_quiet_s = (uint32_t) v;

        r = get_u32(l, g, "vendor", &def.vendor);
        def.has_vendor = b->has_vendor = r > 0;
        def.bad_vendor = r < 0;
        b->vendor = def.vendor;
        r = get_u32(l, g, "product", &def.product);
        def.has_product = b->has_product = r > 0;
        def.bad_product = r < 0;
        b->product = def.product;

        s = config_setting_get_member(g, "devices");
        if (s)
                parse_devices(l, s, &def, b, src);
        s = config_setting_get_member(g, "dcf");
        if (s)
                parse_dcf(l, s, src);
}

static void parse_root(loader *l, const config_setting_t *root, lssconf *c, lssconf_bus_src **ret_src) {
        const config_setting_t *buses;
        long long v;

        warn_unknown_keys(l, root, root_keys);
        if (get_integer(l, root, "lss_timeout_ms", 1, LSSCONF_LSS_TIMEOUT_MS_MAX, &v, NULL) > 0)
                c->lss_timeout_ms = (uint32_t) v;
        (void) get_lss_timing(l, root, &c->lss_timing);
        if (get_integer(l, root, "boot_ready_limit_s", 1, LSSCONF_BOOT_READY_LIMIT_S_MAX, &v, NULL) > 0)
                c->boot_ready_limit_s = (uint32_t) v;
        if (get_integer(l, root, "foreign_master_quiet_s", 1, LSSCONF_FOREIGN_MASTER_QUIET_S_MAX, &v, NULL) > 0)
                c->foreign_master_quiet_s = (uint32_t) v;

        buses = config_setting_get_member(root, "buses");
        if (!buses) {
                /* an empty or truncated file must not pass for a configuration that serves nothing */
                lssconf_diag_add(l->diag, LSSCONF_DIAG_ERROR, "%s:1: no buses configured (no 'buses' list)", l->name);
                return;
        }
        if (config_setting_type(buses) != CONFIG_TYPE_LIST) {
                error_at(l, buses, "expected a list ( { ... }, ... ), got %s", type_name(buses));
                return;
        }
        size_t n = (size_t) config_setting_length(buses);
        if (n == 0) {
                /* said on purpose (the installed starter file): lssd serves nothing */
                warning_at(l, buses, "empty list: lssd serves no bus until one is added");
                return;
        }

        c->buses = calloc(n, sizeof(*c->buses));
        lssconf_bus_src *src = *ret_src = calloc(n, sizeof(*src));
        if (!c->buses || !src) {
                l->oom = -ENOMEM;
                return;
        }
        c->n_buses = n;
        for (size_t i = 0; i < n; i++) {
                parse_bus(l, config_setting_get_elem(buses, (unsigned) i), c, &c->buses[i], &src[i]);
                if (l->oom < 0)
                        return;
                if (lssconf_check_bus(l->name, i, &c->buses[i], &src[i], l->diag) < 0 ||
                    lssconf_read_bus_dcfs(l->name, l->dir, i, c, &c->buses[i], &src[i], l->diag) < 0)
                        l->oom = -ENOMEM;
        }
        if (lssconf_check_interfaces(l->name, c, src, l->diag) < 0)
                l->oom = -ENOMEM;
}

/* ---- entry points ---- */

static int load_tree(loader *l, const char *text, unsigned open_comment_line, lssconf **ret) {
        lssconf_bus_src *src = NULL;
        lssconf *c = NULL;
        size_t n_src = 0;
        config_t cfg;
        int r;

        config_init(&cfg);
        if (!config_read_string(&cfg, text)) {
                lssconf_diag_add(l->diag, LSSCONF_DIAG_ERROR, "%s:%d: %s", l->name, config_error_line(&cfg),
                              config_error_text(&cfg) ? config_error_text(&cfg) : "cannot parse");
                r = -EINVAL;
                goto finish;
        }
        if (open_comment_line > 0) {
                lssconf_diag_add(l->diag, LSSCONF_DIAG_ERROR, "%s:%u: unterminated /* comment", l->name,
                                 open_comment_line);
                r = -EINVAL;
                goto finish;
        }

        r = lssconf_new(&c);
        if (r < 0)
                goto finish;
        c->source = strdup(l->name);
        if (!c->source) {
                r = -ENOMEM;
                goto finish;
        }
        size_t errors = l->diag->n_errors;
        parse_root(l, config_root_setting(&cfg), c, &src);
        n_src = src ? c->n_buses : 0;
        if (l->oom < 0)
                r = l->oom;
        else if (l->diag->n_errors > errors)
                r = -EINVAL;
        else {
                *ret = c;
                c = NULL;
        }

finish:
        for (size_t i = 0; i < n_src; i++) {
                free(src[i].devices);
                free(src[i].dcf);
        }
        free(src);
        lssconf_free(c);
        config_destroy(&cfg);
        return r;
}

static int load_text(const char *text, size_t len, const char *name, const char *dir, lssconf **ret,
                     lssconf_diag *diag) {
        lssconf_diag local = LSSCONF_DIAG_INIT;
        loader l = {
                .name = name ? name : "(config)",
                .dir = dir,
                .diag = diag ? diag : &local,
        };
        unsigned open_comment_line = 0;
        char *fixed = NULL;

        *ret = NULL;
        int r = lssconf_prescan(text, len, l.name, l.diag, &fixed, &open_comment_line);
        if (r >= 0)
                r = load_tree(&l, fixed, open_comment_line, ret);
        free(fixed);
        lssconf_diag_clear(&local);
        return r;
}

int lssconf_load_buffer(const char *text, size_t len, const char *name,
                            lssconf **ret, lssconf_diag *diag) {
        return load_text(text, len, name, NULL, ret, diag);
}

int lssconf_load_file(const char *path, lssconf **ret, lssconf_diag *diag) {
        lssconf_diag local = LSSCONF_DIAG_INIT;
        lssconf_diag *d = diag ? diag : &local;
        char *text = NULL;
        size_t len = 0;

        *ret = NULL;
        int r = lssconf_read_text(path, LSSCONF_SIZE_MAX, &text, &len, d);
        /* relative `dcf` patterns are the file's neighbours */
        const char *slash = strrchr(path, '/');
        char *dir = slash ? strndup(path, slash == path ? 1 : (size_t) (slash - path)) : strdup(".");
        if (r >= 0 && !dir)
                r = -ENOMEM;
        if (r >= 0)
                r = load_text(text, len, path, dir, ret, d);
        free(dir);
        free(text);
        lssconf_diag_clear(&local);
        return r;
}
