/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* monitor: every signal lssd sends (its own, PropertiesChanged, objects
 * added and removed) and lssd starting or stopping, one line each, until
 * ^C. */
#include <errno.h>
#include <inttypes.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <systemd/sd-event.h>

#include "ctl/ctl.h"
#include "ctl/ctl_errors.h"
#include "ctl/ctl_json.h"
#include "util/time_util.h"

typedef struct monitor {
        ctl_context *c;
        sd_event *event;
} monitor;

/* A device path as its identity, a bus path as its interface name; other
 * paths stay as they are. Returns a newly allocated string. */
static char *path_label(const char *path) {
        char *ifname = NULL, *dev = NULL, *s = NULL;
        uint32_t id[4];

        if (ctl_path_parse(path, &ifname, &dev) < 0)
                return strdup(path);
        if (!dev)
                return ifname;
        if (sscanf(dev, "%8" SCNx32 "_%8" SCNx32 "_%8" SCNx32 "_%8" SCNx32, &id[0], &id[1], &id[2], &id[3]) != 4 ||
            asprintf(&s, "0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32, id[0], id[1], id[2],
                     id[3]) < 0)
                s = strdup(path);
        free(ifname);
        free(dev);
        return s;
}

/* One value of any type, as JSON or as text (text: dict entries k=v,
 * arrays space-separated, object paths by label). */
static int dump_value(sd_bus_message *m, ctl_json *j, FILE *f, bool json) {
        const char *contents;
        char type;
        int r;

        r = sd_bus_message_peek_type(m, &type, &contents);
        if (r <= 0)
                return r;
        switch (type) {
        case 's': case 'o': case 'g': {
                const char *s;
                r = sd_bus_message_read_basic(m, type, &s);
                if (r < 0)
                        return r;
                if (type == 'o' && !json) {
                        char *l = path_label(s);
                        fputs(l ? l : s, f);
                        free(l);
                } else if (json)
                        ctl_json_string(j, s);
                else
                        fputs(s, f);
                return 1;
        }
        case 'b': {
                int b;
                r = sd_bus_message_read_basic(m, type, &b);
                if (r < 0)
                        return r;
                if (json)
                        ctl_json_bool(j, b);
                else
                        fputs(b ? "yes" : "no", f);
                return 1;
        }
        case 'd': {
                double d;
                r = sd_bus_message_read_basic(m, type, &d);
                if (r < 0)
                        return r;
                if (json)
                        ctl_json_double(j, d);
                else
                        fprintf(f, "%.2f", d);
                return 1;
        }
        case 'y': case 'q': case 'u': case 't': case 'n': case 'i': case 'x': case 'h': {
                union { uint8_t y; uint16_t q; uint32_t u; uint64_t t; int16_t n; int32_t i; int64_t x; } v;
                r = sd_bus_message_read_basic(m, type, &v);
                if (r < 0)
                        return r;
                uint64_t u = type == 'y' ? v.y : type == 'q' ? v.q : type == 'u' || type == 'h' ? v.u :
                             type == 't' ? v.t : type == 'n' ? (uint64_t) v.n : type == 'i' ? (uint64_t) v.i :
                             (uint64_t) v.x;
                if (json)
                        ctl_json_uint(j, u);
                else
                        fprintf(f, "%" PRIu64, u);
                return 1;
        }
        case 'v':
                r = sd_bus_message_enter_container(m, type, contents);
                if (r < 0)
                        return r;
                r = dump_value(m, j, f, json);
                if (r < 0)
                        return r;
                r = sd_bus_message_exit_container(m);
                return r < 0 ? r : 1;
        case 'a':
        case 'r': {
                bool dict = type == 'a' && contents[0] == '{';
                bool first = true;
                char entry[16] = "";
                if (dict) {
                        size_t len = strlen(contents);
                        if (len < 3 || len - 2 >= sizeof(entry))
                                return sd_bus_message_skip(m, NULL);
                        memcpy(entry, contents + 1, len - 2); /* "{sv}" -> "sv" */
                }
                r = sd_bus_message_enter_container(m, type, contents);
                if (r < 0)
                        return r;
                if (json) {
                        if (dict)
                                ctl_json_object_begin(j);
                        else
                                ctl_json_array_begin(j);
                }
                for (;;) {
                        if (dict) {
                                const char *key;
                                r = sd_bus_message_enter_container(m, 'e', entry);
                                if (r <= 0)
                                        break;
                                /* keys are strings in lssd's dicts */
                                r = sd_bus_message_read(m, "s", &key);
                                if (r < 0)
                                        return r;
                                if (json)
                                        ctl_json_key(j, key);
                                else
                                        fprintf(f, "%s%s=", first ? "" : " ", key);
                                r = dump_value(m, j, f, json);
                                if (r < 0)
                                        return r;
                                r = sd_bus_message_exit_container(m);
                                if (r < 0)
                                        return r;
                        } else {
                                if (sd_bus_message_at_end(m, false) > 0)
                                        break;
                                if (!first && !json)
                                        fputc(' ', f);
                                r = dump_value(m, j, f, json);
                                if (r <= 0)
                                        break;
                        }
                        first = false;
                }
                if (r < 0)
                        return r;
                if (json) {
                        if (dict)
                                ctl_json_object_end(j);
                        else
                                ctl_json_array_end(j);
                }
                r = sd_bus_message_exit_container(m);
                return r < 0 ? r : 1;
        }
        default:
                r = sd_bus_message_skip(m, NULL);
                return r < 0 ? r : 1;
        }
}

static void print_time(FILE *f) {
        struct timespec ts;
        struct tm tm;
        char buf[32];

        clock_gettime(CLOCK_REALTIME, &ts);
        localtime_r(&ts.tv_sec, &tm);
        strftime(buf, sizeof(buf), "%H:%M:%S", &tm);
        fprintf(f, "%s.%03ld", buf, ts.tv_nsec / 1000000);
}

static bool wanted(const ctl_context *c, const char *label_bus) {
        return !c->bus_name || (label_bus && strcmp(label_bus, c->bus_name) == 0);
}

static int on_signal_message(sd_bus_message *m, void *userdata, sd_bus_error *ret_error) {
        monitor *mon = userdata;
        ctl_context *c = mon->c;
        const char *member = sd_bus_message_get_member(m);
        const char *path = sd_bus_message_get_path(m);
        char *ifname = NULL, *subject = NULL;
        int r;

        if (!member || !path)
                return 0;

        /* lssd going away or coming back */
        if (strcmp(member, "NameOwnerChanged") == 0) {
                const char *name, *old_owner, *new_owner;
                if (sd_bus_message_read(m, "sss", &name, &old_owner, &new_owner) < 0 ||
                    strcmp(name, LSSD_BUS_NAME) != 0)
                        return 0;
                const char *what = *new_owner ? "started" : "stopped";
                if (c->json) {
                        ctl_json j;
                        ctl_json_init(&j, stdout);
                        ctl_json_object_begin(&j);
                        ctl_json_key(&j, "time");
                        ctl_json_uint(&j, clock_now_us(CLOCK_REALTIME));
                        ctl_json_key(&j, "signal");
                        ctl_json_string(&j, *new_owner ? "LssdStarted" : "LssdStopped");
                        ctl_json_object_end(&j);
                        ctl_json_finish(&j);
                } else {
                        print_time(stdout);
                        printf(" lssd %s\n", what);
                        fflush(stdout);
                }
                return 0;
        }

        /* the bus it is about: from the path, or from the path in the body
         * for the object manager's signals */
        const char *about = path;
        const char *first_path = NULL;
        if (strcmp(member, "InterfacesAdded") == 0 || strcmp(member, "InterfacesRemoved") == 0) {
                if (sd_bus_message_read(m, "o", &first_path) < 0)
                        return 0;
                about = first_path;
                sd_bus_message_rewind(m, true);
        }
        (void) ctl_path_ifname(about, &ifname);
        if (!wanted(c, ifname))
                goto finish;
        subject = path_label(about);

        if (c->json) {
                ctl_json j;
                ctl_json_init(&j, stdout);
                ctl_json_object_begin(&j);
                ctl_json_key(&j, "time");
                ctl_json_uint(&j, clock_now_us(CLOCK_REALTIME));
                ctl_json_key(&j, "signal");
                ctl_json_string(&j, member);
                ctl_json_key(&j, "path");
                ctl_json_string(&j, about);
                ctl_json_key(&j, "bus");
                if (ifname)
                        ctl_json_string(&j, ifname);
                else
                        ctl_json_null(&j);
                ctl_json_key(&j, "args");
                ctl_json_array_begin(&j);
                while ((r = dump_value(m, &j, stdout, true)) > 0)
                        ;
                ctl_json_array_end(&j);
                ctl_json_object_end(&j);
                ctl_json_finish(&j);
        } else {
                print_time(stdout);
                printf(" %s", ifname ? ifname : "-");
                if (subject && ifname && strcmp(subject, ifname) != 0)
                        printf(" %s", subject);
                if (strcmp(member, "PropertiesChanged") == 0) {
                        const char *iface;
                        /* interface name, changed a{sv}, invalidated as */
                        if (sd_bus_message_read(m, "s", &iface) >= 0) {
                                putchar(' ');
                                dump_value(m, NULL, stdout, false);
                        }
                } else if (strcmp(member, LSSD_SIGNAL_UNKNOWN_DEVICE) == 0) {
                        uint32_t id[4];
                        if (sd_bus_message_read(m, "uuuu", &id[0], &id[1], &id[2], &id[3]) >= 0)
                                printf(" UnknownDevice 0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32,
                                       id[0], id[1], id[2], id[3]);
                } else if (strcmp(member, "InterfacesAdded") == 0 || strcmp(member, "InterfacesRemoved") == 0) {
                        printf(" %s", strcmp(member, "InterfacesAdded") == 0 ? "added" : "removed");
                } else {
                        printf(" %s", member);
                        while (sd_bus_message_at_end(m, false) == 0) {
                                putchar(' ');
                                if (dump_value(m, NULL, stdout, false) <= 0)
                                        break;
                        }
                }
                putchar('\n');
                fflush(stdout);
        }
finish:
        free(ifname);
        free(subject);
        return 0;
}

static int on_quit(sd_event_source *s, const struct signalfd_siginfo *si, void *userdata) {
        monitor *mon = userdata;
        return sd_event_exit(mon->event, 0);
}

int verb_monitor(ctl_context *c) {
        sd_event_source *sigint = NULL, *sigterm = NULL;
        char **paths = NULL, **ifnames = NULL;
        monitor mon = { .c = c };
        sigset_t mask, old;
        size_t n = 0;
        int r;

        /* lssd must be there (and serve --bus) when we start */
        r = ctl_buses(c, &paths, &ifnames, &n);
        ctl_strv_free(paths, n);
        ctl_strv_free(ifnames, n);
        if (r < 0)
                return r;

        sigemptyset(&mask);
        sigaddset(&mask, SIGINT);
        sigaddset(&mask, SIGTERM);
        sigprocmask(SIG_BLOCK, &mask, &old);

        r = sd_event_new(&mon.event);
        if (r >= 0)
                r = sd_event_add_signal(mon.event, &sigint, SIGINT, on_quit, &mon);
        if (r >= 0)
                r = sd_event_add_signal(mon.event, &sigterm, SIGTERM, on_quit, &mon);
        if (r >= 0)
                r = sd_bus_attach_event(c->bus, mon.event, SD_EVENT_PRIORITY_NORMAL);
        if (r >= 0)
                r = sd_bus_add_match(c->bus, NULL, "type='signal',sender='" LSSD_BUS_NAME "'", on_signal_message, &mon);
        if (r >= 0)
                r = sd_bus_add_match(c->bus, NULL,
                                     "type='signal',sender='org.freedesktop.DBus',interface='org.freedesktop.DBus',"
                                     "member='NameOwnerChanged',arg0='" LSSD_BUS_NAME "'",
                                     on_signal_message, &mon);
        if (r < 0) {
                r = ctl_fail(c, CTL_EXIT_FAILURE, r, "Failed to watch lssd's signals: %s", strerror(-r));
                goto finish;
        }
        /* the matches are in place (sd_bus_add_match() waits for the bus):
         * say so, as busctl monitor does; scripts wait for this line */
        fprintf(stderr, "Monitoring lssd%s%s; press ^C to stop.\n", c->bus_name ? " on " : "",
                c->bus_name ? c->bus_name : "");
        r = sd_event_loop(mon.event);
        if (r < 0)
                r = ctl_fail(c, CTL_EXIT_FAILURE, r, "Event loop failed: %s", strerror(-r));
finish:
        sd_bus_detach_event(c->bus);
        sd_event_source_unref(sigint);
        sd_event_source_unref(sigterm);
        sd_event_unref(mon.event);
        sigprocmask(SIG_SETMASK, &old, NULL);
        return r;
}
