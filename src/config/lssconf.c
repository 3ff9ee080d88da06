/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The configuration object: construction, freeing, look-ups, formatting. */
#include <errno.h>
#include <inttypes.h>
#include <net/if.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config/lssconf.h"

_Static_assert(LSSCONF_IFNAME_MAX + 1 == IFNAMSIZ, "interface name size must match the kernel's");

int lssconf_new(lssconf **ret) {
        lssconf *c = calloc(1, sizeof(*c));
        if (!c)
                return -ENOMEM;
        c->lss_timeout_ms = LSSCONF_LSS_TIMEOUT_MS_DEFAULT;
        c->lss_timing = LSSCONF_LSS_TIMING_ADAPTIVE;
        c->boot_ready_limit_s = LSSCONF_BOOT_READY_LIMIT_S_DEFAULT;
        c->foreign_master_quiet_s = LSSCONF_FOREIGN_MASTER_QUIET_S_DEFAULT;
        *ret = c;
        return 0;
}

int lssconf_add_default_bus(lssconf *c, const char *ifname, lssconf_bus **ret) {
        if (!lssconf_ifname_valid(ifname))
                return -EINVAL;
        if (lssconf_find_bus(c, ifname))
                return -EEXIST;

        lssconf_bus *buses = realloc(c->buses, (c->n_buses + 1) * sizeof(*buses));
        if (!buses)
                return -ENOMEM;
        c->buses = buses;

        lssconf_bus *b = &c->buses[c->n_buses++];
        *b = (lssconf_bus) {
                .bitrate = LSSCONF_BITRATE_DEFAULT,
                .lss_timeout_ms = c->lss_timeout_ms,
                .lss_timing = c->lss_timing,
                .foreign_master_quiet_s = c->foreign_master_quiet_s,
                .store = true,
                .unknown = LSSCONF_UNKNOWN_IGNORE,
        };
        strcpy(b->interface, ifname); /* length checked by lssconf_ifname_valid() */
        if (ret)
                *ret = b;
        return 0;
}

lssconf *lssconf_free(lssconf *c) {
        if (!c)
                return NULL;
        for (size_t i = 0; i < c->n_buses; i++)
                free(c->buses[i].devices);
        free(c->buses);
        for (size_t i = 0; i < c->n_sources; i++)
                free(c->sources[i]);
        free(c->sources);
        free(c->source);
        free(c);
        return NULL;
}

const lssconf_bus *lssconf_find_bus(const lssconf *c, const char *ifname) {
        if (!c || !ifname)
                return NULL;
        for (size_t i = 0; i < c->n_buses; i++)
                if (strcmp(c->buses[i].interface, ifname) == 0)
                        return &c->buses[i];
        return NULL;
}

bool lssconf_device_matches(const lssconf_device *d, const lss_identity *id) {
        return lss_identity_matches(&d->identity, d->has_revision, id);
}

const lssconf_device *lssconf_lookup_device(const lssconf_bus *b, const lss_identity *id) {
        if (!b || !id)
                return NULL;
        for (size_t i = 0; i < b->n_devices; i++)
                if (lssconf_device_matches(&b->devices[i], id))
                        return &b->devices[i];
        return NULL;
}

const char *lssconf_device_source(const lssconf *c, const lssconf_device *d) {
        return d->source > 0 && d->source <= c->n_sources ? c->sources[d->source - 1] : NULL;
}

const lssconf_device *lssconf_bus_find_node_id(const lssconf_bus *b, uint8_t node_id) {
        if (!b)
                return NULL;
        for (size_t i = 0; i < b->n_devices; i++)
                if (b->devices[i].node_id == node_id)
                        return &b->devices[i];
        return NULL;
}

const char *lssconf_bus_describe(const lssconf_bus *b, char *buf, size_t size) {
        char unknown[32];

        if (!buf || size == 0)
                return buf;
        if (b->unknown == LSSCONF_UNKNOWN_POOL)
                snprintf(unknown, sizeof(unknown), "pool %u..%u", b->pool_lo, b->pool_hi);
        else
                snprintf(unknown, sizeof(unknown), "ignore");

        size_t from_dcf = 0;
        char dcf[40] = "";
        for (size_t i = 0; i < b->n_devices; i++)
                from_dcf += b->devices[i].source > 0;
        if (from_dcf > 0)
                snprintf(dcf, sizeof(dcf), " (%zu from DCFs)", from_dcf);

        snprintf(buf, size,
                 "%s: %" PRIu32 " bit/s, %zu mapped device%s%s, auto-assign %s, store %s, "
                 "unknown devices: %s, nmt-stop %s, replace %s, reset after pass %s, bit-rate change %s, "
                 "LSS timeout %" PRIu32 " ms (%s), quiet after another master %" PRIu32 " s",
                 b->interface, b->bitrate, b->n_devices, b->n_devices == 1 ? "" : "s", dcf,
                 b->auto_assign ? "on" : "off", b->store ? "on" : "off", unknown,
                 b->nmt_stop ? "on" : "off", b->replace ? "on" : "off", b->reset_after_pass ? "on" : "off",
                 b->bitrate_change ? "allowed" : "off",
                 b->lss_timeout_ms, lssconf_lss_timing_to_string(b->lss_timing), b->foreign_master_quiet_s);
        return buf;
}

bool lssconf_ifname_valid(const char *name) {
        if (!name)
                return false;
        size_t n = strlen(name);
        if (n == 0 || n > LSSCONF_IFNAME_MAX)
                return false;
        if (strcmp(name, ".") == 0 || strcmp(name, "..") == 0)
                return false;
        for (const unsigned char *p = (const unsigned char *) name; *p; p++)
                /* The kernel refuses '/', ':' and whitespace; control characters
                 * would only garble logs. */
                if (*p <= ' ' || *p == 0x7F || *p == '/' || *p == ':')
                        return false;
        return true;
}

static const char *const unknown_policy_names[] = {
        [LSSCONF_UNKNOWN_IGNORE] = "ignore",
        [LSSCONF_UNKNOWN_POOL] = "pool",
};

static const char *const lss_timing_names[] = {
        [LSSCONF_LSS_TIMING_ADAPTIVE] = "adaptive",
        [LSSCONF_LSS_TIMING_FIXED] = "fixed",
};

static int name_lookup(const char *const *names, size_t n, const char *s) {
        if (!s)
                return -EINVAL;
        for (size_t i = 0; i < n; i++)
                if (strcmp(names[i], s) == 0)
                        return (int) i;
        return -EINVAL;
}

const char *lssconf_unknown_policy_to_string(lssconf_unknown_policy p) {
        return (unsigned) p < sizeof(unknown_policy_names) / sizeof(unknown_policy_names[0]) ?
                unknown_policy_names[p] : NULL;
}

int lssconf_unknown_policy_from_string(const char *s) {
        return name_lookup(unknown_policy_names, sizeof(unknown_policy_names) / sizeof(unknown_policy_names[0]), s);
}

const char *lssconf_lss_timing_to_string(lssconf_lss_timing t) {
        return (unsigned) t < sizeof(lss_timing_names) / sizeof(lss_timing_names[0]) ?
                lss_timing_names[t] : NULL;
}

int lssconf_lss_timing_from_string(const char *s) {
        return name_lookup(lss_timing_names, sizeof(lss_timing_names) / sizeof(lss_timing_names[0]), s);
}
