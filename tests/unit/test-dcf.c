/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The CiA 306 reader (src/config/dcf.h): the public DCFs of tests/unit/dcf/
 * (origins and licences in tests/unit/dcf/README.md) and hand-made text
 * with every error it names. */
#include <check.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check-main.h"
#include "config/dcf.h"
#include "diag-util.h"

/* ---- helpers ---- */

static char *data_path(const char *name) {
        const char *dir = getenv("LSSD_TEST_DATA");
        char *p;
        ck_assert_msg(dir, "LSSD_TEST_DATA is not set (run through meson test)");
        ck_assert_int_ge(asprintf(&p, "%s/dcf/%s", dir, name), 0);
        return p;
}

static char *slurp(const char *path, size_t *len) {
        FILE *f = fopen(path, "rb");
        ck_assert_msg(f, "cannot open %s", path);
        char *buf = NULL;
        size_t n = 0, cap = 0;
        for (;;) {
                if (n == cap) {
                        cap = cap ? cap * 2 : 65536;
                        buf = realloc(buf, cap + 1);
                        ck_assert_ptr_nonnull(buf);
                }
                size_t k = fread(buf + n, 1, cap - n, f);
                if (k == 0)
                        break;
                n += k;
        }
        fclose(f);
        buf[n] = '\0';
        *len = n;
        return buf;
}

/* Reads a file of tests/unit/dcf/ into m; returns what dcf_map_read_file did. */
static int read_data(dcf_map *m, const char *name, lssconf_diag *d) {
        char *p = data_path(name);
        int r = dcf_map_read_file(m, p, d);
        free(p);
        return r;
}

static void parse_data(const char *name, dcf_file *f, lssconf_diag *d) {
        size_t len;
        char *p = data_path(name);
        char *text = slurp(p, &len);
        int r = dcf_parse(text, len, name, f, d);
        if (r < 0)
                dump(d);
        ck_assert_int_eq(r, 0);
        free(text);
        free(p);
}

/* A public file that describes one device and no entry: left out at line, why. */
static void expect_left_out_alone(const char *name, unsigned line, const char *why) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_map m;
        dcf_map_init(&m);
        ck_assert_int_eq(read_data(&m, name, &d), 0);
        ck_assert_uint_eq(m.n_entries, 0);
        ck_assert_uint_eq(m.n_left_out, 1);
        ck_assert_uint_eq(m.left_out[0].line, line);
        ck_assert_msg(strstr(m.left_out[0].why, why), "%s: %s", name, m.left_out[0].why);
        ck_assert_uint_eq(d.n_errors, 0);
        dcf_map_done(&m);
        lssconf_diag_clear(&d);
}

static int read_text(dcf_map *m, const char *name, const char *text, lssconf_diag *d) {
        return dcf_map_read_buffer(m, text, strlen(text), name, d);
}

/* text must fail as a file of its own, with an error carrying the substrings, adding nothing */
#define expect_file_error(text, ...) \
        do { \
                dcf_map _m; \
                lssconf_diag _d = LSSCONF_DIAG_INIT; \
                dcf_map_init(&_m); \
                ck_assert_int_eq(read_text(&_m, "t.dcf", text, &_d), -EINVAL); \
                expect_message(&_d, LSSCONF_DIAG_ERROR, __VA_ARGS__); \
                ck_assert_uint_eq(_m.n_entries, 0); \
                ck_assert_uint_eq(_m.n_left_out, 0); \
                dcf_map_done(&_m); \
                lssconf_diag_clear(&_d); \
        } while (0)

static void expect_identity(const dcf_entry *e, uint32_t vendor, uint32_t product, uint32_t revision, bool has_revision,
                            uint32_t serial, uint8_t node_id) {
        ck_assert_uint_eq(e->identity.vendor, vendor);
        ck_assert_uint_eq(e->identity.product, product);
        ck_assert_int_eq(e->has_revision, has_revision);
        if (has_revision)
                ck_assert_uint_eq(e->identity.revision, revision);
        ck_assert_uint_eq(e->identity.serial, serial);
        ck_assert_uint_eq(e->node_id, node_id);
}

static const char *file_of(const dcf_map *m, size_t file) {
        const char *s = strrchr(m->files[file].name, '/');
        return s ? s + 1 : m->files[file].name;
}

/* ---- the public files ---- */

/* lely-core's NMT test: the slave's DCF and the master's expectation of it
 * (1F84h..1F88h as compact arrays) name one device: one entry. */
START_TEST(lely_slave_and_master_are_one_entry) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_map m;
        dcf_map_init(&m);
        ck_assert_int_eq(read_data(&m, "lely-co-nmt-slave.dcf", &d), 0);
        ck_assert_uint_eq(m.n_entries, 1);
        expect_identity(&m.entries[0], 0x360, 2, 3, true, 4, 2);
        ck_assert_str_eq(file_of(&m, m.entries[0].file), "lely-co-nmt-slave.dcf");
        ck_assert_uint_eq(m.entries[0].line, 17); /* NodeID=0x02 */
        ck_assert(!m.entries[0].merged);

        ck_assert_int_eq(read_data(&m, "lely-co-nmt-master.dcf", &d), 0);
        ck_assert_uint_eq(m.n_entries, 1);
        ck_assert(m.entries[0].merged);
        ck_assert_str_eq(file_of(&m, m.entries[0].also_file), "lely-co-nmt-master.dcf");
        ck_assert_uint_eq(m.entries[0].also_line, 230); /* [1F88Value] 2=0x00000004 */
        ck_assert_uint_eq(m.n_left_out, 0);
        if (d.n_messages)
                dump(&d);
        ck_assert_uint_eq(d.n_messages, 0);
        ck_assert_uint_eq(dcf_map_baudrate(&m, &d), 0); /* neither says */

        /* a file read again is not read twice */
        ck_assert_int_eq(read_data(&m, "lely-co-nmt-master.dcf", &d), 0);
        ck_assert_uint_eq(m.n_files, 2);
        dcf_map_done(&m);

        /* the master alone */
        dcf_map_init(&m);
        ck_assert_int_eq(read_data(&m, "lely-co-nmt-master.dcf", &d), 0);
        ck_assert_uint_eq(m.n_entries, 1);
        expect_identity(&m.entries[0], 0x360, 2, 3, true, 4, 2);
        ck_assert_uint_eq(m.entries[0].line, 230);
        /* its own device (NodeID 1, no serial number) is the master's: not mentioned */
        ck_assert_uint_eq(m.n_left_out, 0);
        dcf_map_done(&m);
        lssconf_diag_clear(&d);
}
END_TEST

START_TEST(lely_master_as_parsed) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_file f;
        parse_data("lely-co-nmt-master.dcf", &f, &d);
        ck_assert(f.master);
        ck_assert(f.commissioning);
        ck_assert(f.node_id.given);
        ck_assert_uint_eq(f.node_id.value, 1);
        ck_assert_uint_eq(f.node_id.line, 15);
        ck_assert_uint_eq(f.expected[2].vendor.value, 0x360);
        ck_assert_uint_eq(f.expected[2].product.value, 2);
        ck_assert_uint_eq(f.expected[2].revision.value, 3);
        ck_assert_uint_eq(f.expected[2].serial.value, 4);
        for (unsigned n = 1; n <= DCF_SUB_MAX; n++)
                if (n != 2)
                        ck_assert(!f.expected[n].serial.given && !f.expected[n].vendor.given);
        ck_assert(!f.serial.given);
        dcf_file_done(&f);
        ck_assert_uint_eq(d.n_messages, 0);
}
END_TEST

/* lely-core's LSS slave: an identity (DefaultValue), no [DeviceComissioning]:
 * left out; the serial number's DefaultValue is not a serial number. */
START_TEST(lely_lss_slave_is_not_commissioned) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_file f;
        parse_data("lely-coapp-lss-slave.dcf", &f, &d);
        ck_assert(!f.master && !f.commissioning && !f.node_id.given);
        ck_assert_uint_eq(f.vendor.value, 0x360);
        ck_assert_uint_eq(f.product.value, 2);
        ck_assert_uint_eq(f.revision.value, 3);
        ck_assert(!f.serial.given);
        dcf_file_done(&f);
        ck_assert_uint_eq(d.n_messages, 0);
        expect_left_out_alone("lely-coapp-lss-slave.dcf", 1, "no [DeviceComissioning] NodeID");
}
END_TEST

/* canopen-python's sample: NodeID 0x10 and a NodeName, LSS_SerialNumber=0,
 * [1018sub4] without a value: left out for want of a serial number. Its
 * $NODEID expressions are what CiA 306 numbers look like. */
START_TEST(canopen_python_sample) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_file f;
        parse_data("canopen-python-sample.eds", &f, &d);
        ck_assert_uint_eq(f.node_id.value, 0x10);
        ck_assert_str_eq(f.node_name, "Some name");
        ck_assert_uint_eq(f.baudrate.value, 500);
        ck_assert_uint_eq(f.vendor.value, 1);
        ck_assert(!f.product.given && !f.revision.given && !f.serial.given);
        dcf_file_done(&f);
        ck_assert_uint_eq(d.n_messages, 0);
        expect_left_out_alone("canopen-python-sample.eds", 33, "no serial number");

        /* every DefaultValue with $NODEID in the file: NODEID + a constant */
        size_t len, seen = 0;
        char *p = data_path("canopen-python-sample.eds");
        char *text = slurp(p, &len);
        for (char *line = strtok(text, "\r\n"); line; line = strtok(NULL, "\r\n")) {
                if (strncmp(line, "DefaultValue=", 13) != 0 || !strstr(line, "$NODEID"))
                        continue;
                const char *v = line + 13;
                uint32_t a, b;
                ck_assert_int_eq(dcf_parse_number(v, strlen(v), 0x10, &a), 0);
                ck_assert_int_eq(dcf_parse_number(v, strlen(v), 0x20, &b), 0);
                ck_assert_uint_eq(b - a, 0x10);
                ck_assert_uint_ge(a, 0x10 + 0x180);
                ck_assert_int_eq(dcf_parse_number(v, strlen(v), -1, &a), -ENOENT);
                seen++;
        }
        ck_assert_uint_ge(seen, 8);
        free(text);
        free(p);
}
END_TEST

/* canopen-python's e35 example: [DeviceInfo] and 1018h disagree; 1018h wins, warned. */
START_TEST(canopen_python_e35_identity_disagrees) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_file f;
        parse_data("canopen-python-e35.eds", &f, &d);
        ck_assert_uint_eq(f.vendor.value, 0xFF);
        ck_assert_uint_eq(f.product.value, 0x01);
        ck_assert_uint_eq(f.revision.value, 0x01);
        dcf_file_done(&f);
        ck_assert_uint_eq(d.n_errors, 0);
        ck_assert_uint_eq(d.n_warnings, 3);
        expect_message(&d, LSSCONF_DIAG_WARNING, "canopen-python-e35.eds:89: [1018sub1] gives vendor-ID 0x000000FF",
                       "[DeviceInfo] VendorNumber at line 16 0x00000065", "0x000000FF is taken");
        expect_message(&d, LSSCONF_DIAG_WARNING, "[1018sub2] gives product code 0x00000001", "ProductNumber");
        expect_message(&d, LSSCONF_DIAG_WARNING, "[1018sub3] gives revision 0x00000001", "0x00000127");
        lssconf_diag_clear(&d);
}
END_TEST

/* Elmo's CANeds output (ros_canopen): CRLF line ends, the identity in
 * ParameterValue, no [DeviceComissioning]. */
START_TEST(whistle_gold_crlf) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_file f;
        parse_data("ros_canopen-Whistle-Gold-V002.dcf", &f, &d);
        ck_assert_uint_eq(f.vendor.value, 0x9A);
        ck_assert_uint_eq(f.product.value, 0x30923);
        ck_assert_uint_eq(f.revision.value, 0x103F6);
        ck_assert(f.serial.given);
        ck_assert_uint_eq(f.serial.value, 0x5555555);
        ck_assert(!f.commissioning && !f.master);
        dcf_file_done(&f);
        ck_assert_uint_eq(d.n_messages, 0);
        expect_left_out_alone("ros_canopen-Whistle-Gold-V002.dcf", 1, "no [DeviceComissioning] NodeID");
}
END_TEST

/* Technosoft's (ros_canopen): [DeviceCommissioning] spelt right, NodeId=0;
 * VendorNumber=419 is 1018h's 0x1A3. */
START_TEST(isd860_commissioning_spelling) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_file f;
        parse_data("ros_canopen-ISD860.dcf", &f, &d);
        ck_assert(f.commissioning);
        ck_assert_uint_eq(f.commissioning_line, 51);
        ck_assert(f.node_id.given);
        ck_assert_uint_eq(f.node_id.value, 0);
        ck_assert_uint_eq(f.vendor.value, 0x1A3);
        ck_assert_uint_eq(f.product.value, 0);
        dcf_file_done(&f);
        ck_assert_uint_eq(d.n_messages, 0);
        expect_left_out_alone("ros_canopen-ISD860.dcf", 52, "NodeID 0 is out of 1..127");
}
END_TEST

/* A master DCF by lely's dcfgen (ros_canopen): vendors expected at node-IDs
 * 2 and 3, no serial numbers: left out, each saying so. */
START_TEST(ros_master_without_serial_numbers) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_map m;
        dcf_map_init(&m);
        ck_assert_int_eq(read_data(&m, "ros_canopen-master.dcf", &d), 0);
        ck_assert_uint_eq(m.n_entries, 0);
        ck_assert_uint_eq(m.n_left_out, 2);
        ck_assert_uint_eq(m.left_out[0].line, 763);
        ck_assert_uint_eq(m.left_out[1].line, 764);
        ck_assert_ptr_nonnull(strstr(m.left_out[0].why, "1F88h sub 2 gives no serial number"));
        dcf_map_done(&m);
        ck_assert_uint_eq(d.n_messages, 0);
}
END_TEST

/* Every public file at once (lssctl import-dcf of the folder): one entry. */
START_TEST(all_public_files) {
        static const char *const files[] = {
                "canopen-python-e35.eds", "canopen-python-sample.eds", "lely-co-nmt-master.dcf",
                "lely-co-nmt-slave.dcf", "lely-coapp-lss-slave.dcf", "ros_canopen-ISD860.dcf",
                "ros_canopen-Whistle-Gold-V002.dcf", "ros_canopen-master.dcf",
        };
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_map m;
        dcf_map_init(&m);
        for (size_t i = 0; i < sizeof(files) / sizeof(files[0]); i++)
                ck_assert_int_eq(read_data(&m, files[i], &d), 0);
        ck_assert_uint_eq(d.n_errors, 0);
        ck_assert_uint_eq(m.n_entries, 1);
        expect_identity(&m.entries[0], 0x360, 2, 3, true, 4, 2);
        ck_assert_uint_eq(m.n_left_out, 7);
        dcf_map_done(&m);
        lssconf_diag_clear(&d);
}
END_TEST

/* ---- numbers ---- */

static const struct number_case {
        const char *text;
        int node_id;
        int result;
        uint32_t value;
} number_cases[] = {
        { "10", -1, 0, 10 },
        { "0x0A", -1, 0, 10 },
        { "0X0a", -1, 0, 10 },
        { "012", -1, 0, 10 },          /* octal */
        { "0", -1, 0, 0 },
        { "00", -1, 0, 0 },
        { " 5 ", -1, 0, 5 },
        { "5 ; a comment", -1, 0, 5 },
        { "5;", -1, 0, 5 },
        { "4294967295", -1, 0, 0xFFFFFFFFu },
        { "0xFFFFFFFF", -1, 0, 0xFFFFFFFFu },
        { "0x00000000FFFFFFFF", -1, 0, 0xFFFFFFFFu },
        { "$NODEID+0x180", 5, 0, 0x185 },
        { "$nodeid + 0x180", 5, 0, 0x185 },
        { "0x180+$NODEID", 5, 0, 0x185 },
        { "$NODEID", 127, 0, 127 },
        { "$NODEID-1", 5, 0, 4 },
        { "1+2+3", -1, 0, 6 },
        { "0xFFFFFFFF+1-1", -1, -ERANGE, 0 },
        { "", -1, -ENODATA, 0 },
        { "   ", -1, -ENODATA, 0 },
        { "; only a comment", -1, -ENODATA, 0 },
        { "08", -1, -EINVAL, 0 },
        { "0x", -1, -EINVAL, 0 },
        { "0xG", -1, -EINVAL, 0 },
        { "12abc", -1, -EINVAL, 0 },
        { "1.5", -1, -EINVAL, 0 },
        { "1e3", -1, -EINVAL, 0 },
        { "0b101", -1, -EINVAL, 0 },
        { "+5", -1, -EINVAL, 0 },
        { "-5", -1, -EINVAL, 0 },
        { "5+", -1, -EINVAL, 0 },
        { "5 5", -1, -EINVAL, 0 },
        { "$NODE", 5, -EINVAL, 0 },
        { "$NODEIDS", 5, -EINVAL, 0 },
        { "abc", -1, -EINVAL, 0 },
        { "4294967296", -1, -ERANGE, 0 },
        { "0x100000000", -1, -ERANGE, 0 },
        { "99999999999999999999999", -1, -ERANGE, 0 },
        { "$NODEID-6", 5, -ERANGE, 0 },
        { "$NODEID+0x180", -1, -ENOENT, 0 },
};

START_TEST(numbers) {
        const struct number_case *c = &number_cases[_i];
        uint32_t v = 0xDEADBEEF;
        int r = dcf_parse_number(c->text, strlen(c->text), c->node_id, &v);
        ck_assert_msg(r == c->result, "\"%s\": got %d, want %d", c->text, r, c->result);
        if (r == 0)
                ck_assert_msg(v == c->value, "\"%s\": got 0x%X, want 0x%X", c->text, v, c->value);
}
END_TEST

/* ---- hand-made files ---- */

#define DEVICE(node_id, serial) \
        "[DeviceInfo]\nVendorNumber=0xEC\nProductNumber=0x1234\nRevisionNumber=0x10002\n" \
        "[DeviceComissioning]\nNodeID=" node_id "\nNodeName=drive\nLSS_SerialNumber=" serial "\n"

START_TEST(device_dcf) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_map m;
        dcf_map_init(&m);
        ck_assert_int_eq(read_text(&m, "a.dcf", DEVICE("5", "0x1276"), &d), 0);
        ck_assert_uint_eq(m.n_entries, 1);
        expect_identity(&m.entries[0], 0xEC, 0x1234, 0x10002, true, 0x1276, 5);
        ck_assert_uint_eq(m.entries[0].line, 6);
        ck_assert_str_eq(m.entries[0].node_name, "drive");
        ck_assert_uint_eq(d.n_messages, 0);
        dcf_map_done(&m);

        /* the serial number from 1018h when LSS_SerialNumber is 0; 1018h's
         * identity over [DeviceInfo]'s; $NODEID where the value uses it */
        dcf_map_init(&m);
        ck_assert_int_eq(read_text(&m, "b.dcf",
                                   "[1018sub4]\nDefaultValue=7\nParameterValue=$NODEID+0x1000\n"
                                   "[1018sub1]\nDefaultValue=0x9A\n"
                                   DEVICE("9", "0"), &d), 0);
        ck_assert_uint_eq(m.n_entries, 1);
        expect_identity(&m.entries[0], 0x9A, 0x1234, 0x10002, true, 0x1009, 9);
        expect_message(&d, LSSCONF_DIAG_WARNING, "b.dcf:5: [1018sub1] gives vendor-ID 0x0000009A",
                       "VendorNumber at line 7 0x000000EC");
        lssconf_diag_clear(&d);
        dcf_map_done(&m);

        /* LSS_SerialNumber over a different 1018h serial number, warned */
        dcf_map_init(&m);
        ck_assert_int_eq(read_text(&m, "c.dcf", DEVICE("9", "0x55") "[1018sub4]\nParameterValue=0x66\n", &d), 0);
        ck_assert_uint_eq(m.entries[0].identity.serial, 0x55);
        expect_message(&d, LSSCONF_DIAG_WARNING, "c.dcf:8: LSS_SerialNumber is 0x00000055",
                       "[1018sub4] ParameterValue at line 10 0x00000066", "0x00000055 is taken");
        lssconf_diag_clear(&d);
        dcf_map_done(&m);

        /* no revision: any revision */
        dcf_map_init(&m);
        ck_assert_int_eq(read_text(&m, "d.dcf", "[DeviceInfo]\nVendorNumber=1\nProductNumber=2\n"
                                   "[DeviceComissioning]\nNodeID=3\nLSS_SerialNumber=4\n", &d), 0);
        expect_identity(&m.entries[0], 1, 2, 0, false, 4, 3);
        dcf_map_done(&m);
        ck_assert_uint_eq(d.n_messages, 0);
}
END_TEST

/* What Windows tools write: a byte order mark, CRLF, other case, comments. */
START_TEST(crlf_bom_case_comments) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_map m;
        dcf_map_init(&m);
        ck_assert_int_eq(read_text(&m, "w.dcf",
                                   "\xEF\xBB\xBF[FileInfo]\r\n"
                                   "; a comment\r\n"
                                   "# another\r\n"
                                   "Some junk line outside what is read\r\n"
                                   "\r\n"
                                   "[ deviceinfo ]  ; the section\r\n"
                                   "vendornumber = 0x000000ec ; the vendor\r\n"
                                   "PRODUCTNUMBER=4660\r\n"
                                   "[DEVICECOMMISSIONING]\r\n"
                                   "nodeid=010\r\n"
                                   "NodeName = Left drive; rear\r\n"
                                   "lss_serialnumber=0x1276\r\n"
                                   "[1018Sub3]\r\n"
                                   "ParameterValue=\r\n"
                                   "DefaultValue=0x00010002\r", &d), 0);
        if (d.n_messages)
                dump(&d);
        ck_assert_uint_eq(d.n_messages, 0);
        ck_assert_uint_eq(m.n_entries, 1);
        expect_identity(&m.entries[0], 0xEC, 0x1234, 0x10002, true, 0x1276, 8); /* 010 is octal */
        ck_assert_uint_eq(m.entries[0].line, 10);
        ck_assert_str_eq(m.entries[0].node_name, "Left drive; rear");
        dcf_map_done(&m);
}
END_TEST

START_TEST(devices_left_out) {
        static const struct {
                const char *text;
                const char *why;
                unsigned line;
        } cases[] = {
                { DEVICE("255", "1"), "NodeID 255: non-configured", 6 },
                { DEVICE("0", "1"), "NodeID 0 is out of 1..127", 6 },
                { DEVICE("128", "1"), "NodeID 128 is out of 1..127", 6 },
                { DEVICE("0x1FF", "1"), "NodeID 511 is out of 1..127", 6 },
                { DEVICE("5", "0"), "no serial number", 6 },
                { DEVICE("5", "0") "[1018sub4]\nDefaultValue=0x1234\n", "no serial number", 6 },
                { "[DeviceComissioning]\nNodeID=5\nLSS_SerialNumber=1\n[DeviceInfo]\nProductNumber=1\n",
                  "no vendor-ID", 2 },
                { "[DeviceComissioning]\nNodeID=5\nLSS_SerialNumber=1\n[1018sub1]\nParameterValue=1\n",
                  "no product code", 2 },
                { "[DeviceInfo]\nVendorNumber=1\n", "no [DeviceComissioning] NodeID", 1 },
                { "", "no [DeviceComissioning] NodeID", 1 },
        };
        for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
                lssconf_diag d = LSSCONF_DIAG_INIT;
                dcf_map m;
                dcf_map_init(&m);
                ck_assert_int_eq(read_text(&m, "l.dcf", cases[i].text, &d), 0);
                ck_assert_uint_eq(d.n_messages, 0);
                ck_assert_uint_eq(m.n_entries, 0);
                ck_assert_uint_eq(m.n_left_out, 1);
                ck_assert_msg(strstr(m.left_out[0].why, cases[i].why), "case %zu: %s", i, m.left_out[0].why);
                ck_assert_uint_eq(m.left_out[0].line, cases[i].line);
                dcf_map_done(&m);
        }
}
END_TEST

/* Sub-objects and compact arrays; 0 is "not checked". */
START_TEST(master_dcf) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_map m;
        dcf_map_init(&m);
        ck_assert_int_eq(read_text(&m, "master.dcf",
                                   "[DeviceComissioning]\n"          /* 1 */
                                   "NodeID=1\n"
                                   "[1F85]\nObjectType=0x8\nCompactSubObj=127\n"
                                   "[1F85Value]\n"                   /* 6 */
                                   "NrOfEntries=4\n"
                                   "5=0xEC\n6=0xEC\n7=0xEC\n0x0A=0xEC\n"
                                   "[1F86Value]\n"                   /* 12 */
                                   "5=0x1234\n6=0x1234\n7=0x1234\n10=0x1234\n"
                                   "[1F87sub5]\nParameterValue=0x10002\n" /* 17 */
                                   "[1F87sub6]\nParameterValue=0\n"
                                   "[1F88sub5]\nParameterValue=0x1001\n"  /* 21 */
                                   "[1F88sub6]\nDefaultValue=0x1002\n"
                                   "[1F88sub7]\nParameterValue=0\nDefaultValue=0x1003\n"
                                   "[1F88subA]\nParameterValue=$NODEID+0x1009\n" /* 28 */
                                   "[1F88sub80]\nParameterValue=0x1080\n"
                                   "[1F88sub9]\nParameterValue=0x1009\n"          /* 32: no vendor */
                                   "[1F88Name]\n5=left\n", &d), 0);
        if (d.n_messages)
                dump(&d);
        ck_assert_uint_eq(d.n_messages, 0);
        ck_assert_uint_eq(m.n_entries, 3);
        expect_identity(&m.entries[0], 0xEC, 0x1234, 0x10002, true, 0x1001, 5);
        ck_assert_uint_eq(m.entries[0].line, 22);
        expect_identity(&m.entries[1], 0xEC, 0x1234, 0, false, 0x1002, 6);  /* 1F87h 0: any revision */
        expect_identity(&m.entries[2], 0xEC, 0x1234, 0, false, 0x100A, 10); /* $NODEID is the master's */
        ck_assert_uint_eq(m.entries[2].line, 29);
        ck_assert_uint_eq(m.n_left_out, 3);
        ck_assert_ptr_nonnull(strstr(m.left_out[0].why, "sub-index 7 of 1F85h/1F86h names a device, but 1F88h sub 7 "
                                     "gives no serial number"));
        ck_assert_uint_eq(m.left_out[0].line, 10);
        ck_assert_ptr_nonnull(strstr(m.left_out[1].why, "node-ID 9: 1F85h sub 9 gives no vendor-ID"));
        ck_assert_uint_eq(m.left_out[1].line, 33);
        ck_assert_ptr_nonnull(strstr(m.left_out[2].why, "1F88h sub-index 128 (0x80) is no node-ID"));
        dcf_map_done(&m);
}
END_TEST

/* ---- errors ---- */

START_TEST(file_errors) {
        expect_file_error("[DeviceComissioning]\nNodeID=0x\n", "t.dcf:2: [DeviceComissioning] NodeID: \"0x\" is not a "
                          "number");
        expect_file_error("[DeviceComissioning]\nNodeID=5\nLSS_SerialNumber=08\n", "t.dcf:3:", "LSS_SerialNumber",
                          "\"08\" is not a number");
        expect_file_error("[DeviceComissioning]\nNodeID=5\nLSS_SerialNumber=0x1FFFFFFFF\n", "t.dcf:3:",
                          "is out of range 0..0xFFFFFFFF");
        expect_file_error("[DeviceInfo]\nVendorNumber=Lely\n", "t.dcf:2: [DeviceInfo] VendorNumber: \"Lely\" is not "
                          "a number");
        expect_file_error("[1018sub2]\nParameterValue=0x12 0x34\n", "t.dcf:2: [1018sub2] ParameterValue");
        expect_file_error("[1018sub3]\nDefaultValue=1.0\n", "t.dcf:2: [1018sub3] DefaultValue");
        expect_file_error("[1F88sub5]\nParameterValue=x\n", "t.dcf:2: [1F88sub5] ParameterValue");
        expect_file_error("[1F85Value]\n5=0xZZ\n", "t.dcf:2: [1F85Value] 5: \"0xZZ\"");
        expect_file_error("[DeviceComissioning]\nNodeName=x\n", "t.dcf:1: [DeviceComissioning] without NodeID");
        expect_file_error("[DeviceComissioning]\nNodeID=\n", "t.dcf:1: [DeviceComissioning] without NodeID");
        expect_file_error("[DeviceComissioning]\nNodeID=$NODEID\n", "t.dcf:2:", "uses $NODEID");
        expect_file_error("[1018sub4]\nParameterValue=$NODEID+1\n", "t.dcf:2:", "uses $NODEID, but "
                          "[DeviceComissioning] gives no NodeID");
        expect_file_error("[DeviceInfo\nVendorNumber=1\n", "t.dcf:1: section header without ']'");
        expect_file_error("[DeviceInfo] x\n", "t.dcf:1: text after the section header");
        expect_file_error("[DeviceComissioning]\nNodeID=5\nNodeID=6\n", "t.dcf:3: [DeviceComissioning] \"NodeID\": "
                          "given again (first at line 2)");
        expect_file_error("[1018sub1]\nParameterValue=1\n[1018sub1]\nParameterValue=2\n", "t.dcf:4: [1018sub1] "
                          "\"ParameterValue\": given again (first at line 2)");
        expect_file_error("[1F88Value]\n5=1\n[1F88sub5]\nParameterValue=1\n", "t.dcf:4:", "given again");
        expect_file_error("[DeviceComissioning]\nNodeID 5\n", "t.dcf:2: [DeviceComissioning]: \"NodeID 5\" is not "
                          "KEY=VALUE");
        expect_file_error("[1F88Value]\n0=5\n", "t.dcf:2: [1F88Value]: \"0\" is not a sub-index (1..255)");
        expect_file_error("[1F88Value]\nfive=5\n", "t.dcf:2: [1F88Value]: \"five\" is not a sub-index");
        /* the entry of a file with an error is not added, nor its left-out devices */
        expect_file_error(DEVICE("5", "1") "[1F88sub5]\nParameterValue=1\n[1F85Value]\n5=x\n", "t.dcf:12:");

        /* a NUL byte, and one of the messages every error makes */
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_map m;
        dcf_map_init(&m);

        /* a long value is quoted bounded; one that just fits whole */
#define LONG55 "012345678901234567890123456789012345678901234567890123z"
        char text[200];
        snprintf(text, sizeof(text), "[DeviceComissioning]\nNodeID=%0120d\n", 9);
        text[28 + 16] = 'x'; /* after "[DeviceComissioning]\nNodeID=" and 16 zeros */
        ck_assert_int_eq(read_text(&m, "q.dcf", text, &d), -EINVAL);
        expect_message(&d, LSSCONF_DIAG_ERROR, "q.dcf:2: [DeviceComissioning] NodeID: \"0000000000000000x", "...\" is not");
        lssconf_diag_clear(&d);
        ck_assert_int_eq(read_text(&m, "q.dcf", "[DeviceComissioning]\nNodeID=" LONG55 "\n",
                                   &d), -EINVAL);
        expect_message(&d, LSSCONF_DIAG_ERROR, "NodeID: \"" LONG55 "\" is not"); /* as long as fits */
        lssconf_diag_clear(&d);
        ck_assert_int_eq(dcf_map_read_buffer(&m, "[DeviceInfo]\n\0x", 15, "n.dcf", &d), -EINVAL);
        expect_message(&d, LSSCONF_DIAG_ERROR, "n.dcf:2: NUL byte, this is not a text file");
        lssconf_diag_clear(&d);

        ck_assert_int_eq(dcf_map_read_file(&m, "/nonexistent/x.dcf", &d), -ENOENT);
        expect_message(&d, LSSCONF_DIAG_ERROR, "/nonexistent/x.dcf: cannot open: No such file or directory");
        ck_assert_uint_eq(m.n_entries, 0);
        dcf_map_done(&m);
        lssconf_diag_clear(&d);
}
END_TEST

START_TEST(conflicts_between_files) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_map m;

        /* one serial number, two node-IDs */
        dcf_map_init(&m);
        ck_assert_int_eq(read_text(&m, "a.dcf", DEVICE("5", "0x1276"), &d), 0);
        ck_assert_int_eq(read_text(&m, "b.dcf", DEVICE("6", "0x1276"), &d), -EINVAL);
        expect_message(&d, LSSCONF_DIAG_ERROR, "b.dcf:6: one device gets two node-IDs: vendor 0x000000EC, product "
                       "0x00001234, serial 0x00001276 gets node-ID 6 here and node-ID 5 at a.dcf:6");
        ck_assert_uint_eq(m.n_entries, 1);
        lssconf_diag_clear(&d);

        /* one node-ID, two devices */
        ck_assert_int_eq(read_text(&m, "c.dcf", DEVICE("5", "0x1277"), &d), -EINVAL);
        expect_message(&d, LSSCONF_DIAG_ERROR, "c.dcf:6: node-ID 5 is given to two devices: vendor 0x000000EC, "
                       "product 0x00001234, revision 0x00010002, serial 0x00001277 here, ",
                       "serial 0x00001276 at a.dcf:6");
        lssconf_diag_clear(&d);

        /* the master names a.dcf's device at node-ID 5 with another revision: two devices */
        ck_assert_int_eq(read_text(&m, "m.dcf", "[1F85sub5]\nParameterValue=0xEC\n[1F86sub5]\nParameterValue=0x1234\n"
                                   "[1F87sub5]\nParameterValue=0x10003\n[1F88sub5]\nParameterValue=0x1276\n", &d),
                         -EINVAL);
        expect_message(&d, LSSCONF_DIAG_ERROR, "m.dcf:8: node-ID 5 is given to two devices", "revision 0x00010003",
                       "at a.dcf:6");
        lssconf_diag_clear(&d);

        /* ... and with any revision: the same device, one entry */
        ck_assert_int_eq(read_text(&m, "m2.dcf", "[1F85sub5]\nParameterValue=0xEC\n[1F86sub5]\nParameterValue=0x1234\n"
                                   "[1F88sub5]\nParameterValue=0x1276\n", &d), 0);
        ck_assert_uint_eq(m.n_entries, 1);
        ck_assert(m.entries[0].merged);
        ck_assert_str_eq(m.files[m.entries[0].also_file].name, "m2.dcf");
        ck_assert_uint_eq(m.entries[0].also_line, 6);
        ck_assert(m.entries[0].has_revision);
        dcf_map_done(&m);

        /* the master first, any revision; the device's DCF gives it */
        dcf_map_init(&m);
        ck_assert_int_eq(read_text(&m, "m2.dcf", "[1F85sub5]\nParameterValue=0xEC\n[1F86sub5]\nParameterValue=0x1234\n"
                                   "[1F88sub5]\nParameterValue=0x1276\n", &d), 0);
        ck_assert_int_eq(read_text(&m, "a.dcf", DEVICE("5", "0x1276"), &d), 0);
        ck_assert_uint_eq(m.n_entries, 1);
        expect_identity(&m.entries[0], 0xEC, 0x1234, 0x10002, true, 0x1276, 5);
        ck_assert_str_eq(m.entries[0].node_name, "drive");
        ck_assert_uint_eq(m.files[0].n_entries, 1);
        ck_assert_uint_eq(m.files[1].n_entries, 1);
        dcf_map_done(&m);

        /* within one master: a serial number at two sub-indices */
        dcf_map_init(&m);
        ck_assert_int_eq(read_text(&m, "m3.dcf", "[1F85Value]\n5=1\n6=1\n[1F86Value]\n5=2\n6=2\n[1F88Value]\n"
                                   "5=0x77\n6=0x77\n", &d), -EINVAL);
        expect_message(&d, LSSCONF_DIAG_ERROR, "m3.dcf:9: one device gets two node-IDs", "gets node-ID 6 here and "
                       "node-ID 5 at m3.dcf:8");
        ck_assert_uint_eq(m.n_entries, 0);
        dcf_map_done(&m);
        ck_assert_uint_eq(d.n_errors, 1);
        lssconf_diag_clear(&d);

        /* another vendor's serial number is another device */
        dcf_map_init(&m);
        ck_assert_int_eq(read_text(&m, "a.dcf", DEVICE("5", "0x1276"), &d), 0);
        ck_assert_int_eq(read_text(&m, "x.dcf", "[DeviceInfo]\nVendorNumber=0x9A\nProductNumber=0x1234\n"
                                   "[DeviceComissioning]\nNodeID=6\nLSS_SerialNumber=0x1276\n", &d), 0);
        ck_assert_uint_eq(m.n_entries, 2);
        dcf_map_done(&m);
        ck_assert_uint_eq(d.n_messages, 0);
}
END_TEST

/* lssd.conf's own entries against the DCFs' */
START_TEST(config_entries) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lss_identity id = { 0xEC, 0x1234, 0x10002, 0x1276 }, other = { 0xEC, 0x1234, 0x10002, 0x1277 };
        dcf_map m;
        dcf_map_init(&m);
        ck_assert_int_eq(dcf_map_add_config(&m, "lssd.conf", 10, &id, false, 5, &d), 0);
        /* the configuration's entries are not checked against each other */
        ck_assert_int_eq(dcf_map_add_config(&m, "lssd.conf", 11, &other, false, 5, &d), 0);
        ck_assert_uint_eq(m.n_files, 1);
        ck_assert_uint_eq(d.n_messages, 0);
        /* the same from a DCF: merged into the configuration's, which keeps its revision (any) */
        ck_assert_int_eq(read_text(&m, "a.dcf", DEVICE("5", "0x1276"), &d), 0);
        ck_assert_uint_eq(m.n_entries, 2);
        ck_assert(m.entries[0].merged && !m.entries[0].has_revision);
        ck_assert_uint_eq(m.entries[0].also_line, 6);
        /* in conflict with it */
        ck_assert_int_eq(read_text(&m, "b.dcf", DEVICE("7", "0x1276"), &d), -EINVAL);
        expect_message(&d, LSSCONF_DIAG_ERROR, "b.dcf:6: one device gets two node-IDs", "node-ID 5 at lssd.conf:10");
        lssconf_diag_clear(&d);
        dcf_map_done(&m);

        /* a DCF first, then the configuration */
        dcf_map_init(&m);
        ck_assert_int_eq(read_text(&m, "a.dcf", DEVICE("5", "0x1276"), &d), 0);
        ck_assert_int_eq(dcf_map_add_config(&m, "lssd.conf", 10, &other, true, 5, &d), -EINVAL);
        expect_message(&d, LSSCONF_DIAG_ERROR, "lssd.conf:10: node-ID 5 is given to two devices", "at a.dcf:6");
        dcf_map_done(&m);
        lssconf_diag_clear(&d);
}
END_TEST

START_TEST(network_of_the_files) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        dcf_map m;
        dcf_map_init(&m);
        ck_assert_int_eq(read_text(&m, "a.dcf", DEVICE("5", "1") "Baudrate=500\nNetNumber=1\n", &d), 0);
        ck_assert_int_eq(read_text(&m, "b.dcf", DEVICE("6", "2") "Baudrate=500\n", &d), 0);
        /* a file without entries does not count */
        ck_assert_int_eq(read_text(&m, "c.dcf", DEVICE("255", "3") "Baudrate=125\n", &d), 0);
        ck_assert_uint_eq(dcf_map_baudrate(&m, &d), 500);
        ck_assert_uint_eq(d.n_messages, 0);
        ck_assert_int_eq(read_text(&m, "e.dcf", DEVICE("7", "4") "Baudrate=250\nNetNumber=2\n", &d), 0);
        ck_assert_uint_eq(dcf_map_baudrate(&m, &d), 0);
        expect_message(&d, LSSCONF_DIAG_WARNING, "e.dcf:9: Baudrate 250 kbit/s, but a.dcf:9 says 500 kbit/s: the "
                       "DCFs are not of one network");
        expect_message(&d, LSSCONF_DIAG_WARNING, "e.dcf:10: NetNumber 2, but a.dcf:10 says 1");
        dcf_map_done(&m);
        lssconf_diag_clear(&d);
}
END_TEST

static void add_tests(TCase *tc) {
        tcase_add_test(tc, lely_slave_and_master_are_one_entry);
        tcase_add_test(tc, lely_master_as_parsed);
        tcase_add_test(tc, lely_lss_slave_is_not_commissioned);
        tcase_add_test(tc, canopen_python_sample);
        tcase_add_test(tc, canopen_python_e35_identity_disagrees);
        tcase_add_test(tc, whistle_gold_crlf);
        tcase_add_test(tc, isd860_commissioning_spelling);
        tcase_add_test(tc, ros_master_without_serial_numbers);
        tcase_add_test(tc, all_public_files);
        tcase_add_loop_test(tc, numbers, 0, sizeof(number_cases) / sizeof(number_cases[0]));
        tcase_add_test(tc, device_dcf);
        tcase_add_test(tc, crlf_bom_case_comments);
        tcase_add_test(tc, devices_left_out);
        tcase_add_test(tc, master_dcf);
        tcase_add_test(tc, file_errors);
        tcase_add_test(tc, conflicts_between_files);
        tcase_add_test(tc, config_entries);
        tcase_add_test(tc, network_of_the_files);
}

int main(void) {
        return check_main("dcf", add_tests);
}
