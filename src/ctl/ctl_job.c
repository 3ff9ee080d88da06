/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "ctl/ctl_agent.h"
#include "ctl/ctl_job.h"

#define BAR_WIDTH 30

struct ctl_runner {
        ctl_context *c;
        sd_event *event;
        sigset_t old_mask;
        sd_event_source *sigint, *sigterm;
        bool progress;
        bool interrupted;
        bool quit;              /* leave the loop without an answer */

        /* the call in flight */
        const char *bus_path, *ifname, *job;
        sd_bus_message *reply;
        sd_bus_error error;
        bool done;
        bool cancel_sent;
        bool bar_shown;
        char running[64];       /* the bus's Job property */
        double fraction;        /* its Progress */
};

static void bar_clear(ctl_runner *run) {
        if (!run->bar_shown)
                return;
        fputs("\r\033[K", stderr);
        fflush(stderr);
        run->bar_shown = false;
}

static void bar_draw(ctl_runner *run) {
        if (!run->progress || run->done)
                return;
        bool ours = strcmp(run->running, run->job) == 0;
        double f = ours ? run->fraction : 0;
        if (!(f >= 0))
                f = 0;
        if (f > 1)
                f = 1;
        int filled = (int) lround(f * BAR_WIDTH);

        fprintf(stderr, "\r\033[K%s %s [", run->ifname, run->job);
        for (int i = 0; i < BAR_WIDTH; i++)
                fputc(i < filled ? '#' : '.', stderr);
        if (ours)
                fprintf(stderr, "] %3d%%", (int) lround(f * 100));
        else if (run->running[0])
                fprintf(stderr, "] waiting for %s", run->running);
        else
                fprintf(stderr, "] starting");
        fflush(stderr);
        run->bar_shown = true;
}

static int on_properties_changed(sd_bus_message *m, void *userdata, sd_bus_error *ret_error) {
        ctl_runner *run = userdata;
        const char *iface;
        int r;

        r = sd_bus_message_read(m, "s", &iface);
        if (r < 0 || strcmp(iface, LSSD_BUS_IFACE) != 0)
                return 0;
        r = sd_bus_message_enter_container(m, 'a', "{sv}");
        if (r < 0)
                return 0;
        while (sd_bus_message_enter_container(m, 'e', "sv") > 0) {
                const char *name, *contents;
                char type;
                if (sd_bus_message_read(m, "s", &name) < 0 || sd_bus_message_peek_type(m, &type, &contents) < 0)
                        return 0;
                if (strcmp(name, "Job") == 0 && contents && strcmp(contents, "s") == 0) {
                        const char *s;
                        if (sd_bus_message_read(m, "v", "s", &s) < 0)
                                return 0;
                        snprintf(run->running, sizeof(run->running), "%s", s);
                } else if (strcmp(name, "Progress") == 0 && contents && strcmp(contents, "d") == 0) {
                        if (sd_bus_message_read(m, "v", "d", &run->fraction) < 0)
                                return 0;
                } else if (sd_bus_message_skip(m, "v") < 0)
                        return 0;
                if (sd_bus_message_exit_container(m) < 0)
                        return 0;
        }
        bar_draw(run);
        return 0;
}

static int on_reply(sd_bus_message *m, void *userdata, sd_bus_error *ret_error) {
        ctl_runner *run = userdata;

        run->done = true;
        if (sd_bus_message_is_method_error(m, NULL))
                sd_bus_error_copy(&run->error, sd_bus_message_get_error(m));
        else
                run->reply = sd_bus_message_ref(m);
        return 0;
}

/* ^C: cancel the job if it is the one running (not somebody else's); a
 * second ^C leaves at once */
static int on_signal(sd_event_source *s, const struct signalfd_siginfo *si, void *userdata) {
        ctl_runner *run = userdata;
        sd_bus_error error = SD_BUS_ERROR_NULL;
        char *running = NULL;
        int r;

        run->interrupted = true;
        if (run->done || run->cancel_sent || !run->job) {
                run->quit = true;
                return 0;
        }

        r = sd_bus_get_property_string(run->c->bus, LSSD_BUS_NAME, run->bus_path, LSSD_BUS_IFACE, "Job", &error,
                                       &running);
        if (r >= 0 && strcmp(running, run->job) == 0) {
                sd_bus_error_free(&error);
                r = sd_bus_call_method(run->c->bus, LSSD_BUS_NAME, run->bus_path, LSSD_BUS_IFACE, "Cancel", &error,
                                       NULL, NULL);
                if (r >= 0) {
                        run->cancel_sent = true;
                        free(running);
                        sd_bus_error_free(&error);
                        return 0; /* the reply (Cancelled) ends the loop */
                }
        }
        bar_clear(run);
        if (r < 0)
                fprintf(stderr, "lssctl: could not cancel the job: %s\n",
                        sd_bus_error_is_set(&error) ? error.message : strerror(-r));
        else
                fprintf(stderr, "lssctl: the %s job is still queued (behind '%s') and was not cancelled.\n",
                        run->job, running);
        free(running);
        sd_bus_error_free(&error);
        run->quit = true;
        return 0;
}

int ctl_runner_new(ctl_context *c, bool progress, ctl_runner **ret) {
        sigset_t mask;
        int r;

        ctl_runner *run = calloc(1, sizeof(*run));
        if (!run)
                return -ENOMEM;
        run->c = c;
        run->progress = progress;
        run->error = SD_BUS_ERROR_NULL;

        sigemptyset(&mask);
        sigaddset(&mask, SIGINT);
        sigaddset(&mask, SIGTERM);
        if (sigprocmask(SIG_BLOCK, &mask, &run->old_mask) < 0) {
                r = -errno;
                free(run);
                return r;
        }
        r = sd_event_new(&run->event);
        if (r < 0)
                goto fail;
        r = sd_event_add_signal(run->event, &run->sigint, SIGINT, on_signal, run);
        if (r < 0)
                goto fail;
        r = sd_event_add_signal(run->event, &run->sigterm, SIGTERM, on_signal, run);
        if (r < 0)
                goto fail;
        r = sd_bus_attach_event(c->bus, run->event, SD_EVENT_PRIORITY_NORMAL);
        if (r < 0)
                goto fail;
        *ret = run;
        return 0;
fail:
        ctl_runner_free(run);
        return r;
}

ctl_runner *ctl_runner_free(ctl_runner *run) {
        if (!run)
                return NULL;
        bar_clear(run);
        if (run->c->bus)
                sd_bus_detach_event(run->c->bus);
        sd_event_source_unref(run->sigint);
        sd_event_source_unref(run->sigterm);
        sd_event_unref(run->event);
        sd_bus_error_free(&run->error);
        sd_bus_message_unref(run->reply);
        sigprocmask(SIG_SETMASK, &run->old_mask, NULL);
        free(run);
        return NULL;
}

int ctl_runner_call(ctl_runner *run, sd_bus_message *m, const char *bus_path, const char *ifname, const char *job,
                    sd_bus_message **ret_reply, sd_bus_error *error) {
        sd_bus_slot *match = NULL, *call = NULL;
        int r;

        if (run->interrupted)
                return -EINTR;
        run->bus_path = bus_path;
        run->ifname = ifname;
        run->job = job;
        run->done = run->cancel_sent = false;
        run->running[0] = 0;
        run->fraction = 0;

        if (run->progress) {
                /* before the call, so that no change is missed */
                r = sd_bus_match_signal(run->c->bus, &match, LSSD_BUS_NAME, bus_path,
                                        "org.freedesktop.DBus.Properties", "PropertiesChanged",
                                        on_properties_changed, run);
                if (r < 0)
                        return r;
        }
        if (run->progress) {
                /* what runs already, so that a queued call says what it waits for */
                char *now = NULL;
                if (sd_bus_get_property_string(run->c->bus, LSSD_BUS_NAME, bus_path, LSSD_BUS_IFACE, "Job", NULL,
                                               &now) >= 0)
                        snprintf(run->running, sizeof(run->running), "%s", now);
                free(now);
        }
        /* no time limit: a job may wait in the queue; ^C is the way out */
        r = sd_bus_call_async(run->c->bus, &call, m, on_reply, run, UINT64_MAX);
        if (r < 0)
                goto finish;
        /* with an agent, polkit may prompt now: a bar would stand before its
         * first line; it comes with the first change of the bus instead */
        if (!ctl_agent_running())
                bar_draw(run);
        /* not sd_event_loop(): its exit would close the bus, which later calls need */
        run->quit = false;
        while (!run->done && !run->quit) {
                r = sd_event_run(run->event, UINT64_MAX);
                if (r < 0)
                        break;
        }
        bar_clear(run);
        if (r < 0)
                goto finish;

        if (!run->done) {
                r = -EINTR; /* left on ^C without an answer */
                goto finish;
        }
        if (run->reply) {
                *ret_reply = run->reply;
                run->reply = NULL;
                r = 0;
        } else {
                r = sd_bus_error_get_errno(&run->error);
                sd_bus_error_move(error, &run->error);
                if (run->interrupted && run->cancel_sent)
                        r = -EINTR;
                if (r >= 0)
                        r = -EIO;
        }
finish:
        sd_bus_slot_unref(call);
        sd_bus_slot_unref(match);
        run->bus_path = run->ifname = run->job = NULL;
        return r;
}
