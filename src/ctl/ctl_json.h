/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* A small streaming JSON writer for --json: one document per line, keys in
 * the order written, commas handled here. */
#pragma once

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#define CTL_JSON_DEPTH_MAX 8

typedef struct ctl_json {
        FILE *f;
        unsigned depth;
        bool first[CTL_JSON_DEPTH_MAX + 1]; /* nothing written yet at this level */
        bool after_key;
} ctl_json;

void ctl_json_init(ctl_json *j, FILE *f);
void ctl_json_object_begin(ctl_json *j);
void ctl_json_object_end(ctl_json *j);
void ctl_json_array_begin(ctl_json *j);
void ctl_json_array_end(ctl_json *j);
void ctl_json_key(ctl_json *j, const char *key);
void ctl_json_string(ctl_json *j, const char *s);
void ctl_json_uint(ctl_json *j, uint64_t v);
void ctl_json_double(ctl_json *j, double v);
void ctl_json_bool(ctl_json *j, bool v);
void ctl_json_null(ctl_json *j);
/* Ends the document with a newline. */
void ctl_json_finish(ctl_json *j);
