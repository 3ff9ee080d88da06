/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <check.h>
#include <dirent.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "config/lssconf.h"
#include "diag-util.h"
#include "sim/sim_random.h"
#include "util/time_util.h"

/* ---- helpers ---- */

static char *test_data_path(const char *rel) {
        const char *dir = getenv("LSSD_TEST_DATA");
        char *p;
        ck_assert_msg(dir, "LSSD_TEST_DATA is not set (run through meson test)");
        ck_assert_int_ge(asprintf(&p, "%s/%s", dir, rel), 0);
        return p;
}

/* A temporary file holding len bytes of text; the caller unlinks and frees. */
static char *write_temp(const char *text, size_t len) {
        const char *tmp = getenv("TMPDIR");
        char *path;
        ck_assert_int_ge(asprintf(&path, "%s/lssd-test-config-XXXXXX", tmp && *tmp ? tmp : "/tmp"), 0);
        int fd = mkstemp(path);
        ck_assert_int_ge(fd, 0);
        for (size_t done = 0; done < len; ) {
                ssize_t k = write(fd, text + done, len - done);
                ck_assert_int_gt(k, 0);
                done += (size_t) k;
        }
        ck_assert_int_eq(close(fd), 0);
        return path;
}

/* Loads text through a real file, as the daemon does. */
static int load_len(const char *text, size_t len, lssconf **ret, lssconf_diag *d) {
        char *path = write_temp(text, len);
        int r = lssconf_load_file(path, ret, d);
        ck_assert_int_eq(unlink(path), 0);
        free(path);
        /* the contract: config on success only, and an error message on failure */
        if (r < 0) {
                ck_assert_ptr_null(*ret);
                ck_assert(lssconf_diag_has_errors(d));
        } else
                ck_assert_ptr_nonnull(*ret);
        return r;
}

static int load(const char *text, lssconf **ret, lssconf_diag *d) {
        return load_len(text, strlen(text), ret, d);
}

/* The text must fail to load with an error carrying all the substrings. */
#define expect_load_error(text, ...) \
        do { \
                lssconf_diag _d = LSSCONF_DIAG_INIT; \
                lssconf *_c = NULL; \
                ck_assert_int_eq(load(text, &_c, &_d), -EINVAL); \
                expect_message(&_d, LSSCONF_DIAG_ERROR, __VA_ARGS__); \
                lssconf_diag_clear(&_d); \
        } while (0)

/* One device entry in an otherwise valid bus. */
static int load_device(const char *device, lssconf **ret, lssconf_diag *d) {
        char *text;
        ck_assert_int_ge(asprintf(&text,
                                  "buses = (\n"
                                  "  {\n"
                                  "    interface = \"can0\";\n"
                                  "    devices = (\n"
                                  "      { %s }\n"
                                  "    );\n"
                                  "  }\n"
                                  ");\n", device), 0);
        int r = load(text, ret, d);
        free(text);
        return r;
}

/* One key set in a bus that is otherwise minimal. */
static int load_bus_key(const char *key_value, lssconf **ret, lssconf_diag *d) {
        char *text;
        ck_assert_int_ge(asprintf(&text,
                                  "buses = (\n"
                                  "  {\n"
                                  "    interface = \"can0\";\n"
                                  "    %s\n"
                                  "  }\n"
                                  ");\n", key_value), 0);
        int r = load(text, ret, d);
        free(text);
        return r;
}

/* ---- happy paths ---- */

START_TEST(example_conf_loads_cleanly) {
        char *path = test_data_path("../../conf/lssd.conf");
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        int r = lssconf_load_file(path, &c, &d);
        if (r < 0 || d.n_messages)
                dump(&d);
        ck_assert_int_eq(r, 0);
        ck_assert_uint_eq(d.n_messages, 0);
        ck_assert_str_eq(c->source, path);

        ck_assert_uint_eq(c->lss_timeout_ms, 20);
        ck_assert_int_eq(c->lss_timing, LSSCONF_LSS_TIMING_ADAPTIVE);
        ck_assert_uint_eq(c->boot_ready_limit_s, 1800); /* commented out: the default */
        ck_assert_uint_eq(c->foreign_master_quiet_s, 3);
        ck_assert_uint_eq(c->n_buses, 2);
        const lssconf_bus *b = lssconf_find_bus(c, "can0");
        ck_assert_ptr_eq(b, &c->buses[0]);
        ck_assert_uint_eq(b->bitrate, 250000);
        ck_assert(b->auto_assign);
        ck_assert(b->store);
        ck_assert_int_eq(b->unknown, LSSCONF_UNKNOWN_POOL);
        ck_assert_uint_eq(b->pool_lo, 100);
        ck_assert_uint_eq(b->pool_hi, 110);
        ck_assert_uint_eq(b->lss_timeout_ms, 20);
        ck_assert_uint_eq(b->foreign_master_quiet_s, 3);
        ck_assert_uint_eq(b->n_devices, 4);
        ck_assert_uint_eq(b->devices[1].identity.serial, 0x80002468u);
        ck_assert(b->devices[1].has_revision);
        ck_assert_uint_eq(b->devices[2].identity.vendor, 0x9A);
        ck_assert_uint_eq(b->devices[3].identity.serial, 0xFFFFFFFFu);
        ck_assert_uint_eq(b->devices[3].identity.vendor, 0xEC);

        const lssconf_bus *b1 = lssconf_find_bus(c, "can1");
        ck_assert_ptr_eq(b1, &c->buses[1]);
        ck_assert_uint_eq(b1->n_devices, 0);
        ck_assert(!b1->auto_assign);
        lssconf_free(c);
        lssconf_diag_clear(&d);
        free(path);
}
END_TEST

START_TEST(all_keys) {
        char *path = test_data_path("config/all-keys.conf");
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        int r = lssconf_load_file(path, &c, &d);
        if (r < 0 || d.n_messages)
                dump(&d);
        ck_assert_int_eq(r, 0);
        ck_assert_uint_eq(d.n_messages, 0);

        ck_assert_uint_eq(c->lss_timeout_ms, 35);
        ck_assert_int_eq(c->lss_timing, LSSCONF_LSS_TIMING_FIXED);
        ck_assert_uint_eq(c->boot_ready_limit_s, 600);
        ck_assert_uint_eq(c->foreign_master_quiet_s, 10);
        ck_assert_uint_eq(c->n_buses, 2);

        const lssconf_bus *b = &c->buses[0];
        ck_assert_str_eq(b->interface, "can0");
        ck_assert_uint_eq(b->line, 5);
        ck_assert_uint_eq(b->bitrate, 500000);
        ck_assert(b->auto_assign);
        ck_assert(!b->store);
        ck_assert_int_eq(b->unknown, LSSCONF_UNKNOWN_POOL);
        ck_assert_uint_eq(b->pool_lo, 120);
        ck_assert_uint_eq(b->pool_hi, 126);
        ck_assert(b->nmt_stop);
        ck_assert(b->replace);
        ck_assert_uint_eq(b->lss_timeout_ms, 50);
        ck_assert_int_eq(b->lss_timing, LSSCONF_LSS_TIMING_ADAPTIVE);
        ck_assert_uint_eq(b->foreign_master_quiet_s, 7);
        ck_assert(b->has_vendor && b->has_product);
        ck_assert_uint_eq(b->vendor, 0xEC);
        ck_assert_uint_eq(b->product, 0x1234);
        ck_assert(b->bitrate_change);
        ck_assert_uint_eq(b->n_devices, 4);

        const lssconf_device *dev = &b->devices[0];
        ck_assert_uint_eq(dev->identity.vendor, 0xEC);
        ck_assert_uint_eq(dev->identity.product, 0x1234);
        ck_assert_uint_eq(dev->identity.serial, 0x1276);
        ck_assert(!dev->has_revision);
        ck_assert_uint_eq(dev->node_id, 5);
        ck_assert_uint_eq(dev->line, 20);
        dev = &b->devices[2];
        ck_assert_uint_eq(dev->identity.vendor, 0x9A);
        ck_assert_uint_eq(dev->identity.product, 3);
        ck_assert_uint_eq(dev->identity.serial, 17);
        ck_assert(dev->has_revision);
        ck_assert_uint_eq(dev->identity.revision, 0);
        ck_assert_uint_eq(dev->node_id, 127);

        /* the second bus inherits the global timing and timeout (0 = inherit) */
        b = &c->buses[1];
        ck_assert_str_eq(b->interface, "vcan-test_1.x");
        ck_assert_uint_eq(b->bitrate, 10000);
        ck_assert_uint_eq(b->lss_timeout_ms, 35);
        ck_assert_int_eq(b->lss_timing, LSSCONF_LSS_TIMING_FIXED);
        ck_assert_uint_eq(b->foreign_master_quiet_s, 10);
        ck_assert_int_eq(b->unknown, LSSCONF_UNKNOWN_POOL);
        ck_assert_uint_eq(b->pool_lo, 1);
        ck_assert_uint_eq(b->pool_hi, 1);
        ck_assert(!b->has_vendor && !b->has_product);
        ck_assert(b->store);
        lssconf_free(c);
        lssconf_diag_clear(&d);
        free(path);
}
END_TEST

START_TEST(defaults) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        ck_assert_int_eq(load("buses = ( { interface = \"can0\"; } );\n", &c, &d), 0);
        ck_assert_uint_eq(d.n_messages, 0);
        ck_assert_uint_eq(c->lss_timeout_ms, LSSCONF_LSS_TIMEOUT_MS_DEFAULT);
        ck_assert_int_eq(c->lss_timing, LSSCONF_LSS_TIMING_ADAPTIVE);
        ck_assert_uint_eq(c->boot_ready_limit_s, 1800);
        ck_assert_uint_eq(LSSCONF_BOOT_READY_LIMIT_S_DEFAULT, 1800);
        ck_assert_uint_eq(c->foreign_master_quiet_s, 3);
        const lssconf_bus *b = &c->buses[0];
        ck_assert_uint_eq(b->bitrate, 125000);
        ck_assert(!b->auto_assign);
        ck_assert(b->store);
        ck_assert(!b->nmt_stop);
        ck_assert(!b->replace);
        ck_assert(!b->bitrate_change);
        ck_assert_int_eq(b->unknown, LSSCONF_UNKNOWN_IGNORE);
        ck_assert_uint_eq(b->lss_timeout_ms, 20);
        ck_assert_int_eq(b->lss_timing, LSSCONF_LSS_TIMING_ADAPTIVE);
        ck_assert_uint_eq(b->foreign_master_quiet_s, 3);
        ck_assert_uint_eq(b->n_devices, 0);
        ck_assert_ptr_null(b->devices);
        lssconf_free(c);
        lssconf_diag_clear(&d);
}
END_TEST

START_TEST(every_bitrate) {
        for (unsigned i = 0; i < 256; i++) {
                uint32_t rate = lss_bit_timing_rate((uint8_t) i);
                if (!rate)
                        continue;
                char kv[64];
                lssconf_diag d = LSSCONF_DIAG_INIT;
                lssconf *c = NULL;
                snprintf(kv, sizeof(kv), "bitrate = %u;", rate);
                ck_assert_int_eq(load_bus_key(kv, &c, &d), 0);
                ck_assert_uint_eq(c->buses[0].bitrate, rate);
                lssconf_free(c);
                lssconf_diag_clear(&d);
        }
}
END_TEST

/* ---- 32-bit identity values on libconfig 1.5 ---- */

static const struct {
        const char *literal;
        bool ok;
        uint32_t value;
        const char *shown; /* how the error quotes it */
} u32_cases[] = {
        { "0xFFFFFFFF", true, 0xFFFFFFFFu, NULL },
        { "0x80000000", true, 0x80000000u, NULL },
        { "0x7FFFFFFF", true, 0x7FFFFFFFu, NULL },
        { "0x00000000", true, 0, NULL },
        { "4294967295", true, 0xFFFFFFFFu, NULL },
        { "2147483648", true, 0x80000000u, NULL },
        { "2147483647", true, 0x7FFFFFFFu, NULL },
        { "0", true, 0, NULL },
        { "+17", true, 17, NULL },
        { "4294967295L", true, 0xFFFFFFFFu, NULL },
        { "0xFFFFFFFFL", true, 0xFFFFFFFFu, NULL },
        { "0x0FFFFFFFF", true, 0xFFFFFFFFu, NULL },
        { "4294967296", false, 0, "4294967296 is out of range 0x0..0xFFFFFFFF" },
        { "-1", false, 0, "-1 is out of range" },
        { "-2147483648", false, 0, "-2147483648 is out of range" },
        { "-2147483649", false, 0, "-2147483649 is out of range" },
        { "0x1FFFFFFFF", false, 0, "0x1FFFFFFFF is out of range" },
        { "0x100000000", false, 0, "0x100000000 is out of range" },
        { "4294967296L", false, 0, "4294967296 is out of range" },
        { "0xFFFFFFFFFFFFFFFFL", false, 0, "0xFFFFFFFFFFFFFFFF is out of range" },
        { "0xFFFFFFFFFFFFFFFF", false, 0, "0xFFFFFFFFFFFFFFFF is out of range" },
        { "9223372036854775807", false, 0, "9223372036854775807 is out of range" },
        { "99999999999999999999", false, 0, "integer 99999999999999999999 does not fit in 64 bits" },
        { "0x10000000000000000", false, 0, "integer 0x10000000000000000 does not fit in 64 bits" },
        { "-9223372036854775809", false, 0, "does not fit in 64 bits" },
        { "1.0", false, 0, "expected an integer, got a float" },
        { "\"1\"", false, 0, "expected an integer, got a string" },
};

START_TEST(u32_values) {
        static const char *const fields[] = { "vendor", "product", "revision", "serial" };
        for (size_t f = 0; f < 4; f++) {
                char device[256];
                lssconf_diag d = LSSCONF_DIAG_INIT;
                lssconf *c = NULL;
                const char *field = fields[f];
                /* the field under test comes last so the others keep their defaults */
                snprintf(device, sizeof(device), "%s%s%s%s node_id = 1; %s = %s;",
                         f == 0 ? "" : "vendor = 1; ", f == 1 ? "" : "product = 2; ",
                         f == 2 ? "" : "revision = 3; ", f == 3 ? "" : "serial = 4; ",
                         field, u32_cases[_i].literal);
                int r = load_device(device, &c, &d);
                if (u32_cases[_i].ok) {
                        if (r < 0)
                                dump(&d);
                        ck_assert_int_eq(r, 0);
                        lss_identity id = c->buses[0].devices[0].identity;
                        ck_assert_uint_eq(lss_identity_field(&id, (enum lss_field) f), u32_cases[_i].value);
                        ck_assert(c->buses[0].devices[0].has_revision);
                } else {
                        ck_assert_int_eq(r, -EINVAL);
                        expect_message(&d, LSSCONF_DIAG_ERROR, ":5:", u32_cases[_i].shown);
                        if (!strstr(u32_cases[_i].shown, "64 bits")) {
                                char path[64];
                                snprintf(path, sizeof(path), "buses[0].devices[0].%s: ", field);
                                expect_message(&d, LSSCONF_DIAG_ERROR, path);
                        }
                }
                lssconf_free(c);
                lssconf_diag_clear(&d);
        }
}
END_TEST

/* The rewrite touches only real integer literals. */
START_TEST(literals_in_strings_names_comments) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        const char *text =
                "# 99999999999999999999 in a comment\n"
                "// 0x1FFFFFFFFFFFFFFFFF too\n"
                "/* 4294967296\n"
                "   and 99999999999999999999 */\n"
                "k4294967296 = 1;\n"
                "f = 99999999999999999999.5;\n"
                "e = 1e99999999999999999999;\n"
                "s = \"a\\\"99999999999999999999\\\\\";\n"
                "buses = ( { interface = \"4294967296\"; bitrate = 0x1E848; } );\n";
        int r = load(text, &c, &d);
        if (r < 0)
                dump(&d);
        ck_assert_int_eq(r, 0);
        ck_assert_str_eq(c->buses[0].interface, "4294967296");
        ck_assert_uint_eq(c->buses[0].bitrate, 125000);
        expect_message(&d, LSSCONF_DIAG_WARNING, ":5: k4294967296: unknown key");
        expect_message(&d, LSSCONF_DIAG_WARNING, ":8: s: unknown key");
        ck_assert_uint_eq(d.n_warnings, 4);
        ck_assert_uint_eq(d.n_errors, 0);
        lssconf_free(c);
        lssconf_diag_clear(&d);
}
END_TEST

/* node_id and other plain integers get the exact value too. */
START_TEST(node_id_range) {
        expect_load_error("buses = ({ interface = \"can0\";\n"
                          "devices = ({ vendor = 1; product = 2; serial = 3;\n"
                          "  node_id = 200; }); });\n",
                          ":3: buses[0].devices[0].node_id: 200 is out of range 1..127");
        expect_load_error("buses = ({ interface = \"can0\"; devices = ({ vendor = 1; product = 2; serial = 3; node_id = 0; }); });",
                          ":1:", "node_id: 0 is out of range 1..127");
        expect_load_error("buses = ({ interface = \"can0\"; devices = ({ vendor = 1; product = 2; serial = 3; node_id = 128; }); });",
                          "node_id: 128 is out of range 1..127");
        expect_load_error("buses = ({ interface = \"can0\"; devices = ({ vendor = 1; product = 2; serial = 3; node_id = 0xFFFFFFFF; }); });",
                          "node_id: 0xFFFFFFFF is out of range 1..127");
        /* 4294967301 would wrap to 5 without the literal rewrite */
        expect_load_error("buses = ({ interface = \"can0\"; devices = ({ vendor = 1; product = 2; serial = 3; node_id = 4294967301; }); });",
                          "node_id: 4294967301 is out of range 1..127");
        expect_load_error("buses = ({ interface = \"can0\"; devices = ({ vendor = 1; product = 2; serial = 3; node_id = 0x100000005; }); });",
                          "node_id: 0x100000005 is out of range 1..127");

        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        ck_assert_int_eq(load_device("vendor = 1; product = 2; serial = 3; node_id = 0x7F;", &c, &d), 0);
        ck_assert_uint_eq(c->buses[0].devices[0].node_id, 127);
        lssconf_free(c);
        lssconf_diag_clear(&d);
}
END_TEST

/* ---- type and value errors, key by key ---- */

static const struct {
        const char *key_value; /* in a minimal bus, line 4 */
        const char *message;
} bus_key_errors[] = {
        { "bitrate = \"fast\";", "buses[0].bitrate: expected an integer, got a string" },
        { "bitrate = 1.5;", "buses[0].bitrate: expected an integer, got a float" },
        { "bitrate = 123456;", "buses[0].bitrate: 123456 bit/s is not a CiA 301 bit rate (1000000, 800000, 500000, 250000, 125000, 100000, 50000, 20000, 10000)" },
        { "bitrate = -125000;", "buses[0].bitrate: -125000 is out of range 0..4294967295" },
        { "bitrate = 0;", "buses[0].bitrate: 0 bit/s is not a CiA 301 bit rate" },
        { "auto_assign = 1;", "buses[0].auto_assign: expected true or false, got an integer" },
        { "store = \"yes\";", "buses[0].store: expected true or false, got a string" },
        { "nmt_stop = 0;", "buses[0].nmt_stop: expected true or false, got an integer" },
        { "replace = \"yes\";", "buses[0].replace: expected true or false, got a string" },
        { "bitrate_change = [ true ];", "buses[0].bitrate_change: expected true or false, got an array [ ]" },
        { "unknown = 1;", "buses[0].unknown: expected a string, got an integer" },
        { "unknown = \"maybe\";", "buses[0].unknown: \"maybe\" is not \"ignore\" or \"pool\"" },
        { "unknown = \"pool\";", "buses[0].unknown: \"pool\" needs pool = [ lo, hi ] in the same bus" },
        { "unknown = \"pool\"; pool = 5;", "buses[0].pool: expected [ lo, hi ], got an integer" },
        { "unknown = \"pool\"; pool = [ 1 ];", "buses[0].pool: expected two node-IDs [ lo, hi ], got 1 value" },
        { "unknown = \"pool\"; pool = [ 1, 2, 3 ];", "buses[0].pool: expected two node-IDs [ lo, hi ], got 3 values" },
        { "unknown = \"pool\"; pool = [ \"a\", \"b\" ];", "buses[0].pool[0]: expected an integer, got a string" },
        { "unknown = \"pool\"; pool = [ 0, 5 ];", "buses[0].pool[0]: 0 is out of range 1..127" },
        { "unknown = \"pool\"; pool = [ 5, 128 ];", "buses[0].pool[1]: 128 is out of range 1..127" },
        { "unknown = \"pool\"; pool = [ 10, 5 ];", "buses[0].pool: 10..5 is empty (lo > hi)" },
        { "lss_timeout_ms = \"x\";", "buses[0].lss_timeout_ms: expected an integer, got a string" },
        { "lss_timeout_ms = -1;", "buses[0].lss_timeout_ms: -1 is out of range 0..10000" },
        { "lss_timeout_ms = 10001;", "buses[0].lss_timeout_ms: 10001 is out of range 0..10000" },
        { "lss_timing = \"slow\";", "buses[0].lss_timing: \"slow\" is not \"adaptive\" or \"fixed\"" },
        { "foreign_master_quiet_s = \"3\";", "buses[0].foreign_master_quiet_s: expected an integer, got a string" },
        { "foreign_master_quiet_s = -1;", "buses[0].foreign_master_quiet_s: -1 is out of range 0..3600" },
        { "foreign_master_quiet_s = 3601;", "buses[0].foreign_master_quiet_s: 3601 is out of range 0..3600" },
        { "lss_timing = true;", "buses[0].lss_timing: expected a string, got a boolean" },
        { "vendor = \"x\";", "buses[0].vendor: expected an integer, got a string" },
        { "product = -5;", "buses[0].product: -5 is out of range 0x0..0xFFFFFFFF" },
        { "devices = 5;", "buses[0].devices: expected a list ( { ... }, ... ), got an integer" },
        { "devices = { serial = 1; };", "buses[0].devices: expected a list ( { ... }, ... ), got a group { }" },
        { "devices = ( 5 );", "buses[0].devices[0]: expected a device entry { serial = ...; node_id = ...; }, got an integer" },
        { "devices = ( { vendor = 1; product = 1; serial = 1; node_id = \"7\"; } );", "buses[0].devices[0].node_id: expected an integer, got a string" },
        { "devices = ( { vendor = 1; product = 1; serial = 1; node_id = 7; revision = 1.0; } );", "buses[0].devices[0].revision: expected an integer, got a float" },
        { "devices = ( { vendor = 1; product = 1; serial = (1); node_id = 7; } );", "buses[0].devices[0].serial: expected an integer, got a list ( )" },
};

START_TEST(bus_key_error) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        ck_assert_int_eq(load_bus_key(bus_key_errors[_i].key_value, &c, &d), -EINVAL);
        char want[320];
        snprintf(want, sizeof(want), ":4: %s", bus_key_errors[_i].message);
        expect_message(&d, LSSCONF_DIAG_ERROR, want);
        lssconf_diag_clear(&d);
}
END_TEST

static const struct {
        const char *name;
        bool ok;
} ifnames[] = {
        { "can0", true },
        { "a", true },
        { "abcdefghijklmno", true },      /* 15 */
        { "vcan-1_x.y@z", true },
        { "", false },
        { "abcdefghijklmnop", false },    /* 16 */
        { "can/0", false },
        { "can 0", false },
        { "can\t0", false },
        { "can:0", false },
        { ".", false },
        { "..", false },
        { "can\x7f", false },
};

START_TEST(interface_names) {
        ck_assert(lssconf_ifname_valid(ifnames[_i].name) == ifnames[_i].ok);

        /* through the loader, with a printable quote in the message */
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        char text[256];
        snprintf(text, sizeof(text), "buses = (\n  {\n    interface = \"%s\";\n  }\n);\n", ifnames[_i].name);
        int r = load(text, &c, &d);
        if (ifnames[_i].ok) {
                ck_assert_int_eq(r, 0);
                ck_assert_str_eq(c->buses[0].interface, ifnames[_i].name);
        } else {
                ck_assert_int_eq(r, -EINVAL);
                expect_message(&d, LSSCONF_DIAG_ERROR, ":3: buses[0].interface: \"",
                               "is not a valid interface name");
                for (const char *p = d.messages[0].text; *p; p++)
                        ck_assert_msg(*p >= ' ' && *p < 0x7F, "unprintable byte in message");
        }
        lssconf_free(c);
        lssconf_diag_clear(&d);
}
END_TEST

START_TEST(global_key_errors) {
        expect_load_error("\nlss_timeout_ms = 0;\n", ":2: lss_timeout_ms: 0 is out of range 1..10000");
        expect_load_error("lss_timeout_ms = 10001;\n", ":1: lss_timeout_ms: 10001 is out of range 1..10000");
        expect_load_error("lss_timeout_ms = \"20\";\n", ":1: lss_timeout_ms: expected an integer, got a string");
        expect_load_error("\n\nboot_ready_limit_s = 0;\n", ":3: boot_ready_limit_s: 0 is out of range 1..86400");
        expect_load_error("boot_ready_limit_s = 86401;\n", ":1: boot_ready_limit_s: 86401 is out of range 1..86400");
        expect_load_error("boot_ready_limit_s = -5;\n", ":1: boot_ready_limit_s: -5 is out of range 1..86400");
        expect_load_error("boot_ready_limit_s = 0x100000000;\n", "boot_ready_limit_s:", "out of range 1..86400");
        expect_load_error("boot_ready_limit_s = \"30\";\n", ":1: boot_ready_limit_s: expected an integer, got a string");
        expect_load_error("boot_ready_limit_s = 30.5;\n", ":1: boot_ready_limit_s: expected an integer");
        expect_load_error("lss_timing = 5;\n", ":1: lss_timing: expected a string, got an integer");
        expect_load_error("\nforeign_master_quiet_s = 0;\n", ":2: foreign_master_quiet_s: 0 is out of range 1..3600");
        expect_load_error("foreign_master_quiet_s = 3601;\n", ":1: foreign_master_quiet_s: 3601 is out of range 1..3600");
        expect_load_error("foreign_master_quiet_s = 2.5;\n", ":1: foreign_master_quiet_s: expected an integer");
        expect_load_error("lss_timing = \"Fixed\";\n", ":1: lss_timing: \"Fixed\" is not \"adaptive\" or \"fixed\"");
        expect_load_error("\n\nbuses = 5;\n", ":3: buses: expected a list ( { ... }, ... ), got an integer");
        expect_load_error("buses = { interface = \"can0\"; };\n", ":1: buses: expected a list");
        expect_load_error("buses = ( 5 );\n", ":1: buses[0]: expected a bus { interface = ...; ... }, got an integer");
        expect_load_error("buses = ( \"can0\" );\n", "buses[0]: expected a bus", "got a string");
}
END_TEST

/* boot_ready_limit_s: its range, its default, errors naming the file and line,
 * and that it is a global key (in a bus it is unknown there, ignored). */
START_TEST(boot_ready_limit) {
        static const struct { const char *text; uint32_t want; } good[] = {
                { "buses = ( );\n", 1800 },
                { "boot_ready_limit_s = 1;\nbuses = ( );\n", 1 },
                { "boot_ready_limit_s = 86400;\nbuses = ( );\n", 86400 },
                { "boot_ready_limit_s = 0x3C;\nbuses = ( );\n", 60 },
                { "buses = ( );\nboot_ready_limit_s = 120;\n", 120 },
        };
        for (size_t i = 0; i < sizeof(good) / sizeof(good[0]); i++) {
                lssconf_diag d = LSSCONF_DIAG_INIT;
                lssconf *c = NULL;
                ck_assert_int_eq(load(good[i].text, &c, &d), 0);
                ck_assert_uint_eq(d.n_errors, 0);
                ck_assert_uint_eq(c->boot_ready_limit_s, good[i].want);
                lssconf_free(c);
                lssconf_diag_clear(&d);
        }

        /* the whole message, file name and line first */
        const char *text = "lss_timeout_ms = 20;\n# the limit\nboot_ready_limit_s = 86401;\nbuses = ( );\n";
        char *path = write_temp(text, strlen(text)), *want;
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        ck_assert_int_eq(lssconf_load_file(path, &c, &d), -EINVAL);
        ck_assert_ptr_null(c);
        ck_assert_int_ge(asprintf(&want, "%s:3: boot_ready_limit_s: 86401 is out of range 1..86400", path), 0);
        expect_message(&d, LSSCONF_DIAG_ERROR, want);
        ck_assert_uint_eq(d.n_errors, 1);
        free(want);
        lssconf_diag_clear(&d);
        ck_assert_int_eq(unlink(path), 0);
        free(path);

        ck_assert_int_eq(load_bus_key("boot_ready_limit_s = 5;", &c, &d), 0);
        expect_message(&d, LSSCONF_DIAG_WARNING, ":4: buses[0].boot_ready_limit_s: unknown key, ignored");
        ck_assert_uint_eq(c->boot_ready_limit_s, 1800);
        lssconf_free(c);
        lssconf_diag_clear(&d);

        /* the built-in configuration (--bus only) has the default too */
        ck_assert_int_eq(lssconf_new(&c), 0);
        ck_assert_uint_eq(c->boot_ready_limit_s, LSSCONF_BOOT_READY_LIMIT_S_DEFAULT);
        lssconf_free(c);
}
END_TEST

START_TEST(long_string_is_quoted_bounded) {
        char text[2048];
        char name[1001];
        memset(name, 'x', 1000);
        name[1000] = '\0';
        snprintf(text, sizeof(text), "lss_timing = \"%s\";\n", name);
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        ck_assert_int_eq(load(text, &c, &d), -EINVAL);
        expect_message(&d, LSSCONF_DIAG_ERROR, "xxx...\" is not \"adaptive\" or \"fixed\"");
        ck_assert_uint_lt(strlen(d.messages[0].text), 200 + strlen("lssd-test-config-XXXXXX") + 64);
        lssconf_diag_clear(&d);

        /* escapes in the quote */
        ck_assert_int_eq(load("lss_timing = \"a\\\"b\\\\c\\n\";\n", &c, &d), -EINVAL);
        expect_message(&d, LSSCONF_DIAG_ERROR, "\"a\\\"b\\\\c\\x0a\" is not");
        lssconf_diag_clear(&d);
}
END_TEST

/* ---- missing required keys: error at the group's line ---- */

START_TEST(missing_keys) {
        expect_load_error("buses = (\n"
                          "  {\n"
                          "    bitrate = 250000;\n"
                          "  }\n"
                          ");\n",
                          ":2: buses[0]: missing required key 'interface'");
        expect_load_error("buses = ( { interface = \"can0\"; devices = (\n"
                          "  { vendor = 1; product = 2; node_id = 5; }\n"
                          "); } );\n",
                          ":2: buses[0].devices[0]: missing required key 'serial'");
        expect_load_error("buses = ( { interface = \"can0\"; devices = (\n"
                          "  { vendor = 1; product = 2; serial = 5; },\n"
                          "  { vendor = 1; product = 2; serial = 6;\n"
                          "  }\n"
                          "); } );\n",
                          ":3: buses[0].devices[1]: missing required key 'node_id'");
        expect_load_error("buses = ( { interface = \"can0\"; product = 7; devices = (\n"
                          "  { serial = 5; node_id = 1; }\n"
                          "); } );\n",
                          ":2: buses[0].devices[0]: missing required key 'vendor' (give it here or as the bus default)");
        expect_load_error("buses = ( { interface = \"can0\"; vendor = 7; devices = (\n"
                          "  { serial = 5; node_id = 1; }\n"
                          "); } );\n",
                          ":2: buses[0].devices[0]: missing required key 'product'");

        /* a bad bus default is reported once, not again for every entry */
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        ck_assert_int_eq(load("buses = ( { interface = \"can0\"; vendor = \"x\"; product = -1; devices = (\n"
                              "  { serial = 5; node_id = 1; },\n"
                              "  { serial = 6; node_id = 2; }\n"
                              "); } );\n", &c, &d), -EINVAL);
        ck_assert_uint_eq(d.n_errors, 2);
        expect_message(&d, LSSCONF_DIAG_ERROR, ":1: buses[0].vendor: expected an integer");
        expect_message(&d, LSSCONF_DIAG_ERROR, ":1: buses[0].product: -1 is out of range");
        lssconf_diag_clear(&d);
}
END_TEST

/* ---- semantic rules ---- */

START_TEST(semantic_errors_fixture) {
        char *path = test_data_path("config/semantic-errors.conf");
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        ck_assert_int_eq(lssconf_load_file(path, &c, &d), -EINVAL);
        ck_assert_ptr_null(c);
        expect_message(&d, LSSCONF_DIAG_ERROR, "semantic-errors.conf:11: buses[0].devices[1].node_id: 5 is already mapped to devices[0] at line 10");
        expect_message(&d, LSSCONF_DIAG_ERROR, "semantic-errors.conf:12: buses[0].devices[2]: same device as devices[0] at line 10",
                       "serial 0x00000001, revision 0x00000007");
        expect_message(&d, LSSCONF_DIAG_ERROR, "semantic-errors.conf:6: buses[0].pool: 10..20 contains node-ID 15 mapped to devices[3] at line 13");
        expect_message(&d, LSSCONF_DIAG_ERROR, "semantic-errors.conf:16: buses[0].devices[6]: same device as devices[4] at line 14");
        expect_message(&d, LSSCONF_DIAG_ERROR, "semantic-errors.conf:17: buses[0].devices[7].node_id: 200 is out of range 1..127");
        expect_message(&d, LSSCONF_DIAG_ERROR, "semantic-errors.conf:21: buses[1].interface: \"can0\" is already configured by buses[0] at line 3");
        if (d.n_errors != 6)
                dump(&d);
        ck_assert_uint_eq(d.n_errors, 6); /* devices[5] (revision 2) clashes with nothing */
        ck_assert_uint_eq(d.n_warnings, 0);
        lssconf_diag_clear(&d);
        free(path);
}
END_TEST

START_TEST(identity_rules) {
        static const char *const head = "buses = ( { interface = \"can0\"; vendor = 1; product = 2; devices = (\n";
        static const char *const tail = "); } );\n";
        static const struct {
                const char *entries;
                const char *message; /* NULL: loads */
                size_t n_errors;
        } cases[] = {
                /* same revision */
                { "{ serial = 1; node_id = 1; revision = 3; },\n{ serial = 1; node_id = 2; revision = 3; }\n",
                  ":3: buses[0].devices[1]: same device as devices[0] at line 2", 1 },
                /* different revisions: two devices */
                { "{ serial = 1; node_id = 1; revision = 3; },\n{ serial = 1; node_id = 2; revision = 4; }\n", NULL, 0 },
                /* the entry without revision comes second */
                { "{ serial = 1; node_id = 1; revision = 3; },\n{ serial = 1; node_id = 2; }\n",
                  ":3: buses[0].devices[1]: same device as devices[0] at line 2 (vendor 0x00000001, product 0x00000002, serial 0x00000001, revision any)", 1 },
                /* both without revision */
                { "{ serial = 0xFFFFFFFF; node_id = 1; },\n{ serial = 4294967295; node_id = 2; }\n",
                  ":3: buses[0].devices[1]: same device as devices[0]", 1 },
                /* other vendor or product or serial: different devices */
                { "{ serial = 1; node_id = 1; },\n{ vendor = 9; serial = 1; node_id = 2; },\n"
                  "{ product = 9; serial = 1; node_id = 3; },\n{ serial = 2; node_id = 4; }\n", NULL, 0 },
                /* later revision entries report the earliest clash */
                { "{ serial = 1; node_id = 1; revision = 5; },\n{ serial = 1; node_id = 2; },\n"
                  "{ serial = 1; node_id = 3; revision = 5; }\n",
                  ":4: buses[0].devices[2]: same device as devices[0] at line 2", 2 },
                { "{ serial = 1; node_id = 1; revision = 6; },\n{ serial = 1; node_id = 2; },\n"
                  "{ serial = 1; node_id = 3; revision = 5; }\n",
                  ":4: buses[0].devices[2]: same device as devices[1] at line 3", 2 },
                /* duplicate node-ID */
                { "{ serial = 1; node_id = 9; },\n{ serial = 2;\n node_id = 9; }\n",
                  ":4: buses[0].devices[1].node_id: 9 is already mapped to devices[0] at line 2", 1 },
        };
        for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
                char *text;
                lssconf_diag d = LSSCONF_DIAG_INIT;
                lssconf *c = NULL;
                ck_assert_int_ge(asprintf(&text, "%s%s%s", head, cases[i].entries, tail), 0);
                int r = load(text, &c, &d);
                free(text);
                if (cases[i].message) {
                        ck_assert_int_eq(r, -EINVAL);
                        expect_message(&d, LSSCONF_DIAG_ERROR, cases[i].message);
                        ck_assert_uint_eq(d.n_errors, cases[i].n_errors);
                } else {
                        if (r < 0)
                                dump(&d);
                        ck_assert_int_eq(r, 0);
                }
                lssconf_free(c);
                lssconf_diag_clear(&d);
        }
}
END_TEST

START_TEST(pool_rules) {
        /* the pool may touch but not contain mapped node-IDs */
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        ck_assert_int_eq(load_bus_key("unknown = \"pool\"; pool = [ 10, 20 ]; vendor = 1; product = 1;\n"
                                      "devices = ( { serial = 1; node_id = 9; }, { serial = 2; node_id = 21; } );",
                                      &c, &d), 0);
        ck_assert_uint_eq(d.n_messages, 0);
        lssconf_free(c);

        expect_load_error("buses = ( { interface = \"can0\"; unknown = \"pool\";\n"
                          "pool = [ 10, 20 ]; vendor = 1; product = 1;\n"
                          "devices = ( { serial = 1; node_id = 20; }, { serial = 2; node_id = 10; } ); } );\n",
                          ":2: buses[0].pool: 10..20 contains node-ID 20 mapped to devices[0] at line 3");
        expect_load_error("buses = ( { interface = \"can0\"; unknown = \"pool\";\n"
                          "pool = [ 10, 20 ]; vendor = 1; product = 1;\n"
                          "devices = ( { serial = 1; node_id = 20; }, { serial = 2; node_id = 10; } ); } );\n",
                          "pool: 10..20 contains node-ID 10 mapped to devices[1]");

        /* a pool that is not used is only a warning, and not checked for overlap */
        ck_assert_int_eq(load_bus_key("pool = [ 1, 127 ]; vendor = 1; product = 1;\n"
                                      "devices = ( { serial = 1; node_id = 9; } );", &c, &d), 0);
        expect_message(&d, LSSCONF_DIAG_WARNING, ":4: buses[0].pool: ignored unless unknown = \"pool\"");
        ck_assert_uint_eq(d.n_errors, 0);
        ck_assert_int_eq(c->buses[0].unknown, LSSCONF_UNKNOWN_IGNORE);
        lssconf_free(c);
        lssconf_diag_clear(&d);
}
END_TEST

START_TEST(duplicate_interfaces) {
        expect_load_error("buses = (\n"
                          "  { interface = \"can1\"; },\n"
                          "  { interface = \"can0\"; },\n"
                          "  { interface = \"can1\"; },\n"
                          "  {\n"
                          "    interface = \"can0\";\n"
                          "  }\n"
                          ");\n",
                          ":4: buses[2].interface: \"can1\" is already configured by buses[0] at line 2");
        expect_load_error("buses = (\n"
                          "  { interface = \"can1\"; },\n"
                          "  { interface = \"can0\"; },\n"
                          "  { interface = \"can1\"; },\n"
                          "  {\n"
                          "    interface = \"can0\";\n"
                          "  }\n"
                          ");\n",
                          ":6: buses[3].interface: \"can0\" is already configured by buses[1] at line 3");
}
END_TEST

/* ---- warnings ---- */

START_TEST(unknown_keys_warn) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        int r = load("lss_timeout = 20;\n"
                     "buses = (\n"
                     "  {\n"
                     "    interface = \"can0\";\n"
                     "    bitrat = 250000;\n"
                     "    devices = ( { vendor = 1; product = 2; serial = 3; node_id = 4;\n"
                     "                  nodeid = 5; } );\n"
                     "  }\n"
                     ");\n", &c, &d);
        ck_assert_int_eq(r, 0);
        ck_assert_uint_eq(d.n_errors, 0);
        ck_assert_uint_eq(d.n_warnings, 3);
        expect_message(&d, LSSCONF_DIAG_WARNING, ":1: lss_timeout: unknown key, ignored");
        expect_message(&d, LSSCONF_DIAG_WARNING, ":5: buses[0].bitrat: unknown key, ignored");
        expect_message(&d, LSSCONF_DIAG_WARNING, ":7: buses[0].devices[0].nodeid: unknown key, ignored");
        ck_assert_uint_eq(c->buses[0].bitrate, 125000);
        lssconf_free(c);
        lssconf_diag_clear(&d);
}
END_TEST

START_TEST(empty_and_no_buses) {
        static const char *const texts[] = { "", "\n\n# only a comment\n", "lss_timeout_ms = 30;\n" };
        for (size_t i = 0; i < 3; i++) {
                lssconf_diag d = LSSCONF_DIAG_INIT;
                lssconf *c = NULL;
                ck_assert_int_lt(load(texts[i], &c, &d), 0);
                ck_assert_ptr_null(c);
                ck_assert_uint_eq(d.n_errors, 1);
                ck_assert_uint_eq(d.n_warnings, 0);
                expect_message(&d, LSSCONF_DIAG_ERROR, ":1: no buses configured");
                lssconf_diag_clear(&d);
        }

        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        /* an empty list says "nothing yet" on purpose: a warning, lssd serves no bus */
        ck_assert_int_eq(load("\nbuses = ( );\n", &c, &d), 0);
        ck_assert_uint_eq(d.n_errors, 0);
        expect_message(&d, LSSCONF_DIAG_WARNING, ":2: buses: empty list: lssd serves no bus until one is added");
        ck_assert_uint_eq(c->n_buses, 0);
        lssconf_free(c);
        c = NULL;
        lssconf_diag_clear(&d);

        /* an empty device list is fine */
        ck_assert_int_eq(load_bus_key("devices = ( );", &c, &d), 0);
        ck_assert_uint_eq(d.n_messages, 0);
        ck_assert_uint_eq(c->buses[0].n_devices, 0);
        lssconf_free(c);
        lssconf_diag_clear(&d);
}
END_TEST

/* ---- broken files ---- */

START_TEST(syntax_error_line) {
        expect_load_error("a = 1;\n\nb = ;\n", ":3: syntax error");
        expect_load_error("buses = (\n  { interface = \"can0\"; }\n  { interface = \"can1\"; }\n);\n", ":3: syntax error");
        expect_load_error("a = 1;\nb = 2;\na = 3;\n", ":3: duplicate setting name");
        expect_load_error("x = 1;\n\n@include \"/etc/passwd\"\n", ":3: @include is not supported");
        expect_load_error("x = 1;\n/* unterminated\n comment\n", ":2: unterminated /* comment");
        expect_load_error("x = 1; /* a */ y = 2; /* b *\n/", ":1: unterminated /* comment");
        expect_load_error("x = \"unterminated\n\n", ":");
}
END_TEST

START_TEST(nul_byte_in_buffer) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        static const char text[] = "a = 1;\n\n\0 b = 2;\n";
        ck_assert_int_eq(load_len(text, sizeof(text) - 1, &c, &d), -EINVAL);
        expect_message(&d, LSSCONF_DIAG_ERROR, ":3: NUL byte");
        lssconf_diag_clear(&d);
}
END_TEST

START_TEST(nonexistent_file) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = (lssconf *) 1;
        ck_assert_int_eq(lssconf_load_file("/nonexistent/lssd.conf", &c, &d), -ENOENT);
        ck_assert_ptr_null(c);
        expect_message(&d, LSSCONF_DIAG_ERROR, "/nonexistent/lssd.conf: cannot open: No such file or directory");
        lssconf_diag_clear(&d);

        /* a directory opens but cannot be read */
        const char *tmp = getenv("TMPDIR");
        ck_assert_int_eq(lssconf_load_file(tmp && *tmp ? tmp : "/tmp", &c, &d), -EISDIR);
        expect_message(&d, LSSCONF_DIAG_ERROR, "cannot read: Is a directory");
        lssconf_diag_clear(&d);

        /* no diag: the error is still returned */
        ck_assert_int_eq(lssconf_load_file("/nonexistent/lssd.conf", &c, NULL), -ENOENT);
}
END_TEST

static double now_s(void) {
        return (double) clock_now_us(CLOCK_MONOTONIC) / 1e6;
}

START_TEST(one_megabyte_of_junk) {
        const size_t size = 1024 * 1024;
        char *junk = malloc(size);
        uint64_t seed = 0x2468ACE1u + (uint64_t) _i;
        ck_assert_ptr_nonnull(junk);

        for (size_t i = 0; i < size; i++) {
                uint32_t r = (uint32_t) sim_random_next(&seed);
                switch (_i) {
                case 0: /* any byte */
                        junk[i] = (char) r;
                        break;
                case 1: /* no NUL: libconfig's parser sees it */
                        junk[i] = (char) (r % 255 + 1);
                        break;
                case 2: { /* plausible tokens, many lines */
                        static const char tokens[] = "{}()[]=;:,\"\n#/*0123456789xLabc-+. \t@\\";
                        junk[i] = tokens[r % (sizeof(tokens) - 1)];
                        break;
                }
                default: /* deep nesting */
                        junk[i] = i < 4 ? "a = "[i] : '(';
                }
        }

        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        double t0 = now_s();
        ck_assert_int_eq(load_len(junk, size, &c, &d), -EINVAL);
        ck_assert_double_lt(now_s() - t0, 20.0);
        /* every message has a file:line: prefix */
        ck_assert_uint_gt(d.n_messages, 0);
        for (size_t i = 0; i < d.n_messages; i++)
                ck_assert_msg(strstr(d.messages[i].text, "lssd-test-config-") && strchr(d.messages[i].text, ':'),
                              "message without location: %s", d.messages[i].text);
        lssconf_diag_clear(&d);
        free(junk);
}
END_TEST

START_TEST(too_big) {
        size_t size = LSSCONF_SIZE_MAX + 1;
        char *text = malloc(size);
        ck_assert_ptr_nonnull(text);
        memset(text, '\n', size);
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        ck_assert_int_eq(load_len(text, size, &c, &d), -EFBIG);
        expect_message(&d, LSSCONF_DIAG_ERROR, "refusing to read it");
        lssconf_diag_clear(&d);
        free(text);
}
END_TEST

START_TEST(many_messages_are_capped) {
        size_t n = 5000;
        char *text = malloc(n * 16 + 64), *p = text;
        ck_assert_ptr_nonnull(text);
        for (size_t i = 0; i < n; i++)
                p += sprintf(p, "k%zu = %zu;\n", i, i);
        sprintf(p, "buses = ( { interface = \"can0\"; } );\n");
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        ck_assert_int_eq(load(text, &c, &d), 0);
        ck_assert_uint_eq(d.n_warnings, n);
        ck_assert_uint_eq(d.n_messages, LSSCONF_DIAG_MAX);
        ck_assert_uint_eq(d.n_dropped, n - LSSCONF_DIAG_MAX);
        expect_message(&d, LSSCONF_DIAG_WARNING, ":1: k0: unknown key");
        lssconf_free(c);
        lssconf_diag_clear(&d);
        free(text);
}
END_TEST

/* Many entries: the duplicate checks must not be quadratic. */
START_TEST(many_devices) {
        size_t n = 20000;
        char *text = malloc(n * 64 + 256), *p = text;
        ck_assert_ptr_nonnull(text);
        p += sprintf(p, "buses = ( { interface = \"can0\"; vendor = 1; product = 2; devices = (\n");
        for (size_t i = 0; i < n; i++)
                p += sprintf(p, "{ serial = 7; node_id = %zu; },\n", i % 127 + 1);
        p += sprintf(p, "{ serial = 8; node_id = 1; }\n); } );\n");
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        double t0 = now_s();
        ck_assert_int_eq(load(text, &c, &d), -EINVAL);
        ck_assert_double_lt(now_s() - t0, 20.0);
        ck_assert_uint_eq(d.n_errors, (n - 1) + (n - 127) + 1); /* identity, node-ID */
        ck_assert_uint_eq(d.n_messages, LSSCONF_DIAG_MAX);
        lssconf_diag_clear(&d);
        free(text);
}
END_TEST

/* ---- API ---- */

START_TEST(lookups) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        ck_assert_int_eq(load("buses = ( { interface = \"can0\"; vendor = 1; product = 2; devices = (\n"
                              "  { serial = 10; node_id = 5; },\n"
                              "  { serial = 11; node_id = 6; revision = 3; }\n"
                              "); }, { interface = \"can1\"; } );\n", &c, &d), 0);
        const lssconf_bus *b = lssconf_find_bus(c, "can0");
        ck_assert_ptr_nonnull(b);
        ck_assert_ptr_null(lssconf_find_bus(c, "can2"));
        ck_assert_ptr_null(lssconf_find_bus(c, NULL));
        ck_assert_ptr_null(lssconf_find_bus(NULL, "can0"));

        lss_identity id = { .vendor = 1, .product = 2, .revision = 99, .serial = 10 };
        ck_assert_ptr_eq(lssconf_lookup_device(b, &id), &b->devices[0]); /* any revision */
        id.serial = 11;
        ck_assert_ptr_null(lssconf_lookup_device(b, &id)); /* revision 3 only */
        id.revision = 3;
        ck_assert_ptr_eq(lssconf_lookup_device(b, &id), &b->devices[1]);
        id.vendor = 9;
        ck_assert_ptr_null(lssconf_lookup_device(b, &id));
        id = (lss_identity) { .vendor = 1, .product = 3, .revision = 3, .serial = 11 };
        ck_assert_ptr_null(lssconf_lookup_device(b, &id));
        ck_assert_ptr_null(lssconf_lookup_device(NULL, &id));
        ck_assert_ptr_null(lssconf_lookup_device(b, NULL));

        ck_assert_ptr_eq(lssconf_bus_find_node_id(b, 6), &b->devices[1]);
        ck_assert_ptr_null(lssconf_bus_find_node_id(b, 7));
        ck_assert_ptr_null(lssconf_bus_find_node_id(NULL, 6));
        ck_assert_uint_eq(b->devices[1].line, 3);

        lssconf_free(c);
        lssconf_diag_clear(&d);
        ck_assert_ptr_null(lssconf_free(NULL));
}
END_TEST

START_TEST(describe) {
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        char buf[LSSCONF_BUS_DESCRIBE_MAX];
        ck_assert_int_eq(load("lss_timing = \"fixed\";\n"
                              "buses = ( { interface = \"can0\"; bitrate = 250000; auto_assign = true; unknown = \"pool\";\n"
                              "pool = [ 100, 110 ]; nmt_stop = true; replace = true; reset_after_pass = true;\n"
                              "bitrate_change = true; lss_timeout_ms = 30; foreign_master_quiet_s = 7;\n"
                              "vendor = 1; product = 2; devices = ( { serial = 10; node_id = 5; } ); },\n"
                              "{ interface = \"can1\"; store = false; devices = ( { vendor = 1; product = 2; serial = 10; node_id = 5; },\n"
                              "{ vendor = 1; product = 2; serial = 11; node_id = 6; } ); } );\n", &c, &d), 0);
        ck_assert_str_eq(lssconf_bus_describe(&c->buses[0], buf, sizeof(buf)),
                         "can0: 250000 bit/s, 1 mapped device, auto-assign on, store on, unknown devices: pool 100..110, "
                         "nmt-stop on, replace on, reset after pass on, bit-rate change allowed, LSS timeout 30 ms (fixed), "
                         "quiet after another master 7 s");
        ck_assert_str_eq(lssconf_bus_describe(&c->buses[1], buf, sizeof(buf)),
                         "can1: 125000 bit/s, 2 mapped devices, auto-assign off, store off, unknown devices: ignore, "
                         "nmt-stop off, replace off, reset after pass off, bit-rate change off, LSS timeout 20 ms "
                         "(fixed), quiet after another master 3 s");
        /* the longest a bus can say is not cut */
        lssconf_device many[127] = { { .source = 1 } };
        for (size_t i = 0; i < 127; i++)
                many[i].source = 1;
        lssconf_bus longest = { .interface = "can-0123456789a", .bitrate = 1000000, .lss_timeout_ms = 10000,
                                .lss_timing = LSSCONF_LSS_TIMING_ADAPTIVE, .foreign_master_quiet_s = 3600,
                                .auto_assign = true, .unknown = LSSCONF_UNKNOWN_POOL, .pool_lo = 100, .pool_hi = 127,
                                .bitrate_change = true, .devices = many, .n_devices = 127 };
        lssconf_bus_describe(&longest, buf, sizeof(buf));
        ck_assert_msg(strlen(buf) + 1 < sizeof(buf), "cut: %s", buf);
        ck_assert(strstr(buf, "quiet after another master 3600 s"));
        /* truncation is safe */
        char small[8];
        ck_assert_str_eq(lssconf_bus_describe(&c->buses[0], small, sizeof(small)), "can0: 2");
        ck_assert_ptr_null(lssconf_bus_describe(&c->buses[0], NULL, 0));
        lssconf_free(c);
        lssconf_diag_clear(&d);
}
END_TEST

START_TEST(built_in_config) {
        lssconf *c = NULL;
        lssconf_bus *b = NULL;
        ck_assert_int_eq(lssconf_new(&c), 0);
        ck_assert_ptr_null(c->source);
        ck_assert_uint_eq(c->n_buses, 0);
        ck_assert_int_eq(lssconf_add_default_bus(c, "vcan0", &b), 0);
        ck_assert_ptr_eq(b, &c->buses[0]);
        ck_assert_int_eq(lssconf_add_default_bus(c, "vcan1", NULL), 0);
        ck_assert_int_eq(lssconf_add_default_bus(c, "vcan0", NULL), -EEXIST);
        ck_assert_int_eq(lssconf_add_default_bus(c, "bad/name", NULL), -EINVAL);
        ck_assert_int_eq(lssconf_add_default_bus(c, NULL, NULL), -EINVAL);
        ck_assert_uint_eq(c->n_buses, 2);
        b = &c->buses[0];
        ck_assert_str_eq(b->interface, "vcan0");
        ck_assert_uint_eq(b->bitrate, LSSCONF_BITRATE_DEFAULT);
        ck_assert(!b->auto_assign);
        ck_assert(b->store);
        ck_assert_int_eq(b->unknown, LSSCONF_UNKNOWN_IGNORE);
        ck_assert_uint_eq(b->lss_timeout_ms, LSSCONF_LSS_TIMEOUT_MS_DEFAULT);
        ck_assert_uint_eq(b->n_devices, 0);
        ck_assert_ptr_eq(lssconf_find_bus(c, "vcan1"), &c->buses[1]);
        lssconf_free(c);
}
END_TEST

START_TEST(enum_strings) {
        ck_assert_str_eq(lssconf_unknown_policy_to_string(LSSCONF_UNKNOWN_IGNORE), "ignore");
        ck_assert_str_eq(lssconf_unknown_policy_to_string(LSSCONF_UNKNOWN_POOL), "pool");
        ck_assert_ptr_null(lssconf_unknown_policy_to_string((lssconf_unknown_policy) 7));
        ck_assert_int_eq(lssconf_unknown_policy_from_string("pool"), LSSCONF_UNKNOWN_POOL);
        ck_assert_int_eq(lssconf_unknown_policy_from_string("Pool"), -EINVAL);
        ck_assert_int_eq(lssconf_unknown_policy_from_string(NULL), -EINVAL);
        ck_assert_str_eq(lssconf_lss_timing_to_string(LSSCONF_LSS_TIMING_FIXED), "fixed");
        ck_assert_ptr_null(lssconf_lss_timing_to_string((lssconf_lss_timing) 2));
        ck_assert_int_eq(lssconf_lss_timing_from_string("adaptive"), LSSCONF_LSS_TIMING_ADAPTIVE);
        ck_assert_int_eq(lssconf_lss_timing_from_string(""), -EINVAL);
        ck_assert_str_eq(lssconf_diag_severity_to_string(LSSCONF_DIAG_ERROR), "error");
        ck_assert_str_eq(lssconf_diag_severity_to_string(LSSCONF_DIAG_WARNING), "warning");
}
END_TEST

START_TEST(load_buffer_api) {
        static const char text[] = "buses = ( { interface = \"can0\"; } );\nbuses2 = 1;\n";
        lssconf *c = NULL;
        lssconf_diag d = LSSCONF_DIAG_INIT;

        /* not NUL-terminated: only len bytes count */
        ck_assert_int_eq(lssconf_load_buffer(text, strlen("buses = ( { interface = \"can0\"; } );\n"),
                                                 "mem.conf", &c, &d), 0);
        ck_assert_uint_eq(d.n_messages, 0);
        ck_assert_str_eq(c->source, "mem.conf");
        lssconf_free(c);

        ck_assert_int_eq(lssconf_load_buffer(text, strlen(text), NULL, &c, &d), 0);
        expect_message(&d, LSSCONF_DIAG_WARNING, "(config):2: buses2: unknown key");
        lssconf_free(c);
        lssconf_diag_clear(&d);

        /* diag is optional */
        ck_assert_int_eq(lssconf_load_buffer("x = ;", 5, "m", &c, NULL), -EINVAL);
        ck_assert_ptr_null(c);
        ck_assert_int_eq(lssconf_load_buffer(text, strlen(text), "m", &c, NULL), 0);
        lssconf_free(c);

        /* messages append to what is there */
        lssconf_diag_add(&d, LSSCONF_DIAG_ERROR, "earlier %d", 1);
        ck_assert_int_eq(lssconf_load_buffer(text, strlen(text), "m", &c, &d), 0);
        ck_assert_uint_eq(d.n_messages, 2);
        ck_assert_str_eq(d.messages[0].text, "earlier 1");
        lssconf_free(c);
        lssconf_diag_clear(&d);
        ck_assert_uint_eq(d.n_messages, 0);
        ck_assert_uint_eq(d.n_errors, 0);
}
END_TEST

/* ---- dcf: the map from CiA 306 DCFs (config/dcf.h has the reader's tests) ---- */

/* A folder of its own; the caller removes it with remove_folder(). */
static char *make_folder(void) {
        const char *tmp = getenv("TMPDIR");
        char *dir;
        ck_assert_int_ge(asprintf(&dir, "%s/lssd-test-dcf-XXXXXX", tmp && *tmp ? tmp : "/tmp"), 0);
        ck_assert_ptr_nonnull(mkdtemp(dir));
        return dir;
}

static void put_file(const char *dir, const char *name, const char *text) {
        char *path;
        ck_assert_int_ge(asprintf(&path, "%s/%s", dir, name), 0);
        FILE *f = fopen(path, "w");
        ck_assert_ptr_nonnull(f);
        ck_assert_int_eq(fputs(text, f) >= 0, 1);
        ck_assert_int_eq(fclose(f), 0);
        free(path);
}

static void remove_folder(char *dir) {
        DIR *d = opendir(dir);
        ck_assert_ptr_nonnull(d);
        for (struct dirent *e; (e = readdir(d)); ) {
                char *path;
                if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                        continue;
                ck_assert_int_ge(asprintf(&path, "%s/%s", dir, e->d_name), 0);
                ck_assert_int_eq(unlink(path), 0);
                free(path);
        }
        closedir(d);
        ck_assert_int_eq(rmdir(dir), 0);
        free(dir);
}

/* dir/lssd.conf with text, loaded as lssd does */
static int load_in(const char *dir, const char *text, lssconf **ret, lssconf_diag *d) {
        char *path;
        put_file(dir, "lssd.conf", text);
        ck_assert_int_ge(asprintf(&path, "%s/lssd.conf", dir), 0);
        int r = lssconf_load_file(path, ret, d);
        free(path);
        if (r < 0) {
                ck_assert_ptr_null(*ret);
                ck_assert(lssconf_diag_has_errors(d));
        }
        return r;
}

#define DCF_DEVICE(node_id, serial) \
        "[DeviceInfo]\nVendorNumber=0xEC\nProductNumber=0x1234\nRevisionNumber=0x10002\n" \
        "[DeviceComissioning]\nNodeID=" node_id "\nNodeName=drive " node_id "\nLSS_SerialNumber=" serial "\n"
#define DCF_MASTER_5 \
        "[DeviceComissioning]\nNodeID=1\n[1F85Value]\n5=0xEC\n[1F86Value]\n5=0x1234\n[1F88Value]\n5=0x1005\n"

static const char *source_name(const lssconf *c, const lssconf_device *d) {
        const char *s = lssconf_device_source(c, d);
        if (!s)
                return NULL;
        const char *slash = strrchr(s, '/');
        return slash ? slash + 1 : s;
}

START_TEST(dcf_map_from_files) {
        char *dir = make_folder();
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        char buf[LSSCONF_BUS_DESCRIBE_MAX];
        put_file(dir, "drive5.dcf", DCF_DEVICE("5", "0x1005"));
        put_file(dir, "drive6.dcf", DCF_DEVICE("6", "0x1006"));
        put_file(dir, "master.dcf", DCF_MASTER_5);
        put_file(dir, "spare.dcf", DCF_DEVICE("255", "0x1099"));
        put_file(dir, "notes.txt", "not read");
        ck_assert_int_eq(load_in(dir, "buses = ( {\n"
                                      "  interface = \"can0\";\n"
                                      "  bitrate = 250000;\n"
                                      "  vendor = 0xEC; product = 0x1234;\n"
                                      "  devices = ( { serial = 0x1007; node_id = 7; },\n"
                                      "              { serial = 0x1006; node_id = 6; } );\n"
                                      "  dcf = [ \"*.dcf\" ];\n"
                                      "} );\n", &c, &d), 0);
        const lssconf_bus *b = &c->buses[0];
        /* lssd.conf's two, then drive5 (also the master's); drive6 is devices[1] */
        ck_assert_uint_eq(b->n_devices, 3);
        ck_assert_ptr_null(lssconf_device_source(c, &b->devices[0]));
        ck_assert_uint_eq(b->devices[0].line, 5);
        ck_assert_ptr_null(lssconf_device_source(c, &b->devices[1]));
        ck_assert_str_eq(source_name(c, &b->devices[2]), "drive5.dcf");
        ck_assert_uint_eq(b->devices[2].line, 6);
        ck_assert_uint_eq(b->devices[2].node_id, 5);
        ck_assert_uint_eq(b->devices[2].identity.serial, 0x1005);
        ck_assert(b->devices[2].has_revision);
        ck_assert_uint_eq(b->devices[2].identity.revision, 0x10002);
        ck_assert_ptr_eq(lssconf_lookup_device(b, &b->devices[2].identity), &b->devices[2]);
        ck_assert_uint_eq(c->n_sources, 1);
        /* the non-configured spare: left out, warned; notes.txt not read */
        ck_assert_uint_eq(d.n_errors, 0);
        ck_assert_uint_eq(d.n_warnings, 1);
        expect_message(&d, LSSCONF_DIAG_WARNING, "spare.dcf:6: left out of the map of can0 (NodeName \"drive 255\"): "
                       "NodeID 255: non-configured");
        ck_assert_str_eq(lssconf_bus_describe(b, buf, sizeof(buf)),
                         "can0: 250000 bit/s, 3 mapped devices (1 from DCFs), auto-assign off, store on, unknown "
                         "devices: ignore, nmt-stop off, replace off, reset after pass off, bit-rate change off, LSS "
                         "timeout 20 ms (adaptive), quiet after another master 3 s");
        lssconf_free(c);
        lssconf_diag_clear(&d);

        /* a pattern of a file's name, an absolute one, several buses, the same file twice */
        char *abs_master;
        ck_assert_int_ge(asprintf(&abs_master, "buses = ( { interface = \"can0\"; dcf = [ \"drive6.dcf\", \"%s/master.dcf\", "
                                  "\"master.dcf\" ]; },\n{ interface = \"can1\"; dcf = \"drive6.dcf\"; } );\n", dir), 0);
        ck_assert_int_eq(load_in(dir, abs_master, &c, &d), 0);
        ck_assert_uint_eq(c->buses[0].n_devices, 2);
        ck_assert_str_eq(source_name(c, &c->buses[0].devices[0]), "drive6.dcf");
        ck_assert_str_eq(source_name(c, &c->buses[0].devices[1]), "master.dcf");
        ck_assert(!c->buses[0].devices[1].has_revision);
        ck_assert_uint_eq(c->buses[1].n_devices, 1);
        ck_assert_uint_eq(c->n_sources, 2);
        ck_assert_uint_eq(d.n_messages, 0);
        lssconf_free(c);
        free(abs_master);
        remove_folder(dir);
}
END_TEST

/* lely-core's NMT slave and master (tests/unit/dcf/): one entry */
START_TEST(dcf_public_files) {
        char *dir = make_folder();
        char *data = test_data_path("dcf"), *text;
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        ck_assert_int_ge(asprintf(&text, "buses = ( { interface = \"can0\"; dcf = [ \"%s/lely-co-nmt-*.dcf\" ]; } );\n",
                                  data), 0);
        ck_assert_int_eq(load_in(dir, text, &c, &d), 0);
        ck_assert_uint_eq(c->buses[0].n_devices, 1);
        const lssconf_device *e = &c->buses[0].devices[0];
        ck_assert_str_eq(source_name(c, e), "lely-co-nmt-master.dcf");
        ck_assert_uint_eq(e->line, 230);
        ck_assert_uint_eq(e->node_id, 2);
        ck_assert_uint_eq(e->identity.vendor, 0x360);
        ck_assert_uint_eq(e->identity.serial, 4);
        ck_assert_uint_eq(d.n_messages, 0);
        lssconf_free(c);
        free(text);
        free(data);
        remove_folder(dir);
}
END_TEST

START_TEST(dcf_errors) {
        static const struct {
                const char *file;  /* bad.dcf, or NULL */
                const char *conf;  /* the bus's keys after interface */
                const char *message[2];
        } cases[] = {
                /* an error in a DCF: its file and line */
                { "[DeviceComissioning]\nNodeID=0x\n", "dcf = [ \"*.dcf\" ];",
                  { "/bad.dcf:2: [DeviceComissioning] NodeID: \"0x\" is not a number", NULL } },
                { "[DeviceComissioning]\nNodeName=x\n", "dcf = [ \"bad.dcf\" ];",
                  { "/bad.dcf:1: [DeviceComissioning] without NodeID", NULL } },
                /* in conflict with lssd.conf's devices, either way */
                { DCF_DEVICE("9", "0x1005"), "devices = ( { vendor = 0xEC; product = 0x1234; serial = 0x1005; "
                  "node_id = 5; } );\n dcf = [ \"*.dcf\" ];",
                  { "/bad.dcf:6: one device gets two node-IDs", "gets node-ID 9 here and node-ID 5 at " } },
                { DCF_DEVICE("5", "0x1005"), "devices = ( { vendor = 0xEC; product = 0x1234; serial = 0x1777; "
                  "node_id = 5; } );\n dcf = [ \"*.dcf\" ];",
                  { "/bad.dcf:6: node-ID 5 is given to two devices", "/lssd.conf:2" } },
                /* a node-ID of a DCF in the pool */
                { DCF_DEVICE("105", "0x1005"), "unknown = \"pool\"; pool = [ 100, 110 ]; dcf = [ \"*.dcf\" ];",
                  { "/lssd.conf:2: buses[0].pool: 100..110 contains node-ID 105 mapped by ", "/bad.dcf:6" } },
                /* what names no file, or cannot be read */
                { NULL, "dcf = [ \"missing.dcf\" ];",
                  { "/missing.dcf: cannot open: No such file or directory", NULL } },
                { NULL, "dcf = [ \"nofolder/*.dcf\" ];",
                  { "/lssd.conf:2: buses[0].dcf[0]: cannot read ", "/nofolder: No such file or directory" } },
                /* the key itself */
                { NULL, "dcf = 5;", { "/lssd.conf:2: buses[0].dcf: expected [ \"GLOB\", ... ], got an integer", NULL } },
                { NULL, "dcf = [ \"\" ];", { "/lssd.conf:2: buses[0].dcf[0]: an empty pattern names no file", NULL } },
                { NULL, "dcf = ( \"a\", 5 );", { "buses[0].dcf[1]: expected a file name pattern \"GLOB\", got an "
                                                 "integer", NULL } },
        };
        for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
                char *dir = make_folder(), *text;
                lssconf_diag d = LSSCONF_DIAG_INIT;
                lssconf *c = NULL;
                if (cases[i].file)
                        put_file(dir, "bad.dcf", cases[i].file);
                ck_assert_int_ge(asprintf(&text, "buses = ( { interface = \"can0\";\n %s } );\n", cases[i].conf), 0);
                int r = load_in(dir, text, &c, &d);
                if (r != -EINVAL || !has_message(&d, LSSCONF_DIAG_ERROR, cases[i].message[0], cases[i].message[1],
                                                 (const char *) NULL)) {
                        dump(&d);
                        ck_abort_msg("case %zu: %d, no error with %s", i, r, cases[i].message[0]);
                }
                lssconf_diag_clear(&d);
                free(text);
                remove_folder(dir);
        }
}
END_TEST

START_TEST(dcf_warnings) {
        char *dir = make_folder();
        lssconf_diag d = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        put_file(dir, "a.dcf", DCF_DEVICE("5", "0x1005") "Baudrate=500\n");
        ck_assert_int_eq(load_in(dir, "buses = ( { interface = \"can0\"; bitrate = 250000;\n"
                                      "dcf = [ \"*.dcf\", \"none-*.dcf\" ]; } );\n", &c, &d), 0);
        ck_assert_uint_eq(c->buses[0].n_devices, 1);
        ck_assert_uint_eq(d.n_warnings, 2);
        expect_message(&d, LSSCONF_DIAG_WARNING, "/lssd.conf:2: buses[0].dcf: the DCFs say Baudrate 500 kbit/s, the bus "
                       "runs at 250000 bit/s (bitrate)");
        expect_message(&d, LSSCONF_DIAG_WARNING, "/lssd.conf:2: buses[0].dcf[1]: \"", "/none-*.dcf\" matches no file");
        lssconf_free(c);
        lssconf_diag_clear(&d);

        /* the same entry in lssd.conf and a DCF: one, lssd.conf's */
        ck_assert_int_eq(load_in(dir, "buses = ( { interface = \"can0\"; bitrate = 500000;\n"
                                      "devices = ( { vendor = 0xEC; product = 0x1234; serial = 0x1005; node_id = 5; } );\n"
                                      "dcf = [ \"*.dcf\" ]; } );\n", &c, &d), 0);
        ck_assert_uint_eq(c->buses[0].n_devices, 1);
        ck_assert_ptr_null(lssconf_device_source(c, &c->buses[0].devices[0]));
        ck_assert(!c->buses[0].devices[0].has_revision);
        ck_assert_uint_eq(d.n_messages, 0);
        lssconf_free(c);

        /* from memory: no file is read */
        const char *text = "buses = ( { interface = \"can0\"; dcf = [ \"*.dcf\" ]; } );\n";
        ck_assert_int_eq(lssconf_load_buffer(text, strlen(text), "mem.conf", &c, &d), 0);
        ck_assert_uint_eq(c->buses[0].n_devices, 0);
        expect_message(&d, LSSCONF_DIAG_WARNING, "mem.conf:1: buses[0].dcf: not read (a configuration from memory "
                       "reads no file)");
        lssconf_free(c);
        lssconf_diag_clear(&d);
        remove_folder(dir);
}
END_TEST

int main(void) {
        Suite *s = suite_create("config");
        TCase *tc = tcase_create("load");
        tcase_set_timeout(tc, 120);
        tcase_add_test(tc, example_conf_loads_cleanly);
        tcase_add_test(tc, all_keys);
        tcase_add_test(tc, defaults);
        tcase_add_test(tc, every_bitrate);
        tcase_add_loop_test(tc, u32_values, 0, sizeof(u32_cases) / sizeof(u32_cases[0]));
        tcase_add_test(tc, literals_in_strings_names_comments);
        tcase_add_test(tc, node_id_range);
        tcase_add_loop_test(tc, bus_key_error, 0, sizeof(bus_key_errors) / sizeof(bus_key_errors[0]));
        tcase_add_loop_test(tc, interface_names, 0, sizeof(ifnames) / sizeof(ifnames[0]));
        tcase_add_test(tc, global_key_errors);
        tcase_add_test(tc, boot_ready_limit);
        tcase_add_test(tc, long_string_is_quoted_bounded);
        tcase_add_test(tc, missing_keys);
        tcase_add_test(tc, semantic_errors_fixture);
        tcase_add_test(tc, identity_rules);
        tcase_add_test(tc, pool_rules);
        tcase_add_test(tc, duplicate_interfaces);
        tcase_add_test(tc, unknown_keys_warn);
        tcase_add_test(tc, empty_and_no_buses);
        tcase_add_test(tc, syntax_error_line);
        tcase_add_test(tc, nul_byte_in_buffer);
        tcase_add_test(tc, nonexistent_file);
        tcase_add_loop_test(tc, one_megabyte_of_junk, 0, 4);
        tcase_add_test(tc, too_big);
        tcase_add_test(tc, many_messages_are_capped);
        tcase_add_test(tc, many_devices);
        tcase_add_test(tc, lookups);
        tcase_add_test(tc, describe);
        tcase_add_test(tc, built_in_config);
        tcase_add_test(tc, enum_strings);
        tcase_add_test(tc, load_buffer_api);
        tcase_add_test(tc, dcf_map_from_files);
        tcase_add_test(tc, dcf_public_files);
        tcase_add_test(tc, dcf_errors);
        tcase_add_test(tc, dcf_warnings);
        suite_add_tcase(s, tc);
        SRunner *sr = srunner_create(s);
        srunner_run_all(sr, CK_NORMAL);
        int failed = srunner_ntests_failed(sr);
        srunner_free(sr);
        return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
