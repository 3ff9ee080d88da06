/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* lssctl: the command-line client of lssd. A thin D-Bus client: every verb
 * is a few calls to org.lssd.LSS1; it never opens a CAN socket. */
#include <errno.h>
#include <getopt.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "ctl/ctl.h"
#include "ctl/ctl_agent.h"
#include "ctl/ctl_errors.h"
#include "ctl/ctl_pager.h"
#include "ctl/ctl_parse.h"

/* which options each verb accepts */
enum {
        OPT_BUS = 1 << 0,
        OPT_JSON = 1 << 1,
        OPT_NO_PAGER = 1 << 2,
        OPT_NO_LEGEND = 1 << 3,
        OPT_NO_STORE = 1 << 4,
        OPT_NO_VERIFY = 1 << 5,
        OPT_DELAY = 1 << 6,
        OPT_VENDOR = 1 << 7, /* and --product */
        OPT_SKIP_MISSING = 1 << 8,
        OPT_FORCE = 1 << 9,
        OPT_QUIET = 1 << 10,
        OPT_DRY_RUN = 1 << 11,
        OPT_RESET = 1 << 12,
        OPT_AS_CONFIG = 1 << 13,
        OPT_NO_SDO = 1 << 14,
        OPT_GLOBAL = 1 << 15,
        OPT_AS_DCF = 1 << 16,
        OPT_LAST = OPT_AS_DCF,
};

typedef struct verb {
        const char *name;
        int min_args, max_args; /* -1: any */
        unsigned options;
        bool pager;             /* output may go through the pager */
        bool polkit;            /* lssd asks polkit: the text agent comes along (ctl_agent.h) */
        int (*run)(ctl_context *c);
} verb;

static const verb verbs[] = {
        { "status", 0, 0, OPT_BUS | OPT_JSON | OPT_NO_PAGER, true, false, verb_status },
        { "list", 0, 0, OPT_BUS | OPT_JSON | OPT_NO_PAGER | OPT_NO_LEGEND, true, false, verb_list },
        { "scan", 0, 0,
          OPT_BUS | OPT_JSON | OPT_NO_PAGER | OPT_NO_LEGEND | OPT_VENDOR | OPT_AS_CONFIG | OPT_NO_SDO | OPT_AS_DCF,
          false, true, verb_scan },
        { "assign", 2, 2, OPT_BUS | OPT_JSON | OPT_NO_STORE | OPT_NO_VERIFY | OPT_FORCE | OPT_QUIET, false, true,
          verb_assign },
        { "unassign", 1, 1, OPT_BUS | OPT_JSON | OPT_NO_STORE | OPT_RESET | OPT_QUIET, false, true, verb_unassign },
        { "auto-assign", 0, 0,
          OPT_BUS | OPT_JSON | OPT_NO_PAGER | OPT_NO_LEGEND | OPT_NO_STORE | OPT_QUIET | OPT_DRY_RUN, false, true,
          verb_auto_assign },
        { "set-bitrate", 1, 1, OPT_BUS | OPT_DELAY | OPT_NO_STORE | OPT_SKIP_MISSING | OPT_GLOBAL | OPT_QUIET,
          false, true, verb_set_bitrate },
        { "reload", 0, 0, OPT_QUIET, false, true, verb_reload },
        { "monitor", 0, 0, OPT_BUS | OPT_JSON, false, false, verb_monitor },
        { "raw", 1, -1, OPT_BUS | OPT_JSON, false, true, verb_raw },
        { "import-dcf", 1, -1, OPT_BUS, false, false, verb_import_dcf },
};

static void help(void) {
        printf("lssctl [OPTIONS...] COMMAND ...\n\n"
               "Query and control lssd, the CANopen LSS master.\n\n"
               "Commands:\n"
               "  status                   Buses, their state, running job, device counts (default)\n"
               "  list                     Devices lssd knows: identity, node-ID, state, last seen\n"
               "  scan                     Find every device (LSS; SDO 1018h for configured ones)\n"
               "  assign SERIAL|VENDOR:PRODUCT:REVISION:SERIAL NODEID\n"
               "                           Give one device a node-ID (1..127)\n"
               "  unassign SERIAL|VENDOR:PRODUCT:REVISION:SERIAL\n"
               "                           Make one device non-configured (node-ID 255)\n"
               "  auto-assign              Give every device its node-ID from the map\n"
               "  set-bitrate BITRATE      Switch every slave and the interface to BITRATE\n"
               "  reload                   Make lssd read its configuration again\n"
               "  monitor                  Show signals and property changes until ^C\n"
               "  raw SERVICE [ARGS]...    Run raw LSS services while holding the bus\n"
               "  import-dcf FILE...       Print the map of CiA 306 DCFs as the buses of lssd.conf(5)\n"
               "                           (no lssd needed)\n\n"
               "Options:\n"
               "  -h --help                Show this help\n"
               "     --version             Show the version\n"
               "  -b --bus IFACE           Act on this CAN interface only (import-dcf: the bus printed)\n"
               "     --json                JSON output (status, list, scan, assign, unassign, auto-assign, monitor,\n"
               "                           raw)\n"
               "     --no-pager            Do not pipe output into a pager\n"
               "     --no-legend           No column headers (list, scan, auto-assign)\n"
               "     --no-store            Do not store in the slaves (assign, unassign, auto-assign,\n"
               "                           set-bitrate)\n"
               "     --no-verify           Do not wait for the boot-up after assigning (assign)\n"
               "     --force               Give the node-ID even if another device answers to it (assign)\n"
               "     --dry-run             Say what auto-assign would change, send nothing but discovery\n"
               "     --reset               Reset the device so that 255 takes effect now, and check it (unassign)\n"
               "  -q --quiet               Do not say what was done (assign, unassign, auto-assign, set-bitrate,\n"
               "                           reload)\n"
               "     --delay MS            Switch delay for set-bitrate (default 100)\n"
               "     --skip-missing        set-bitrate: go ahead without mapped devices the scan misses\n"
               "     --global              set-bitrate: all devices at once (CiA 305's global procedure), for\n"
               "                           devices that do not take the selective switch; see lssd(8)\n"
               "     --vendor ID --product ID\n"
               "                           Also look for configured slaves of this pair (scan)\n"
               "     --as-config           Print what scan found as the buses of lssd.conf(5), a map\n"
               "     --as-dcf DIR          scan: write a CiA 306 DCF fragment per configured device found into DIR\n"
               "     --no-sdo              scan: LSS only, do not ask every node-ID for its identity by SDO\n"
               "     --no-ask-password     Do not ask for a password when polkit wants one (no agent)\n\n"
               "See the lssctl(1) man page for details and the exit codes.\n");
}

enum {
        ARG_VERSION = 0x100,
        ARG_JSON,
        ARG_NO_PAGER,
        ARG_NO_LEGEND,
        ARG_NO_STORE,
        ARG_NO_VERIFY,
        ARG_DELAY,
        ARG_VENDOR,
        ARG_PRODUCT,
        ARG_SKIP_MISSING,
        ARG_FORCE,
        ARG_DRY_RUN,
        ARG_RESET,
        ARG_AS_CONFIG,
        ARG_NO_SDO,
        ARG_GLOBAL,
        ARG_AS_DCF,
        ARG_NO_ASK_PASSWORD,
};

static const char *option_name(unsigned flag) {
        switch (flag) {
        case OPT_BUS: return "--bus";
        case OPT_JSON: return "--json";
        case OPT_NO_PAGER: return "--no-pager";
        case OPT_NO_LEGEND: return "--no-legend";
        case OPT_NO_STORE: return "--no-store";
        case OPT_NO_VERIFY: return "--no-verify";
        case OPT_DELAY: return "--delay";
        case OPT_VENDOR: return "--vendor/--product";
        case OPT_SKIP_MISSING: return "--skip-missing";
        case OPT_FORCE: return "--force";
        case OPT_QUIET: return "--quiet";
        case OPT_DRY_RUN: return "--dry-run";
        case OPT_RESET: return "--reset";
        case OPT_AS_CONFIG: return "--as-config";
        case OPT_NO_SDO: return "--no-sdo";
        case OPT_GLOBAL: return "--global";
        case OPT_AS_DCF: return "--as-dcf";
        default: return "?";
        }
}

static int add_arg(ctl_context *c, char *arg) {
        char **a = realloc(c->args, (c->n_args + 1) * sizeof(char *));
        if (!a)
                return ctl_fail(c, CTL_EXIT_FAILURE, -ENOMEM, "Out of memory.");
        c->args = a;
        c->args[c->n_args++] = arg;
        return 0;
}

/* 1: run; 0: done (--help, --version); <0: usage error (reported) */
static int parse_argv(int argc, char *argv[], ctl_context *c, unsigned *given) {
        static const struct option options[] = {
                { "help", no_argument, NULL, 'h' },
                { "version", no_argument, NULL, ARG_VERSION },
                { "bus", required_argument, NULL, 'b' },
                { "json", optional_argument, NULL, ARG_JSON },
                { "no-pager", no_argument, NULL, ARG_NO_PAGER },
                { "no-legend", no_argument, NULL, ARG_NO_LEGEND },
                { "no-store", no_argument, NULL, ARG_NO_STORE },
                { "no-verify", no_argument, NULL, ARG_NO_VERIFY },
                { "delay", required_argument, NULL, ARG_DELAY },
                { "vendor", required_argument, NULL, ARG_VENDOR },
                { "product", required_argument, NULL, ARG_PRODUCT },
                { "skip-missing", no_argument, NULL, ARG_SKIP_MISSING },
                { "force", no_argument, NULL, ARG_FORCE },
                { "dry-run", no_argument, NULL, ARG_DRY_RUN },
                { "reset", no_argument, NULL, ARG_RESET },
                { "as-config", no_argument, NULL, ARG_AS_CONFIG },
                { "as-dcf", required_argument, NULL, ARG_AS_DCF },
                { "no-sdo", no_argument, NULL, ARG_NO_SDO },
                { "global", no_argument, NULL, ARG_GLOBAL },
                { "no-ask-password", no_argument, NULL, ARG_NO_ASK_PASSWORD },
                { "quiet", no_argument, NULL, 'q' },
                {}
        };
        int opt, r;
        uint32_t v;

        opterr = 0;
        for (;;) {
                opt = getopt_long(argc, argv, "+:hqb:", options, NULL);
                if (opt < 0) {
                        /* "--" ends the options; else a command or argument: keep it and
                         * look for more options after it */
                        if (optind >= argc || strcmp(argv[optind - 1], "--") == 0)
                                break;
                        r = add_arg(c, argv[optind++]);
                        if (r < 0)
                                return r;
                        continue;
                }
                switch (opt) {
                case 'h':
                        help();
                        return 0;
                case ARG_VERSION:
                        printf("lssctl %s\n", LSSCTL_VERSION);
                        return 0;
                case 'b':
                        c->bus_name = optarg;
                        *given |= OPT_BUS;
                        break;
                case ARG_JSON:
                        if (optarg && strcmp(optarg, "short") != 0)
                                return ctl_usage(c, "--json takes no value but 'short', not '%s'.", optarg);
                        c->json = true;
                        *given |= OPT_JSON;
                        break;
                case ARG_NO_PAGER:
                        c->no_pager = true;
                        *given |= OPT_NO_PAGER;
                        break;
                case ARG_NO_LEGEND:
                        c->no_legend = true;
                        *given |= OPT_NO_LEGEND;
                        break;
                case ARG_NO_STORE:
                        c->no_store = true;
                        *given |= OPT_NO_STORE;
                        break;
                case ARG_NO_VERIFY:
                        c->no_verify = true;
                        *given |= OPT_NO_VERIFY;
                        break;
                case ARG_DELAY:
                        if (ctl_parse_u32(optarg, &v) < 0 || v > 65535)
                                return ctl_usage(c, "Invalid --delay '%s': 0..65535 ms.", optarg);
                        c->delay_ms = (uint16_t) v;
                        c->has_delay = true;
                        *given |= OPT_DELAY;
                        break;
                case ARG_SKIP_MISSING:
                        c->skip_missing = true;
                        *given |= OPT_SKIP_MISSING;
                        break;
                case ARG_FORCE:
                        c->force = true;
                        *given |= OPT_FORCE;
                        break;
                case ARG_DRY_RUN:
                        c->dry_run = true;
                        *given |= OPT_DRY_RUN;
                        break;
                case ARG_RESET:
                        c->reset = true;
                        *given |= OPT_RESET;
                        break;
                case ARG_NO_SDO:
                        c->no_sdo = true;
                        *given |= OPT_NO_SDO;
                        break;
                case ARG_GLOBAL:
                        c->global = true;
                        *given |= OPT_GLOBAL;
                        break;
                case ARG_NO_ASK_PASSWORD:
                        c->no_ask_password = true;
                        break;
                case ARG_AS_CONFIG:
                        c->as_config = true;
                        *given |= OPT_AS_CONFIG;
                        break;
                case ARG_AS_DCF:
                        if (!*optarg)
                                return ctl_usage(c, "--as-dcf needs a folder.");
                        c->as_dcf = optarg;
                        *given |= OPT_AS_DCF;
                        break;
                case 'q':
                        c->quiet = true;
                        *given |= OPT_QUIET;
                        break;
                case ARG_VENDOR:
                case ARG_PRODUCT:
                        if (ctl_parse_u32(optarg, &v) < 0)
                                return ctl_usage(c, "Invalid --%s '%s': a 32-bit number.",
                                                 opt == ARG_VENDOR ? "vendor" : "product", optarg);
                        if (opt == ARG_VENDOR) {
                                c->vendor = v;
                                c->has_vendor = true;
                        } else {
                                c->product = v;
                                c->has_product = true;
                        }
                        *given |= OPT_VENDOR;
                        break;
                case ':':
                        return ctl_usage(c, "Option '%s' needs a value.", argv[optind - 1]);
                case '?':
                        if (optopt && optopt < 0x100)
                                return ctl_usage(c, "Unknown option '-%c'.", optopt);
                        return ctl_usage(c, "Unknown option '%s'.", argv[optind - 1]);
                default:
                        return ctl_usage(c, "Unexpected option.");
                }
        }
        /* after "--": the rest are arguments */
        for (; optind < argc; optind++) {
                r = add_arg(c, argv[optind]);
                if (r < 0)
                        return r;
        }
        return 1;
}

static bool colors_wanted(int fd) {
        const char *e = getenv("SYSTEMD_COLORS");
        if (getenv("NO_COLOR"))
                return false;
        if (e && (strcmp(e, "0") == 0 || strcmp(e, "false") == 0 || strcmp(e, "no") == 0))
                return false;
        if (e && (strcmp(e, "1") == 0 || strcmp(e, "true") == 0 || strcmp(e, "yes") == 0))
                return true;
        e = getenv("TERM");
        if (e && strcmp(e, "dumb") == 0)
                return false;
        return isatty(fd);
}

int main(int argc, char *argv[]) {
        ctl_context c = { .exit_code = CTL_EXIT_SUCCESS };
        ctl_pager pager = { 0 };
        unsigned given = 0;
        const verb *v = NULL;
        char **storage = NULL;
        int r;

        c.stdout_tty = isatty(STDOUT_FILENO);
        c.stderr_tty = isatty(STDERR_FILENO);
        c.colors = colors_wanted(STDOUT_FILENO);
        c.err_colors = colors_wanted(STDERR_FILENO);

        r = parse_argv(argc, argv, &c, &given);
        storage = c.args;
        if (r <= 0)
                goto finish;

        const char *name = c.n_args > 0 ? c.args[0] : "status";
        for (size_t i = 0; i < sizeof(verbs) / sizeof(verbs[0]); i++)
                if (strcmp(verbs[i].name, name) == 0)
                        v = &verbs[i];
        if (!v) {
                r = ctl_usage(&c, "Unknown command '%s'.", name);
                goto finish;
        }
        if (c.n_args > 0) {
                c.args++;
                c.n_args--;
        }
        if (c.n_args < v->min_args || (v->max_args >= 0 && c.n_args > v->max_args)) {
                r = c.n_args < v->min_args ? ctl_usage(&c, "Too few arguments for '%s'.", v->name)
                                           : ctl_usage(&c, "Too many arguments for '%s'.", v->name);
                goto finish;
        }
        for (unsigned flag = 1; flag <= OPT_LAST; flag <<= 1)
                if ((given & flag) && !(v->options & flag)) {
                        r = ctl_usage(&c, "Option %s does not go with '%s'.", option_name(flag), v->name);
                        goto finish;
                }
        if (c.as_config && (c.json || c.no_legend || c.as_dcf)) {
                r = ctl_usage(&c, "--as-config does not go with %s: it prints lssd.conf(5) text.",
                              c.json ? "--json" : c.no_legend ? "--no-legend" : "--as-dcf");
                goto finish;
        }
        if (c.as_dcf && (c.json || c.no_legend)) {
                r = ctl_usage(&c, "--as-dcf does not go with %s: it writes files.", c.json ? "--json" : "--no-legend");
                goto finish;
        }
        if (c.has_vendor != c.has_product) {
                r = ctl_usage(&c, "--vendor and --product go together.");
                goto finish;
        }

        if (v->pager && !c.no_pager && !c.json) {
                r = ctl_pager_open(&pager);
                if (r < 0)
                        c.no_pager = true; /* not worth failing for */
        }
        if (v->polkit && !c.no_ask_password)
                (void) ctl_agent_open(); /* without it polkit cannot ask; lssd says so */
        r = v->run(&c);
        ctl_agent_close();
        ctl_pager_close(&pager);

finish:
        free(storage);
        sd_bus_flush_close_unref(c.bus);
        if (r < 0 && c.exit_code == CTL_EXIT_SUCCESS)
                c.exit_code = CTL_EXIT_FAILURE;
        return c.exit_code;
}
