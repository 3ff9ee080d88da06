/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The authorization decision (lssd_auth.h): the rule without polkit, the
 * decision from each answer of polkit, and the asynchronous path on a
 * private dbus-daemon with a fake org.freedesktop.PolicyKit1 in this
 * process: allowed, denied, challenge, interactive flag, polkit absent
 * (the rule of old, noted once), polkit slow and polkit gone while the call
 * waits; the loop serves other calls meanwhile, and the subject polkit gets
 * is this process (pid, start time, uid). Needs dbus-daemon. */
#include <check.h>
#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <systemd/sd-bus.h>
#include <systemd/sd-event.h>
#include <unistd.h>

#include "daemon/lssd_auth.h"

#include "check-main.h"

/* ---- the rule without polkit ---- */

START_TEST(allowed_root) {
        lssd_auth none = { 0 };
        lssd_auth both = { .have_uid = true, .have_gid = true, .uid = 990, .gid = 991 };
        ck_assert(lssd_auth_allowed(&none, 0, NULL, 0));
        ck_assert(lssd_auth_allowed(&both, 0, NULL, 0));
}
END_TEST

START_TEST(allowed_other_uid) {
        lssd_auth none = { 0 };
        lssd_auth both = { .have_uid = true, .have_gid = true, .uid = 990, .gid = 991 };
        const gid_t other[] = { 100, 990 };
        ck_assert(!lssd_auth_allowed(&none, 1000, NULL, 0));
        ck_assert(!lssd_auth_allowed(&both, 1000, NULL, 0));
        ck_assert(!lssd_auth_allowed(&both, 1000, other, 2));
        /* the uid of user lssd as a group id means nothing */
        ck_assert(!lssd_auth_allowed(&both, 1000, other + 1, 1));
}
END_TEST

START_TEST(allowed_user_lssd) {
        lssd_auth user = { .have_uid = true, .uid = 990 };
        lssd_auth no_user = { .have_uid = false, .uid = 990 };
        ck_assert(lssd_auth_allowed(&user, 990, NULL, 0));
        ck_assert(!lssd_auth_allowed(&user, 991, NULL, 0));
        /* uid is only meaningful when the user exists */
        ck_assert(!lssd_auth_allowed(&no_user, 990, NULL, 0));
}
END_TEST

START_TEST(allowed_group_member) {
        lssd_auth group = { .have_gid = true, .gid = 991 };
        lssd_auth no_group = { .have_gid = false, .gid = 991 };
        const gid_t member[] = { 100, 991 }, other[] = { 100, 992 };
        ck_assert(lssd_auth_allowed(&group, 1000, member, 2));
        ck_assert(lssd_auth_allowed(&group, 1000, member + 1, 1));
        ck_assert(!lssd_auth_allowed(&group, 1000, member, 1));
        ck_assert(!lssd_auth_allowed(&group, 1000, other, 2));
        ck_assert(!lssd_auth_allowed(&no_group, 1000, member, 2));
        /* groups unknown: only the user counts */
        ck_assert(!lssd_auth_allowed(&group, 1000, NULL, 0));
        ck_assert(!lssd_auth_allowed(&group, 1000, NULL, 2));
}
END_TEST

/* ---- the decision from polkit's answer ---- */

START_TEST(action_ids) {
        ck_assert_str_eq(lssd_action_id(LSSD_ACTION_SCAN), "org.lssd.LSS1.scan");
        ck_assert_str_eq(lssd_action_id(LSSD_ACTION_ASSIGN), "org.lssd.LSS1.assign");
        ck_assert_str_eq(lssd_action_id(LSSD_ACTION_SET_BITRATE), "org.lssd.LSS1.set-bitrate");
        ck_assert_str_eq(lssd_action_id(LSSD_ACTION_RAW), "org.lssd.LSS1.raw");
        ck_assert_str_eq(lssd_action_id(LSSD_ACTION_RELOAD), "org.lssd.LSS1.reload");
        ck_assert_ptr_null(lssd_action_id(_LSSD_ACTION_MAX));
}
END_TEST

START_TEST(decide_each_answer) {
        lssd_auth a = { .have_gid = true, .gid = 991 };
        const gid_t member[] = { 100, 991 }, other[] = { 100 };
        sd_bus_error e = SD_BUS_ERROR_NULL, failure = SD_BUS_ERROR_NULL;

        ck_assert_int_eq(lssd_auth_decide(&a, LSSD_ACTION_SCAN, LSSD_POLKIT_YES, NULL, 1000, other, 1, &e), 0);
        ck_assert(!sd_bus_error_is_set(&e));

        /* polkit's no is final, whatever the groups */
        ck_assert_int_eq(lssd_auth_decide(&a, LSSD_ACTION_ASSIGN, LSSD_POLKIT_NO, NULL, 1000, member, 2, &e), -EACCES);
        ck_assert(sd_bus_error_has_name(&e, SD_BUS_ERROR_ACCESS_DENIED));
        ck_assert_ptr_nonnull(strstr(e.message, "org.lssd.LSS1.assign"));
        sd_bus_error_free(&e);

        ck_assert_int_lt(lssd_auth_decide(&a, LSSD_ACTION_RAW, LSSD_POLKIT_CHALLENGE, NULL, 1000, member, 2, &e), 0);
        ck_assert(sd_bus_error_has_name(&e, SD_BUS_ERROR_INTERACTIVE_AUTHORIZATION_REQUIRED));
        ck_assert_ptr_nonnull(strstr(e.message, "org.lssd.LSS1.raw"));
        sd_bus_error_free(&e);
        ck_assert_int_lt(lssd_auth_decide(&a, LSSD_ACTION_SCAN, LSSD_POLKIT_NO_AGENT, NULL, 1000, member, 2, &e), 0);
        ck_assert(sd_bus_error_has_name(&e, SD_BUS_ERROR_INTERACTIVE_AUTHORIZATION_REQUIRED));
        ck_assert_ptr_nonnull(strstr(e.message, "org.lssd.LSS1.scan"));
        ck_assert_ptr_nonnull(strstr(e.message, "no authentication agent"));
        sd_bus_error_free(&e);

        /* polkit there but failing: refused, even for a member of group lssd */
        sd_bus_error_set(&failure, SD_BUS_ERROR_NO_REPLY, "gone");
        ck_assert_int_eq(lssd_auth_decide(&a, LSSD_ACTION_RELOAD, LSSD_POLKIT_FAILED, &failure, 1000, member, 2, &e),
                         -EACCES);
        ck_assert(sd_bus_error_has_name(&e, SD_BUS_ERROR_ACCESS_DENIED));
        ck_assert_ptr_nonnull(strstr(e.message, SD_BUS_ERROR_NO_REPLY));
        ck_assert_ptr_nonnull(strstr(e.message, "org.lssd.LSS1.reload"));
        sd_bus_error_free(&e);
        sd_bus_error_free(&failure);

        /* polkit absent: the rule of old, said once */
        ck_assert_uint_eq(a.fallback_notes, 0);
        ck_assert_int_eq(lssd_auth_decide(&a, LSSD_ACTION_SCAN, LSSD_POLKIT_ABSENT, NULL, 1000, member, 2, &e), 0);
        ck_assert(!sd_bus_error_is_set(&e));
        ck_assert_int_eq(lssd_auth_decide(&a, LSSD_ACTION_SET_BITRATE, LSSD_POLKIT_ABSENT, NULL, 1000, other, 1, &e),
                         -EACCES);
        ck_assert(sd_bus_error_has_name(&e, SD_BUS_ERROR_ACCESS_DENIED));
        ck_assert_ptr_nonnull(strstr(e.message, "group 'lssd'"));
        ck_assert_ptr_nonnull(strstr(e.message, "org.lssd.LSS1.set-bitrate"));
        sd_bus_error_free(&e);
        ck_assert_uint_eq(a.fallback_notes, 1);
}
END_TEST

/* ---- the asynchronous path on a private bus ---- */

typedef enum polkit_mode {
        PK_NONE,      /* no polkit on the bus */
        PK_YES,
        PK_NO,
        PK_CHALLENGE,
        PK_SLOW,      /* never answers */
        PK_GONE,      /* leaves the bus while asked */
} polkit_mode;

typedef struct world {
        char dir[64], address[192];
        pid_t dbus_daemon;
        sd_event *event;
        sd_bus *daemon, *client, *polkit;
        sd_event_source *close_polkit;
        lssd_auth auth;
        polkit_mode mode;
        unsigned handler_runs, allowed_runs, polkit_calls;
        bool kept_after_answer;
        /* what the fake polkit was asked */
        char subject_kind[32], action_id[64];
        uint32_t pid, flags;
        uint64_t start_time;
        int32_t uid;
        sd_bus_message *held; /* PK_SLOW */
} world;

static world w;
static unsigned answers_in; /* answers of the running test, in order */

static uint64_t own_start_time(void) {
        char buf[1024], *save = NULL;
        FILE *f = fopen("/proc/self/stat", "re");
        ck_assert_ptr_nonnull(f);
        size_t n = fread(buf, 1, sizeof(buf) - 1, f);
        fclose(f);
        buf[n] = '\0';
        int field = 2;
        for (char *t = strtok_r(strrchr(buf, ')') + 1, " ", &save); t; t = strtok_r(NULL, " ", &save))
                if (++field == 22)
                        return strtoull(t, NULL, 10);
        return 0;
}

static int method_do(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        uint32_t action;
        int r = sd_bus_message_read(m, "u", &action);
        if (r < 0)
                return r;
        w.handler_runs++;
        r = lssd_auth_check(&w.auth, m, (lssd_action) action, error);
        if (r != 1) /* the answer: used, not kept */
                w.kept_after_answer = w.auth.queries != NULL;
        if (r != 0)
                return r;
        w.allowed_runs++;
        return sd_bus_reply_method_return(m, "s", "done");
}

static int method_ping(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        return sd_bus_reply_method_return(m, NULL);
}

static const sd_bus_vtable daemon_vtable[] = {
        SD_BUS_VTABLE_START(0),
        SD_BUS_METHOD("Do", "u", "s", method_do, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_METHOD("Ping", "", "", method_ping, SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_VTABLE_END
};

static int on_close_polkit(sd_event_source *s, void *userdata) {
        w.polkit = sd_bus_close_unref(w.polkit);
        return 0;
}

static int check_authorization(sd_bus_message *m, void *userdata, sd_bus_error *error) {
        const char *kind, *action, *cancel, *key;
        int r;

        w.polkit_calls++;
        r = sd_bus_message_enter_container(m, 'r', "sa{sv}");
        ck_assert_int_ge(r, 0);
        ck_assert_int_ge(sd_bus_message_read(m, "s", &kind), 0);
        snprintf(w.subject_kind, sizeof(w.subject_kind), "%s", kind);
        ck_assert_int_ge(sd_bus_message_enter_container(m, 'a', "{sv}"), 0);
        while ((r = sd_bus_message_enter_container(m, 'e', "sv")) > 0) {
                ck_assert_int_ge(sd_bus_message_read(m, "s", &key), 0);
                if (strcmp(key, "pid") == 0)
                        ck_assert_int_ge(sd_bus_message_read(m, "v", "u", &w.pid), 0);
                else if (strcmp(key, "start-time") == 0)
                        ck_assert_int_ge(sd_bus_message_read(m, "v", "t", &w.start_time), 0);
                else if (strcmp(key, "uid") == 0)
                        ck_assert_int_ge(sd_bus_message_read(m, "v", "i", &w.uid), 0);
                else
                        ck_assert_int_ge(sd_bus_message_skip(m, "v"), 0);
                ck_assert_int_ge(sd_bus_message_exit_container(m), 0);
        }
        ck_assert_int_ge(sd_bus_message_exit_container(m), 0);
        ck_assert_int_ge(sd_bus_message_exit_container(m), 0);
        ck_assert_int_ge(sd_bus_message_read(m, "s", &action), 0);
        snprintf(w.action_id, sizeof(w.action_id), "%s", action);
        ck_assert_int_ge(sd_bus_message_skip(m, "a{ss}"), 0);
        ck_assert_int_ge(sd_bus_message_read(m, "us", &w.flags, &cancel), 0);

        switch (w.mode) {
        case PK_SLOW:
                w.held = sd_bus_message_ref(m);
                return 1;
        case PK_GONE:
                ck_assert_int_ge(sd_event_add_defer(w.event, &w.close_polkit, on_close_polkit, NULL), 0);
                return 1;
        default:
                return sd_bus_reply_method_return(m, "(bba{ss})", w.mode == PK_YES, w.mode == PK_CHALLENGE, 0);
        }
}

static const sd_bus_vtable polkit_vtable[] = {
        SD_BUS_VTABLE_START(0),
        SD_BUS_METHOD("CheckAuthorization", "(sa{sv})sa{ss}us", "(bba{ss})", check_authorization,
                      SD_BUS_VTABLE_UNPRIVILEGED),
        SD_BUS_VTABLE_END
};

static sd_bus *connect_bus(void) {
        sd_bus *b = NULL;
        ck_assert_int_ge(sd_bus_new(&b), 0);
        ck_assert_int_ge(sd_bus_set_address(b, w.address), 0);
        ck_assert_int_ge(sd_bus_set_bus_client(b, 1), 0);
        ck_assert_int_ge(sd_bus_start(b), 0);
        ck_assert_int_ge(sd_bus_attach_event(b, w.event, 0), 0);
        return b;
}

/* A dbus-daemon of our own, the "daemon" (org.lssd.Test, /test), a client,
 * and with `mode` a fake polkit. Root is not trusted here (root_uid moved)
 * and user lssd does not exist: every call goes to polkit. */
static void world_up(polkit_mode mode) {
        char conf[160], sock[160];
        FILE *f;

        memset(&w, 0, sizeof(w));
        answers_in = 0;
        w.mode = mode;
        snprintf(w.dir, sizeof(w.dir), "/tmp/lssd-auth-test.XXXXXX");
        ck_assert_ptr_nonnull(mkdtemp(w.dir));
        snprintf(sock, sizeof(sock), "%s/bus", w.dir);
        snprintf(w.address, sizeof(w.address), "unix:path=%s", sock);
        snprintf(conf, sizeof(conf), "%s/bus.conf", w.dir);
        f = fopen(conf, "we");
        ck_assert_ptr_nonnull(f);
        fprintf(f, "<!DOCTYPE busconfig PUBLIC \"-//freedesktop//DTD D-BUS Bus Configuration 1.0//EN\" "
                   "\"http://www.freedesktop.org/standards/dbus/1.0/busconfig.dtd\">\n"
                   "<busconfig><type>custom</type><listen>%s</listen><auth>EXTERNAL</auth>"
                   "<policy context=\"default\"><allow user=\"*\"/><allow own=\"*\"/><allow send_type=\"method_call\"/>"
                   "<allow send_type=\"signal\"/><allow send_requested_reply=\"true\" send_type=\"method_return\"/>"
                   "<allow send_requested_reply=\"true\" send_type=\"error\"/><allow receive_type=\"method_call\"/>"
                   "<allow receive_type=\"method_return\"/><allow receive_type=\"error\"/>"
                   "<allow receive_type=\"signal\"/></policy>"
                   "</busconfig>\n", w.address);
        fclose(f);

        /* ready when it prints its address (the socket exists before it listens) */
        int ready[2];
        ck_assert_int_eq(pipe(ready), 0);
        w.dbus_daemon = fork();
        ck_assert_int_ge(w.dbus_daemon, 0);
        if (w.dbus_daemon == 0) {
                char arg[192], fd_arg[32];
                close(ready[0]);
                /* gone with the test, even one that failed half-way */
                prctl(PR_SET_PDEATHSIG, SIGTERM);
                snprintf(arg, sizeof(arg), "--config-file=%s", conf);
                snprintf(fd_arg, sizeof(fd_arg), "--print-address=%d", ready[1]);
                execlp("dbus-daemon", "dbus-daemon", "--nofork", "--nopidfile", arg, fd_arg, (char *) NULL);
                _exit(127);
        }
        close(ready[1]);
        struct pollfd p = { .fd = ready[0], .events = POLLIN };
        char line[256];
        ck_assert_msg(poll(&p, 1, 10000) == 1 && read(ready[0], line, sizeof(line)) > 0,
                      "dbus-daemon did not start (installed?)");
        close(ready[0]);
        struct stat st;
        ck_assert_int_eq(stat(sock, &st), 0);

        ck_assert_int_ge(sd_event_new(&w.event), 0);
        lssd_auth_init(&w.auth);
        w.auth.root_uid = (uid_t) -2;
        w.auth.have_uid = false;
        w.auth.have_gid = false;
        w.daemon = connect_bus();
        ck_assert_int_ge(sd_bus_add_object_vtable(w.daemon, NULL, "/test", "org.lssd.Test", daemon_vtable, NULL), 0);
        ck_assert_int_ge(sd_bus_request_name(w.daemon, "org.lssd.Test", 0), 0);
        w.client = connect_bus();
        if (mode != PK_NONE) {
                w.polkit = connect_bus();
                ck_assert_int_ge(sd_bus_add_object_vtable(w.polkit, NULL, "/org/freedesktop/PolicyKit1/Authority",
                                                          "org.freedesktop.PolicyKit1.Authority", polkit_vtable, NULL),
                                 0);
                ck_assert_int_ge(sd_bus_request_name(w.polkit, "org.freedesktop.PolicyKit1", 0), 0);
        }
}

static void world_down(void) {
        lssd_auth_done(&w.auth);
        sd_bus_message_unref(w.held);
        sd_event_source_disable_unref(w.close_polkit);
        sd_bus_close_unref(w.polkit);
        sd_bus_close_unref(w.client);
        sd_bus_close_unref(w.daemon);
        sd_event_unref(w.event);
        kill(w.dbus_daemon, SIGTERM);
        waitpid(w.dbus_daemon, NULL, 0);
        char path[128];
        snprintf(path, sizeof(path), "%s/bus", w.dir);
        unlink(path);
        snprintf(path, sizeof(path), "%s/bus.conf", w.dir);
        unlink(path);
        rmdir(w.dir);
}

typedef struct answer {
        bool in;
        unsigned order; /* 1 = the first answer of the test */
        uint64_t at;    /* CLOCK_MONOTONIC, µs */
        char name[128], message[512];
} answer;

static int on_answer(sd_bus_message *reply, void *userdata, sd_bus_error *error) {
        answer *a = userdata;
        const sd_bus_error *e = sd_bus_message_get_error(reply);
        a->in = true;
        a->order = ++answers_in;
        ck_assert_int_ge(sd_event_now(w.event, CLOCK_MONOTONIC, &a->at), 0);
        if (e) {
                snprintf(a->name, sizeof(a->name), "%s", e->name);
                snprintf(a->message, sizeof(a->message), "%s", e->message ? e->message : "");
        }
        return 0;
}

static void call_async(const char *member, lssd_action action, bool interactive, answer *a) {
        sd_bus_message *m = NULL;
        ck_assert_int_ge(sd_bus_message_new_method_call(w.client, &m, "org.lssd.Test", "/test", "org.lssd.Test", member),
                         0);
        if (strcmp(member, "Do") == 0)
                ck_assert_int_ge(sd_bus_message_append(m, "u", (uint32_t) action), 0);
        ck_assert_int_ge(sd_bus_message_set_allow_interactive_authorization(m, interactive), 0);
        ck_assert_int_ge(sd_bus_call_async(w.client, NULL, m, on_answer, a, 10 * 1000000ULL), 0);
        sd_bus_message_unref(m);
}

/* Runs the loop until `a` is answered (10 s at most), then until idle. */
static void run_until(answer *a) {
        for (int i = 0; i < 10000 && !a->in; i++)
                ck_assert_int_ge(sd_event_run(w.event, 1000), 0);
        ck_assert_msg(a->in, "no answer");
        while (sd_event_run(w.event, 0) > 0)
                ;
}

static answer call(lssd_action action, bool interactive) {
        answer a = { 0 };
        call_async("Do", action, interactive, &a);
        run_until(&a);
        return a;
}

/* Refused with `name`, the message naming the action, nothing done. */
static void expect_refused(const answer *a, const char *name, lssd_action action) {
        ck_assert_str_eq(a->name, name);
        ck_assert_msg(strstr(a->message, lssd_action_id(action)), "%s", a->message);
        ck_assert_uint_eq(w.allowed_runs, 0);
}

START_TEST(polkit_yes) {
        world_up(PK_YES);
        answer a = call(LSSD_ACTION_SCAN, false);
        ck_assert_msg(a.name[0] == '\0', "%s: %s", a.name, a.message);
        ck_assert_uint_eq(w.polkit_calls, 1);
        /* asked once, dispatched again with the answer */
        ck_assert_uint_eq(w.handler_runs, 2);
        ck_assert_uint_eq(w.allowed_runs, 1);
        ck_assert_str_eq(w.action_id, "org.lssd.LSS1.scan");
        /* the subject: this process, as the bus daemon and /proc tell it */
        ck_assert_str_eq(w.subject_kind, "unix-process");
        ck_assert_uint_eq(w.pid, (uint32_t) getpid());
        ck_assert_int_eq(w.uid, (int32_t) geteuid());
        ck_assert_uint_eq(w.start_time, own_start_time());
        ck_assert_uint_ne(w.start_time, 0);
        ck_assert_uint_eq(w.flags, 0);
        /* the answer was used once and dropped */
        ck_assert(!w.kept_after_answer);
        ck_assert_ptr_null(w.auth.queries);
        world_down();
}
END_TEST

START_TEST(polkit_no) {
        world_up(PK_NO);
        answer a = call(LSSD_ACTION_ASSIGN, false);
        expect_refused(&a, SD_BUS_ERROR_ACCESS_DENIED, LSSD_ACTION_ASSIGN);
        ck_assert_uint_eq(w.handler_runs, 2);
        ck_assert(!w.kept_after_answer);
        ck_assert_ptr_null(w.auth.queries);
        world_down();
}
END_TEST

START_TEST(polkit_challenge) {
        world_up(PK_CHALLENGE);
        answer a = call(LSSD_ACTION_RAW, false);
        expect_refused(&a, SD_BUS_ERROR_INTERACTIVE_AUTHORIZATION_REQUIRED, LSSD_ACTION_RAW);
        ck_assert_uint_eq(w.flags, 0);
        world_down();
}
END_TEST

/* polkit's challenge to a call that allowed interaction: it had no agent to
 * ask with (a text agent outside a login session); the message must not say
 * the call did not allow it */
START_TEST(polkit_challenge_interactive) {
        world_up(PK_CHALLENGE);
        answer a = call(LSSD_ACTION_SCAN, true);
        expect_refused(&a, SD_BUS_ERROR_INTERACTIVE_AUTHORIZATION_REQUIRED, LSSD_ACTION_SCAN);
        ck_assert_uint_eq(w.flags, 1);
        ck_assert_msg(strstr(a.message, "no authentication agent"), "%s", a.message);
        ck_assert_msg(!strstr(a.message, "did not allow"), "%s", a.message);
        world_down();
}
END_TEST

/* A call that allows interactive authorization lets polkit ask (flag 1). */
START_TEST(polkit_interactive_flag) {
        world_up(PK_YES);
        answer a = call(LSSD_ACTION_SET_BITRATE, true);
        ck_assert_msg(a.name[0] == '\0', "%s: %s", a.name, a.message);
        ck_assert_str_eq(w.action_id, "org.lssd.LSS1.set-bitrate");
        ck_assert_uint_eq(w.flags, 1);
        world_down();
}
END_TEST

/* The groups the bus daemon gives this process, the first one. */
static gid_t own_bus_gid(void) {
        sd_bus_message *reply = NULL;
        const char *name;
        const void *p;
        size_t size;
        uint32_t g = 0;
        ck_assert_int_ge(sd_bus_get_unique_name(w.client, &name), 0);
        ck_assert_int_ge(sd_bus_call_method(w.client, "org.freedesktop.DBus", "/org/freedesktop/DBus",
                                            "org.freedesktop.DBus", "GetConnectionCredentials", NULL, &reply, "s",
                                            name),
                         0);
        ck_assert_int_ge(sd_bus_message_enter_container(reply, 'a', "{sv}"), 0);
        while (sd_bus_message_enter_container(reply, 'e', "sv") > 0) {
                const char *key;
                ck_assert_int_ge(sd_bus_message_read(reply, "s", &key), 0);
                if (strcmp(key, "UnixGroupIDs") == 0) {
                        ck_assert_int_ge(sd_bus_message_enter_container(reply, 'v', "au"), 0);
                        ck_assert_int_ge(sd_bus_message_read_array(reply, 'u', &p, &size), 0);
                        ck_assert_uint_ge(size, sizeof(g));
                        memcpy(&g, p, sizeof(g));
                        ck_assert_int_ge(sd_bus_message_exit_container(reply), 0);
                } else
                        ck_assert_int_ge(sd_bus_message_skip(reply, "v"), 0);
                ck_assert_int_ge(sd_bus_message_exit_container(reply), 0);
        }
        sd_bus_message_unref(reply);
        return (gid_t) g;
}

/* No polkit on the bus: group lssd decides, and the journal hears it once. */
START_TEST(polkit_absent) {
        world_up(PK_NONE);
        w.auth.have_gid = true;
        w.auth.gid = own_bus_gid();
        answer a = call(LSSD_ACTION_SCAN, false);
        ck_assert_msg(a.name[0] == '\0', "a member: %s: %s", a.name, a.message);
        ck_assert_uint_eq(w.allowed_runs, 1);

        w.auth.gid = 65533;
        a = call(LSSD_ACTION_ASSIGN, false);
        ck_assert_str_eq(a.name, SD_BUS_ERROR_ACCESS_DENIED);
        ck_assert_msg(strstr(a.message, "group 'lssd'") && strstr(a.message, "org.lssd.LSS1.assign"), "%s", a.message);
        ck_assert_uint_eq(w.allowed_runs, 1);
        ck_assert_uint_eq(w.auth.fallback_notes, 1);
        world_down();
}
END_TEST

/* polkit does not answer in time: refused, and the loop served another
 * call meanwhile, long before the wait was over. */
START_TEST(polkit_slow) {
        uint64_t t0;
        world_up(PK_SLOW);
        w.auth.timeout_usec = 1000 * 1000;
        answer slow = { 0 }, ping = { 0 };
        ck_assert_int_ge(sd_event_now(w.event, CLOCK_MONOTONIC, &t0), 0);
        call_async("Do", LSSD_ACTION_SCAN, false, &slow);
        call_async("Ping", 0, false, &ping);
        run_until(&slow);
        ck_assert(ping.in);
        ck_assert_uint_eq(ping.order, 1);
        ck_assert_uint_eq(slow.order, 2);
        ck_assert_uint_lt(ping.at - t0, 500 * 1000);
        ck_assert_uint_ge(slow.at - t0, 1000 * 1000);
        ck_assert_uint_eq(w.polkit_calls, 1);
        expect_refused(&slow, SD_BUS_ERROR_ACCESS_DENIED, LSSD_ACTION_SCAN);
        ck_assert_msg(strstr(slow.message, "polkit could not be asked"), "%s", slow.message);
        world_down();
}
END_TEST

/* polkit leaves the bus while the call waits (NoReply): refused. */
START_TEST(polkit_gone) {
        world_up(PK_GONE);
        answer a = call(LSSD_ACTION_RELOAD, false);
        ck_assert_uint_eq(w.polkit_calls, 1);
        ck_assert_ptr_null(w.polkit);
        expect_refused(&a, SD_BUS_ERROR_ACCESS_DENIED, LSSD_ACTION_RELOAD);
        ck_assert_msg(strstr(a.message, SD_BUS_ERROR_NO_REPLY), "%s", a.message);
        world_down();
}
END_TEST

/* Root needs nobody's word: polkit (which would say no) is not asked. */
START_TEST(root_not_asked) {
        world_up(PK_NO);
        w.auth.root_uid = geteuid();
        answer a = call(LSSD_ACTION_RAW, false);
        ck_assert_msg(a.name[0] == '\0', "%s: %s", a.name, a.message);
        ck_assert_uint_eq(w.polkit_calls, 0);
        ck_assert_uint_eq(w.allowed_runs, 1);
        world_down();
}
END_TEST

static void add(TCase *tc) {
        tcase_add_test(tc, allowed_root);
        tcase_add_test(tc, allowed_other_uid);
        tcase_add_test(tc, allowed_user_lssd);
        tcase_add_test(tc, allowed_group_member);
        tcase_add_test(tc, action_ids);
        tcase_add_test(tc, decide_each_answer);
        tcase_add_test(tc, polkit_yes);
        tcase_add_test(tc, polkit_no);
        tcase_add_test(tc, polkit_challenge);
        tcase_add_test(tc, polkit_challenge_interactive);
        tcase_add_test(tc, polkit_interactive_flag);
        tcase_add_test(tc, polkit_absent);
        tcase_add_test(tc, polkit_slow);
        tcase_add_test(tc, polkit_gone);
        tcase_add_test(tc, root_not_asked);
}

int main(void) {
        return check_main("daemon-auth", add);
}
