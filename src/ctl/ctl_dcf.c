/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* import-dcf (no lssd needed) and the writing of scan --as-dcf. */
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "config/dcf.h"
#include "ctl/ctl_dcf.h"
#include "ctl/ctl_errors.h"
#include "ctl/ctl_map_entry.h"
#include "lss/lss_proto.h"

/* ---- import-dcf ---- */

/* the interface of the printed bus: what lssd.conf(5) takes, printable */
static bool ifname_printable(const char *s) {
        size_t n = strlen(s);
        if (n == 0 || n > 15)
                return false;
        for (; *s; s++)
                if ((unsigned char) *s <= ' ' || (unsigned char) *s >= 0x7F || *s == '"' || *s == '\\' || *s == '/' ||
                    *s == ':')
                        return false;
        return true;
}

static int compare_entries(const void *a, const void *b) {
        const dcf_entry *x = *(const dcf_entry *const *) a, *y = *(const dcf_entry *const *) b;
        return (x->node_id > y->node_id) - (x->node_id < y->node_id);
}

/* "FILE:LINE (NodeName "X")"; the comment stays one line whatever the file's name */
static void print_source(const dcf_map *m, size_t file, unsigned line, const char *node_name) {
        for (const char *p = m->files[file].name; *p; p++)
                putchar((unsigned char) *p < ' ' || *p == 0x7F ? '?' : *p);
        printf(":%u", line);
        if (node_name)
                printf(" (NodeName \"%s\")", node_name);
}

static int print_bus(const ctl_context *c, const dcf_map *m, uint32_t kbit) {
        const dcf_entry **v = calloc(m->n_entries ? m->n_entries : 1, sizeof(*v));
        size_t n_dcf = 0;
        if (!v)
                return -ENOMEM;
        for (size_t i = 0; i < m->n_files; i++)
                n_dcf += m->files[i].dcf;
        for (size_t i = 0; i < m->n_entries; i++)
                v[i] = &m->entries[i];
        qsort(v, m->n_entries, sizeof(*v), compare_entries);

        printf("# lssd.conf(5) buses from CiA 306 DCFs by 'lssctl import-dcf', lssctl %s:\n", LSSCTL_VERSION);
        printf("# %zu device%s from %zu file%s", m->n_entries, m->n_entries == 1 ? "" : "s", n_dcf,
               n_dcf == 1 ? "" : "s");
        if (m->n_left_out > 0)
                printf(", %zu left out (see there)", m->n_left_out);
        printf(".\n"
               "# It replaces the buses = ( ... ); of lssd's configuration file (lssd.conf(5):\n"
               "# /etc/lssd/lssd.conf unless lssd runs with --config), or extends it by\n"
               "# this bus; the global settings there stay. lssd can also read the DCFs\n"
               "# itself: dcf = [ \"/etc/lssd/dcf/*.dcf\" ]; in the bus instead of devices.\n"
               "# Check the file with 'lssd --check-config FILE', then 'lssctl reload'.\n"
               "buses = (\n"
               "  {\n");
        if (c->bus_name)
                printf("    interface = \"%s\";\n", c->bus_name);
        else
                printf("    interface = \"can0\";   # no --bus IFACE given: the interface of this network\n");
        if (kbit > 0 && kbit <= UINT32_MAX / 1000 && lss_bit_timing_index(kbit * 1000) >= 0)
                printf("    bitrate = %" PRIu32 ";   # the DCFs' Baudrate\n", kbit * 1000);
        else if (kbit > 0)
                printf("    # bitrate = ...;  the DCFs' Baudrate %" PRIu32 " kbit/s is no CiA 301 bit rate: give it\n",
                       kbit);
        else
                printf("    # bitrate = ...;  the DCFs do not say the bit rate (Baudrate): give it\n");
        printf("    auto_assign = true;   # at start, every device below gets its node-ID\n"
               "    devices = (\n");
        for (size_t i = 0; i < m->n_entries; i++) {
                const dcf_entry *e = v[i];
                uint32_t id[4] = { e->identity.vendor, e->identity.product, e->identity.revision, e->identity.serial };
                ctl_print_map_entry(id, e->has_revision, e->node_id, true, i + 1 < m->n_entries);
                printf("  # ");
                print_source(m, e->file, e->line, e->node_name);
                if (e->merged)
                        printf(", also %s:%u", m->files[e->also_file].name, e->also_line);
                putchar('\n');
        }
        for (size_t i = 0; i < m->n_left_out; i++) {
                const dcf_left_out *l = &m->left_out[i];
                printf("      # left out: ");
                print_source(m, l->file, l->line, l->node_name);
                printf(": %s\n", l->why);
        }
        printf("    );\n"
               "  }\n"
               ");\n");
        free(v);
        return 0;
}

int verb_import_dcf(ctl_context *c) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_map m;
        int r = 0;

        if (c->bus_name && !ifname_printable(c->bus_name))
                return ctl_usage(c, "Invalid --bus '%s': an interface name of 1..15 characters.", c->bus_name);
        dcf_map_init(&m);
        /* every file, so that one run names every problem */
        for (int i = 0; i < c->n_args && r != -ENOMEM; i++) {
                int k = dcf_map_read_file(&m, c->args[i], &d);
                if (k < 0)
                        r = k;
        }
        uint32_t kbit = r >= 0 ? dcf_map_baudrate(&m, &d) : 0;
        for (size_t i = 0; i < d.n_messages; i++)
                fprintf(stderr, "lssctl: %s%s\n", d.messages[i].severity == LSSCONF_DIAG_WARNING ? "warning: " : "",
                        d.messages[i].text);
        if (d.n_dropped > 0)
                fprintf(stderr, "lssctl: (%zu more messages)\n", d.n_dropped);
        if (r == -ENOMEM || d.oom)
                r = ctl_fail(c, CTL_EXIT_FAILURE, -ENOMEM, "Out of memory.");
        else if (r < 0 || d.n_errors > 0)
                r = ctl_fail(c, CTL_EXIT_BAD_CONFIG, -EINVAL, "%zu error%s in the DCFs (above): no map printed.",
                             d.n_errors, d.n_errors == 1 ? "" : "s");
        else if (print_bus(c, &m, kbit) < 0)
                r = ctl_fail(c, CTL_EXIT_FAILURE, -ENOMEM, "Out of memory.");
        else {
                if (m.n_entries == 0)
                        fprintf(stderr, "lssctl: warning: no device of these files can be a map entry.\n");
        }
        dcf_map_done(&m);
        lssconf_diag_clear(&d);
        return r;
}

/* ---- scan --as-dcf ---- */

static void write_object(FILE *f, unsigned sub, const char *name, const char *type, uint32_t value) {
        fprintf(f, "[1018sub%u]\r\nParameterName=%s\r\nObjectType=0x7\r\nDataType=%s\r\nAccessType=ro\r\n", sub, name,
                type);
        if (sub == 0)
                fprintf(f, "DefaultValue=%" PRIu32 "\r\n", value);
        else
                fprintf(f, "ParameterValue=0x%08" PRIX32 "\r\n", value);
        fprintf(f, "PDOMapping=0\r\n\r\n");
}

/* The fragment, CRLF as CiA 306 tools write it. */
static void write_dcf(FILE *f, const char *file_name, const ctl_dcf_device *d, const struct tm *tm) {
        char date[16] = "", hm[16] = "", when[32] = "";
        strftime(date, sizeof(date), "%m-%d-%Y", tm);
        strftime(hm, sizeof(hm), "%I:%M%p", tm);
        strftime(when, sizeof(when), "%Y-%m-%d %H:%M:%S UTC", tm);
        fprintf(f, "; A DCF fragment: the identity and node-ID of one device as lssd found it.\r\n"
                "[FileInfo]\r\nFileName=%s\r\nFileVersion=1\r\nFileRevision=0\r\nEDSVersion=4.0\r\n"
                "Description=Device at node-ID %u on %s, found by lssctl scan --as-dcf, %s\r\n"
                "CreationTime=%s\r\nCreationDate=%s\r\nCreatedBy=lssctl %s\r\n\r\n",
                file_name, d->node_id, d->ifname, when, hm, date, LSSCTL_VERSION);
        fprintf(f, "[DeviceInfo]\r\nVendorNumber=0x%08" PRIX32 "\r\nProductNumber=0x%08" PRIX32 "\r\n"
                "RevisionNumber=0x%08" PRIX32 "\r\nLSS_Supported=1\r\n\r\n", d->id[0], d->id[1], d->id[2]);
        fprintf(f, "[DeviceComissioning]\r\nNodeID=%u\r\n", d->node_id);
        if (d->bitrate > 0)
                fprintf(f, "Baudrate=%" PRIu32 "\r\n", d->bitrate / 1000);
        fprintf(f, "LSS_SerialNumber=0x%08" PRIX32 "\r\n\r\n", d->id[3]);
        fprintf(f, "[1018]\r\nParameterName=Identity object\r\nObjectType=0x9\r\nSubNumber=5\r\n\r\n");
        write_object(f, 0, "Highest sub-index supported", "0x0005", 4);
        write_object(f, 1, "Vendor-ID", "0x0007", d->id[0]);
        write_object(f, 2, "Product code", "0x0007", d->id[1]);
        write_object(f, 3, "Revision number", "0x0007", d->id[2]);
        write_object(f, 4, "Serial number", "0x0007", d->id[3]);
}

/* DIR/NAME through a temporary file, renamed over the old one when whole */
static int write_one(ctl_context *c, const char *dir, const ctl_dcf_device *d, const struct tm *tm, char **ret_path) {
        char name[64], *path = NULL, *tmp = NULL;
        int r;

        snprintf(name, sizeof(name), "%s-node%03u.dcf", d->ifname, d->node_id);
        if (asprintf(&path, "%s/%s", dir, name) < 0 || asprintf(&tmp, "%s/.%s.XXXXXX", dir, name) < 0) {
                free(path);
                return ctl_fail(c, CTL_EXIT_FAILURE, -ENOMEM, "Out of memory.");
        }
        int fd = mkostemp(tmp, O_CLOEXEC);
        FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
        if (!f) {
                r = -errno;
                if (fd >= 0) {
                        close(fd);
                        unlink(tmp);
                }
                r = ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to write %s: %s", path, strerror(-r));
                goto finish;
        }
        (void) fchmod(fileno(f), 0644);
        write_dcf(f, name, d, tm);
        bool bad = ferror(f);
        r = fclose(f) != 0 ? -errno : bad ? -EIO : rename(tmp, path) < 0 ? -errno : 0;
        if (r < 0) {
                unlink(tmp);
                r = ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to write %s: %s", path, strerror(-r));
                goto finish;
        }
        *ret_path = path;
        path = NULL;
        r = 0;
finish:
        free(path);
        free(tmp);
        return r;
}

int ctl_write_dcfs(ctl_context *c, const char *dir, const ctl_dcf_device *v, size_t n) {
        time_t now = time(NULL);
        struct tm tm;

        if (mkdir(dir, 0755) < 0 && errno != EEXIST)
                return ctl_fail(c, CTL_EXIT_FAILURE, -errno, "Failed to make the folder %s: %s", dir, strerror(errno));
        if (!gmtime_r(&now, &tm))
                memset(&tm, 0, sizeof(tm));
        for (size_t i = 0; i < n; i++) {
                char *path = NULL;
                int r = write_one(c, dir, &v[i], &tm, &path);
                if (r < 0)
                        return r;
                printf("%s: device 0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 " at node-ID %u: %s\n",
                       v[i].ifname, v[i].id[0], v[i].id[1], v[i].id[2], v[i].id[3], v[i].node_id, path);
                free(path);
        }
        return 0;
}
