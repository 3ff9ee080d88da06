/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* lssd: the CANopen LSS master daemon. */
#include <errno.h>
#include <inttypes.h>
#include <getopt.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <systemd/sd-daemon.h>

#include "daemon/lssd_bus.h"
#include "daemon/lssd_context.h"
#include "daemon/lssd_errors.h"
#include "daemon/lssd_log.h"
#include "daemon/lssd_ready.h"
#include "simbus/simbus.h"

static void help(void) {
        printf("lssd [OPTIONS...]\n\n"
               "CANopen LSS master daemon (CiA 305), serving " LSSD_BUS_NAME " on the system bus.\n\n"
               "  -h --help              Show this help\n"
               "     --version           Show the version\n"
               "  -c --config FILE       Configuration file (default: %s if it exists)\n"
               "  -b --bus IFACE         Serve this CAN interface too (repeatable; no map, no auto-assign)\n"
               "     --check-config [FILE]\n"
               "                         Check the configuration, touch no bus, exit\n"
               "     --queue-size N      Jobs each bus queues at most (default %u)\n"
               "     --lss-timeout MS    LSS answer timeout of the --bus buses (default %u)\n"
               "     --simulate          Simulated in-memory buses instead of SocketCAN (tests, demos)\n"
               "     --sim-slave IFACE:VENDOR:PRODUCT:REVISION:SERIAL[:NODEID[:PROFILE]]\n"
               "                         A simulated slave on simulated bus IFACE (implies --simulate);\n"
               "                         PROFILE: " SIMBUS_PROFILES "\n"
               "     --sim-foreign-master IFACE:AFTER[:COUNT[:PERIOD_MS]]\n"
               "                         Another LSS master on simulated bus IFACE: once lssd wrote AFTER LSS\n"
               "                         requests there (@CS: its first with that cs), COUNT requests\n"
               "                         " SIMBUS_FOREIGN_FRAME ", PERIOD_MS apart\n",
               LSSD_DEFAULT_CONFIG, LSSD_QUEUE_MAX_DEFAULT, LSSCONF_LSS_TIMEOUT_MS_DEFAULT);
}

enum {
        ARG_VERSION = 0x100,
        ARG_CHECK_CONFIG,
        ARG_QUEUE_SIZE,
        ARG_LSS_TIMEOUT,
        ARG_SIMULATE,
        ARG_SIM_SLAVE,
        ARG_SIM_FOREIGN_MASTER,
};

static int add_bus_name(lssd_args *a, const char *name) {
        for (size_t i = 0; i < a->n_buses; i++)
                if (strcmp(a->buses[i], name) == 0)
                        return 0;
        char **v = realloc(a->buses, (a->n_buses + 1) * sizeof(*v));
        if (!v)
                return -ENOMEM;
        a->buses = v;
        a->buses[a->n_buses] = strdup(name);
        if (!a->buses[a->n_buses])
                return -ENOMEM;
        a->n_buses++;
        return 0;
}

/* 1: run; 0: exit successfully (--help); <0: error */
static int parse_argv(int argc, char *argv[], lssd_args *a) {
        static const struct option options[] = {
                { "help", no_argument, NULL, 'h' },
                { "version", no_argument, NULL, ARG_VERSION },
                { "config", required_argument, NULL, 'c' },
                { "bus", required_argument, NULL, 'b' },
                { "check-config", optional_argument, NULL, ARG_CHECK_CONFIG },
                { "queue-size", required_argument, NULL, ARG_QUEUE_SIZE },
                { "lss-timeout", required_argument, NULL, ARG_LSS_TIMEOUT },
                { "simulate", no_argument, NULL, ARG_SIMULATE },
                { "sim-slave", required_argument, NULL, ARG_SIM_SLAVE },
                { "sim-foreign-master", required_argument, NULL, ARG_SIM_FOREIGN_MASTER },
                {}
        };
        int c, r;

        while ((c = getopt_long(argc, argv, "hc:b:", options, NULL)) >= 0)
                switch (c) {
                case 'h':
                        help();
                        return 0;
                case ARG_VERSION:
                        printf("lssd %s\n", LSSD_VERSION);
                        return 0;
                case 'c':
                        free(a->config_path);
                        a->config_path = strdup(optarg);
                        if (!a->config_path)
                                return log_error_errno(-ENOMEM, "Out of memory");
                        a->config_explicit = true;
                        break;
                case 'b':
                        r = add_bus_name(a, optarg);
                        if (r < 0)
                                return log_error_errno(r, "Out of memory");
                        break;
                case ARG_CHECK_CONFIG:
                        a->check_config = true;
                        if (optarg) { /* --check-config=FILE */
                                free(a->config_path);
                                a->config_path = strdup(optarg);
                                if (!a->config_path)
                                        return log_error_errno(-ENOMEM, "Out of memory");
                                a->config_explicit = true;
                        }
                        break;
                case ARG_QUEUE_SIZE: {
                        char *end;
                        errno = 0;
                        unsigned long v = strtoul(optarg, &end, 10);
                        if (errno || *end || v < 1 || v > 100000) {
                                log_error("Invalid --queue-size '%s': 1..100000", optarg);
                                return -EINVAL;
                        }
                        a->queue_max = v;
                        break;
                }
                case ARG_LSS_TIMEOUT: {
                        char *end;
                        errno = 0;
                        unsigned long v = strtoul(optarg, &end, 10);
                        if (errno || *end || v < 1 || v > LSSCONF_LSS_TIMEOUT_MS_MAX) {
                                log_error("Invalid --lss-timeout '%s': 1..%u ms", optarg, LSSCONF_LSS_TIMEOUT_MS_MAX);
                                return -EINVAL;
                        }
                        a->lss_timeout_ms = (unsigned) v;
                        break;
                }
                case ARG_SIMULATE:
                        a->simulate = true;
                        break;
                case ARG_SIM_SLAVE: {
                        lssd_sim_slave s;
                        if (simbus_slave_parse(optarg, s.ifname, &s.id, &s.node_id, &s.profile) < 0) {
                                log_error("Invalid --sim-slave '%s': IFACE:VENDOR:PRODUCT:REVISION:SERIAL[:NODEID"
                                          "[:PROFILE]] (PROFILE: " SIMBUS_PROFILES ")", optarg);
                                return -EINVAL;
                        }
                        lssd_sim_slave *v = realloc(a->sim_slaves, (a->n_sim_slaves + 1) * sizeof(*v));
                        if (!v)
                                return log_error_errno(-ENOMEM, "Out of memory");
                        a->sim_slaves = v;
                        a->sim_slaves[a->n_sim_slaves++] = s;
                        a->simulate = true;
                        r = add_bus_name(a, s.ifname);
                        if (r < 0)
                                return log_error_errno(r, "Out of memory");
                        break;
                }
                case ARG_SIM_FOREIGN_MASTER: {
                        simbus_foreign f;
                        if (simbus_foreign_parse(optarg, &f) < 0) {
                                log_error("Invalid --sim-foreign-master '%s': IFACE:AFTER[:COUNT[:PERIOD_MS]] (AFTER "
                                          "0..1000000 or @CS 0..255, COUNT 1..100000, PERIOD_MS 1..60000)", optarg);
                                return -EINVAL;
                        }
                        simbus_foreign *v = realloc(a->sim_foreign, (a->n_sim_foreign + 1) * sizeof(*v));
                        if (!v)
                                return log_error_errno(-ENOMEM, "Out of memory");
                        a->sim_foreign = v;
                        a->sim_foreign[a->n_sim_foreign++] = f;
                        a->simulate = true;
                        break;
                }
                case '?':
                        return -EINVAL;
                default:
                        return -EINVAL;
                }

        /* `lssd --check-config FILE`: the first word is the file, any other is one too many */
        if (optind < argc && a->check_config && !a->config_path) {
                a->config_path = strdup(argv[optind]);
                if (!a->config_path)
                        return log_error_errno(-ENOMEM, "Out of memory");
                a->config_explicit = true;
                optind++;
        }
        if (optind < argc) {
                log_error("Unexpected argument '%s' (see --help)", argv[optind]);
                return -EINVAL;
        }
        return 1;
}

/* --check-config: load, print every diagnostic and what would be served. */
static int check_config(lssd_context *ctx) {
        lssconf_diag diag = LSSCONF_DIAG_INIT;
        lssconf *c = NULL;
        int r = lssd_context_read_config(ctx, &c, &diag);

        for (size_t i = 0; i < diag.n_messages; i++)
                fprintf(stderr, "%s: %s\n", lssconf_diag_severity_to_string(diag.messages[i].severity),
                        diag.messages[i].text);
        if (diag.n_dropped)
                fprintf(stderr, "(%zu more messages)\n", diag.n_dropped);
        lssconf_diag_clear(&diag);
        if (r < 0) {
                fprintf(stderr, "Configuration %s is bad.\n",
                        ctx->args.config_path ? ctx->args.config_path : LSSD_DEFAULT_CONFIG);
                return r;
        }
        if (!c->source && c->n_buses == 0) {
                fprintf(stderr, "Nothing to check: %s does not exist and no --bus was given (lssd --check-config "
                        "FILE).\n", LSSD_DEFAULT_CONFIG);
                lssconf_free(c);
                return -ENOENT;
        }
        /* what was read, the map too: a typo shows here, not at the next boot */
        for (size_t i = 0; i < c->n_buses; i++) {
                const lssconf_bus *b = &c->buses[i];
                char desc[LSSCONF_BUS_DESCRIBE_MAX];
                printf("%s\n", lssconf_bus_describe(b, desc, sizeof(desc)));
                for (size_t k = 0; k < b->n_devices; k++) {
                        const lssconf_device *d = &b->devices[k];
                        const char *dcf = lssconf_device_source(c, d);
                        char rev[16] = "any";
                        if (d->has_revision)
                                snprintf(rev, sizeof(rev), "0x%08" PRIx32, d->identity.revision);
                        /* an entry of a DCF names its file, one of the configuration its line */
                        if (dcf)
                                printf("  %s:%u: ", dcf, d->line);
                        else
                                printf("  line %u: ", d->line);
                        printf("vendor 0x%08" PRIx32 " product 0x%08" PRIx32 " revision %s serial 0x%08" PRIx32
                               " -> node-ID %u\n", d->identity.vendor, d->identity.product, rev, d->identity.serial,
                               d->node_id);
                }
        }
        printf("Configuration %s is good: %zu bus%s.\n", c->source ? c->source : "(command line)", c->n_buses,
               c->n_buses == 1 ? "" : "es");
        lssconf_free(c);
        return 0;
}

static int on_signal(sd_event_source *s, const struct signalfd_siginfo *si, void *userdata) {
        lssd_context *ctx = userdata;
        if (si->ssi_signo == SIGHUP) {
                sd_bus_error e = SD_BUS_ERROR_NULL;
                (void) lssd_context_reload(ctx, &e);
                sd_bus_error_free(&e);
                return 0;
        }
        log_info("Got %s", si->ssi_signo == SIGTERM ? "SIGTERM" : "SIGINT");
        lssd_context_stop(ctx);
        return 0;
}

static int setup_signals(lssd_context *ctx) {
        static const int signals[] = { SIGTERM, SIGINT, SIGHUP };
        sigset_t mask;
        int r;

        sigemptyset(&mask);
        for (size_t i = 0; i < sizeof(signals) / sizeof(signals[0]); i++)
                sigaddset(&mask, signals[i]);
        if (sigprocmask(SIG_BLOCK, &mask, NULL) < 0)
                return log_error_errno(-errno, "Failed to block signals");
        for (size_t i = 0; i < sizeof(signals) / sizeof(signals[0]); i++) {
                r = sd_event_add_signal(ctx->event, NULL, signals[i], on_signal, ctx);
                if (r < 0)
                        return log_error_errno(r, "Failed to watch signal %d", signals[i]);
        }
        return 0;
}

/* A bad configuration at start: its own exit status, which lssd.service's
 * RestartPreventExitStatus= keeps from becoming a restart loop (restarting
 * cannot fix the file). */
#define EXIT_BAD_CONFIG 78 /* EX_CONFIG */
static bool bad_config;

static int run(int argc, char *argv[]) {
        lssd_args args = { 0 };
        lssd_context *ctx = NULL;
        lssconf *config = NULL;
        lssconf_diag diag = LSSCONF_DIAG_INIT;
        int r;

        r = parse_argv(argc, argv, &args);
        if (r <= 0) {
                lssd_args_done(&args);
                return r;
        }
        r = lssd_context_new(&args, &ctx);
        if (r < 0) {
                lssd_args_done(&args);
                return log_error_errno(r, "Out of memory");
        }
        if (ctx->args.check_config) {
                r = check_config(ctx);
                goto finish;
        }

        log_info("lssd %s starting", LSSD_VERSION);
        (void) sd_bus_error_add_map(lssd_error_map);

        /* configuration: the last good one is what a reload falls back to */
        r = lssd_context_read_config(ctx, &config, &diag);
        size_t n_errors = 0;
        for (size_t i = 0; i < diag.n_messages; i++) {
                n_errors += diag.messages[i].severity == LSSCONF_DIAG_ERROR;
                lssd_log(diag.messages[i].severity == LSSCONF_DIAG_ERROR ? LOG_ERR : LOG_WARNING, "%s",
                         diag.messages[i].text);
        }
        lssconf_diag_clear(&diag);
        if (r < 0) {
                /* the file:line lines above say why; strerror(EINVAL) only confused (seen in the boot test) */
                if (n_errors > 0)
                        log_error("The configuration has %zu error%s (above): exiting with status 78, "
                                  "not restarted; fix it and restart lssd", n_errors, n_errors == 1 ? "" : "s");
                else
                        log_error_errno(r, "Failed to load the configuration");
                bad_config = true;
                goto finish;
        }
        if (config->n_buses == 0)
                log_warning("No buses to serve: give --bus IFACE or a configuration file with buses");

        /* event loop, watchdog, signals */
        r = sd_event_default(&ctx->event);
        if (r < 0) {
                log_error_errno(r, "Failed to allocate the event loop");
                goto finish;
        }
        (void) sd_event_set_watchdog(ctx->event, true);
        r = setup_signals(ctx);
        if (r < 0)
                goto finish;

        /* bus: every object (the buses open their sockets but send nothing),
         * then the name, then the first frames: a client that sees the name
         * sees every bus, and a second lssd exits before it sends a frame
         * (its switch to waiting would cut into the running one's job) */
        r = lssd_context_connect_bus(ctx);
        if (r < 0)
                goto finish;
        r = lssd_context_open_rtnl(ctx);
        if (r < 0)
                goto finish;
        r = lssd_context_apply_config(ctx, config);
        config = NULL;
        if (r < 0) {
                log_error_errno(r, "Failed to open the buses");
                goto finish;
        }
        r = lssd_context_request_name(ctx);
        if (r < 0)
                goto finish;
        lssd_context_start_buses(ctx);
        (void) lssd_context_dump_links(ctx);

        lssd_ready_startup_done(ctx);

        r = sd_event_loop(ctx->event);
        if (r < 0)
                log_error_errno(r, "Event loop failed");

finish:
        lssconf_free(config);
        lssd_context_free(ctx);
        return r;
}

int main(int argc, char *argv[]) {
        int r = run(argc, argv);
        return r >= 0 ? EXIT_SUCCESS : bad_config ? EXIT_BAD_CONFIG : EXIT_FAILURE;
}
