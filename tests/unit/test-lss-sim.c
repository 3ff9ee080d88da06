/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* lss-sim without CAN: options, profiles, state files, the transmit queue and
 * the simulated segment driven on virtual time. */
#include <check.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "lss-sim/can_raw.h"
#include "lss-sim/options.h"
#include "lss-sim/profiles.h"
#include "lss-sim/sim.h"
#include "lss-sim/state_file.h"
#include "lss-sim/txqueue.h"

/* ---- helpers ---- */

#define ARGV(...) ((char *[]) { "lss-sim", __VA_ARGS__, NULL })
#define ARGC(...) ((int) (sizeof((char *[]) { "lss-sim", __VA_ARGS__ }) / sizeof(char *)))
/* parse into o; messages land in msg (caller frees) */
#define PARSE(o, msg, ...) parse(o, msg, ARGC(__VA_ARGS__), ARGV(__VA_ARGS__))

static int parse(sim_options *o, char **msg, int argc, char **argv) {
        size_t len;
        FILE *f = open_memstream(msg, &len);
        ck_assert_ptr_nonnull(f);
        int r = sim_options_parse(o, argc, argv, f, f);
        fclose(f);
        return r;
}

/* expect a usage error whose message quotes `needle` */
static void expect_usage_error(int argc, char **argv, const char *needle) {
        sim_options o;
        char *msg = NULL;
        int r = parse(&o, &msg, argc, argv);
        ck_assert_msg(r == -EINVAL, "expected -EINVAL, got %d for '%s'", r, needle);
        ck_assert_msg(strstr(msg, needle), "message '%s' does not name '%s'", msg, needle);
        free(msg);
        sim_options_done(&o);
}
#define USAGE_ERROR(needle, ...) expect_usage_error(ARGC(__VA_ARGS__), ARGV(__VA_ARGS__), needle)

/* "7E5#0401000000000000" -> frame */
static lss_frame frame(const char *s) {
        lss_frame f = {};
        char *end;
        f.id = (uint32_t) strtoul(s, &end, 16);
        ck_assert_int_eq(*end, '#');
        for (const char *p = end + 1; p[0] && p[1]; p += 2) {
                char b[3] = { p[0], p[1], 0 };
                f.data[f.len++] = (uint8_t) strtoul(b, NULL, 16);
        }
        return f;
}

static const char *fmt(const lss_frame *f) {
        static char buf[4][40];
        static unsigned i;
        return lss_frame_format(f, buf[i++ % 4], sizeof(buf[0]));
}

typedef struct capture {
        lss_frame f[64];
        uint64_t t[64];
        size_t n;
} capture;

/* Run the segment on virtual time until `until`, collecting what it sends. */
static void run_until(sim *s, uint64_t until, capture *c) {
        for (;;) {
                uint64_t t = sim_next_deadline(s);
                if (t > until)
                        break;
                sim_on_time(s, t);
                lss_frame f;
                while (sim_next_tx(s, t, &f)) {
                        ck_assert_uint_lt(c->n, 64);
                        c->t[c->n] = t;
                        c->f[c->n++] = f;
                }
        }
}

/* Feed a frame at t, run for 50 ms, expect exactly the frames listed. */
static void exchange(sim *s, uint64_t *t, const char *request, const char *const *expect) {
        capture c = {};
        lss_frame rq = frame(request);
        sim_on_frame(s, &rq, *t);
        run_until(s, *t + 50000, &c);
        size_t n = 0;
        while (expect[n])
                n++;
        ck_assert_msg(c.n == n, "%s: %zu frames instead of %zu (first %s)", request, c.n, n,
                      c.n ? fmt(&c.f[0]) : "-");
        for (size_t i = 0; i < n; i++) {
                lss_frame e = frame(expect[i]);
                ck_assert_msg(c.f[i].id == e.id && c.f[i].len == e.len && c.f[i].flags == 0 &&
                              memcmp(c.f[i].data, e.data, e.len) == 0,
                              "%s: got %s, expected %s", request, fmt(&c.f[i]), expect[i]);
        }
        *t += 100000;
}
#define EXCHANGE(s, t, rq, ...) exchange(s, t, rq, (const char *const[]) { __VA_ARGS__, NULL })
#define SILENCE(s, t, rq) exchange(s, t, rq, (const char *const[]) { NULL })

static sim *new_sim(int argc, char **argv, uint64_t t) {
        sim_options o;
        char *msg = NULL;
        sim *s = NULL;
        ck_assert_int_eq(parse(&o, &msg, argc, argv), 0);
        free(msg);
        size_t len;
        FILE *err = open_memstream(&msg, &len);
        int r = sim_new(&s, &o, t, err);
        fclose(err);
        ck_assert_msg(r == 0, "sim_new: %d: %s", r, msg);
        free(msg);
        sim_options_done(&o);
        return s;
}
#define NEW_SIM(t, ...) new_sim(ARGC(__VA_ARGS__), ARGV(__VA_ARGS__), t)

static char *make_tmpdir(void) {
        const char *base = getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp";
        char *d;
        ck_assert_int_ge(asprintf(&d, "%s/test-lss-sim-XXXXXX", base), 0);
        ck_assert_ptr_nonnull(mkdtemp(d));
        return d;
}

static void remove_tmpdir(char *d) {
        char cmd[4200];
        snprintf(cmd, sizeof(cmd), "rm -rf '%s'", d);
        ck_assert_int_eq(system(cmd), 0);
        free(d);
}

static char *slurp(const char *path) {
        FILE *f = fopen(path, "re");
        ck_assert_msg(f != NULL, "cannot open %s", path);
        char *buf = calloc(1, 8192);
        size_t n = fread(buf, 1, 8191, f);
        buf[n] = '\0';
        fclose(f);
        return buf;
}

/* ---- value parsing ---- */

START_TEST(parse_values) {
        uint32_t v;
        uint64_t w;
        uint8_t nid;

        ck_assert_int_eq(sim_parse_u32("0xFFFFFFFF", &v), 0);
        ck_assert_uint_eq(v, 0xFFFFFFFFu);
        ck_assert_int_eq(sim_parse_u32("4294967295", &v), 0);
        ck_assert_uint_eq(v, 0xFFFFFFFFu);
        ck_assert_int_eq(sim_parse_u32("0x80002468", &v), 0);
        ck_assert_uint_eq(v, 0x80002468u);
        ck_assert_int_eq(sim_parse_u32("0X1a", &v), 0);
        ck_assert_uint_eq(v, 0x1A);
        ck_assert_int_eq(sim_parse_u32("010", &v), 0); /* decimal, not octal */
        ck_assert_uint_eq(v, 10);
        ck_assert_int_eq(sim_parse_u32("4294967296", &v), -ERANGE);
        ck_assert_int_eq(sim_parse_u32("0x100000000", &v), -ERANGE);
        ck_assert_int_eq(sim_parse_u64("18446744073709551616", &w), -ERANGE);
        ck_assert_int_eq(sim_parse_u32("-1", &v), -EINVAL);
        ck_assert_int_eq(sim_parse_u32("+1", &v), -EINVAL);
        ck_assert_int_eq(sim_parse_u32("", &v), -EINVAL);
        ck_assert_int_eq(sim_parse_u32("0x", &v), -EINVAL);
        ck_assert_int_eq(sim_parse_u32(" 1", &v), -EINVAL);
        ck_assert_int_eq(sim_parse_u32("1 ", &v), -EINVAL);
        ck_assert_int_eq(sim_parse_u32("12g", &v), -EINVAL);

        ck_assert_int_eq(sim_parse_ms("2", &v), 0);
        ck_assert_uint_eq(v, 2000);
        ck_assert_int_eq(sim_parse_ms("0.5", &v), 0);
        ck_assert_uint_eq(v, 500);
        ck_assert_int_eq(sim_parse_ms("1.234", &v), 0);
        ck_assert_uint_eq(v, 1234);
        ck_assert_int_eq(sim_parse_ms("1.2345", &v), -EINVAL);
        ck_assert_int_eq(sim_parse_ms(".", &v), -EINVAL);
        ck_assert_int_eq(sim_parse_ms("1.2.3", &v), -EINVAL);
        ck_assert_int_eq(sim_parse_ms("5000000", &v), -ERANGE);

        ck_assert_int_eq(sim_parse_node_id("1", &nid), 0);
        ck_assert_uint_eq(nid, 1);
        ck_assert_int_eq(sim_parse_node_id("127", &nid), 0);
        ck_assert_uint_eq(nid, 127);
        ck_assert_int_eq(sim_parse_node_id("0xFF", &nid), 0);
        ck_assert_uint_eq(nid, 0xFF);
        ck_assert_int_lt(sim_parse_node_id("0", &nid), 0);
        ck_assert_int_lt(sim_parse_node_id("128", &nid), 0);
        ck_assert_int_lt(sim_parse_node_id("0xFE", &nid), 0);
        ck_assert_int_lt(sim_parse_node_id("256", &nid), 0);
}
END_TEST

START_TEST(parse_identity) {
        sim_slave_spec s;
        const char *what = NULL;

        ck_assert_int_eq(sim_parse_slave("0x9A:3:0x00010002:0xFFFFFFFF:0x44", &s, &what), 0);
        ck_assert_uint_eq(s.id.vendor, 0x9A);
        ck_assert_uint_eq(s.id.product, 3);
        ck_assert_uint_eq(s.id.revision, 0x00010002);
        ck_assert_uint_eq(s.id.serial, 0xFFFFFFFFu);
        ck_assert(s.node_id_given);
        ck_assert_uint_eq(s.node_id, 0x44);

        ck_assert_int_eq(sim_parse_slave("1:2:3:4", &s, &what), 0);
        ck_assert(!s.node_id_given);
        ck_assert_uint_eq(s.id.serial, 4);
        ck_assert_int_eq(sim_parse_slave("1:2:3:4:0xFF", &s, &what), 0);
        ck_assert(s.node_id_given);
        ck_assert_uint_eq(s.node_id, 0xFF);

        ck_assert_int_eq(sim_parse_slave("1:2:3", &s, &what), -EINVAL);
        /* what was expected and what came instead (issue 21: "bad expected") */
        ck_assert_str_eq(what, "expected VENDOR:PRODUCT:REVISION:SERIAL[:NODEID], got 3 fields");
        ck_assert_int_eq(sim_parse_slave("1:2:3:4:5:6", &s, &what), -EINVAL);
        ck_assert_str_eq(what, "expected VENDOR:PRODUCT:REVISION:SERIAL[:NODEID], got more than 5 fields");
        ck_assert_int_eq(sim_parse_slave("x:2:3:4", &s, &what), -EINVAL);
        ck_assert_str_eq(what, "vendor 'x': expected a number, decimal or 0x hexadecimal, 0..0xFFFFFFFF");
        ck_assert_int_eq(sim_parse_slave("1:2:3:0x100000000", &s, &what), -EINVAL);
        ck_assert_str_eq(what, "serial '0x100000000': expected a number, decimal or 0x hexadecimal, 0..0xFFFFFFFF");
        ck_assert_int_eq(sim_parse_slave("1::3:4", &s, &what), -EINVAL);
        ck_assert_str_eq(what, "product '': expected a number, decimal or 0x hexadecimal, 0..0xFFFFFFFF");
        ck_assert_int_eq(sim_parse_slave("1:2:3:4:0", &s, &what), -EINVAL);
        ck_assert_str_eq(what, "node-ID '0': expected 1..127, or 0xFF for non-configured");
        ck_assert_int_eq(sim_parse_slave("1:2:3:4:128", &s, &what), -EINVAL);
        ck_assert_int_eq(sim_parse_slave("1:2:3:4:", &s, &what), -EINVAL);
}
END_TEST

/* ---- command line ---- */

START_TEST(options_full) {
        sim_options o;
        char *msg = NULL;

        int r = PARSE(&o, &msg, "--slave", "0x9A:3:0x10002:0xFFFFFFFF:5", "vcan0", "--slave", "1:2:3:4",
                      "--random", "3", "--seed", "0x1234", "--latency", "2.5", "--jitter", "1",
                      "--profile", "encoder", "--state", "/tmp/st", "--bitrate", "500000",
                      "--fault", "silent@4", "--fault", "ignore-cs=0x5E", "--no-follow-bitrate", "-v");
        ck_assert_msg(r == 0, "%s", msg);
        free(msg);
        ck_assert_str_eq(o.ifname, "vcan0");
        ck_assert_uint_eq(o.n_slaves, 2);
        ck_assert_uint_eq(o.slaves[0].id.serial, 0xFFFFFFFFu);
        ck_assert_uint_eq(o.slaves[0].node_id, 5);
        ck_assert(!o.slaves[1].node_id_given);
        ck_assert_uint_eq(o.random_count, 3);
        ck_assert_uint_eq(o.seed, 0x1234);
        ck_assert(o.latency_given);
        ck_assert_uint_eq(o.latency_us, 2500);
        ck_assert_uint_eq(o.jitter_us, 1000);
        ck_assert_str_eq(o.profile->name, "encoder");
        ck_assert_str_eq(o.state_dir, "/tmp/st");
        ck_assert_uint_eq(o.bitrate, 500000);
        ck_assert_uint_eq(o.n_faults, 2);
        ck_assert_int_eq(o.faults[0].knob, SIM_KNOB_SILENT);
        ck_assert(o.faults[0].has_serial);
        ck_assert_uint_eq(o.faults[0].serial, 4);
        ck_assert_int_eq(o.faults[1].knob, SIM_KNOB_IGNORE_CS);
        ck_assert_uint_eq(o.faults[1].value, 0x5E);
        ck_assert(!o.follow_bitrate);
        ck_assert(o.verbose);
        sim_options_done(&o);

        /* defaults */
        r = PARSE(&o, &msg, "can0");
        free(msg);
        ck_assert_int_eq(r, 0);
        ck_assert_str_eq(o.profile->name, "servo-drive");
        ck_assert_uint_eq(o.bitrate, 125000);
        ck_assert_uint_eq(o.seed, 1);
        ck_assert(o.follow_bitrate);
        ck_assert_ptr_null(o.state_dir);
        sim_options_done(&o);
}
END_TEST

START_TEST(options_errors) {
        USAGE_ERROR("--slave 'x:2:3:4': vendor 'x': expected a number", "vcan0", "--slave", "x:2:3:4");
        USAGE_ERROR("'1:2:3:4:0'", "vcan0", "--slave", "1:2:3:4:0");
        USAGE_ERROR("node-ID", "vcan0", "--slave", "1:2:3:4:200");
        USAGE_ERROR("--slave '1:2:3': expected VENDOR:PRODUCT:REVISION:SERIAL[:NODEID], got 3 fields", "vcan0", "--slave", "1:2:3");
        USAGE_ERROR("--random 'many'", "vcan0", "--random", "many");
        USAGE_ERROR("--random '10001'", "vcan0", "--random", "10001");
        USAGE_ERROR("--seed '-3'", "vcan0", "--seed", "-3");
        USAGE_ERROR("--latency 'x'", "vcan0", "--latency", "x");
        USAGE_ERROR("--jitter '1.0001'", "vcan0", "--jitter", "1.0001");
        USAGE_ERROR("--profile 'drive'", "vcan0", "--profile", "drive");
        USAGE_ERROR("canopennode-bitrate, lely)", "vcan0", "--profile", "drive");
        USAGE_ERROR("--bitrate '123456'", "vcan0", "--bitrate", "123456");
        USAGE_ERROR("--fault 'bogus'", "vcan0", "--fault", "bogus");
        USAGE_ERROR("--fault 'ignore-cs'", "vcan0", "--fault", "ignore-cs");
        USAGE_ERROR("--fault 'ignore-cs=0x100'", "vcan0", "--fault", "ignore-cs=0x100");
        USAGE_ERROR("--fault 'early-config=serial'", "vcan0", "--fault", "early-config=serial");
        USAGE_ERROR("--fault 'silent=maybe'", "vcan0", "--fault", "silent=maybe");
        USAGE_ERROR("--fault 'silent@x'", "vcan0", "--fault", "silent@x");
        USAGE_ERROR("--fault 'bit-index-unsupported=32'", "vcan0", "--fault", "bit-index-unsupported=32");
        USAGE_ERROR("--fault 'drop'", "vcan0", "--fault", "drop");
        USAGE_ERROR("--fault 'drop=1.5'", "vcan0", "--fault", "drop=1.5");
        USAGE_ERROR("--fault 'drop=2%'", "vcan0", "--fault", "drop=2%");
        USAGE_ERROR("--fault 'drop=0.0000001'", "vcan0", "--fault", "drop=0.0000001");
        USAGE_ERROR("--fault 'drop=.'", "vcan0", "--fault", "drop=.");
        USAGE_ERROR("--state", "vcan0", "--state", "");
        USAGE_ERROR("missing IFACE", "--slave", "1:2:3:4");
        USAGE_ERROR("'vcan1'", "vcan0", "vcan1");
        USAGE_ERROR("--frobnicate", "vcan0", "--frobnicate");
        USAGE_ERROR("--slave", "vcan0", "--slave");
        USAGE_ERROR("IFACE", "an-interface-name-far-too-long");
}
END_TEST

START_TEST(options_help_version) {
        sim_options o;
        char *msg = NULL;

        ck_assert_int_eq(PARSE(&o, &msg, "--help"), 1);
        ck_assert_ptr_nonnull(strstr(msg, "--slave"));
        ck_assert_ptr_nonnull(strstr(msg, "canopennode"));
        ck_assert_ptr_nonnull(strstr(msg, "miss-activation"));
        ck_assert_ptr_nonnull(strstr(msg, "  lely "));
        ck_assert_ptr_nonnull(strstr(msg, "lely-lss"));
        ck_assert_ptr_nonnull(strstr(msg, ".state"));
        free(msg);
        sim_options_done(&o);

        ck_assert_int_eq(PARSE(&o, &msg, "--version"), 1);
        ck_assert_ptr_nonnull(strstr(msg, "lss-sim "));
        free(msg);
        sim_options_done(&o);
}
END_TEST

/* ---- fault knobs and profiles ---- */

static void apply(lss_slave_faults *f, const char *arg) {
        sim_fault_spec spec;
        const char *what = NULL;
        ck_assert_msg(sim_parse_fault(arg, &spec, &what) == 0, "%s: %s", arg, what);
        sim_fault_apply(&spec, f);
}

START_TEST(fault_knobs) {
        lss_slave_faults f;
        lss_slave_faults_default(&f);

        apply(&f, "silent");
        ck_assert(f.silent);
        apply(&f, "silent=0");
        ck_assert(!f.silent);
        apply(&f, "ignore-cs=0x5E");
        ck_assert_int_eq(f.ignore_cs, 0x5E);
        apply(&f, "ignore-cs=none");
        ck_assert_int_eq(f.ignore_cs, -1);
        apply(&f, "wrong-dlc=yes");
        ck_assert(f.wrong_dlc);
        apply(&f, "fastscan-when-configured");
        ck_assert(f.fastscan_when_configured);
        apply(&f, "store-unsupported");
        ck_assert(f.store_unsupported);
        apply(&f, "store-fails=on");
        ck_assert(f.store_fails);
        apply(&f, "early-config=product");
        ck_assert_int_eq(f.early_config, SLAVE_EARLY_AFTER_PRODUCT);
        apply(&f, "early-config=revision");
        ck_assert_int_eq(f.early_config, SLAVE_EARLY_AFTER_REVISION);
        apply(&f, "early-config=vendor");
        ck_assert_int_eq(f.early_config, SLAVE_EARLY_AFTER_VENDOR);
        apply(&f, "needs-nmt-stopped");
        ck_assert(f.needs_nmt_stopped);
        apply(&f, "no-identify");
        ck_assert(f.no_identify);
        apply(&f, "bit-timing-silent");
        ck_assert(f.bit_timing_silent);
        apply(&f, "bit-index-unsupported=5");
        apply(&f, "bit-index-unsupported=0x1,8");
        ck_assert_uint_eq(f.bit_index_unsupported, (1u << 5) | (1u << 1) | (1u << 8));
        apply(&f, "bit-index-unsupported=none");
        ck_assert_uint_eq(f.bit_index_unsupported, 0);
        apply(&f, "miss-activation");
        ck_assert(f.miss_activation);
        apply(&f, "duplicate-answers");
        ck_assert(f.duplicate_answers);
        apply(&f, "configure-error-specific");
        ck_assert(f.configure_error_specific);
        apply(&f, "lely-lss");
        ck_assert(f.lely_lss);
        apply(&f, "lely-lss=off");
        ck_assert(!f.lely_lss);
        apply(&f, "latency=12.5");
        ck_assert_uint_eq(f.latency_us, 12500);
        apply(&f, "jitter=3");
        ck_assert_uint_eq(f.jitter_us, 3000);
        /* drop=P: both ways, in parts per million */
        apply(&f, "drop=0.02");
        ck_assert_uint_eq(f.rx_loss_ppm, 20000);
        ck_assert_uint_eq(f.tx_loss_ppm, 20000);
        apply(&f, "drop=1");
        ck_assert_uint_eq(f.rx_loss_ppm, 1000000);
        apply(&f, "drop=0.000001");
        ck_assert_uint_eq(f.tx_loss_ppm, 1);
        apply(&f, "drop=0");
        ck_assert_uint_eq(f.rx_loss_ppm + f.tx_loss_ppm, 0);

        sim_fault_spec spec;
        const char *what;
        ck_assert_int_eq(sim_parse_fault("store-fails@0xFFFFFFFF", &spec, &what), 0);
        ck_assert(spec.has_serial);
        ck_assert_uint_eq(spec.serial, 0xFFFFFFFFu);
        for (int k = 0; k < _SIM_KNOB_MAX; k++)
                ck_assert_ptr_nonnull(sim_knob_name((enum sim_knob) k));
}
END_TEST

START_TEST(profiles) {
        lss_slave_faults f;
        size_t n;
        const sim_profile *all = sim_profile_all(&n);

        ck_assert_uint_eq(n, 7);
        ck_assert_ptr_eq(all, sim_profile_default());
        ck_assert_str_eq(sim_profile_default()->name, "servo-drive");
        ck_assert_ptr_null(sim_profile_find("nope"));

        const sim_profile *p = sim_profile_find("servo-drive");
        sim_profile_faults(p, &f);
        ck_assert(!f.no_identify && !f.needs_nmt_stopped && !f.bit_timing_silent);
        ck_assert_uint_eq(f.bit_index_unsupported, 0);
        ck_assert_uint_eq(p->default_node_id, 0xFF);

        p = sim_profile_find("encoder");
        ck_assert(p->fixed_vendor);
        ck_assert_uint_eq(p->vendor, 0xEC);
        ck_assert_uint_eq(p->default_node_id, 1);
        sim_profile_faults(p, &f);
        ck_assert(f.needs_nmt_stopped);

        p = sim_profile_find("transmitter");
        sim_profile_faults(p, &f);
        ck_assert_uint_eq(f.bit_index_unsupported, 1u << 5);

        p = sim_profile_find("generic");
        sim_profile_faults(p, &f);
        ck_assert(!f.no_identify && !f.needs_nmt_stopped && !f.bit_timing_silent && !f.silent);
        ck_assert_int_eq(f.ignore_cs, -1);

        p = sim_profile_find("canopennode");
        sim_profile_faults(p, &f);
        ck_assert(f.no_identify);
        ck_assert(f.bit_timing_silent);

        p = sim_profile_find("canopennode-bitrate");
        sim_profile_faults(p, &f);
        ck_assert(f.no_identify && f.canopennode_lss && !f.bit_timing_silent);

        /* lss_slave_faults_lely(): the profile's knobs do not undo its 13 01 */
        p = sim_profile_find("lely");
        ck_assert_uint_eq(p->default_node_id, 0xFF);
        sim_profile_faults(p, &f);
        ck_assert(f.lely_lss && f.miss_activation && !f.no_identify && !f.canopennode_lss);
        ck_assert_uint_eq(f.bit_index_unsupported, UINT32_MAX);
}
END_TEST

/* ---- state files ---- */

START_TEST(state_round_trip) {
        lss_identity id = { 0x9A, 3, 0x00010002, 0xFFFFFFFFu };
        lss_slave_state st = {
                .active_node_id = 0xFF, .pending_node_id = 0x44, .stored_node_id = 0x44,
                .bit_index = 4, .pending_bit_index = 2, .stored_bit_index = 2,
                .configuration = true, .nmt = SLAVE_NMT_STOPPED,
        };
        char text[1024], path[256];
        state_record r;
        unsigned line = 0;

        ck_assert_int_gt(state_file_format(text, sizeof(text), &id, &st), 0);
        ck_assert_ptr_nonnull(strstr(text, "\nserial=0xffffffff\n"));
        ck_assert_ptr_nonnull(strstr(text, "\nstored_node_id=68\n"));
        ck_assert_ptr_nonnull(strstr(text, "\nactive_node_id=255\n"));
        ck_assert_ptr_nonnull(strstr(text, "\nlss_state=configuration\n"));
        ck_assert_ptr_nonnull(strstr(text, "\nnmt_state=stopped\n"));
        ck_assert_int_eq(state_file_format(text, 16, &id, &st), -ENOBUFS);

        char *dir = make_tmpdir();
        ck_assert_int_eq(state_file_path(path, sizeof(path), dir, 0xABCD, false), 0);
        ck_assert_ptr_nonnull(strstr(path, "/0000abcd.state"));
        ck_assert_int_eq(state_file_path(path, sizeof(path), dir, 0xABCD, true), 0);
        ck_assert_ptr_nonnull(strstr(path, "/0000ABCD.state"));
        ck_assert_int_eq(state_file_path(path, 8, dir, 0xABCD, false), -ENAMETOOLONG);

        ck_assert_int_eq(state_file_path(path, sizeof(path), dir, id.serial, false), 0);
        ck_assert_int_eq(state_file_read(path, &r, &line), -ENOENT);
        ck_assert_int_eq(state_file_write(path, &id, &st), 0);
        ck_assert_int_eq(state_file_read(path, &r, &line), 0);
        ck_assert(lss_identity_equal(&r.id, &id));
        ck_assert_uint_eq(r.st.active_node_id, st.active_node_id);
        ck_assert_uint_eq(r.st.pending_node_id, st.pending_node_id);
        ck_assert_uint_eq(r.st.stored_node_id, st.stored_node_id);
        ck_assert_uint_eq(r.st.bit_index, st.bit_index);
        ck_assert_uint_eq(r.st.pending_bit_index, st.pending_bit_index);
        ck_assert_uint_eq(r.st.stored_bit_index, st.stored_bit_index);
        ck_assert(r.st.configuration);
        ck_assert_int_eq(r.st.nmt, SLAVE_NMT_STOPPED);
        ck_assert_uint_eq(r.have, (1u << 12) - 1);
        ck_assert(state_record_matches(&r, &id));
        lss_identity other = id;
        other.revision++;
        ck_assert(!state_record_matches(&r, &other));

        /* rewriting replaces the file, no temporary left behind */
        st.configuration = false;
        ck_assert_int_eq(state_file_write(path, &id, &st), 0);
        ck_assert_int_eq(state_file_read(path, &r, &line), 0);
        ck_assert(!r.st.configuration);
        char tmp[300];
        snprintf(tmp, sizeof(tmp), "%s.tmp", path);
        ck_assert_int_ne(access(tmp, F_OK), 0);
        remove_tmpdir(dir);
}
END_TEST

START_TEST(state_parse) {
        state_record r;
        unsigned line = 0;

        /* hand-written: blanks, comments, hex, unknown keys, partial identity */
        ck_assert_int_eq(state_file_parse("# x\n\n  serial = 0x11 \r\nstored_node_id=0x44\nfuture_key=1\n"
                                          "stored_bit_timing_index=2", &r, &line), 0);
        ck_assert_uint_eq(r.have, STATE_HAVE_SERIAL | STATE_HAVE_STORED_NODE_ID | STATE_HAVE_STORED_BIT_INDEX);
        ck_assert_uint_eq(r.st.stored_node_id, 0x44);
        ck_assert_uint_eq(r.st.stored_bit_index, 2);
        lss_identity id = { 1, 2, 3, 0x11 };
        ck_assert(state_record_matches(&r, &id));
        id.serial = 0x12;
        ck_assert(!state_record_matches(&r, &id));

        ck_assert_int_eq(state_file_parse("serial=1\nno equals sign\n", &r, &line), -EINVAL);
        ck_assert_uint_eq(line, 2);
        ck_assert_int_eq(state_file_parse("stored_node_id=0\n", &r, &line), -EINVAL);
        ck_assert_uint_eq(line, 1);
        ck_assert_int_eq(state_file_parse("a=1\nb=2\nactive_node_id=128\n", &r, &line), -EINVAL);
        ck_assert_uint_eq(line, 3);
        ck_assert_int_eq(state_file_parse("lss_state=sleeping\n", &r, &line), -EINVAL);
        ck_assert_int_eq(state_file_parse("nmt_state=running\n", &r, &line), -EINVAL);
        ck_assert_int_eq(state_file_parse("vendor=0x100000000\n", &r, &line), -EINVAL);
        ck_assert_int_eq(state_file_parse("bit_timing_index=256\n", &r, &line), -EINVAL);
}
END_TEST

/* ---- transmit queue ---- */

START_TEST(txqueue_merge) {
        txqueue q = {};
        txq_entry e;
        size_t merged;
        lss_frame a = frame("7E4#4F00000000000000"), b = frame("7E4#5E05000000000000"), c = frame("701#00");

        ck_assert(!txq_pop(&q, 1000, &e, &merged));
        ck_assert_uint_eq(txq_next_due(&q), UINT64_MAX);

        /* four slaves answer a ping at 1000..1100 µs: one frame */
        for (uint32_t i = 0; i < 4; i++)
                ck_assert_int_eq(txq_push(&q, 1000 + 33 * i, i, &a), 0);
        /* same frame 101 µs after the first: a frame of its own */
        ck_assert_int_eq(txq_push(&q, 1101, 7, &a), 0);
        /* different frame inside the window: kept */
        ck_assert_int_eq(txq_push(&q, 1050, 9, &b), 0);
        ck_assert_uint_eq(txq_next_due(&q), 1000);
        ck_assert(!txq_pop(&q, 999, &e, &merged));

        ck_assert(txq_pop(&q, 1000, &e, &merged));
        ck_assert_uint_eq(merged, 3);
        ck_assert_uint_eq(e.due_us, 1000);
        ck_assert_uint_eq(txq_size(&q), 2);
        ck_assert(!txq_pop(&q, 1000, &e, &merged));
        ck_assert(txq_pop(&q, 2000, &e, &merged));
        ck_assert_uint_eq(e.frame.data[0], 0x5E);
        ck_assert_uint_eq(merged, 0);
        ck_assert(txq_pop(&q, 2000, &e, &merged));
        ck_assert_uint_eq(e.from, 7);
        ck_assert_uint_eq(txq_size(&q), 0);

        /* one sender's duplicate is its own frame; the other slave's copy merges */
        ck_assert_int_eq(txq_push(&q, 5000, 1, &a), 0);
        ck_assert_int_eq(txq_push(&q, 5000, 1, &a), 0);
        ck_assert_int_eq(txq_push(&q, 5000, 2, &a), 0);
        ck_assert(txq_pop(&q, 5000, &e, &merged));
        ck_assert_uint_eq(merged, 1);
        ck_assert(txq_pop(&q, 5000, &e, &merged));
        ck_assert_uint_eq(merged, 0);
        ck_assert_uint_eq(e.from, 1);

        /* FIFO at equal times, order by time otherwise, drop_front */
        ck_assert_int_eq(txq_push(&q, 9000, 1, &c), 0);
        ck_assert_int_eq(txq_push(&q, 8000, 2, &b), 0);
        ck_assert_int_eq(txq_push(&q, 9000, 3, &a), 0);
        txq_drop_front(&q);
        ck_assert(txq_pop(&q, 9000, &e, NULL));
        ck_assert_uint_eq(e.from, 1);
        ck_assert(txq_pop(&q, 9000, &e, NULL));
        ck_assert_uint_eq(e.from, 3);

        /* many senders: the scratch list grows */
        for (uint32_t i = 0; i < 1000; i++)
                ck_assert_int_eq(txq_push(&q, 20000, i, &a), 0);
        ck_assert(txq_pop(&q, 20000, &e, &merged));
        ck_assert_uint_eq(merged, 999);
        ck_assert_uint_eq(txq_size(&q), 0);
        txq_done(&q);
}
END_TEST

/* ---- the segment on virtual time ---- */

/* The seed example, byte for byte: one non-configured generic slave. */
START_TEST(seed_example) {
        uint64_t t = 1000;
        sim *s = NEW_SIM(t, "vcan0", "--profile", "generic", "--slave", "1:2:3:4");
        capture c = {};

        ck_assert_uint_eq(s->n_slaves, 1);
        ck_assert_uint_eq(s->slaves[0].s.st.active_node_id, 0xFF);
        run_until(s, t + 50000, &c);
        ck_assert_uint_eq(c.n, 0); /* non-configured: no boot-up at power-on */

        SILENCE(s, &t, "7E5#0401000000000000");
        EXCHANGE(s, &t, "7E5#1144000000000000", "7E4#1100000000000000");
        EXCHANGE(s, &t, "7E5#1700000000000000", "7E4#1700000000000000");
        EXCHANGE(s, &t, "7E5#0400000000000000", "744#00");
        ck_assert_uint_eq(s->slaves[0].s.st.active_node_id, 0x44);
        ck_assert_uint_eq(s->slaves[0].s.st.stored_node_id, 0x44);
        sim_free(s);
}
END_TEST

START_TEST(configured_slave_boots) {
        uint64_t t = 0;
        sim *s = NEW_SIM(t, "vcan0", "--slave", "1:2:3:4:5", "--latency", "1");
        capture c = {};
        run_until(s, t + 50000, &c);
        ck_assert_uint_eq(c.n, 1);
        ck_assert_str_eq(fmt(&c.f[0]), "705#00");
        ck_assert_uint_eq(c.t[0], 1000); /* the answer latency applies */
        t = 100000;
        /* inquire in configuration state */
        SILENCE(s, &t, "7E5#0401000000000000");
        EXCHANGE(s, &t, "7E5#5E00000000000000", "7E4#5E05000000000000");
        EXCHANGE(s, &t, "7E5#5D00000000000000", "7E4#5D04000000000000");
        /* NMT reset communication for node 5: boot-up again */
        EXCHANGE(s, &t, "000#8205", "705#00");
        sim_free(s);
}
END_TEST

/* Many slaves answering one fastscan ping: one frame on the bus. */
START_TEST(fastscan_ping_merges) {
        uint64_t t = 0;
        sim *s = NEW_SIM(t, "vcan0", "--random", "20", "--seed", "5");
        EXCHANGE(s, &t, "7E5#5100000000800000", "7E4#4F00000000000000");
        ck_assert_uint_eq(s->stats.merged_frames, 19);
        /* duplicate-answers: every slave's second copy is a second frame */
        sim_free(s);

        t = 0;
        s = NEW_SIM(t, "vcan0", "--random", "3", "--fault", "duplicate-answers");
        EXCHANGE(s, &t, "7E5#5100000000800000", "7E4#4F00000000000000", "7E4#4F00000000000000");
        sim_free(s);
}
END_TEST

START_TEST(random_identities) {
        sim *a = NEW_SIM(0, "vcan0", "--random", "500", "--seed", "42", "--slave", "7:7:7:7");
        sim *b = NEW_SIM(0, "vcan0", "--random", "500", "--seed", "42", "--slave", "7:7:7:7");
        sim *c = NEW_SIM(0, "vcan0", "--random", "500", "--seed", "43", "--profile", "generic");
        sim *e = NEW_SIM(0, "vcan0", "--random", "3", "--profile", "encoder");

        ck_assert_uint_eq(a->n_slaves, 501);
        ck_assert_uint_eq(a->slaves[0].s.id.serial, 7); /* explicit ones first */
        for (size_t i = 1; i < a->n_slaves; i++) {
                ck_assert(lss_identity_equal(&a->slaves[i].s.id, &b->slaves[i].s.id));
                ck_assert_uint_eq(a->slaves[i].s.id.vendor, 0x9A); /* servo-drive fixes it */
                ck_assert_uint_eq(a->slaves[i].s.st.active_node_id, 0xFF);
                for (size_t j = 0; j < i; j++)
                        ck_assert_uint_ne(a->slaves[i].s.id.serial, a->slaves[j].s.id.serial);
        }
        /* another seed, another bus; generic makes vendors up too */
        ck_assert_uint_ne(a->slaves[1].s.id.serial, c->slaves[0].s.id.serial);
        ck_assert_uint_ne(c->slaves[0].s.id.vendor, c->slaves[1].s.id.vendor);
        /* encoders: Baumer, shipped at node-ID 1, several on one bus */
        for (size_t i = 0; i < e->n_slaves; i++) {
                ck_assert_uint_eq(e->slaves[i].s.id.vendor, 0xEC);
                ck_assert_uint_eq(e->slaves[i].s.st.active_node_id, 1);
                ck_assert(e->slaves[i].s.faults.needs_nmt_stopped);
        }
        sim_free(a);
        sim_free(b);
        sim_free(c);
        sim_free(e);
}
END_TEST

START_TEST(faults_per_serial) {
        sim *s = NEW_SIM(0, "vcan0", "--slave", "1:2:3:4", "--slave", "1:2:3:5", "--latency", "3",
                         "--fault", "store-fails@5", "--fault", "latency=7@0x4", "--fault", "ignore-cs=0x5E");
        ck_assert(!s->slaves[0].s.faults.store_fails);
        ck_assert(s->slaves[1].s.faults.store_fails);
        ck_assert_uint_eq(s->slaves[0].s.faults.latency_us, 7000);
        ck_assert_uint_eq(s->slaves[1].s.faults.latency_us, 3000);
        ck_assert_int_eq(s->slaves[0].s.faults.ignore_cs, 0x5E);
        ck_assert_int_eq(s->slaves[1].s.faults.ignore_cs, 0x5E);
        sim_free(s);

        /* a knob for a serial nobody has */
        sim_options o;
        char *msg = NULL;
        ck_assert_int_eq(PARSE(&o, &msg, "vcan0", "--slave", "1:2:3:4", "--fault", "silent@9"), 0);
        free(msg);
        size_t len;
        FILE *err = open_memstream(&msg, &len);
        ck_assert_int_eq(sim_new(&s, &o, 0, err), -EINVAL);
        fclose(err);
        ck_assert_ptr_nonnull(strstr(msg, "silent@9"));
        free(msg);
        sim_options_done(&o);
}
END_TEST

/* Encoder: LSS only in NMT Stopped. */
/* --heartbeat and --nmt-state: heartbeats from the boot-up on, the SDO
 * server of 1018h, no SDO in Stopped. */
START_TEST(heartbeat_and_nmt_state) {
        uint64_t t = 0;
        sim *s = NEW_SIM(t, "vcan0", "--slave", "1:2:3:4:5", "--heartbeat", "20", "--nmt-state", "stopped");
        capture c = {};
        run_until(s, 45000, &c);
        ck_assert_uint_eq(c.n, 3);
        ck_assert_str_eq(fmt(&c.f[0]), "705#00");
        ck_assert_str_eq(fmt(&c.f[1]), "705#04");
        ck_assert_uint_eq(c.t[1], 20000);
        ck_assert_str_eq(fmt(&c.f[2]), "705#04");
        sim_on_frame(s, &(lss_frame) { .id = 0x605, .len = 8, .data = { 0x40, 0x18, 0x10, 0x04 } }, 45000);
        c.n = 0;
        run_until(s, 59000, &c);
        ck_assert_uint_eq(c.n, 0);
        t = 59000;
        EXCHANGE(s, &t, "000#0105", "705#05", "705#05", "705#05");
        /* the exchange ran until 109 ms: the next heartbeat is at 120 ms */
        sim_on_frame(s, &(lss_frame) { .id = 0x605, .len = 8, .data = { 0x40, 0x18, 0x10, 0x04 } }, 110000);
        c.n = 0;
        run_until(s, 110500, &c);
        ck_assert_uint_eq(c.n, 1);
        ck_assert_str_eq(fmt(&c.f[0]), "585#4318100404000000");
        sim_free(s);

        USAGE_ERROR("--heartbeat '70000'", "vcan0", "--heartbeat", "70000");
        USAGE_ERROR("--nmt-state 'running'", "vcan0", "--nmt-state", "running");
}
END_TEST

START_TEST(encoder_needs_stopped) {
        uint64_t t = 0;
        sim *s = NEW_SIM(t, "vcan0", "--profile", "encoder", "--slave", "0xEC:0x1234:1:0x1276");
        capture c = {};
        run_until(s, 50000, &c);
        ck_assert_uint_eq(c.n, 1);
        ck_assert_str_eq(fmt(&c.f[0]), "701#00");
        t = 100000;
        SILENCE(s, &t, "7E5#0401000000000000");
        SILENCE(s, &t, "7E5#5E00000000000000");
        SILENCE(s, &t, "000#0200");
        SILENCE(s, &t, "7E5#0401000000000000");
        EXCHANGE(s, &t, "7E5#5E00000000000000", "7E4#5E01000000000000");
        sim_free(s);
}
END_TEST

/* Transmitter: index 5 answered "not supported"; canopennode: silent. */
START_TEST(profile_bit_timing) {
        uint64_t t = 0;
        sim *s = NEW_SIM(t, "vcan0", "--profile", "transmitter", "--slave", "1:2:3:4");
        SILENCE(s, &t, "7E5#0401000000000000");
        EXCHANGE(s, &t, "7E5#1300050000000000", "7E4#1301000000000000");
        EXCHANGE(s, &t, "7E5#1300030000000000", "7E4#1300000000000000");
        sim_free(s);

        t = 0;
        s = NEW_SIM(t, "vcan0", "--profile", "canopennode", "--slave", "1:2:3:4");
        SILENCE(s, &t, "7E5#4C00000000000000");
        SILENCE(s, &t, "7E5#0401000000000000");
        SILENCE(s, &t, "7E5#1300030000000000");
        EXCHANGE(s, &t, "7E5#5E00000000000000", "7E4#5EFF000000000000");
        sim_free(s);

        t = 0;
        s = NEW_SIM(t, "vcan0", "--profile", "servo-drive", "--slave", "1:2:3:4");
        EXCHANGE(s, &t, "7E5#4C00000000000000", "7E4#5000000000000000");
        sim_free(s);
}
END_TEST

/* lely: a configured slave answers Fastscan too; Identify Non-Configured
 * only the other; Configure Bit Timing "not supported"; a new node-ID
 * waits for an NMT reset, and Reset Node keeps it. */
START_TEST(profile_lely) {
        uint64_t t = 0;
        sim *s = NEW_SIM(t, "vcan0", "--profile", "lely", "--slave", "1:2:3:4:5", "--slave", "1:2:3:6");
        capture c = {};
        run_until(s, 50000, &c);
        ck_assert_uint_eq(c.n, 1);
        ck_assert_str_eq(fmt(&c.f[0]), "705#00");
        t = 100000;
        EXCHANGE(s, &t, "7E5#5100000000800000", "7E4#4F00000000000000");
        ck_assert_uint_eq(s->stats.merged_frames, 1);
        EXCHANGE(s, &t, "7E5#4C00000000000000", "7E4#5000000000000000");
        SILENCE(s, &t, "7E5#4001000000000000");
        SILENCE(s, &t, "7E5#4102000000000000");
        SILENCE(s, &t, "7E5#4203000000000000");
        EXCHANGE(s, &t, "7E5#4304000000000000", "7E4#4400000000000000");
        EXCHANGE(s, &t, "7E5#1300030000000000", "7E4#1301000000000000");
        EXCHANGE(s, &t, "7E5#1107000000000000", "7E4#1100000000000000");
        EXCHANGE(s, &t, "7E5#5E00000000000000", "7E4#5E05000000000000");
        EXCHANGE(s, &t, "7E5#1700000000000000", "7E4#1700000000000000");
        SILENCE(s, &t, "7E5#0400000000000000");
        EXCHANGE(s, &t, "000#8105", "707#00");
        ck_assert_uint_eq(s->slaves[0].s.st.stored_node_id, 7);
        sim_free(s);
}
END_TEST

/* Activate Bit Timing: the segment follows the slaves to the new rate. */
START_TEST(bitrate_follow) {
        uint64_t t = 0;
        sim *s = NEW_SIM(t, "vcan0", "--slave", "1:2:3:4", "--slave", "1:2:3:5", "--fault", "miss-activation@5");
        ck_assert_uint_eq(sim_bitrate(s), 125000);
        SILENCE(s, &t, "7E5#0401000000000000");
        /* both answer: two different slaves, identical frames, one on the bus */
        EXCHANGE(s, &t, "7E5#1300020000000000", "7E4#1300000000000000");
        lss_frame f = frame("7E5#1510000000000000");
        sim_on_frame(s, &f, t);
        ck_assert(!sim_on_time(s, t + 16000));
        ck_assert_uint_eq(sim_bitrate(s), 125000);
        ck_assert(sim_on_time(s, t + 32000));
        ck_assert_uint_eq(sim_bitrate(s), 500000);
        t += 40000;
        /* the slave that missed it is off the bus now; the other answers */
        EXCHANGE(s, &t, "7E5#5D00000000000000", "7E4#5D04000000000000");
        sim_free(s);

        /* --no-follow-bitrate: the switched slave is gone from the segment */
        t = 0;
        s = NEW_SIM(t, "vcan0", "--slave", "1:2:3:4", "--no-follow-bitrate");
        SILENCE(s, &t, "7E5#0401000000000000");
        EXCHANGE(s, &t, "7E5#1300020000000000", "7E4#1300000000000000");
        SILENCE(s, &t, "7E5#1500000000000000");
        SILENCE(s, &t, "7E5#5E00000000000000");
        ck_assert_uint_eq(sim_bitrate(s), 125000);
        /* it does not even hear: still in configuration after "waiting" */
        SILENCE(s, &t, "7E5#0400000000000000");
        ck_assert(s->slaves[0].s.st.configuration);
        sim_free(s);
}
END_TEST

/* --state: written on change, read back as a power cycle. */
START_TEST(state_restart) {
        char *dir = make_tmpdir(), *state, path[4200];
        uint64_t t = 0;
        sim *s = NEW_SIM(t, "vcan0", "--profile", "generic", "--slave", "1:2:3:0xABCDEF01", "--state", dir);
        ck_assert_int_eq(sim_save_state(s, stderr), 0);
        snprintf(path, sizeof(path), "%s/abcdef01.state", dir);
        state = slurp(path);
        ck_assert_ptr_nonnull(strstr(state, "active_node_id=255\n"));
        ck_assert_ptr_nonnull(strstr(state, "lss_state=waiting\n"));
        ck_assert_ptr_nonnull(strstr(state, "bit_timing_index=4\n"));
        free(state);

        SILENCE(s, &t, "7E5#0401000000000000");
        ck_assert_int_eq(sim_save_state(s, stderr), 0);
        state = slurp(path);
        ck_assert_ptr_nonnull(strstr(state, "lss_state=configuration\n"));
        free(state);
        EXCHANGE(s, &t, "7E5#1144000000000000", "7E4#1100000000000000");
        EXCHANGE(s, &t, "7E5#1700000000000000", "7E4#1700000000000000");
        EXCHANGE(s, &t, "7E5#1300030000000000", "7E4#1300000000000000");
        EXCHANGE(s, &t, "7E5#1700000000000000", "7E4#1700000000000000");
        ck_assert_int_eq(sim_save_state(s, stderr), 0);
        state = slurp(path);
        ck_assert_ptr_nonnull(strstr(state, "pending_node_id=68\n"));
        ck_assert_ptr_nonnull(strstr(state, "stored_node_id=68\n"));
        ck_assert_ptr_nonnull(strstr(state, "active_node_id=255\n"));
        ck_assert_ptr_nonnull(strstr(state, "stored_bit_timing_index=3\n"));
        free(state);
        sim_free(s);

        /* restart: stored values active, boot-up at power-on (bus at 250k) */
        t = 0;
        s = NEW_SIM(t, "vcan0", "--profile", "generic", "--slave", "1:2:3:0xABCDEF01", "--state", dir,
                    "--bitrate", "250000");
        ck_assert(s->slaves[0].restored);
        ck_assert_uint_eq(s->slaves[0].s.st.active_node_id, 0x44);
        ck_assert_uint_eq(s->slaves[0].s.st.bit_index, 3);
        capture c = {};
        run_until(s, 50000, &c);
        ck_assert_uint_eq(c.n, 1);
        ck_assert_str_eq(fmt(&c.f[0]), "744#00");
        ck_assert_int_eq(sim_save_state(s, stderr), 0);
        state = slurp(path);
        ck_assert_ptr_nonnull(strstr(state, "active_node_id=68\n"));
        ck_assert_ptr_nonnull(strstr(state, "lss_state=waiting\n"));
        free(state);
        sim_free(s);

        /* at 125k the restored slave is at another rate: deaf and dumb */
        t = 0;
        s = NEW_SIM(t, "vcan0", "--profile", "generic", "--slave", "1:2:3:0xABCDEF01", "--state", dir);
        memset(&c, 0, sizeof(c));
        run_until(s, 50000, &c);
        ck_assert_uint_eq(c.n, 0);
        ck_assert_uint_eq(s->stats.dropped_frames, 1);
        sim_free(s);

        /* another identity with that serial: the file is not its memory */
        t = 0;
        s = NEW_SIM(t, "vcan0", "--profile", "generic", "--slave", "9:2:3:0xABCDEF01", "--state", dir);
        ck_assert(!s->slaves[0].restored);
        ck_assert_uint_eq(s->slaves[0].s.st.active_node_id, 0xFF);
        sim_free(s);

        /* an upper-case file name is read too, and kept */
        snprintf(path, sizeof(path), "%s/0000BEEF.state", dir);
        FILE *f = fopen(path, "we");
        ck_assert_ptr_nonnull(f);
        fputs("serial=0xbeef\nstored_node_id=9\n", f);
        fclose(f);
        s = NEW_SIM(0, "vcan0", "--slave", "1:2:3:0xBEEF", "--state", dir);
        ck_assert_uint_eq(s->slaves[0].s.st.active_node_id, 9);
        ck_assert_str_eq(s->slaves[0].state_path, path);
        sim_free(s);

        /* a broken file is an error naming file and line */
        f = fopen(path, "we");
        ck_assert_ptr_nonnull(f);
        fputs("serial=0xbeef\nstored_node_id=300\n", f);
        fclose(f);
        sim_options o;
        char *msg = NULL;
        ck_assert_int_eq(PARSE(&o, &msg, "vcan0", "--slave", "1:2:3:0xBEEF", "--state", dir), 0);
        free(msg);
        size_t len;
        FILE *err = open_memstream(&msg, &len);
        ck_assert_int_eq(sim_new(&s, &o, 0, err), -EINVAL);
        fclose(err);
        ck_assert_ptr_nonnull(strstr(msg, "0000BEEF.state:2"));
        free(msg);

        /* two slaves, one serial, one file: refused */
        sim_options_done(&o);
        ck_assert_int_eq(PARSE(&o, &msg, "vcan0", "--slave", "1:2:3:7", "--slave", "2:2:3:7", "--state", dir), 0);
        free(msg);
        err = open_memstream(&msg, &len);
        ck_assert_int_eq(sim_new(&s, &o, 0, err), -EINVAL);
        fclose(err);
        ck_assert_ptr_nonnull(strstr(msg, "serial"));
        free(msg);
        sim_options_done(&o);

        remove_tmpdir(dir);
}
END_TEST

START_TEST(print_slaves) {
        sim *s = NEW_SIM(0, "vcan0", "--slave", "0x9A:3:0x10002:0xFFFFFFFF:7", "--slave", "1:2:3:4");
        char *out = NULL;
        size_t len;
        FILE *f = open_memstream(&out, &len);
        sim_print_slaves(s, f);
        fclose(f);
        ck_assert_str_eq(out,
                         "slave vendor=0x0000009a product=0x00000003 revision=0x00010002 serial=0xffffffff "
                         "node_id=7 bitrate=125000\n"
                         "slave vendor=0x00000001 product=0x00000002 revision=0x00000003 serial=0x00000004 "
                         "node_id=255 bitrate=125000\n");
        free(out);
        sim_free(s);
}
END_TEST

int main(void) {
        Suite *s = suite_create("lss-sim");
        TCase *tc = tcase_create("core");
        tcase_add_test(tc, parse_values);
        tcase_add_test(tc, parse_identity);
        tcase_add_test(tc, options_full);
        tcase_add_test(tc, options_errors);
        tcase_add_test(tc, options_help_version);
        tcase_add_test(tc, fault_knobs);
        tcase_add_test(tc, profiles);
        tcase_add_test(tc, state_round_trip);
        tcase_add_test(tc, state_parse);
        tcase_add_test(tc, txqueue_merge);
        tcase_add_test(tc, seed_example);
        tcase_add_test(tc, configured_slave_boots);
        tcase_add_test(tc, fastscan_ping_merges);
        tcase_add_test(tc, random_identities);
        tcase_add_test(tc, faults_per_serial);
        tcase_add_test(tc, encoder_needs_stopped);
        tcase_add_test(tc, heartbeat_and_nmt_state);
        tcase_add_test(tc, profile_bit_timing);
        tcase_add_test(tc, profile_lely);
        tcase_add_test(tc, bitrate_follow);
        tcase_add_test(tc, state_restart);
        tcase_add_test(tc, print_slaves);
        suite_add_tcase(s, tc);
        SRunner *sr = srunner_create(s);
        srunner_run_all(sr, CK_NORMAL);
        int failed = srunner_ntests_failed(sr);
        srunner_free(sr);
        return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
