/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <getopt.h>
#include <net/if.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lss-sim/options.h"
#include "lss-sim/profiles.h"

#define _attribute_printf_(a, b) __attribute__((format(printf, a, b)))

#ifndef LSS_SIM_VERSION
#define LSS_SIM_VERSION "unknown"
#endif

int sim_parse_u64(const char *s, uint64_t *ret) {
        unsigned base = 10;
        uint64_t v = 0;

        if (!s)
                return -EINVAL;
        if (s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
                base = 16;
                s += 2;
        }
        if (*s == '\0')
                return -EINVAL;
        for (; *s; s++) {
                unsigned d;
                if (*s >= '0' && *s <= '9')
                        d = (unsigned) (*s - '0');
                else if (base == 16 && *s >= 'a' && *s <= 'f')
                        d = (unsigned) (*s - 'a') + 10;
                else if (base == 16 && *s >= 'A' && *s <= 'F')
                        d = (unsigned) (*s - 'A') + 10;
                else
                        return -EINVAL;
                if (v > (UINT64_MAX - d) / base)
                        return -ERANGE;
                v = v * base + d;
        }
        *ret = v;
        return 0;
}

int sim_parse_u32(const char *s, uint32_t *ret) {
        uint64_t v;
        int r = sim_parse_u64(s, &v);
        if (r < 0)
                return r;
        if (v > UINT32_MAX)
                return -ERANGE;
        *ret = (uint32_t) v;
        return 0;
}

/* A decimal with up to `places` decimals, scaled by 10^places; at most
 * UINT32_MAX. */
static int parse_fixed(const char *s, unsigned places, uint32_t *ret) {
        uint64_t v = 0;
        unsigned decimals = 0;
        bool dot = false, digits = false;

        if (!s)
                return -EINVAL;
        for (; *s; s++) {
                if (*s == '.' && !dot) {
                        dot = true;
                        continue;
                }
                if (*s < '0' || *s > '9')
                        return -EINVAL;
                if (dot && ++decimals > places)
                        return -EINVAL;
                digits = true;
                v = v * 10 + (uint64_t) (*s - '0');
                if (v > UINT32_MAX)
                        return -ERANGE;
        }
        if (!digits)
                return -EINVAL;
        for (; decimals < places; decimals++)
                v *= 10;
        if (v > UINT32_MAX)
                return -ERANGE;
        *ret = (uint32_t) v;
        return 0;
}

int sim_parse_ms(const char *s, uint32_t *ret_us) {
        return parse_fixed(s, 3, ret_us);
}

int sim_parse_probability(const char *s, uint32_t *ret_ppm) {
        uint32_t v;
        int r = parse_fixed(s, 6, &v);
        if (r < 0)
                return r;
        if (v > 1000000u)
                return -ERANGE;
        *ret_ppm = v;
        return 0;
}

int sim_parse_node_id(const char *s, uint8_t *ret) {
        uint32_t v;
        if (sim_parse_u32(s, &v) < 0)
                return -EINVAL;
        if (v != LSS_NODE_ID_UNCONFIGURED && !lss_node_id_valid(v))
                return -ERANGE;
        *ret = (uint8_t) v;
        return 0;
}

int sim_parse_slave(const char *s, sim_slave_spec *ret, const char **what) {
        /* each a whole phrase, what was expected and what came: printed as "--slave 'X': <what>" */
        static const char *const names[] = { "vendor", "product", "revision", "serial" };
        static char message[320];
        sim_slave_spec spec = {};
        char buf[128];
        char *fields[6] = {};
        size_t n = 0;

        if (strlen(s) >= sizeof(buf)) {
                *what = "too long";
                return -EINVAL;
        }
        strcpy(buf, s);
        for (char *p = buf, *colon; n < 6; p = colon + 1) {
                fields[n++] = p;
                colon = strchr(p, ':');
                if (!colon)
                        break;
                *colon = '\0';
        }
        if (n < 4 || n > 5) {
                if (n > 5)
                        *what = "expected VENDOR:PRODUCT:REVISION:SERIAL[:NODEID], got more than 5 fields";
                else {
                        snprintf(message, sizeof(message),
                                 "expected VENDOR:PRODUCT:REVISION:SERIAL[:NODEID], got %zu field%s", n,
                                 n == 1 ? "" : "s");
                        *what = message;
                }
                return -EINVAL;
        }
        for (unsigned i = 0; i < LSS_FIELD_COUNT; i++) {
                uint32_t v;
                if (sim_parse_u32(fields[i], &v) < 0) {
                        snprintf(message, sizeof(message),
                                 "%s '%s': expected a number, decimal or 0x hexadecimal, 0..0xFFFFFFFF", names[i],
                                 fields[i]);
                        *what = message;
                        return -EINVAL;
                }
                lss_identity_set_field(&spec.id, i, v);
        }
        if (n == 5) {
                if (sim_parse_node_id(fields[4], &spec.node_id) < 0) {
                        snprintf(message, sizeof(message), "node-ID '%s': expected 1..127, or 0xFF for non-configured",
                                 fields[4]);
                        *what = message;
                        return -EINVAL;
                }
                spec.node_id_given = true;
        }
        *ret = spec;
        return 0;
}

static const struct {
        const char *name;
        enum { VAL_BOOL, VAL_CS, VAL_EARLY, VAL_INDEXES, VAL_MS, VAL_PROBABILITY } type;
} knobs[_SIM_KNOB_MAX] = {
        [SIM_KNOB_SILENT] = { "silent", VAL_BOOL },
        [SIM_KNOB_IGNORE_CS] = { "ignore-cs", VAL_CS },
        [SIM_KNOB_WRONG_DLC] = { "wrong-dlc", VAL_BOOL },
        [SIM_KNOB_FASTSCAN_WHEN_CONFIGURED] = { "fastscan-when-configured", VAL_BOOL },
        [SIM_KNOB_STORE_UNSUPPORTED] = { "store-unsupported", VAL_BOOL },
        [SIM_KNOB_STORE_FAILS] = { "store-fails", VAL_BOOL },
        [SIM_KNOB_EARLY_CONFIG] = { "early-config", VAL_EARLY },
        [SIM_KNOB_NEEDS_NMT_STOPPED] = { "needs-nmt-stopped", VAL_BOOL },
        [SIM_KNOB_NO_IDENTIFY] = { "no-identify", VAL_BOOL },
        [SIM_KNOB_BIT_TIMING_SILENT] = { "bit-timing-silent", VAL_BOOL },
        [SIM_KNOB_BIT_INDEX_UNSUPPORTED] = { "bit-index-unsupported", VAL_INDEXES },
        [SIM_KNOB_MISS_ACTIVATION] = { "miss-activation", VAL_BOOL },
        [SIM_KNOB_DUPLICATE_ANSWERS] = { "duplicate-answers", VAL_BOOL },
        [SIM_KNOB_CONFIGURE_ERROR_SPECIFIC] = { "configure-error-specific", VAL_BOOL },
        [SIM_KNOB_CANOPENNODE_LSS] = { "canopennode-lss", VAL_BOOL },
        [SIM_KNOB_LELY_LSS] = { "lely-lss", VAL_BOOL },
        [SIM_KNOB_FASTSCAN_ANY] = { "fastscan-any", VAL_BOOL },
        [SIM_KNOB_LATENCY] = { "latency", VAL_MS },
        [SIM_KNOB_JITTER] = { "jitter", VAL_MS },
        [SIM_KNOB_DROP] = { "drop", VAL_PROBABILITY },
};

const char *sim_knob_name(enum sim_knob k) {
        return k < _SIM_KNOB_MAX ? knobs[k].name : NULL;
}

static int parse_bool(const char *s, uint32_t *ret) {
        if (!s || strcmp(s, "1") == 0 || strcmp(s, "yes") == 0 || strcmp(s, "true") == 0 || strcmp(s, "on") == 0)
                *ret = 1;
        else if (strcmp(s, "0") == 0 || strcmp(s, "no") == 0 || strcmp(s, "false") == 0 || strcmp(s, "off") == 0)
                *ret = 0;
        else
                return -EINVAL;
        return 0;
}

/* "5" or "5,6,8": table-0 indexes 0..31 as a bitmask */
static int parse_indexes(const char *s, uint32_t *ret) {
        char buf[128];
        uint32_t mask = 0;

        if (!s || strlen(s) >= sizeof(buf))
                return -EINVAL;
        strcpy(buf, s);
        for (char *p = buf, *comma; p; p = comma ? comma + 1 : NULL) {
                uint32_t v;
                comma = strchr(p, ',');
                if (comma)
                        *comma = '\0';
                if (sim_parse_u32(p, &v) < 0 || v > 31)
                        return -EINVAL;
                mask |= 1u << v;
        }
        *ret = mask;
        return 0;
}

int sim_parse_fault(const char *s, sim_fault_spec *ret, const char **what) {
        sim_fault_spec spec = { .arg = s };
        char buf[128];
        char *value, *at;
        int k;

        if (strlen(s) >= sizeof(buf)) {
                *what = "too long";
                return -EINVAL;
        }
        strcpy(buf, s);
        at = strchr(buf, '@');
        if (at) {
                *at++ = '\0';
                if (sim_parse_u32(at, &spec.serial) < 0) {
                        *what = "bad serial number after '@'";
                        return -EINVAL;
                }
                spec.has_serial = true;
        }
        value = strchr(buf, '=');
        if (value)
                *value++ = '\0';

        for (k = 0; k < _SIM_KNOB_MAX; k++)
                if (strcmp(buf, knobs[k].name) == 0)
                        break;
        if (k == _SIM_KNOB_MAX) {
                *what = "unknown fault knob (see --help)";
                return -EINVAL;
        }
        spec.knob = (enum sim_knob) k;

        switch (knobs[k].type) {
        case VAL_BOOL:
                if (parse_bool(value, &spec.value) < 0) {
                        *what = "value must be 1/yes/on or 0/no/off";
                        return -EINVAL;
                }
                break;
        case VAL_CS:
                if (value && strcmp(value, "none") == 0)
                        spec.value = UINT32_MAX;
                else if (!value || sim_parse_u32(value, &spec.value) < 0 || spec.value > 0xFF) {
                        *what = "needs a command specifier 0..0xFF (e.g. ignore-cs=0x5E) or none";
                        return -EINVAL;
                }
                break;
        case VAL_EARLY:
                if (value && strcmp(value, "vendor") == 0)
                        spec.value = SLAVE_EARLY_AFTER_VENDOR;
                else if (value && strcmp(value, "product") == 0)
                        spec.value = SLAVE_EARLY_AFTER_PRODUCT;
                else if (value && strcmp(value, "revision") == 0)
                        spec.value = SLAVE_EARLY_AFTER_REVISION;
                else if (value && strcmp(value, "none") == 0)
                        spec.value = SLAVE_EARLY_NONE;
                else {
                        *what = "needs vendor, product, revision or none";
                        return -EINVAL;
                }
                break;
        case VAL_INDEXES:
                if (value && strcmp(value, "none") == 0)
                        spec.clear = true;
                else if (parse_indexes(value, &spec.value) < 0) {
                        *what = "needs bit timing indexes 0..31, comma separated (e.g. =5), or none";
                        return -EINVAL;
                }
                break;
        case VAL_MS:
                if (sim_parse_ms(value, &spec.value) < 0) {
                        *what = "needs milliseconds (e.g. =2 or =0.5)";
                        return -EINVAL;
                }
                break;
        case VAL_PROBABILITY:
                if (sim_parse_probability(value, &spec.value) < 0) {
                        *what = "needs a probability 0..1 (e.g. =0.02)";
                        return -EINVAL;
                }
                break;
        }
        *ret = spec;
        return 0;
}

void sim_fault_apply(const sim_fault_spec *spec, lss_slave_faults *f) {
        bool on = spec->value != 0;

        switch (spec->knob) {
        case SIM_KNOB_SILENT: f->silent = on; break;
        case SIM_KNOB_IGNORE_CS: f->ignore_cs = spec->value == UINT32_MAX ? -1 : (int) spec->value; break;
        case SIM_KNOB_WRONG_DLC: f->wrong_dlc = on; break;
        case SIM_KNOB_FASTSCAN_WHEN_CONFIGURED: f->fastscan_when_configured = on; break;
        case SIM_KNOB_STORE_UNSUPPORTED: f->store_unsupported = on; break;
        case SIM_KNOB_STORE_FAILS: f->store_fails = on; break;
        case SIM_KNOB_EARLY_CONFIG: f->early_config = (enum lss_slave_early_config) spec->value; break;
        case SIM_KNOB_NEEDS_NMT_STOPPED: f->needs_nmt_stopped = on; break;
        case SIM_KNOB_NO_IDENTIFY: f->no_identify = on; break;
        case SIM_KNOB_CANOPENNODE_LSS: f->canopennode_lss = on; break;
        case SIM_KNOB_LELY_LSS: f->lely_lss = on; break;
        case SIM_KNOB_FASTSCAN_ANY: f->fastscan_any = on; break;
        case SIM_KNOB_BIT_TIMING_SILENT: f->bit_timing_silent = on; break;
        case SIM_KNOB_BIT_INDEX_UNSUPPORTED:
                /* indexes add up over several --fault options; "none" clears */
                f->bit_index_unsupported = spec->clear ? 0 : (f->bit_index_unsupported | spec->value);
                break;
        case SIM_KNOB_MISS_ACTIVATION: f->miss_activation = on; break;
        case SIM_KNOB_DUPLICATE_ANSWERS: f->duplicate_answers = on; break;
        case SIM_KNOB_CONFIGURE_ERROR_SPECIFIC: f->configure_error_specific = on; break;
        case SIM_KNOB_LATENCY: f->latency_us = spec->value; break;
        case SIM_KNOB_JITTER: f->jitter_us = spec->value; break;
        /* a frame lost on the way in (a receive FIFO overrun) or out (a full
         * transmit queue): the master sees the same either way */
        case SIM_KNOB_DROP: f->rx_loss_ppm = f->tx_loss_ppm = spec->value; break;
        case _SIM_KNOB_MAX: break;
        }
}

static void help(FILE *out) {
        size_t n;
        const sim_profile *p = sim_profile_all(&n);

        fprintf(out,
                "lss-sim IFACE [OPTIONS]\n\n"
                "Simulates CANopen LSS slaves (CiA 305) on the SocketCAN interface IFACE.\n"
                "Prints one line per slave, then \"ready\" once it listens.\n\n"
                "  --slave V:P:R:S[:NODEID]   add a slave (vendor, product, revision, serial;\n"
                "                             hex 0x... or decimal). NODEID 1..127, or absent\n"
                "                             or 0xFF for non-configured (profile default)\n"
                "  --random N                 add N slaves with made-up identities (distinct\n"
                "                             serials; vendor/product from the profile if fixed)\n"
                "  --seed S                   seed of --random, the jitter and drop (default 1)\n"
                "  --profile NAME             device behaviour (default %s)\n"
                "  --latency MS               answer latency of every slave (e.g. 2 or 0.3)\n"
                "  --jitter MS                plus a random 0..MS on every answer\n"
                "  --bitrate BITRATE          bit rate the slaves and the simulated bus start\n"
                "                             at (CiA table 0; default %u)\n"
                "  --no-follow-bitrate        keep the bus at --bitrate after Activate Bit\n"
                "                             Timing (default: the bus follows the slaves, as\n"
                "                             the master retunes its interface in the window)\n"
                "  --fault KNOB[=VALUE][@SERIAL]\n"
                "                             a slave-model fault, for every slave or the one\n"
                "                             with that serial; applied in command line order\n"
                "  --heartbeat MS             heartbeat producer time (object 1017h) of every\n"
                "                             slave; 0 = no heartbeat (default)\n"
                "  --nmt-state STATE          NMT state of the slaves after their boot-up at\n"
                "                             start: pre-operational (default), operational or\n"
                "                             stopped (no SDO answers); NMT commands change it\n"
                "  --state DIR                keep each slave's state in DIR/<serial>.state\n"
                "  -v --verbose               log every frame received and sent to stderr\n"
                "  -h --help, --version\n\n"
                "Profiles:\n",
                sim_profile_default()->name, SIM_DEFAULT_BITRATE);
        for (size_t i = 0; i < n; i++)
                fprintf(out, "  %-14s %s\n", p[i].name, p[i].summary);
        fprintf(out,
                "\nFault knobs (booleans take =0/=1, default 1):\n"
                "  silent, ignore-cs=CS|none, wrong-dlc, fastscan-when-configured,\n"
                "  store-unsupported, store-fails, early-config=vendor|product|revision|none,\n"
                "  needs-nmt-stopped, no-identify, bit-timing-silent,\n"
                "  bit-index-unsupported=I[,I...]|none, miss-activation, duplicate-answers,\n"
                "  configure-error-specific, canopennode-lss, lely-lss, fastscan-any,\n"
                "  latency=MS, jitter=MS, drop=P (each frame received and each answer\n"
                "  lost with probability P, 0..1)\n\n"
                "State files: DIR/<serial as 8 lower-case hex digits>.state (an upper-case\n"
                "name is read too), key=value lines: vendor, product, revision, serial\n"
                "(0x + 8 hex digits), active_node_id, pending_node_id, stored_node_id,\n"
                "bit_timing_index, pending_bit_timing_index, stored_bit_timing_index\n"
                "(decimal; node-ID 255 = non-configured), lss_state (waiting|configuration),\n"
                "nmt_state (pre-operational|operational|stopped). Rewritten atomically on\n"
                "every change. At start only the stored_* values are read back: a restart\n"
                "is a power cycle. A file whose identity differs is ignored (and replaced).\n\n"
                "Exit status: 0 on SIGINT/SIGTERM, 1 on a run-time failure, 2 on bad usage.\n");
}

_attribute_printf_(2, 3)
static int fail(FILE *err, const char *fmt, ...) {
        va_list ap;

        fputs("lss-sim: ", err);
        va_start(ap, fmt);
        vfprintf(err, fmt, ap);
        va_end(ap);
        fputc('\n', err);
        return -EINVAL;
}

enum {
        ARG_VERSION = 0x100,
        ARG_SLAVE,
        ARG_RANDOM,
        ARG_SEED,
        ARG_LATENCY,
        ARG_JITTER,
        ARG_PROFILE,
        ARG_STATE,
        ARG_BITRATE,
        ARG_FAULT,
        ARG_NO_FOLLOW,
        ARG_HEARTBEAT,
        ARG_NMT_STATE,
};

int sim_options_parse(sim_options *o, int argc, char **argv, FILE *out, FILE *err) {
        static const struct option options[] = {
                { "help", no_argument, NULL, 'h' },
                { "version", no_argument, NULL, ARG_VERSION },
                { "verbose", no_argument, NULL, 'v' },
                { "slave", required_argument, NULL, ARG_SLAVE },
                { "random", required_argument, NULL, ARG_RANDOM },
                { "seed", required_argument, NULL, ARG_SEED },
                { "latency", required_argument, NULL, ARG_LATENCY },
                { "jitter", required_argument, NULL, ARG_JITTER },
                { "profile", required_argument, NULL, ARG_PROFILE },
                { "state", required_argument, NULL, ARG_STATE },
                { "bitrate", required_argument, NULL, ARG_BITRATE },
                { "fault", required_argument, NULL, ARG_FAULT },
                { "no-follow-bitrate", no_argument, NULL, ARG_NO_FOLLOW },
                { "heartbeat", required_argument, NULL, ARG_HEARTBEAT },
                { "nmt-state", required_argument, NULL, ARG_NMT_STATE },
                {}
        };
        const char *what;
        uint32_t v;
        int c;

        *o = (sim_options) {
                .seed = 1,
                .profile = sim_profile_default(),
                .bitrate = SIM_DEFAULT_BITRATE,
                .follow_bitrate = true,
                .nmt_state = SLAVE_NMT_PRE_OPERATIONAL,
        };

        /* 0 re-initialises getopt, so the tests can parse several times */
        optind = 0;
        opterr = 0;
        while ((c = getopt_long(argc, argv, ":hv", options, NULL)) >= 0) {
                switch (c) {
                case 'h':
                        help(out);
                        return 1;
                case ARG_VERSION:
                        fprintf(out, "lss-sim %s\n", LSS_SIM_VERSION);
                        return 1;
                case 'v':
                        o->verbose = true;
                        break;
                case ARG_SLAVE: {
                        sim_slave_spec *n = reallocarray(o->slaves, o->n_slaves + 1, sizeof(*n));
                        if (!n)
                                return -ENOMEM;
                        o->slaves = n;
                        if (sim_parse_slave(optarg, &o->slaves[o->n_slaves], &what) < 0)
                                return fail(err, "--slave '%s': %s", optarg, what);
                        o->n_slaves++;
                        break;
                }
                case ARG_RANDOM:
                        if (sim_parse_u32(optarg, &v) < 0 || v > SIM_RANDOM_MAX)
                                return fail(err, "--random '%s': need a count 0..%u", optarg, SIM_RANDOM_MAX);
                        o->random_count = v;
                        break;
                case ARG_SEED:
                        if (sim_parse_u64(optarg, &o->seed) < 0)
                                return fail(err, "--seed '%s': %s", optarg, "need an unsigned number");
                        break;
                case ARG_LATENCY:
                        if (sim_parse_ms(optarg, &o->latency_us) < 0)
                                return fail(err, "--latency '%s': %s", optarg, "need milliseconds (e.g. 2 or 0.5)");
                        o->latency_given = true;
                        break;
                case ARG_JITTER:
                        if (sim_parse_ms(optarg, &o->jitter_us) < 0)
                                return fail(err, "--jitter '%s': %s", optarg, "need milliseconds (e.g. 2 or 0.5)");
                        o->jitter_given = true;
                        break;
                case ARG_PROFILE:
                        o->profile = sim_profile_find(optarg);
                        if (!o->profile) {
                                char names[256];
                                sim_profile_names(names, sizeof(names));
                                return fail(err, "--profile '%s': unknown profile (%s)", optarg, names);
                        }
                        break;
                case ARG_STATE:
                        if (optarg[0] == '\0')
                                return fail(err, "--state '%s': %s", optarg, "need a directory");
                        o->state_dir = optarg;
                        break;
                case ARG_BITRATE:
                        if (sim_parse_u32(optarg, &v) < 0 || lss_bit_timing_index(v) < 0)
                                return fail(err, "--bitrate '%s': %s", optarg,
                                            "not in CiA table 0 (1000000 800000 500000 250000 125000 100000 50000 20000 10000)");
                        o->bitrate = v;
                        break;
                case ARG_FAULT: {
                        sim_fault_spec *n = reallocarray(o->faults, o->n_faults + 1, sizeof(*n));
                        if (!n)
                                return -ENOMEM;
                        o->faults = n;
                        if (sim_parse_fault(optarg, &o->faults[o->n_faults], &what) < 0)
                                return fail(err, "--fault '%s': %s", optarg, what);
                        o->n_faults++;
                        break;
                }
                case ARG_NO_FOLLOW:
                        o->follow_bitrate = false;
                        break;
                case ARG_HEARTBEAT:
                        if (sim_parse_u32(optarg, &v) < 0 || v > UINT16_MAX)
                                return fail(err, "--heartbeat '%s': %s", optarg, "need milliseconds 0..65535 (0: off)");
                        o->heartbeat_ms = (uint16_t) v;
                        break;
                case ARG_NMT_STATE:
                        if (strcmp(optarg, "pre-operational") == 0)
                                o->nmt_state = SLAVE_NMT_PRE_OPERATIONAL;
                        else if (strcmp(optarg, "operational") == 0)
                                o->nmt_state = SLAVE_NMT_OPERATIONAL;
                        else if (strcmp(optarg, "stopped") == 0)
                                o->nmt_state = SLAVE_NMT_STOPPED;
                        else
                                return fail(err, "--nmt-state '%s': %s", optarg,
                                            "need pre-operational, operational or stopped");
                        break;
                case ':':
                        return fail(err, "%s: %s", argv[optind - 1], "needs an argument");
                default:
                        return fail(err, "%s: %s (see --help)", argv[optind - 1], "unknown option");
                }
        }

        if (optind >= argc)
                return fail(err, "missing IFACE (see --help)");
        if (argc - optind > 1)
                return fail(err, "'%s': %s", argv[optind + 1], "unexpected argument (only one IFACE)");
        o->ifname = argv[optind];
        if (o->ifname[0] == '\0' || strlen(o->ifname) >= IFNAMSIZ || strchr(o->ifname, '/'))
                return fail(err, "IFACE '%s': %s", o->ifname, "not a valid interface name");
        return 0;
}

void sim_options_done(sim_options *o) {
        free(o->slaves);
        free(o->faults);
        *o = (sim_options) {};
}
