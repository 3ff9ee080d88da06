/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* One text file per simulated slave, key=value lines, so that tests (and a
 * restarted simulator) can see what the slave would keep in its memory. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "lss/lss_proto.h"
#include "sim/lss_slave.h"

/* Which keys a parsed file had. */
enum {
        STATE_HAVE_VENDOR = 1u << 0,
        STATE_HAVE_PRODUCT = 1u << 1,
        STATE_HAVE_REVISION = 1u << 2,
        STATE_HAVE_SERIAL = 1u << 3,
        STATE_HAVE_ACTIVE_NODE_ID = 1u << 4,
        STATE_HAVE_PENDING_NODE_ID = 1u << 5,
        STATE_HAVE_STORED_NODE_ID = 1u << 6,
        STATE_HAVE_BIT_INDEX = 1u << 7,
        STATE_HAVE_PENDING_BIT_INDEX = 1u << 8,
        STATE_HAVE_STORED_BIT_INDEX = 1u << 9,
        STATE_HAVE_LSS_STATE = 1u << 10,
        STATE_HAVE_NMT_STATE = 1u << 11,
};

typedef struct state_record {
        lss_identity id;
        lss_slave_state st;
        unsigned have;            /* STATE_HAVE_* */
} state_record;

/* "DIR/0000abcd.state" (upper_case: "DIR/0000ABCD.state"); -ENAMETOOLONG */
int state_file_path(char *buf, size_t size, const char *dir, uint32_t serial, bool upper_case);
/* The file's text; returns its length or -ENOBUFS. */
int state_file_format(char *buf, size_t size, const lss_identity *id, const lss_slave_state *st);
/* Writes `path` atomically (temporary file in the same directory + rename). */
int state_file_write(const char *path, const lss_identity *id, const lss_slave_state *st);
/* Parses a file's text. Unknown keys, blank lines and '#' comments are
 * skipped; on -EINVAL *line is the bad line (1-based). */
int state_file_parse(const char *text, state_record *ret, unsigned *line);
/* -ENOENT when there is none; -EINVAL with *line as above. */
int state_file_read(const char *path, state_record *ret, unsigned *line);
/* Whether the identity keys present in the file agree with `id`. */
bool state_record_matches(const state_record *r, const lss_identity *id);

