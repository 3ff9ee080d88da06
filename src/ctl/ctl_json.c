/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <inttypes.h>
#include <math.h>

#include "ctl/ctl_json.h"

void ctl_json_init(ctl_json *j, FILE *f) {
        *j = (ctl_json) { .f = f };
        j->first[0] = true;
}

/* a comma before every value but the first of its container (keys carry it) */
static void value_prefix(ctl_json *j) {
        if (j->after_key) {
                j->after_key = false;
                return;
        }
        if (!j->first[j->depth])
                fputc(',', j->f);
        j->first[j->depth] = false;
}

static void json_open(ctl_json *j, char ch) {
        value_prefix(j);
        fputc(ch, j->f);
        if (j->depth < CTL_JSON_DEPTH_MAX)
                j->depth++;
        j->first[j->depth] = true;
}

static void json_close(ctl_json *j, char ch) {
        fputc(ch, j->f);
        if (j->depth > 0)
                j->depth--;
}

void ctl_json_object_begin(ctl_json *j) { json_open(j, '{'); }
void ctl_json_object_end(ctl_json *j) { json_close(j, '}'); }
void ctl_json_array_begin(ctl_json *j) { json_open(j, '['); }
void ctl_json_array_end(ctl_json *j) { json_close(j, ']'); }

static void write_string(FILE *f, const char *s) {
        fputc('"', f);
        for (const unsigned char *p = (const unsigned char *) s; *p; p++) {
                switch (*p) {
                case '"':  fputs("\\\"", f); break;
                case '\\': fputs("\\\\", f); break;
                case '\n': fputs("\\n", f); break;
                case '\t': fputs("\\t", f); break;
                case '\r': fputs("\\r", f); break;
                default:
                        if (*p < 0x20)
                                fprintf(f, "\\u%04x", *p);
                        else
                                fputc(*p, f);
                }
        }
        fputc('"', f);
}

void ctl_json_key(ctl_json *j, const char *key) {
        value_prefix(j);
        write_string(j->f, key);
        fputc(':', j->f);
        j->after_key = true;
}

void ctl_json_string(ctl_json *j, const char *s) {
        value_prefix(j);
        write_string(j->f, s ? s : "");
}

void ctl_json_uint(ctl_json *j, uint64_t v) {
        value_prefix(j);
        fprintf(j->f, "%" PRIu64, v);
}

void ctl_json_double(ctl_json *j, double v) {
        value_prefix(j);
        if (isfinite(v))
                fprintf(j->f, "%.4g", v);
        else
                fputs("null", j->f);
}

void ctl_json_bool(ctl_json *j, bool v) {
        value_prefix(j);
        fputs(v ? "true" : "false", j->f);
}

void ctl_json_null(ctl_json *j) {
        value_prefix(j);
        fputs("null", j->f);
}

void ctl_json_finish(ctl_json *j) {
        fputc('\n', j->f);
        fflush(j->f);
}
