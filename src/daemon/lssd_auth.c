/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <grp.h>
#include <inttypes.h>
#include <pwd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <systemd/sd-event.h>

#include "daemon/lssd_auth.h"
#include "daemon/lssd_log.h"

#define POLKIT_NAME  "org.freedesktop.PolicyKit1"
#define POLKIT_PATH  "/org/freedesktop/PolicyKit1/Authority"
#define POLKIT_IFACE "org.freedesktop.PolicyKit1.Authority"
#define POLKIT_ALLOW_USER_INTERACTION 1u

static const char *const action_ids[_LSSD_ACTION_MAX] = {
        [LSSD_ACTION_SCAN] = "org.lssd.LSS1.scan",
        [LSSD_ACTION_ASSIGN] = "org.lssd.LSS1.assign",
        [LSSD_ACTION_SET_BITRATE] = "org.lssd.LSS1.set-bitrate",
        [LSSD_ACTION_RAW] = "org.lssd.LSS1.raw",
        [LSSD_ACTION_RELOAD] = "org.lssd.LSS1.reload",
};

const char *lssd_action_id(lssd_action a) {
        return a >= 0 && a < _LSSD_ACTION_MAX ? action_ids[a] : NULL;
}

/* One call being authorized: asked (slot set), then answered (done) until
 * the loop is idle again (cleanup). */
struct lssd_auth_query {
        lssd_auth_query *next;
        lssd_auth *auth;
        sd_bus_message *m;
        lssd_action action;
        sd_bus_slot *slot;
        sd_event_source *cleanup;
        bool done;
        int result;            /* 0 allowed, <0 refused with `error` */
        sd_bus_error error;
        uid_t uid;
        pid_t pid;
        gid_t *gids;
        size_t n_gids;
};

void lssd_auth_init(lssd_auth *a) {
        *a = (lssd_auth) {
                .root_uid = 0,
                .timeout_usec = LSSD_AUTH_TIMEOUT_USEC,
                .interactive_timeout_usec = LSSD_AUTH_INTERACTIVE_TIMEOUT_USEC,
        };
        const struct passwd *pw = getpwnam(LSSD_USER);
        if (pw) {
                a->have_uid = true;
                a->uid = pw->pw_uid;
        }
        const struct group *gr = getgrnam(LSSD_GROUP);
        if (gr) {
                a->have_gid = true;
                a->gid = gr->gr_gid;
        }
}

static void query_free(lssd_auth_query *q) {
        for (lssd_auth_query **p = &q->auth->queries; *p; p = &(*p)->next)
                if (*p == q) {
                        *p = q->next;
                        break;
                }
        sd_bus_slot_unref(q->slot);
        sd_event_source_disable_unref(q->cleanup);
        sd_bus_message_unref(q->m);
        sd_bus_error_free(&q->error);
        free(q->gids);
        free(q);
}

void lssd_auth_done(lssd_auth *a) {
        while (a->queries)
                query_free(a->queries);
}

bool lssd_auth_allowed(const lssd_auth *a, uid_t euid, const gid_t *gids, size_t n_gids) {
        if (euid == a->root_uid)
                return true;
        if (a->have_uid && euid == a->uid)
                return true;
        if (a->have_gid && gids)
                for (size_t i = 0; i < n_gids; i++)
                        if (gids[i] == a->gid)
                                return true;
        return false;
}

int lssd_auth_decide(lssd_auth *a, lssd_action action, lssd_polkit_answer answer, const sd_bus_error *failure,
                     uid_t uid, const gid_t *gids, size_t n_gids, sd_bus_error *error) {
        const char *id = lssd_action_id(action);

        switch (answer) {
        case LSSD_POLKIT_YES:
                return 0;
        case LSSD_POLKIT_CHALLENGE:
                return sd_bus_error_setf(error, SD_BUS_ERROR_INTERACTIVE_AUTHORIZATION_REQUIRED,
                                         "Authentication is required for %s (the call did not allow interactive "
                                         "authorization)", id);
        case LSSD_POLKIT_NO_AGENT:
                /* polkit uses a text agent's fallback registration only for a
                 * process in a login session: "did not allow" would be untrue */
                return sd_bus_error_setf(error, SD_BUS_ERROR_INTERACTIVE_AUTHORIZATION_REQUIRED,
                                         "Authentication is required for %s, and polkit found no authentication agent "
                                         "to ask the caller with (the call allowed interactive authorization)", id);
        case LSSD_POLKIT_ABSENT:
                if (a->fallback_notes == 0)
                        log_notice("polkit is not available (no %s on the bus): root and group '%s' may use every "
                                   "method, nobody else (lssd(8), AUTHORIZATION)", POLKIT_NAME, LSSD_GROUP);
                a->fallback_notes = 1;
                if (lssd_auth_allowed(a, uid, gids, n_gids))
                        return 0;
                return sd_bus_error_setf(error, SD_BUS_ERROR_ACCESS_DENIED,
                                         "%s needs root or group '%s' (no polkit; UID %u)", id, LSSD_GROUP,
                                         (unsigned) uid);
        case LSSD_POLKIT_FAILED:
                return sd_bus_error_setf(error, SD_BUS_ERROR_ACCESS_DENIED, "%s: polkit could not be asked (%s: %s)",
                                         id, failure && failure->name ? failure->name : "no answer",
                                         failure && failure->message ? failure->message : "-");
        case LSSD_POLKIT_NO:
        default:
                return sd_bus_error_setf(error, SD_BUS_ERROR_ACCESS_DENIED, "polkit does not grant %s to UID %u", id,
                                         (unsigned) uid);
        }
}

/* ---- the asynchronous path ---- */

static int on_cleanup(sd_event_source *s, void *userdata) {
        query_free(userdata);
        return 0;
}

/* The answer is in: keep it and dispatch the call again, which uses it
 * (lssd_auth_check()); should the call not come back to us (its object
 * went away meanwhile), the answer goes once the loop is idle. */
static void finish(lssd_auth_query *q, int result, const sd_bus_error *error) {
        sd_bus *bus = sd_bus_message_get_bus(q->m);
        int r;

        q->slot = sd_bus_slot_unref(q->slot);
        q->done = true;
        q->result = result;
        if (result < 0) {
                if (error && sd_bus_error_is_set(error))
                        sd_bus_error_copy(&q->error, error);
                else
                        sd_bus_error_set_errno(&q->error, result);
        }

        r = sd_event_add_defer(sd_bus_get_event(bus), &q->cleanup, on_cleanup, q);
        if (r >= 0)
                r = sd_event_source_set_priority(q->cleanup, SD_EVENT_PRIORITY_IDLE);
        if (r >= 0)
                r = sd_bus_message_rewind(q->m, true);
        if (r >= 0)
                r = sd_bus_enqueue_for_read(bus, q->m);
        if (r < 0) {
                log_warning_errno(r, "Could not dispatch %s again after authorization", sd_bus_message_get_member(q->m));
                sd_bus_reply_method_errnof(q->m, r, "Authorization failed: %m");
                query_free(q);
        }
}

static lssd_polkit_answer read_polkit_reply(sd_bus_message *reply) {
        int authorized = 0, challenge = 0;

        if (sd_bus_message_is_method_error(reply, NULL)) {
                const sd_bus_error *e = sd_bus_message_get_error(reply);
                if (sd_bus_error_has_names(e, SD_BUS_ERROR_SERVICE_UNKNOWN, SD_BUS_ERROR_NAME_HAS_NO_OWNER))
                        return LSSD_POLKIT_ABSENT;
                return LSSD_POLKIT_FAILED;
        }
        if (sd_bus_message_enter_container(reply, 'r', "bba{ss}") < 0 ||
            sd_bus_message_read(reply, "bb", &authorized, &challenge) < 0)
                return LSSD_POLKIT_FAILED;
        return authorized ? LSSD_POLKIT_YES : challenge ? LSSD_POLKIT_CHALLENGE : LSSD_POLKIT_NO;
}

static int on_polkit(sd_bus_message *reply, void *userdata, sd_bus_error *ret_error) {
        lssd_auth_query *q = userdata;
        sd_bus_error error = SD_BUS_ERROR_NULL, bad = SD_BUS_ERROR_NULL;
        lssd_polkit_answer answer = read_polkit_reply(reply);
        if (answer == LSSD_POLKIT_CHALLENGE && sd_bus_message_get_allow_interactive_authorization(q->m) > 0)
                answer = LSSD_POLKIT_NO_AGENT;
        const sd_bus_error *failure = sd_bus_message_get_error(reply);

        if (answer == LSSD_POLKIT_FAILED && !failure) {
                sd_bus_error_set(&bad, SD_BUS_ERROR_INVALID_SIGNATURE, "CheckAuthorization's reply is not (bba{ss})");
                failure = &bad;
        }
        int r = lssd_auth_decide(q->auth, q->action, answer, failure, q->uid, q->gids, q->n_gids, &error);
        if (answer == LSSD_POLKIT_FAILED)
                log_warning("polkit could not be asked about %s for UID %u (%s: %s): refused",
                            lssd_action_id(q->action), (unsigned) q->uid, failure->name,
                            failure->message ? failure->message : "-");
        finish(q, r, &error);
        sd_bus_error_free(&error);
        sd_bus_error_free(&bad);
        return 0;
}

/* Field 22 of /proc/PID/stat (clock ticks after boot), as polkit reads it;
 * 0 when lssd may not see the process (ProtectProc=invisible in the unit):
 * polkit then reads it itself. */
static uint64_t process_start_time(pid_t pid) {
        char path[64], buf[1024];
        snprintf(path, sizeof(path), "/proc/%d/stat", (int) pid);
        FILE *f = fopen(path, "re");
        if (!f)
                return 0;
        size_t n = fread(buf, 1, sizeof(buf) - 1, f);
        fclose(f);
        buf[n] = '\0';
        char *p = strrchr(buf, ')'), *save = NULL;
        if (!p)
                return 0;
        int field = 2; /* the ")" ends field 2 */
        for (char *t = strtok_r(p + 1, " ", &save); t; t = strtok_r(NULL, " ", &save))
                if (++field == 22)
                        return strtoull(t, NULL, 10);
        return 0;
}

static int ask_polkit(lssd_auth_query *q) {
        sd_bus *bus = sd_bus_message_get_bus(q->m);
        sd_bus_message *c = NULL;
        bool interactive = sd_bus_message_get_allow_interactive_authorization(q->m) > 0;
        int r;

        r = sd_bus_message_new_method_call(bus, &c, POLKIT_NAME, POLKIT_PATH, POLKIT_IFACE, "CheckAuthorization");
        if (r >= 0)
                r = sd_bus_message_append(c, "(sa{sv})sa{ss}us", "unix-process", 3, "pid", "u", (uint32_t) q->pid,
                                          "start-time", "t", process_start_time(q->pid), "uid", "i", (int32_t) q->uid,
                                          lssd_action_id(q->action), 0,
                                          interactive ? POLKIT_ALLOW_USER_INTERACTION : 0u, "");
        if (r >= 0)
                r = sd_bus_call_async(bus, &q->slot, c, on_polkit, q,
                                      interactive ? q->auth->interactive_timeout_usec : q->auth->timeout_usec);
        sd_bus_message_unref(c);
        return r;
}

/* GetConnectionCredentials' a{sv}: UnixUserID, ProcessID, UnixGroupIDs. */
static int read_creds(sd_bus_message *reply, lssd_auth_query *q, bool *have_uid, bool *have_pid) {
        int r;

        r = sd_bus_message_enter_container(reply, 'a', "{sv}");
        if (r < 0)
                return r;
        while ((r = sd_bus_message_enter_container(reply, 'e', "sv")) > 0) {
                const char *key;
                uint32_t v;
                r = sd_bus_message_read_basic(reply, 's', &key);
                if (r < 0)
                        return r;
                if (strcmp(key, "UnixUserID") == 0 || strcmp(key, "ProcessID") == 0) {
                        r = sd_bus_message_read(reply, "v", "u", &v);
                        if (r < 0)
                                return r;
                        if (key[0] == 'U') {
                                q->uid = (uid_t) v;
                                *have_uid = true;
                        } else {
                                q->pid = (pid_t) v;
                                *have_pid = true;
                        }
                } else if (strcmp(key, "UnixGroupIDs") == 0 && !q->gids) {
                        const void *p;
                        size_t size;
                        r = sd_bus_message_enter_container(reply, 'v', "au");
                        if (r >= 0)
                                r = sd_bus_message_read_array(reply, 'u', &p, &size);
                        if (r < 0)
                                return r;
                        q->n_gids = size / sizeof(uint32_t);
                        q->gids = calloc(q->n_gids ? q->n_gids : 1, sizeof(gid_t));
                        if (!q->gids)
                                return -ENOMEM;
                        for (size_t i = 0; i < q->n_gids; i++) {
                                uint32_t g;
                                memcpy(&g, (const uint8_t *) p + i * sizeof(uint32_t), sizeof(g));
                                q->gids[i] = (gid_t) g;
                        }
                        r = sd_bus_message_exit_container(reply);
                } else
                        r = sd_bus_message_skip(reply, "v");
                if (r < 0)
                        return r;
                r = sd_bus_message_exit_container(reply);
                if (r < 0)
                        return r;
        }
        if (r < 0)
                return r;
        return sd_bus_message_exit_container(reply);
}

static int on_creds(sd_bus_message *reply, void *userdata, sd_bus_error *ret_error) {
        lssd_auth_query *q = userdata;
        sd_bus_error error = SD_BUS_ERROR_NULL;
        bool have_uid = false, have_pid = false;
        int r;

        q->slot = sd_bus_slot_unref(q->slot);
        if (sd_bus_message_is_method_error(reply, NULL)) {
                const sd_bus_error *e = sd_bus_message_get_error(reply);
                sd_bus_error_setf(&error, SD_BUS_ERROR_ACCESS_DENIED,
                                  "%s: the caller's credentials could not be read (%s: %s)",
                                  lssd_action_id(q->action), e->name, e->message ? e->message : "-");
                finish(q, -EACCES, &error);
                sd_bus_error_free(&error);
                return 0;
        }
        r = read_creds(reply, q, &have_uid, &have_pid);
        if (r < 0 || !have_uid) {
                sd_bus_error_setf(&error, SD_BUS_ERROR_ACCESS_DENIED,
                                  "%s: the bus did not vouch for the caller's user ID", lssd_action_id(q->action));
                finish(q, -EACCES, &error);
                sd_bus_error_free(&error);
                return 0;
        }
        /* root and lssd itself need nobody's word */
        if (q->uid == q->auth->root_uid || (q->auth->have_uid && q->uid == q->auth->uid)) {
                finish(q, 0, NULL);
                return 0;
        }
        /* no PID (a bus daemon on another system?): only the rule without polkit can decide */
        r = have_pid ? ask_polkit(q) : -ESRCH;
        if (r < 0) {
                sd_bus_error failure = SD_BUS_ERROR_NULL;
                sd_bus_error_set_errnof(&failure, r, "could not call CheckAuthorization: %m");
                r = lssd_auth_decide(q->auth, q->action, have_pid ? LSSD_POLKIT_FAILED : LSSD_POLKIT_ABSENT, &failure,
                                     q->uid, q->gids, q->n_gids, &error);
                finish(q, r, &error);
                sd_bus_error_free(&failure);
                sd_bus_error_free(&error);
        }
        return 0;
}

int lssd_auth_check(lssd_auth *a, sd_bus_message *m, lssd_action action, sd_bus_error *error) {
        const char *sender = sd_bus_message_get_sender(m);
        lssd_auth_query *q;
        int r;

        for (q = a->queries; q; q = q->next)
                if (q->m == m && q->action == action) {
                        if (!q->done)
                                return 1;
                        /* the call came again: its answer, used once (what no call
                         * comes for, e.g. an object gone meanwhile, goes when idle) */
                        r = q->result;
                        if (r < 0) {
                                r = sd_bus_error_copy(error, &q->error);
                                if (r >= 0)
                                        r = -EACCES;
                        }
                        query_free(q);
                        return r;
                }

        if (!sender)
                return sd_bus_error_setf(error, SD_BUS_ERROR_ACCESS_DENIED,
                                         "%s: a call without a sender (no bus daemon vouches for it)",
                                         lssd_action_id(action));

        q = calloc(1, sizeof(*q));
        if (!q)
                return -ENOMEM;
        q->auth = a;
        q->m = sd_bus_message_ref(m);
        q->action = action;
        q->next = a->queries;
        a->queries = q;
        r = sd_bus_call_method_async(sd_bus_message_get_bus(m), &q->slot, "org.freedesktop.DBus",
                                     "/org/freedesktop/DBus", "org.freedesktop.DBus", "GetConnectionCredentials",
                                     on_creds, q, "s", sender);
        if (r < 0) {
                query_free(q);
                return r;
        }
        return 1;
}
