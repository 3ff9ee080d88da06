/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "lss-sim/options.h"
#include "lss-sim/state_file.h"

#define STATE_FILE_MAX 4096

static const char *const nmt_names[] = {
        [SLAVE_NMT_PRE_OPERATIONAL] = "pre-operational",
        [SLAVE_NMT_OPERATIONAL] = "operational",
        [SLAVE_NMT_STOPPED] = "stopped",
};

static const char *state_nmt_name(enum lss_slave_nmt nmt) {
        return (unsigned) nmt < sizeof(nmt_names) / sizeof(nmt_names[0]) ? nmt_names[nmt] : "unknown";
}

int state_file_path(char *buf, size_t size, const char *dir, uint32_t serial, bool upper_case) {
        int n = snprintf(buf, size, upper_case ? "%s/%08" PRIX32 ".state" : "%s/%08" PRIx32 ".state", dir, serial);
        if (n < 0 || (size_t) n >= size)
                return -ENAMETOOLONG;
        return 0;
}

int state_file_format(char *buf, size_t size, const lss_identity *id, const lss_slave_state *st) {
        int n = snprintf(buf, size,
                         "# lss-sim slave state, rewritten on every change\n"
                         "vendor=0x%08" PRIx32 "\n"
                         "product=0x%08" PRIx32 "\n"
                         "revision=0x%08" PRIx32 "\n"
                         "serial=0x%08" PRIx32 "\n"
                         "active_node_id=%u\n"
                         "pending_node_id=%u\n"
                         "stored_node_id=%u\n"
                         "bit_timing_index=%u\n"
                         "pending_bit_timing_index=%u\n"
                         "stored_bit_timing_index=%u\n"
                         "lss_state=%s\n"
                         "nmt_state=%s\n",
                         id->vendor, id->product, id->revision, id->serial,
                         st->active_node_id, st->pending_node_id, st->stored_node_id,
                         st->bit_index, st->pending_bit_index, st->stored_bit_index,
                         st->configuration ? "configuration" : "waiting",
                         state_nmt_name(st->nmt));
        if (n < 0 || (size_t) n >= size)
                return -ENOBUFS;
        return n;
}

static int write_all(int fd, const char *p, size_t n) {
        while (n > 0) {
                ssize_t k = write(fd, p, n);
                if (k < 0) {
                        if (errno == EINTR)
                                continue;
                        return -errno;
                }
                p += k;
                n -= (size_t) k;
        }
        return 0;
}

int state_file_write(const char *path, const lss_identity *id, const lss_slave_state *st) {
        char text[STATE_FILE_MAX], tmp[4096];
        int n, fd, r;

        n = state_file_format(text, sizeof(text), id, st);
        if (n < 0)
                return n;
        /* the temporary name is per file, so two slaves never share one */
        r = snprintf(tmp, sizeof(tmp), "%s.tmp", path);
        if (r < 0 || (size_t) r >= sizeof(tmp))
                return -ENAMETOOLONG;

        fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        if (fd < 0)
                return -errno;
        r = write_all(fd, text, (size_t) n);
        if (close(fd) < 0 && r == 0)
                r = -errno;
        if (r == 0 && rename(tmp, path) < 0)
                r = -errno;
        if (r < 0)
                (void) unlink(tmp);
        return r;
}

static int parse_u8(const char *v, uint8_t *ret) {
        uint32_t x;
        if (sim_parse_u32(v, &x) < 0 || x > 0xFF)
                return -EINVAL;
        *ret = (uint8_t) x;
        return 0;
}

/* Node-IDs: 1..127 or 0xFF, as the slave model keeps them. */
static int parse_node_id(const char *v, uint8_t *ret) {
        return sim_parse_node_id(v, ret) < 0 ? -EINVAL : 0;
}

static int parse_line(char *s, state_record *r) {
        char *eq, *key, *v;
        uint32_t x;

        /* trim both ends: hand-written files may have blanks */
        while (*s == ' ' || *s == '\t')
                s++;
        for (size_t n = strlen(s); n > 0 && (s[n - 1] == ' ' || s[n - 1] == '\t' || s[n - 1] == '\r'); n--)
                s[n - 1] = '\0';
        if (*s == '\0' || *s == '#')
                return 0;

        eq = strchr(s, '=');
        if (!eq)
                return -EINVAL;
        *eq = '\0';
        key = s;
        v = eq + 1;
        for (size_t n = strlen(key); n > 0 && (key[n - 1] == ' ' || key[n - 1] == '\t'); n--)
                key[n - 1] = '\0';
        while (*v == ' ' || *v == '\t')
                v++;

        static const struct {
                const char *key;
                unsigned have;
        } ident[] = {
                { "vendor", STATE_HAVE_VENDOR },
                { "product", STATE_HAVE_PRODUCT },
                { "revision", STATE_HAVE_REVISION },
                { "serial", STATE_HAVE_SERIAL },
        };
        for (unsigned i = 0; i < LSS_FIELD_COUNT; i++)
                if (strcmp(key, ident[i].key) == 0) {
                        if (sim_parse_u32(v, &x) < 0)
                                return -EINVAL;
                        lss_identity_set_field(&r->id, i, x);
                        r->have |= ident[i].have;
                        return 0;
                }

        if (strcmp(key, "active_node_id") == 0) {
                r->have |= STATE_HAVE_ACTIVE_NODE_ID;
                return parse_node_id(v, &r->st.active_node_id);
        }
        if (strcmp(key, "pending_node_id") == 0) {
                r->have |= STATE_HAVE_PENDING_NODE_ID;
                return parse_node_id(v, &r->st.pending_node_id);
        }
        if (strcmp(key, "stored_node_id") == 0) {
                r->have |= STATE_HAVE_STORED_NODE_ID;
                return parse_node_id(v, &r->st.stored_node_id);
        }
        if (strcmp(key, "bit_timing_index") == 0) {
                r->have |= STATE_HAVE_BIT_INDEX;
                return parse_u8(v, &r->st.bit_index);
        }
        if (strcmp(key, "pending_bit_timing_index") == 0) {
                r->have |= STATE_HAVE_PENDING_BIT_INDEX;
                return parse_u8(v, &r->st.pending_bit_index);
        }
        if (strcmp(key, "stored_bit_timing_index") == 0) {
                r->have |= STATE_HAVE_STORED_BIT_INDEX;
                return parse_u8(v, &r->st.stored_bit_index);
        }
        if (strcmp(key, "lss_state") == 0) {
                if (strcmp(v, "waiting") == 0)
                        r->st.configuration = false;
                else if (strcmp(v, "configuration") == 0)
                        r->st.configuration = true;
                else
                        return -EINVAL;
                r->have |= STATE_HAVE_LSS_STATE;
                return 0;
        }
        if (strcmp(key, "nmt_state") == 0) {
                for (unsigned i = 0; i < sizeof(nmt_names) / sizeof(nmt_names[0]); i++)
                        if (strcmp(v, nmt_names[i]) == 0) {
                                r->st.nmt = (enum lss_slave_nmt) i;
                                r->have |= STATE_HAVE_NMT_STATE;
                                return 0;
                        }
                return -EINVAL;
        }
        /* unknown keys: written by a newer version, not an error */
        return 0;
}

int state_file_parse(const char *text, state_record *ret, unsigned *line) {
        state_record r = {};
        unsigned no = 0;

        for (const char *p = text; *p;) {
                const char *nl = strchr(p, '\n');
                size_t len = nl ? (size_t) (nl - p) : strlen(p);
                char buf[256];

                no++;
                if (len >= sizeof(buf)) {
                        *line = no;
                        return -EINVAL;
                }
                memcpy(buf, p, len);
                buf[len] = '\0';
                if (parse_line(buf, &r) < 0) {
                        *line = no;
                        return -EINVAL;
                }
                p += len + (nl ? 1 : 0);
        }
        *ret = r;
        return 0;
}

int state_file_read(const char *path, state_record *ret, unsigned *line) {
        char text[STATE_FILE_MAX + 1];
        size_t n = 0;
        int fd, r = 0;

        *line = 0;
        fd = open(path, O_RDONLY | O_CLOEXEC);
        if (fd < 0)
                return -errno;
        for (;;) {
                ssize_t k = read(fd, text + n, sizeof(text) - 1 - n);
                if (k < 0) {
                        if (errno == EINTR)
                                continue;
                        r = -errno;
                        break;
                }
                if (k == 0)
                        break;
                n += (size_t) k;
                if (n == sizeof(text) - 1) {
                        r = -EFBIG;
                        break;
                }
        }
        close(fd);
        if (r < 0)
                return r;
        text[n] = '\0';
        if (memchr(text, '\0', n)) {
                *line = 1;
                return -EINVAL;
        }
        return state_file_parse(text, ret, line);
}

bool state_record_matches(const state_record *r, const lss_identity *id) {
        static const unsigned have[LSS_FIELD_COUNT] = {
                STATE_HAVE_VENDOR, STATE_HAVE_PRODUCT, STATE_HAVE_REVISION, STATE_HAVE_SERIAL,
        };
        for (unsigned i = 0; i < LSS_FIELD_COUNT; i++)
                if ((r->have & have[i]) && lss_identity_field(&r->id, i) != lss_identity_field(id, i))
                        return false;
        return true;
}
