/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Tokenizes like libconfig 1.5's scanner (comments, strings, names, numbers
 * with flex's longest-match rule) just far enough to find integer literals. */
#include <errno.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "config/lssconf_prescan.h"
#include "config/lssconf_read.h"

typedef struct scan {
        const char *text;
        size_t len;
        const char *name;
        lssconf_diag *diag;
        unsigned line;
        size_t *inserts; /* offsets where an 'L' goes, ascending */
        size_t n_inserts, n_allocated;
        unsigned open_comment_line;
        bool failed;
        bool oom;
} scan;

static bool is_digit(char c) {
        return c >= '0' && c <= '9';
}

static bool is_xdigit(char c) {
        return is_digit(c) || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
}

static bool is_alpha(char c) {
        return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
}

static bool is_name_char(char c) {
        return is_alpha(c) || is_digit(c) || c == '-' || c == '_' || c == '*';
}

static size_t count_digits(const char *p, size_t n) {
        size_t i = 0;
        while (i < n && is_digit(p[i]))
                i++;
        return i;
}

/* [eE][-+]?[0-9]+ at p, or 0 */
static size_t match_exponent(const char *p, size_t n) {
        if (n < 2 || (p[0] != 'e' && p[0] != 'E'))
                return 0;
        size_t i = 1;
        if (p[i] == '+' || p[i] == '-')
                i++;
        size_t d = count_digits(p + i, n - i);
        return d ? i + d : 0;
}

/* libconfig's float: ([-+]?[0-9]*\.[0-9]*([eE][-+]?[0-9]+)?) | ([-+]?[0-9]+(\.[0-9]*)?[eE][-+]?[0-9]+) */
static size_t match_float(const char *p, size_t n) {
        size_t i = 0;
        if (i < n && (p[i] == '+' || p[i] == '-'))
                i++;
        size_t d = count_digits(p + i, n - i);
        i += d;
        if (i < n && p[i] == '.') {
                i++;
                i += count_digits(p + i, n - i);
                return i + match_exponent(p + i, n - i);
        }
        size_t e = d ? match_exponent(p + i, n - i) : 0;
        return e ? i + e : 0;
}

/* [-+]?[0-9]+(L(L)?)?, *digits_end is where the digits end */
static size_t match_decimal(const char *p, size_t n, size_t *digits_end) {
        size_t i = 0;
        if (i < n && (p[i] == '+' || p[i] == '-'))
                i++;
        size_t d = count_digits(p + i, n - i);
        if (d == 0)
                return 0;
        i += d;
        *digits_end = i;
        for (unsigned k = 0; k < 2 && i < n && p[i] == 'L'; k++)
                i++;
        return i;
}

/* 0[Xx][0-9A-Fa-f]+(L(L)?)? */
static size_t match_hex(const char *p, size_t n, size_t *digits_end) {
        if (n < 3 || p[0] != '0' || (p[1] != 'x' && p[1] != 'X') || !is_xdigit(p[2]))
                return 0;
        size_t i = 2;
        while (i < n && is_xdigit(p[i]))
                i++;
        *digits_end = i;
        for (unsigned k = 0; k < 2 && i < n && p[i] == 'L'; k++)
                i++;
        return i;
}

static void scan_error(scan *s, const char *what, const char *literal, size_t len) {
        /* Literals are digits and letters only: safe to quote, but cap the length. */
        lssconf_diag_add(s->diag, LSSCONF_DIAG_ERROR, "%s:%u: integer %.*s%s %s",
                      s->name, s->line, (int) (len > 40 ? 40 : len), literal, len > 40 ? "..." : "", what);
        s->failed = true;
}

static void add_insert(scan *s, size_t offset) {
        if (s->n_inserts == s->n_allocated) {
                size_t n = s->n_allocated ? s->n_allocated * 2 : 16;
                size_t *a = realloc(s->inserts, n * sizeof(*a));
                if (!a) {
                        s->oom = true;
                        return;
                }
                s->inserts = a;
                s->n_allocated = n;
        }
        s->inserts[s->n_inserts++] = offset;
}

/* Value of the digits in p[0..n) in base 10 or 16; false if beyond 64 bits. */
static bool parse_magnitude(const char *p, size_t n, unsigned base, uint64_t *ret) {
        uint64_t v = 0;
        for (size_t i = 0; i < n; i++) {
                unsigned digit = is_digit(p[i]) ? (unsigned) (p[i] - '0') :
                                 (unsigned) ((p[i] | 0x20) - 'a' + 10);
                if (v > (UINT64_MAX - digit) / base)
                        return false;
                v = v * base + digit;
        }
        *ret = v;
        return true;
}

static void check_decimal(scan *s, size_t at, size_t len, size_t digits_end) {
        const char *p = s->text + at;
        bool neg = p[0] == '-';
        size_t start = (p[0] == '-' || p[0] == '+') ? 1 : 0;
        uint64_t mag;

        if (!parse_magnitude(p + start, digits_end - start, 10, &mag) ||
            mag > (neg ? (uint64_t) INT64_MAX + 1 : (uint64_t) INT64_MAX)) {
                scan_error(s, "does not fit in 64 bits", p, len);
                return;
        }
        if (len > digits_end) /* already int64 */
                return;
        if (mag > (neg ? (uint64_t) INT32_MAX + 1 : (uint64_t) INT32_MAX))
                add_insert(s, at + digits_end);
}

static void check_hex(scan *s, size_t at, size_t len, size_t digits_end) {
        const char *p = s->text + at;
        uint64_t v;

        if (!parse_magnitude(p + 2, digits_end - 2, 16, &v)) {
                scan_error(s, "does not fit in 64 bits", p, len);
                return;
        }
        if (len == digits_end && v > UINT32_MAX)
                add_insert(s, at + digits_end);
}

/* Returns the index after the token that starts at i. */
static size_t scan_token(scan *s, size_t i) {
        const char *p = s->text + i;
        size_t n = s->len - i;

        if (p[0] == '\n') {
                s->line++;
                return i + 1;
        }
        if (p[0] == '#' || (p[0] == '/' && n > 1 && p[1] == '/')) {
                const char *nl = memchr(p, '\n', n);
                return nl ? (size_t) (nl - s->text) : s->len;
        }
        if (p[0] == '/' && n > 1 && p[1] == '*') {
                unsigned start = s->line;
                for (i += 2; i < s->len; i++) {
                        if (s->text[i] == '*' && i + 1 < s->len && s->text[i + 1] == '/')
                                return i + 2;
                        if (s->text[i] == '\n')
                                s->line++;
                }
                if (s->open_comment_line == 0)
                        s->open_comment_line = start;
                return s->len;
        }
        if (p[0] == '"') {
                for (i++; i < s->len && s->text[i] != '"'; i++) {
                        if (s->text[i] == '\\' && i + 1 < s->len)
                                i++; /* an escaped char, '"' included */
                        if (s->text[i] == '\n')
                                s->line++;
                }
                return i < s->len ? i + 1 : s->len;
        }
        if (p[0] == '@' && n >= 8 && memcmp(p, "@include", 8) == 0) {
                lssconf_diag_add(s->diag, LSSCONF_DIAG_ERROR, "%s:%u: @include is not supported", s->name, s->line);
                s->failed = true;
                return i + 8;
        }
        if (is_alpha(p[0]) || p[0] == '*') {
                size_t k = 1;
                while (k < n && is_name_char(p[k]))
                        k++;
                return i + k;
        }

        /* Numbers: flex takes the longest match; the float rule comes first. */
        size_t dec_end = 0, hex_end = 0;
        size_t f = match_float(p, n);
        size_t d = match_decimal(p, n, &dec_end);
        size_t h = match_hex(p, n, &hex_end);
        if (h > 0 && h >= d && h > f) {
                check_hex(s, i, h, hex_end);
                return i + h;
        }
        if (d > 0 && d > f) {
                check_decimal(s, i, d, dec_end);
                return i + d;
        }
        if (f > 0)
                return i + f;
        return i + 1;
}

int lssconf_prescan(const char *text, size_t len, const char *name, lssconf_diag *diag,
                        char **ret, unsigned *ret_open_comment_line) {
        scan s = {
                .text = text,
                .len = len,
                .name = name,
                .diag = diag,
                .line = 1,
        };

        if (lssconf_text_check(text, len, name, diag) < 0)
                return -EINVAL;

        for (size_t i = 0; i < len && !s.oom; )
                i = scan_token(&s, i);

        int r;
        if (s.oom)
                r = -ENOMEM;
        else if (s.failed)
                r = -EINVAL;
        else {
                char *out = malloc(len + s.n_inserts + 1);
                if (!out)
                        r = -ENOMEM;
                else {
                        size_t from = 0, to = 0;
                        for (size_t k = 0; k < s.n_inserts; k++) {
                                memcpy(out + to, text + from, s.inserts[k] - from);
                                to += s.inserts[k] - from;
                                from = s.inserts[k];
                                out[to++] = 'L';
                        }
                        memcpy(out + to, text + from, len - from);
                        out[to + len - from] = '\0';
                        *ret = out;
                        *ret_open_comment_line = s.open_comment_line;
                        r = 0;
                }
        }
        free(s.inserts);
        return r;
}
