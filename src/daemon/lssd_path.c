/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <systemd/sd-bus.h>

#include "daemon/lssd_path.h"

int lssd_bus_path(const char *ifname, char **ret) {
        return sd_bus_path_encode(LSSD_BUSES_PATH, ifname, ret);
}

int lssd_device_path(const char *ifname, const lss_identity *id, char **ret) {
        char *bus = NULL, *p = NULL;
        int r = lssd_bus_path(ifname, &bus);
        if (r < 0)
                return r;
        r = asprintf(&p, "%s/devices/%08" PRIx32 "_%08" PRIx32 "_%08" PRIx32 "_%08" PRIx32, bus, id->vendor,
                     id->product, id->revision, id->serial);
        free(bus);
        if (r < 0)
                return -ENOMEM;
        *ret = p;
        return 0;
}

static int parse_hex8(const char *s, uint32_t *ret) {
        uint32_t v = 0;
        for (unsigned i = 0; i < 8; i++) {
                char c = s[i];
                unsigned d;
                if (c >= '0' && c <= '9')
                        d = (unsigned) (c - '0');
                else if (c >= 'a' && c <= 'f')
                        d = (unsigned) (c - 'a' + 10);
                else
                        return -EINVAL;
                v = (v << 4) | d;
        }
        *ret = v;
        return 0;
}

int lssd_device_name_parse(const char *name, lss_identity *ret) {
        uint32_t v[4];
        if (!name || strlen(name) != 4 * 8 + 3)
                return -EINVAL;
        for (unsigned i = 0; i < 4; i++) {
                const char *p = name + i * 9;
                if (i < 3 && p[8] != '_')
                        return -EINVAL;
                if (parse_hex8(p, &v[i]) < 0)
                        return -EINVAL;
        }
        *ret = (lss_identity) { .vendor = v[0], .product = v[1], .revision = v[2], .serial = v[3] };
        return 0;
}
