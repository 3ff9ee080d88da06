/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <ctype.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "ctl/ctl_parse.h"
#include "lss/lss_proto.h"

static int parse_u64(const char *s, int base, uint64_t max, uint64_t *ret) {
        char *end;

        if (!*s || !isxdigit((unsigned char) *s))
                return -EINVAL;
        errno = 0;
        unsigned long long v = strtoull(s, &end, base);
        if (errno || *end || v > max)
                return -EINVAL;
        *ret = v;
        return 0;
}

int ctl_parse_u32(const char *s, uint32_t *ret) {
        uint64_t v;
        int r;

        if (s[0] == '0' && (s[1] == 'x' || s[1] == 'X'))
                r = parse_u64(s + 2, 16, UINT32_MAX, &v);
        else {
                for (const char *p = s; *p; p++)
                        if (!isdigit((unsigned char) *p))
                                return -EINVAL;
                r = parse_u64(s, 10, UINT32_MAX, &v);
        }
        if (r < 0)
                return r;
        *ret = (uint32_t) v;
        return 0;
}

int ctl_parse_node_id(const char *s, uint8_t *ret) {
        uint32_t v;

        if (ctl_parse_u32(s, &v) < 0 || v < 1 || v > 127)
                return -EINVAL;
        *ret = (uint8_t) v;
        return 0;
}

int ctl_parse_identity(const char *s, uint32_t id[4]) {
        char buf[64];
        char *p = buf, *field;
        int n = 0;

        if (!strchr(s, ':'))
                return -ENOENT;
        if (strlen(s) >= sizeof(buf))
                return -EINVAL;
        strcpy(buf, s);
        while ((field = strsep(&p, ":"))) {
                if (n == 4 || ctl_parse_u32(field, &id[n]) < 0)
                        return -EINVAL;
                n++;
        }
        return n == 4 ? 0 : -EINVAL;
}

int ctl_parse_bitrate(const char *s, uint32_t *ret) {
        uint64_t v, mult = 1;
        char buf[32];
        size_t len = strlen(s);

        if (len == 0 || len >= sizeof(buf))
                return -EINVAL;
        strcpy(buf, s);
        if (buf[len - 1] == 'k' || buf[len - 1] == 'K')
                mult = 1000;
        else if (buf[len - 1] == 'M')
                mult = 1000000;
        if (mult > 1)
                buf[len - 1] = 0;
        for (const char *p = buf; *p; p++)
                if (!isdigit((unsigned char) *p))
                        return -EINVAL;
        if (parse_u64(buf, 10, UINT32_MAX, &v) < 0 || v * mult > UINT32_MAX)
                return -EINVAL;
        v *= mult;
        if (lss_bit_timing_index((uint32_t) v) < 0)
                return -ERANGE;
        *ret = (uint32_t) v;
        return 0;
}
