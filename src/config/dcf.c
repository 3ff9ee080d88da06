/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* CiA 306 files: one pass collects the raw text of the keys read (values
 * may use $NODEID before [DeviceComissioning] comes), then they are
 * evaluated into a dcf_file. */
#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "config/dcf.h"
#include "config/lssconf_read.h"

/* ---- numbers ---- */

static bool is_blank(char c) {
        return c == ' ' || c == '\t';
}

static bool is_digit(char c) {
        return c >= '0' && c <= '9';
}

static int hex_digit(char c) {
        if (is_digit(c))
                return c - '0';
        if ((c | 0x20) >= 'a' && (c | 0x20) <= 'f')
                return (c | 0x20) - 'a' + 10;
        return -1;
}

/* One literal at s[*i]: 0x hex, octal with a leading 0, or decimal. */
static int parse_literal(const char *s, size_t n, size_t *i, uint64_t *ret) {
        unsigned base = 10;
        size_t k = *i, digits = 0;
        uint64_t v = 0;

        if (k >= n || !is_digit(s[k]))
                return -EINVAL;
        if (s[k] == '0' && k + 1 < n && (s[k + 1] == 'x' || s[k + 1] == 'X')) {
                base = 16;
                k += 2;
        } else if (s[k] == '0')
                base = 8; /* "0" itself is an octal 0 */
        for (; k < n; k++, digits++) {
                int d = hex_digit(s[k]);
                if (d < 0 || (base != 16 && !is_digit(s[k])))
                        break;
                if ((unsigned) d >= base)
                        return -EINVAL; /* 08, 0x-less hex */
                v = v * base + (unsigned) d;
                if (v > UINT32_MAX)
                        return -ERANGE;
        }
        if (digits == 0)
                return -EINVAL; /* "0x" */
        if (k < n && (hex_digit(s[k]) >= 0 || s[k] == '_' || s[k] == '.' || (s[k] | 0x20) == 'x'))
                return -EINVAL; /* 12abc, 1.5 */
        *i = k;
        *ret = v;
        return 0;
}

int dcf_parse_number(const char *s, size_t n, int node_id, uint32_t *ret) {
        static const char nodeid[] = "$NODEID";
        int64_t sum = 0;
        size_t i = 0;
        int sign = 1;

        const char *comment = memchr(s, ';', n);
        if (comment)
                n = (size_t) (comment - s);
        while (n > 0 && is_blank(s[n - 1]))
                n--;
        while (i < n && is_blank(s[i]))
                i++;
        if (i == n)
                return -ENODATA;

        for (;;) {
                uint64_t term;
                while (i < n && is_blank(s[i]))
                        i++;
                if (n - i >= sizeof(nodeid) - 1 && strncasecmp(s + i, nodeid, sizeof(nodeid) - 1) == 0) {
                        if (node_id < 0)
                                return -ENOENT;
                        term = (uint64_t) node_id;
                        i += sizeof(nodeid) - 1;
                } else {
                        int r = parse_literal(s, n, &i, &term);
                        if (r < 0)
                                return r;
                }
                sum += sign * (int64_t) term;
                if (sum < 0 || sum > UINT32_MAX)
                        return -ERANGE;
                while (i < n && is_blank(s[i]))
                        i++;
                if (i == n)
                        break;
                if (s[i] != '+' && s[i] != '-')
                        return -EINVAL;
                sign = s[i] == '+' ? 1 : -1;
                i++;
        }
        *ret = (uint32_t) sum;
        return 0;
}

/* ---- the pass over the lines ---- */

/* the objects read; their sub-indices 1..DCF_SUB_MAX */
enum { OBJ_1018, OBJ_1F84, OBJ_1F85, OBJ_1F86, OBJ_1F87, OBJ_1F88, N_OBJ };
static const unsigned object_index[N_OBJ] = { 0x1018, 0x1F84, 0x1F85, 0x1F86, 0x1F87, 0x1F88 };

typedef struct raw {
        const char *s;   /* NULL: not given */
        size_t n;
        unsigned line;
        bool compact;    /* from [XXXXValue], not [XXXXsubN] */
} raw;

enum section_kind {
        SECTION_OTHER,        /* not read */
        SECTION_DEVICE_INFO,
        SECTION_COMMISSIONING,
        SECTION_OBJECT,       /* [1F88]: the object itself */
        SECTION_SUB,          /* [1F88sub5] */
        SECTION_VALUE,        /* [1F88Value]: a compact array's values */
};

enum { KEY_VENDOR, KEY_PRODUCT, KEY_REVISION, N_INFO_KEYS };
enum { KEY_NODE_ID, KEY_NODE_NAME, KEY_BAUDRATE, KEY_NET_NUMBER, KEY_SERIAL, N_COMM_KEYS };
static const char *const info_keys[N_INFO_KEYS] = { "VendorNumber", "ProductNumber", "RevisionNumber" };
static const char *const comm_keys[N_COMM_KEYS] = { "NodeID", "NodeName", "Baudrate", "NetNumber",
                                                    "LSS_SerialNumber" };

typedef struct pass {
        const char *name;
        lssconf_diag *diag;
        bool failed;
        bool oom;
        unsigned line;

        /* the section the lines belong to */
        enum section_kind kind;
        unsigned obj, sub;
        const char *section;  /* its name as written, for messages */
        size_t section_len;

        raw info[N_INFO_KEYS];
        bool commissioning;
        unsigned commissioning_line;
        raw comm[N_COMM_KEYS];
        bool has_object[N_OBJ];
        raw pv[N_OBJ][DCF_SUB_MAX + 1]; /* ParameterValue, and a compact array's values */
        raw dv[N_OBJ][DCF_SUB_MAX + 1]; /* DefaultValue */
} pass;

__attribute__((format(printf, 2, 3)))
static void pass_error(pass *p, const char *format, ...) {
        char *text;
        va_list ap;
        va_start(ap, format);
        int r = vasprintf(&text, format, ap);
        va_end(ap);
        if (r < 0) {
                p->oom = true;
                return;
        }
        lssconf_diag_add(p->diag, LSSCONF_DIAG_ERROR, "%s:%u: %s", p->name, p->line, text);
        free(text);
        p->failed = true;
}

/* Text from the file, quoted for a message: printable, bounded. */
static const char *quote(const char *s, size_t n, char *buf, size_t size) {
        size_t k = 0, i = 0;
        buf[k++] = '"';
        for (; i < n && k + 8 < size; i++) {
                unsigned char c = (unsigned char) s[i];
                if (c < ' ' || c == 0x7F || c == '"' || c == '\\')
                        k += (size_t) snprintf(buf + k, size - k, "\\x%02x", c);
                else
                        buf[k++] = (char) c;
        }
        if (i < n) {
                memcpy(buf + k, "...", 3);
                k += 3;
        }
        buf[k++] = '"';
        buf[k] = '\0';
        return buf;
}

static bool name_is(const char *s, size_t n, const char *name) {
        return strlen(name) == n && strncasecmp(s, name, n) == 0;
}

/* "1018", "1F88sub5", "1F88Value": *kind, *obj, *sub; false when not an object read */
static bool parse_object_section(const char *s, size_t n, enum section_kind *kind, unsigned *obj, unsigned *sub) {
        unsigned index = 0;
        if (n < 4)
                return false;
        for (size_t i = 0; i < 4; i++) {
                int d = hex_digit(s[i]);
                if (d < 0)
                        return false;
                index = index * 16 + (unsigned) d;
        }
        for (*obj = 0; *obj < N_OBJ && object_index[*obj] != index; (*obj)++)
                ;
        if (*obj == N_OBJ)
                return false;
        s += 4;
        n -= 4;
        if (n == 0) {
                *kind = SECTION_OBJECT;
                return true;
        }
        if (name_is(s, n, "Value")) {
                *kind = SECTION_VALUE;
                return *obj != OBJ_1018; /* a record has no compact form */
        }
        if (n < 4 || n > 5 || strncasecmp(s, "sub", 3) != 0)
                return false; /* [1F88Name] and the like */
        *sub = 0;
        for (size_t i = 3; i < n; i++) {
                int d = hex_digit(s[i]);
                if (d < 0)
                        return false;
                *sub = *sub * 16 + (unsigned) d;
        }
        *kind = SECTION_SUB;
        return true;
}

static void section_header(pass *p, const char *s, size_t n) {
        const char *end = memchr(s, ']', n);
        if (!end) {
                pass_error(p, "section header without ']'");
                p->kind = SECTION_OTHER;
                return;
        }
        for (const char *q = end + 1; q < s + n && *q != ';'; q++)
                if (!is_blank(*q)) {
                        pass_error(p, "text after the section header");
                        break;
                }
        const char *name = s + 1;
        size_t len = (size_t) (end - name);
        while (len > 0 && is_blank(*name)) {
                name++;
                len--;
        }
        while (len > 0 && is_blank(name[len - 1]))
                len--;
        p->section = name;
        p->section_len = len;

        p->kind = SECTION_OTHER;
        if (name_is(name, len, "DeviceInfo"))
                p->kind = SECTION_DEVICE_INFO;
        else if (name_is(name, len, "DeviceComissioning") || name_is(name, len, "DeviceCommissioning")) {
                p->kind = SECTION_COMMISSIONING;
                if (!p->commissioning)
                        p->commissioning_line = p->line;
                p->commissioning = true;
        } else if (parse_object_section(name, len, &p->kind, &p->obj, &p->sub)) {
                p->has_object[p->obj] = true;
                if (p->kind == SECTION_SUB && (p->sub == 0 || p->sub > DCF_SUB_MAX ||
                                               (p->obj == OBJ_1018 && p->sub > 4)))
                        p->kind = SECTION_OTHER; /* sub 0 (the count) and what is not read */
        } else
                p->kind = SECTION_OTHER;
}

/* A key read: the first time it is given. */
static void set_raw(pass *p, raw *r, const char *key, size_t key_len, const char *value, size_t n) {
        char k[64];
        if (n == 0)
                return; /* an empty value is no value */
        if (r->s) {
                pass_error(p, "[%.*s] %s: given again (first at line %u)", (int) p->section_len, p->section,
                           quote(key, key_len, k, sizeof(k)), r->line);
                return;
        }
        *r = (raw) { .s = value, .n = n, .line = p->line };
}

static void key_value(pass *p, const char *key, size_t key_len, const char *value, size_t n) {
        switch (p->kind) {
        case SECTION_DEVICE_INFO:
                for (unsigned k = 0; k < N_INFO_KEYS; k++)
                        if (name_is(key, key_len, info_keys[k]))
                                set_raw(p, &p->info[k], key, key_len, value, n);
                break;
        case SECTION_COMMISSIONING:
                for (unsigned k = 0; k < N_COMM_KEYS; k++)
                        if (name_is(key, key_len, comm_keys[k]))
                                set_raw(p, &p->comm[k], key, key_len, value, n);
                break;
        case SECTION_SUB:
                if (name_is(key, key_len, "ParameterValue"))
                        set_raw(p, &p->pv[p->obj][p->sub], key, key_len, value, n);
                else if (name_is(key, key_len, "DefaultValue"))
                        set_raw(p, &p->dv[p->obj][p->sub], key, key_len, value, n);
                break;
        case SECTION_VALUE: {
                uint32_t sub;
                char q[64];
                if (name_is(key, key_len, "NrOfEntries"))
                        break;
                if (dcf_parse_number(key, key_len, -1, &sub) < 0 || sub == 0 || sub > DCF_SUB_MAX) {
                        pass_error(p, "[%.*s]: %s is not a sub-index (1..%u)", (int) p->section_len, p->section,
                                   quote(key, key_len, q, sizeof(q)), DCF_SUB_MAX);
                        break;
                }
                set_raw(p, &p->pv[p->obj][sub], key, key_len, value, n);
                p->pv[p->obj][sub].compact = true;
                break;
        }
        default:
                break;
        }
}

static void one_line(pass *p, const char *s, size_t n) {
        while (n > 0 && (is_blank(s[n - 1]) || s[n - 1] == '\r'))
                n--;
        while (n > 0 && is_blank(*s)) {
                s++;
                n--;
        }
        if (n == 0 || *s == ';' || *s == '#')
                return;
        if (*s == '[') {
                section_header(p, s, n);
                return;
        }
        const char *eq = memchr(s, '=', n);
        if (!eq) {
                if (p->kind != SECTION_OTHER) {
                        char q[64];
                        pass_error(p, "[%.*s]: %s is not KEY=VALUE", (int) p->section_len, p->section,
                                   quote(s, n, q, sizeof(q)));
                }
                return;
        }
        size_t key_len = (size_t) (eq - s);
        while (key_len > 0 && is_blank(s[key_len - 1]))
                key_len--;
        const char *value = eq + 1;
        size_t value_len = n - (size_t) (value - s);
        while (value_len > 0 && is_blank(*value)) {
                value++;
                value_len--;
        }
        key_value(p, s, key_len, value, value_len);
}

static void run_pass(pass *p, const char *text, size_t len) {
        size_t i = 0;
        if (len >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0)
                i = 3; /* a UTF-8 byte order mark, as Windows tools write it */
        for (p->line = 1; i < len && !p->oom; p->line++) {
                const char *nl = memchr(text + i, '\n', len - i);
                size_t end = nl ? (size_t) (nl - text) : len;
                one_line(p, text + i, end - i);
                i = end + 1;
        }
}

/* ---- evaluation ---- */

/* A raw value as a number; false (with an error) when malformed. */
static bool eval(pass *p, const raw *r, const char *what, int node_id, dcf_number *ret) {
        char q[64];
        uint32_t v;
        *ret = (dcf_number) { 0 };
        if (!r->s)
                return true;
        int e = dcf_parse_number(r->s, r->n, node_id, &v);
        if (e == -ENODATA)
                return true;
        p->line = r->line;
        if (e == -ENOENT)
                pass_error(p, "%s: %s uses $NODEID, but [DeviceComissioning] gives no NodeID", what,
                           quote(r->s, r->n, q, sizeof(q)));
        else if (e == -ERANGE)
                pass_error(p, "%s: %s is out of range 0..0xFFFFFFFF", what, quote(r->s, r->n, q, sizeof(q)));
        else if (e < 0)
                pass_error(p, "%s: %s is not a number (decimal, 0x hexadecimal, octal with a leading 0, or an "
                           "expression with $NODEID)", what, quote(r->s, r->n, q, sizeof(q)));
        if (e < 0)
                return false;
        *ret = (dcf_number) { .given = true, .value = v, .line = r->line };
        return true;
}

/* ParameterValue, else DefaultValue, of [XXXXsubN] */
static void eval_sub(pass *p, unsigned obj, unsigned sub, bool default_too, int node_id, dcf_number *ret) {
        char what[48];
        const raw *r = &p->pv[obj][sub];
        const char *key = "ParameterValue";
        if (!r->s && default_too) {
                r = &p->dv[obj][sub];
                key = "DefaultValue";
        }
        if (r->compact)
                snprintf(what, sizeof(what), "[%04XValue] %u", object_index[obj], sub);
        else
                snprintf(what, sizeof(what), "[%04Xsub%X] %s", object_index[obj], sub, key);
        (void) eval(p, r, what, node_id, ret);
}

/* 1018h's value, else [DeviceInfo]'s, a difference warned about */
static void resolve(pass *p, const dcf_number *object, const dcf_number *info, const char *what, unsigned sub,
                    const char *info_key, dcf_number *ret) {
        *ret = object->given ? *object : *info;
        if (object->given && info->given && object->value != info->value)
                lssconf_diag_add(p->diag, LSSCONF_DIAG_WARNING,
                                 "%s:%u: [1018sub%u] gives %s 0x%08" PRIX32 ", [DeviceInfo] %s at line %u 0x%08" PRIX32
                                 ": 0x%08" PRIX32 " is taken", p->name, object->line, sub, what, object->value, info_key,
                                 info->line, info->value, object->value);
}

static char *strndup_printable(const char *s, size_t n) {
        char *d = strndup(s, n);
        if (!d)
                return NULL;
        for (char *q = d; *q; q++)
                if ((unsigned char) *q < ' ' || *q == 0x7F)
                        *q = ' ';
        return d;
}

static void evaluate(pass *p, dcf_file *f) {
        dcf_number info[N_INFO_KEYS], object[5];

        f->commissioning = p->commissioning;
        f->commissioning_line = p->commissioning_line;
        bool node_id_ok = eval(p, &p->comm[KEY_NODE_ID], "[DeviceComissioning] NodeID", -1, &f->node_id);
        if (p->commissioning && node_id_ok && !f->node_id.given) {
                p->line = p->commissioning_line;
                pass_error(p, "[DeviceComissioning] without NodeID");
        }
        int node_id = f->node_id.given && f->node_id.value <= 0xFF ? (int) f->node_id.value : -1;
        (void) eval(p, &p->comm[KEY_BAUDRATE], "[DeviceComissioning] Baudrate", node_id, &f->baudrate);
        (void) eval(p, &p->comm[KEY_NET_NUMBER], "[DeviceComissioning] NetNumber", node_id, &f->net_number);
        if (p->comm[KEY_NODE_NAME].s && !(f->node_name = strndup_printable(p->comm[KEY_NODE_NAME].s,
                                                                             p->comm[KEY_NODE_NAME].n)))
                p->oom = true;

        for (unsigned k = 0; k < N_INFO_KEYS; k++) {
                char what[40];
                snprintf(what, sizeof(what), "[DeviceInfo] %s", info_keys[k]);
                (void) eval(p, &p->info[k], what, node_id, &info[k]);
        }
        for (unsigned sub = 1; sub <= 4; sub++)
                eval_sub(p, OBJ_1018, sub, sub != 4, node_id, &object[sub]);
        resolve(p, &object[1], &info[KEY_VENDOR], "vendor-ID", 1, "VendorNumber", &f->vendor);
        resolve(p, &object[2], &info[KEY_PRODUCT], "product code", 2, "ProductNumber", &f->product);
        resolve(p, &object[3], &info[KEY_REVISION], "revision", 3, "RevisionNumber", &f->revision);

        dcf_number lss_serial;
        (void) eval(p, &p->comm[KEY_SERIAL], "[DeviceComissioning] LSS_SerialNumber", node_id, &lss_serial);
        lss_serial.given = lss_serial.given && lss_serial.value != 0;
        object[4].given = object[4].given && object[4].value != 0;
        f->serial = lss_serial.given ? lss_serial : object[4];
        if (lss_serial.given && object[4].given && lss_serial.value != object[4].value)
                lssconf_diag_add(p->diag, LSSCONF_DIAG_WARNING,
                                 "%s:%u: LSS_SerialNumber is 0x%08" PRIX32 ", [1018sub4] ParameterValue at line %u "
                                 "0x%08" PRIX32 ": 0x%08" PRIX32 " is taken", p->name, lss_serial.line,
                                 lss_serial.value, object[4].line, object[4].value, lss_serial.value);

        for (unsigned obj = OBJ_1F84; obj < N_OBJ; obj++)
                f->master = f->master || p->has_object[obj];
        if (!f->master)
                return;
        f->expected = calloc(DCF_SUB_MAX + 1, sizeof(*f->expected));
        if (!f->expected) {
                p->oom = true;
                return;
        }
        for (unsigned sub = 1; sub <= DCF_SUB_MAX; sub++) {
                dcf_expected *e = &f->expected[sub];
                eval_sub(p, OBJ_1F85, sub, true, node_id, &e->vendor);
                eval_sub(p, OBJ_1F86, sub, true, node_id, &e->product);
                eval_sub(p, OBJ_1F87, sub, true, node_id, &e->revision);
                eval_sub(p, OBJ_1F88, sub, true, node_id, &e->serial);
        }
}

void dcf_file_done(dcf_file *f) {
        free(f->name);
        free(f->node_name);
        free(f->expected);
        *f = (dcf_file) { 0 };
}

int dcf_parse(const char *text, size_t len, const char *name, dcf_file *ret, lssconf_diag *diag) {
        *ret = (dcf_file) { 0 };
        if (lssconf_text_check(text, len, name, diag) < 0)
                return -EINVAL;
        pass *p = calloc(1, sizeof(*p));
        if (!p)
                return -ENOMEM;
        p->name = name;
        p->diag = diag;
        run_pass(p, text, len);
        if (!p->oom && !(ret->name = strdup(name)))
                p->oom = true;
        if (!p->oom)
                evaluate(p, ret);
        int r = p->oom ? -ENOMEM : p->failed ? -EINVAL : 0;
        free(p);
        if (r < 0)
                dcf_file_done(ret);
        return r;
}
