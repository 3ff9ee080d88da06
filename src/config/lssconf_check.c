/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Cross-entry rules. Sorting keeps them O(n log n): a fuzzer or a generated
 * file may hold tens of thousands of entries. */
#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config/lssconf_check.h"

typedef struct identity_key {
        uint32_t vendor, product, serial, revision;
        bool has_revision;
        size_t index;
} identity_key;

static int cmp_u32(uint32_t a, uint32_t b) {
        return a < b ? -1 : a > b;
}

static bool same_device(const identity_key *a, const identity_key *b) {
        return a->vendor == b->vendor && a->product == b->product && a->serial == b->serial;
}

/* Entries without revision sort first within a vendor/product/serial group,
 * then by revision, then in file order. */
static int identity_key_compare(const void *x, const void *y) {
        const identity_key *a = x, *b = y;
        int r;
        if ((r = cmp_u32(a->vendor, b->vendor)) ||
            (r = cmp_u32(a->product, b->product)) ||
            (r = cmp_u32(a->serial, b->serial)))
                return r;
        if (a->has_revision != b->has_revision)
                return a->has_revision ? 1 : -1;
        if ((r = cmp_u32(a->revision, b->revision)))
                return r;
        return a->index < b->index ? -1 : a->index > b->index;
}

static void format_revision(const identity_key *k, char *buf, size_t size) {
        if (k->has_revision)
                snprintf(buf, size, "0x%08" PRIX32, k->revision);
        else
                snprintf(buf, size, "any");
}

/* An entry without revision collides with every entry of the same
 * vendor/product/serial; entries with revisions collide when those match. */
static int check_identities(const char *name, size_t bus_index, const lssconf_bus *b,
                            const lssconf_bus_src *src, lssconf_diag *diag) {
        identity_key *keys = calloc(b->n_devices ? b->n_devices : 1, sizeof(*keys));
        size_t n = 0;
        if (!keys)
                return -ENOMEM;

        for (size_t i = 0; i < b->n_devices; i++) {
                const lssconf_device *d = &b->devices[i];
                if (!src->devices[i].ok)
                        continue;
                keys[n++] = (identity_key) {
                        .vendor = d->identity.vendor,
                        .product = d->identity.product,
                        .serial = d->identity.serial,
                        .revision = d->identity.revision,
                        .has_revision = d->has_revision,
                        .index = i,
                };
        }
        qsort(keys, n, sizeof(*keys), identity_key_compare);

        for (size_t g = 0; g < n; ) {
                size_t end = g + 1, group_first = keys[g].index, first_norev = SIZE_MAX;
                while (end < n && same_device(&keys[g], &keys[end]))
                        end++;
                for (size_t k = g; k < end; k++) {
                        if (keys[k].index < group_first)
                                group_first = keys[k].index;
                        if (!keys[k].has_revision && keys[k].index < first_norev)
                                first_norev = keys[k].index;
                }

                size_t first_same_rev = SIZE_MAX;
                for (size_t k = g; k < end; k++) {
                        const identity_key *x = &keys[k];
                        size_t other;

                        if (x->has_revision) {
                                /* sorted by index within equal revisions */
                                if (k == g || !keys[k - 1].has_revision || keys[k - 1].revision != x->revision)
                                        first_same_rev = x->index;
                                other = first_norev < first_same_rev ? first_norev : first_same_rev;
                        } else
                                other = group_first;
                        if (other >= x->index)
                                continue;

                        char rev[16];
                        format_revision(x, rev, sizeof(rev));
                        lssconf_diag_add(diag, LSSCONF_DIAG_ERROR,
                                      "%s:%u: buses[%zu].devices[%zu]: same device as devices[%zu] at line %u "
                                      "(vendor 0x%08" PRIX32 ", product 0x%08" PRIX32 ", serial 0x%08" PRIX32 ", revision %s)",
                                      name, b->devices[x->index].line, bus_index, x->index, other,
                                      b->devices[other].line, x->vendor, x->product, x->serial, rev);
                }
                g = end;
        }
        free(keys);
        return 0;
}

static void check_node_ids(const char *name, size_t bus_index, const lssconf_bus *b,
                           const lssconf_bus_src *src, lssconf_diag *diag) {
        size_t first[LSS_NODE_ID_MAX + 1];
        for (size_t i = 0; i <= LSS_NODE_ID_MAX; i++)
                first[i] = SIZE_MAX;

        for (size_t i = 0; i < b->n_devices; i++) {
                uint8_t nid = b->devices[i].node_id;
                if (!src->devices[i].ok)
                        continue;
                if (first[nid] == SIZE_MAX) {
                        first[nid] = i;
                        continue;
                }
                lssconf_diag_add(diag, LSSCONF_DIAG_ERROR,
                              "%s:%u: buses[%zu].devices[%zu].node_id: %u is already mapped to devices[%zu] at line %u",
                              name, src->devices[i].node_id_line, bus_index, i, nid,
                              first[nid], b->devices[first[nid]].line);
        }
}

int lssconf_check_bus(const char *name, size_t bus_index, const lssconf_bus *b,
                          const lssconf_bus_src *src, lssconf_diag *diag) {
        check_node_ids(name, bus_index, b, src, diag);
        lssconf_check_pool(name, bus_index, b, src, 0, NULL, diag);
        return check_identities(name, bus_index, b, src, diag);
}

void lssconf_check_pool(const char *name, size_t bus_index, const lssconf_bus *b, const lssconf_bus_src *src,
                        size_t from, const lssconf *c, lssconf_diag *diag) {
        if (b->unknown != LSSCONF_UNKNOWN_POOL || !src->pool_ok)
                return;
        for (size_t i = from; i < b->n_devices; i++) {
                const lssconf_device *d = &b->devices[i];
                const char *dcf = c ? lssconf_device_source(c, d) : NULL;
                if (!src->devices[i].ok || d->node_id < b->pool_lo || d->node_id > b->pool_hi)
                        continue;
                if (dcf)
                        lssconf_diag_add(diag, LSSCONF_DIAG_ERROR,
                                         "%s:%u: buses[%zu].pool: %u..%u contains node-ID %u mapped by %s:%u", name,
                                         src->pool_line, bus_index, b->pool_lo, b->pool_hi, d->node_id, dcf, d->line);
                else
                        lssconf_diag_add(diag, LSSCONF_DIAG_ERROR,
                                         "%s:%u: buses[%zu].pool: %u..%u contains node-ID %u mapped to devices[%zu] at "
                                         "line %u", name, src->pool_line, bus_index, b->pool_lo, b->pool_hi,
                                         d->node_id, i, d->line);
        }
}

typedef struct interface_key {
        const char *name;
        size_t index;
} interface_key;

static int interface_key_compare(const void *x, const void *y) {
        const interface_key *a = x, *b = y;
        int r = strcmp(a->name, b->name);
        if (r)
                return r;
        return a->index < b->index ? -1 : a->index > b->index;
}

int lssconf_check_interfaces(const char *name, const lssconf *c,
                                 const lssconf_bus_src *src, lssconf_diag *diag) {
        interface_key *keys = calloc(c->n_buses ? c->n_buses : 1, sizeof(*keys));
        size_t n = 0;
        if (!keys)
                return -ENOMEM;

        for (size_t i = 0; i < c->n_buses; i++)
                if (src[i].interface_ok)
                        keys[n++] = (interface_key) { .name = c->buses[i].interface, .index = i };
        qsort(keys, n, sizeof(*keys), interface_key_compare);

        for (size_t k = 1, first = 0; k < n; k++) {
                if (strcmp(keys[k].name, keys[first].name) != 0) {
                        first = k;
                        continue;
                }
                size_t i = keys[k].index, j = keys[first].index;
                lssconf_diag_add(diag, LSSCONF_DIAG_ERROR,
                              "%s:%u: buses[%zu].interface: \"%s\" is already configured by buses[%zu] at line %u",
                              name, src[i].interface_line, i, keys[k].name, j, c->buses[j].line);
        }
        free(keys);
        return 0;
}
