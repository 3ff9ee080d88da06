/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The entries of DCFs merged into one map: what a file's devices become
 * (an entry, or left out and why), and the rules between sources. A file
 * is checked whole before anything of it is added. */
#include <errno.h>
#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config/dcf.h"
#include "config/lssconf_read.h"

void dcf_map_init(dcf_map *m) {
        *m = (dcf_map) { 0 };
}

static void left_out_free(dcf_left_out *l) {
        free(l->node_name);
        free(l->why);
}

void dcf_map_done(dcf_map *m) {
        for (size_t i = 0; i < m->n_files; i++)
                free(m->files[i].name);
        free(m->files);
        for (size_t i = 0; i < m->n_entries; i++)
                free(m->entries[i].node_name);
        free(m->entries);
        for (size_t i = 0; i < m->n_left_out; i++)
                left_out_free(&m->left_out[i]);
        free(m->left_out);
        dcf_map_init(m);
}

const char *dcf_identity_text(const lss_identity *id, bool has_revision, char *buf, size_t size) {
        char rev[16] = "any";
        if (has_revision)
                snprintf(rev, sizeof(rev), "0x%08" PRIX32, id->revision);
        snprintf(buf, size, "vendor 0x%08" PRIX32 ", product 0x%08" PRIX32 ", revision %s, serial 0x%08" PRIX32,
                 id->vendor, id->product, rev, id->serial);
        return buf;
}

static int add_source(dcf_map *m, const char *name, bool dcf, size_t *ret) {
        dcf_source *v = realloc(m->files, (m->n_files + 1) * sizeof(*v));
        if (!v)
                return -ENOMEM;
        m->files = v;
        v[m->n_files] = (dcf_source) { .name = strdup(name), .dcf = dcf };
        if (!v[m->n_files].name)
                return -ENOMEM;
        *ret = m->n_files++;
        return 0;
}

__attribute__((format(printf, 5, 6)))
static int add_left_out(dcf_map *m, size_t file, unsigned line, const char *node_name, const char *format, ...) {
        dcf_left_out l = { .file = file, .line = line };
        va_list ap;
        va_start(ap, format);
        int r = vasprintf(&l.why, format, ap);
        va_end(ap);
        if (r < 0)
                return -ENOMEM;
        if (node_name && !(l.node_name = strdup(node_name))) {
                free(l.why);
                return -ENOMEM;
        }
        dcf_left_out *v = realloc(m->left_out, (m->n_left_out + 1) * sizeof(*v));
        if (!v) {
                left_out_free(&l);
                return -ENOMEM;
        }
        m->left_out = v;
        v[m->n_left_out++] = l;
        return 0;
}

/* ---- the rules between entries ---- */

enum clash { CLASH_NONE, CLASH_SAME, CLASH_NODE_ID, CLASH_DEVICE };

static enum clash clash(const dcf_entry *x, const dcf_entry *e) {
        if (x->from_config && e->from_config)
                return CLASH_NONE; /* the loader's own rules */
        bool same_device = x->identity.vendor == e->identity.vendor && x->identity.product == e->identity.product &&
                           x->identity.serial == e->identity.serial;
        if (x->node_id == e->node_id) {
                if (same_device && (!x->has_revision || !e->has_revision ||
                                    x->identity.revision == e->identity.revision))
                        return CLASH_SAME;
                return CLASH_NODE_ID;
        }
        return same_device ? CLASH_DEVICE : CLASH_NONE;
}

static void report_clash(const dcf_map *m, const dcf_entry *e, const dcf_entry *x, enum clash c, lssconf_diag *diag) {
        char a[DCF_IDENTITY_TEXT_MAX], b[DCF_IDENTITY_TEXT_MAX];
        if (c == CLASH_NODE_ID)
                lssconf_diag_add(diag, LSSCONF_DIAG_ERROR,
                                 "%s:%u: node-ID %u is given to two devices: %s here, %s at %s:%u",
                                 m->files[e->file].name, e->line, e->node_id,
                                 dcf_identity_text(&e->identity, e->has_revision, a, sizeof(a)),
                                 dcf_identity_text(&x->identity, x->has_revision, b, sizeof(b)),
                                 m->files[x->file].name, x->line);
        else
                lssconf_diag_add(diag, LSSCONF_DIAG_ERROR,
                                 "%s:%u: one device gets two node-IDs: vendor 0x%08" PRIX32 ", product 0x%08" PRIX32
                                 ", serial 0x%08" PRIX32 " gets node-ID %u here and node-ID %u at %s:%u",
                                 m->files[e->file].name, e->line, e->identity.vendor, e->identity.product,
                                 e->identity.serial, e->node_id, x->node_id, m->files[x->file].name, x->line);
}

/* Whether the n entries at v may be added: every clash with the map and
 * among themselves reported. */
static bool entries_fit(const dcf_map *m, const dcf_entry *v, size_t n, lssconf_diag *diag) {
        bool ok = true;
        for (size_t i = 0; i < n; i++) {
                for (size_t k = 0; k < m->n_entries + i; k++) {
                        const dcf_entry *x = k < m->n_entries ? &m->entries[k] : &v[k - m->n_entries];
                        enum clash c = clash(x, &v[i]);
                        if (c == CLASH_SAME)
                                break; /* one entry: any clash is the first one's */
                        if (c != CLASH_NONE) {
                                report_clash(m, &v[i], x, c, diag);
                                ok = false;
                                break;
                        }
                }
        }
        return ok;
}

/* Adds entries that fit: the same as one there is merged into it. Takes
 * each node_name. */
static int add_entries(dcf_map *m, dcf_entry *v, size_t n) {
        if (n == 0)
                return 0;
        dcf_entry *a = realloc(m->entries, (m->n_entries + n) * sizeof(*a));
        if (!a)
                return -ENOMEM;
        m->entries = a;
        for (size_t i = 0; i < n; i++) {
                dcf_entry *x = NULL;
                for (size_t k = 0; k < m->n_entries && !x; k++)
                        if (clash(&m->entries[k], &v[i]) == CLASH_SAME)
                                x = &m->entries[k];
                m->files[v[i].file].n_entries++;
                if (!x) {
                        m->entries[m->n_entries++] = v[i];
                        v[i].node_name = NULL;
                        continue;
                }
                if (!x->merged) {
                        x->merged = true;
                        x->also_file = v[i].file;
                        x->also_line = v[i].line;
                }
                /* the known revision; lssd.conf's entries stay as written */
                if (!x->from_config && !x->has_revision && v[i].has_revision) {
                        x->has_revision = true;
                        x->identity.revision = v[i].identity.revision;
                }
                if (!x->node_name) {
                        x->node_name = v[i].node_name;
                        v[i].node_name = NULL;
                }
        }
        return 0;
}

int dcf_map_add_config(dcf_map *m, const char *config, unsigned line, const lss_identity *id, bool has_revision,
                       uint8_t node_id, lssconf_diag *diag) {
        size_t file = m->n_files;
        /* the configuration is the first source, added once */
        for (size_t i = 0; i < m->n_files && file == m->n_files; i++)
                if (!m->files[i].dcf && strcmp(m->files[i].name, config) == 0)
                        file = i;
        if (file == m->n_files && add_source(m, config, false, &file) < 0)
                return -ENOMEM;
        dcf_entry e = {
                .identity = *id,
                .has_revision = has_revision,
                .node_id = node_id,
                .from_config = true,
                .file = file,
                .line = line,
        };
        if (!entries_fit(m, &e, 1, diag))
                return -EINVAL;
        return add_entries(m, &e, 1);
}

/* ---- what a file's devices become ---- */

typedef struct file_entries {
        dcf_entry *v;
        size_t n;
} file_entries;

static void file_entries_free(file_entries *fe) {
        for (size_t i = 0; i < fe->n; i++)
                free(fe->v[i].node_name);
        free(fe->v);
}

/* The file's own device: an entry, or why not (*why NULL when it is one). */
static int own_device(const dcf_file *f, size_t file, file_entries *fe, char **why) {
        *why = NULL;
        int r = 0;
        if (!f->commissioning)
                r = asprintf(why, "no [DeviceComissioning] NodeID: an EDS, or a DCF not commissioned");
        else if (f->node_id.value == LSS_NODE_ID_UNCONFIGURED)
                r = asprintf(why, "NodeID 255: non-configured");
        else if (f->node_id.value < LSS_NODE_ID_MIN || f->node_id.value > LSS_NODE_ID_MAX)
                r = asprintf(why, "NodeID %" PRIu32 " is out of 1..127", f->node_id.value);
        else if (!f->serial.given)
                r = asprintf(why, "no serial number (LSS_SerialNumber 0 or not given, no ParameterValue of "
                             "[1018sub4])");
        else if (!f->vendor.given)
                r = asprintf(why, "no vendor-ID ([1018sub1] or [DeviceInfo] VendorNumber)");
        else if (!f->product.given)
                r = asprintf(why, "no product code ([1018sub2] or [DeviceInfo] ProductNumber)");
        if (r < 0)
                return -ENOMEM;
        if (*why)
                return 0;
        dcf_entry *e = &fe->v[fe->n++];
        *e = (dcf_entry) {
                .identity = { f->vendor.value, f->product.value, f->revision.value, f->serial.value },
                .has_revision = f->revision.given,
                .node_id = (uint8_t) f->node_id.value,
                .file = file,
                .line = f->node_id.line,
        };
        if (f->node_name && !(e->node_name = strdup(f->node_name)))
                return -ENOMEM;
        return 0;
}

/* A master's sub-index n: an entry, left out, or nothing expected there. */
static int expected_device(dcf_map *m, const dcf_file *f, size_t file, unsigned n, file_entries *fe) {
        const dcf_expected *x = &f->expected[n];
        bool serial = x->serial.given && x->serial.value != 0;
        bool vendor = x->vendor.given && x->vendor.value != 0, product = x->product.given && x->product.value != 0;

        if (!serial) {
                const dcf_number *named = vendor ? &x->vendor : product ? &x->product : NULL;
                if (!named)
                        return 0;
                return add_left_out(m, file, named->line, NULL, "sub-index %u of 1F85h/1F86h names a device, but "
                                    "1F88h sub %u gives no serial number (0: not checked), which LSS needs", n, n);
        }
        if (n > LSS_NODE_ID_MAX)
                return add_left_out(m, file, x->serial.line, NULL, "1F88h sub-index %u (0x%02X) is no node-ID "
                                    "(1..127)", n, n);
        if (!vendor || !product)
                return add_left_out(m, file, x->serial.line, NULL, "node-ID %u: 1F8%ch sub %u gives no %s (0: not "
                                    "checked), which LSS needs", n, !vendor ? '5' : '6', n,
                                    !vendor ? "vendor-ID" : "product code");
        bool revision = x->revision.given && x->revision.value != 0;
        fe->v[fe->n++] = (dcf_entry) {
                .identity = { x->vendor.value, x->product.value, revision ? x->revision.value : 0, x->serial.value },
                .has_revision = revision,
                .node_id = (uint8_t) n,
                .file = file,
                .line = x->serial.line,
        };
        return 0;
}

static int add_file(dcf_map *m, const dcf_file *f, lssconf_diag *diag) {
        file_entries fe = { 0 };
        size_t left_before = m->n_left_out, file;
        char *why = NULL;
        int r;

        if (add_source(m, f->name, true, &file) < 0)
                return -ENOMEM;
        m->files[file].baudrate = f->baudrate;
        m->files[file].net_number = f->net_number;
        fe.v = calloc(1 + DCF_SUB_MAX, sizeof(*fe.v));
        if (!fe.v)
                return -ENOMEM;
        r = own_device(f, file, &fe, &why);
        /* a master's own device: only when it is one (the master is seldom an LSS slave) */
        if (r >= 0 && why && !f->master) {
                unsigned line = f->node_id.given ? f->node_id.line : f->commissioning ? f->commissioning_line : 1;
                r = add_left_out(m, file, line, f->node_name, "%s", why);
        }
        for (unsigned n = 1; r >= 0 && f->master && n <= DCF_SUB_MAX; n++)
                r = expected_device(m, f, file, n, &fe);
        if (r >= 0 && !entries_fit(m, fe.v, fe.n, diag))
                r = -EINVAL;
        if (r >= 0)
                r = add_entries(m, fe.v, fe.n);
        if (r < 0) /* nothing of the file */
                while (m->n_left_out > left_before)
                        left_out_free(&m->left_out[--m->n_left_out]);
        free(why);
        file_entries_free(&fe);
        return r;
}

int dcf_map_read_buffer(dcf_map *m, const char *text, size_t len, const char *name, lssconf_diag *diag) {
        dcf_file f;
        int r = dcf_parse(text, len, name, &f, diag);
        if (r < 0)
                return r;
        r = add_file(m, &f, diag);
        dcf_file_done(&f);
        return r;
}

int dcf_map_read_file(dcf_map *m, const char *path, lssconf_diag *diag) {
        char *text = NULL;
        size_t len = 0;
        for (size_t i = 0; i < m->n_files; i++)
                if (m->files[i].dcf && strcmp(m->files[i].name, path) == 0)
                        return 0;
        int r = lssconf_read_text(path, DCF_SIZE_MAX, &text, &len, diag);
        if (r >= 0)
                r = dcf_map_read_buffer(m, text, len, path, diag);
        free(text);
        return r;
}

/* ---- the network of the files ---- */

static const dcf_number *source_number(const dcf_source *s, bool baudrate) {
        return baudrate ? &s->baudrate : &s->net_number;
}

/* The first source with entries that gives the number; NULL and a warning
 * when one differs from it. */
static const dcf_source *agree(const dcf_map *m, bool baudrate, lssconf_diag *diag) {
        const char *what = baudrate ? "Baudrate" : "NetNumber", *unit = baudrate ? " kbit/s" : "";
        const dcf_source *first = NULL;
        for (size_t i = 0; i < m->n_files; i++) {
                const dcf_source *s = &m->files[i];
                const dcf_number *v = source_number(s, baudrate);
                if (!s->dcf || s->n_entries == 0 || !v->given)
                        continue;
                if (!first) {
                        first = s;
                        continue;
                }
                const dcf_number *f = source_number(first, baudrate);
                if (v->value != f->value) {
                        lssconf_diag_add(diag, LSSCONF_DIAG_WARNING,
                                         "%s:%u: %s %" PRIu32 "%s, but %s:%u says %" PRIu32 "%s: the DCFs are not of "
                                         "one network", s->name, v->line, what, v->value, unit, first->name, f->line,
                                         f->value, unit);
                        return NULL;
                }
        }
        return first;
}

uint32_t dcf_map_baudrate(const dcf_map *m, lssconf_diag *diag) {
        (void) agree(m, false, diag);
        const dcf_source *s = agree(m, true, diag);
        return s ? s->baudrate.value : 0;
}
