/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <glob.h>
#include <inttypes.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config/dcf.h"
#include "config/lssconf_dcf.h"

/* glob(3)'s error callback has no user data: the first folder it could not read */
static __thread int glob_errno;
static __thread char glob_error_path[PATH_MAX];

static int on_glob_error(const char *path, int err) {
        if (glob_errno == 0) {
                glob_errno = err;
                snprintf(glob_error_path, sizeof(glob_error_path), "%s", path);
        }
        return 1; /* stop */
}

/* One pattern: every file it names read into m. -ENOMEM or 0. */
static int expand(const char *name, const char *dir, size_t bus_index, size_t k, const lssconf_dcf_pattern *p,
                  dcf_map *m, lssconf_diag *diag) {
        char *full;
        glob_t g;
        int r = 0;

        if (p->pattern[0] == '/')
                full = strdup(p->pattern);
        else if (asprintf(&full, "%s/%s", dir, p->pattern) < 0)
                full = NULL;
        if (!full)
                return -ENOMEM;
        glob_errno = 0;
        int globbed = glob(full, GLOB_ERR | GLOB_MARK, on_glob_error, &g);
        if (globbed == GLOB_NOMATCH) {
                if (!strpbrk(p->pattern, "*?["))
                        r = dcf_map_read_file(m, full, diag); /* says why it cannot be read */
                else
                        lssconf_diag_add(diag, LSSCONF_DIAG_WARNING, "%s:%u: buses[%zu].dcf[%zu]: \"%s\" matches no "
                                         "file", name, p->line, bus_index, k, full);
        } else if (globbed == GLOB_ABORTED)
                lssconf_diag_add(diag, LSSCONF_DIAG_ERROR, "%s:%u: buses[%zu].dcf[%zu]: cannot read %s: %s", name,
                                 p->line, bus_index, k, glob_error_path, strerror(glob_errno ? glob_errno : EIO));
        else if (globbed != 0)
                r = -ENOMEM;
        for (size_t i = 0; globbed == 0 && i < g.gl_pathc && r != -ENOMEM; i++) {
                const char *path = g.gl_pathv[i];
                if (path[0] && path[strlen(path) - 1] == '/')
                        continue; /* a folder */
                r = dcf_map_read_file(m, path, diag);
        }
        if (globbed == 0)
                globfree(&g);
        free(full);
        return r == -ENOMEM ? r : 0;
}

/* The index + 1 of name in c->sources, added when new; 0 when out of memory. */
static size_t source_of(lssconf *c, const char *name) {
        for (size_t i = 0; i < c->n_sources; i++)
                if (strcmp(c->sources[i], name) == 0)
                        return i + 1;
        char **v = realloc(c->sources, (c->n_sources + 1) * sizeof(*v));
        if (!v)
                return 0;
        c->sources = v;
        if (!(v[c->n_sources] = strdup(name)))
                return 0;
        return ++c->n_sources;
}

/* The DCFs' entries after `devices`. */
static int append(lssconf *c, lssconf_bus *b, lssconf_bus_src *src, const dcf_map *m) {
        size_t n = 0;
        for (size_t i = 0; i < m->n_entries; i++)
                n += !m->entries[i].from_config;
        if (n == 0)
                return 0;
        lssconf_device *d = realloc(b->devices, (b->n_devices + n) * sizeof(*d));
        if (!d)
                return -ENOMEM;
        b->devices = d;
        lssconf_device_src *s = realloc(src->devices, (b->n_devices + n) * sizeof(*s));
        if (!s)
                return -ENOMEM;
        src->devices = s;
        for (size_t i = 0; i < m->n_entries; i++) {
                const dcf_entry *e = &m->entries[i];
                if (e->from_config)
                        continue;
                size_t source = source_of(c, m->files[e->file].name);
                if (source == 0)
                        return -ENOMEM;
                d[b->n_devices] = (lssconf_device) {
                        .identity = e->identity,
                        .has_revision = e->has_revision,
                        .node_id = e->node_id,
                        .line = e->line,
                        .source = source,
                };
                s[b->n_devices++] = (lssconf_device_src) { .node_id_line = e->line, .ok = true };
        }
        return 0;
}

int lssconf_read_bus_dcfs(const char *name, const char *dir, size_t bus_index, lssconf *c, lssconf_bus *b,
                          lssconf_bus_src *src, lssconf_diag *diag) {
        dcf_map m;
        int r = 0;

        if (src->n_dcf == 0)
                return 0;
        if (!dir) {
                lssconf_diag_add(diag, LSSCONF_DIAG_WARNING, "%s:%u: buses[%zu].dcf: not read (a configuration "
                                 "from memory reads no file)", name, src->dcf_line, bus_index);
                return 0;
        }
        dcf_map_init(&m);
        for (size_t i = 0; i < b->n_devices && r >= 0; i++) {
                const lssconf_device *d = &b->devices[i];
                if (src->devices[i].ok)
                        r = dcf_map_add_config(&m, name, d->line, &d->identity, d->has_revision, d->node_id, diag);
        }
        for (size_t k = 0; k < src->n_dcf && r != -ENOMEM; k++)
                r = expand(name, dir, bus_index, k, &src->dcf[k], &m, diag);
        if (r == -ENOMEM)
                goto finish;

        for (size_t i = 0; i < m.n_left_out; i++) {
                const dcf_left_out *l = &m.left_out[i];
                lssconf_diag_add(diag, LSSCONF_DIAG_WARNING, "%s:%u: left out of the map of %s%s%s%s: %s",
                                 m.files[l->file].name, l->line, b->interface, l->node_name ? " (NodeName \"" : "",
                                 l->node_name ? l->node_name : "", l->node_name ? "\")" : "", l->why);
        }
        uint32_t kbit = dcf_map_baudrate(&m, diag);
        if (kbit > 0 && (uint64_t) kbit * 1000 != b->bitrate)
                lssconf_diag_add(diag, LSSCONF_DIAG_WARNING, "%s:%u: buses[%zu].dcf: the DCFs say Baudrate %" PRIu32
                                 " kbit/s, the bus runs at %" PRIu32 " bit/s (bitrate)", name, src->dcf_line,
                                 bus_index, kbit, b->bitrate);

        size_t first = b->n_devices;
        r = append(c, b, src, &m);
        if (r >= 0)
                lssconf_check_pool(name, bus_index, b, src, first, c, diag);
finish:
        dcf_map_done(&m);
        return r;
}
