/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Who may do what: each privileged method asks polkit for an action of its
 * kind (org.lssd.LSS1.scan, .assign, .set-bitrate, .raw, .reload;
 * dbus/org.lssd.LSS1.policy), as systemd's bus services do. Root and user
 * lssd are allowed without asking; where polkit is not on the bus (polkitd
 * not installed), the rule of old decides: root, user lssd and group lssd,
 * and the journal says so once.
 *
 * Nothing here blocks the event loop. The first lssd_auth_check() of a call
 * asks the bus daemon for the caller's credentials and then polkit, both
 * asynchronously, and tells the handler to return (1); with the answer in,
 * the call is dispatched again (sd_bus_enqueue_for_read()), the handler
 * runs from the start and lssd_auth_check() returns the kept answer, once;
 * an answer no call comes back for is dropped once the loop is idle. Credentials come from the
 * bus daemon (GetConnectionCredentials: SO_PEERCRED, SO_PEERGROUPS at
 * connect time), never from /proc: sd-bus's augmented credentials describe
 * whatever the sender's PID is now, not who sent the message. polkit gets
 * the caller as a unix-process subject: pid, start time, uid. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>
#include <systemd/sd-bus.h>

#define LSSD_GROUP "lssd"
#define LSSD_USER  "lssd"

/* how long polkit may take to answer, and with a person typing a password */
#define LSSD_AUTH_TIMEOUT_USEC             (25ULL * 1000000ULL)
#define LSSD_AUTH_INTERACTIVE_TIMEOUT_USEC (300ULL * 1000000ULL)

/* The polkit actions, one per kind of method (lssd(8), AUTHORIZATION). */
typedef enum lssd_action {
        LSSD_ACTION_SCAN,        /* Scan */
        LSSD_ACTION_ASSIGN,      /* AssignNodeId, UnassignNodeId, AutoAssign */
        LSSD_ACTION_SET_BITRATE, /* SetBitrate */
        LSSD_ACTION_RAW,         /* Acquire, Release, the raw services, Execute */
        LSSD_ACTION_RELOAD,      /* ReloadConfig */
        _LSSD_ACTION_MAX,
} lssd_action;

/* "org.lssd.LSS1.scan", ... */
const char *lssd_action_id(lssd_action a);

/* What polkit said, or that it could not be asked. */
typedef enum lssd_polkit_answer {
        LSSD_POLKIT_YES,       /* is_authorized */
        LSSD_POLKIT_NO,        /* neither authorized nor a challenge */
        LSSD_POLKIT_CHALLENGE, /* authorized after authentication, which the call did not allow */
        LSSD_POLKIT_NO_AGENT,  /* the same, though the call allowed it: polkit had no agent to ask with */
        LSSD_POLKIT_ABSENT,    /* not on the bus (ServiceUnknown, NameHasNoOwner): polkitd not installed */
        LSSD_POLKIT_FAILED,    /* any other error: timed out, gone while asked (NoReply), a bad reply */
} lssd_polkit_answer;

typedef struct lssd_auth_query lssd_auth_query;

typedef struct lssd_auth {
        bool have_uid, have_gid;  /* false: no such user / group on this system */
        uid_t uid;                /* of user lssd */
        gid_t gid;                /* of group lssd */
        uid_t root_uid;           /* root, allowed without asking anyone: 0 (tests move it away) */
        uint64_t timeout_usec;    /* polkit's time to answer (LSSD_AUTH_TIMEOUT_USEC) */
        uint64_t interactive_timeout_usec;
        unsigned fallback_notes;  /* "polkit is not available" lines logged (one) */
        lssd_auth_query *queries; /* asked, or answered and not yet used */
} lssd_auth;

/* Looks up user and group `lssd` (absent = root only without polkit). */
void lssd_auth_init(lssd_auth *a);
/* Drops every query (their calls are left unanswered). */
void lssd_auth_done(lssd_auth *a);

/* The rule where polkit is absent, from credentials the bus vouches for:
 * root, user lssd, a member of group lssd. gids may be NULL when the bus
 * could not tell the groups (then only the user counts). */
bool lssd_auth_allowed(const lssd_auth *a, uid_t euid, const gid_t *gids, size_t n_gids);

/* The decision from polkit's answer for a caller (uid, gids) that is neither
 * root nor user lssd: 0 allowed; else -EACCES with the error set:
 * AccessDenied naming the action (NO, ABSENT and not in group lssd,
 * FAILED with polkit's error `failure`), InteractiveAuthorizationRequired
 * (CHALLENGE, NO_AGENT). ABSENT decides by lssd_auth_allowed() and logs once that it
 * does. */
int lssd_auth_decide(lssd_auth *a, lssd_action action, lssd_polkit_answer answer, const sd_bus_error *failure,
                     uid_t uid, const gid_t *gids, size_t n_gids, sd_bus_error *error);

/* May the sender of method call `m` do `action`? 0: yes, go on. 1: polkit
 * (or the bus daemon) was asked: return 1 from the handler without a reply,
 * `m` is dispatched again when the answer is in. <0: no, or the question
 * failed; `error` says why (AccessDenied, InteractiveAuthorizationRequired).
 * Call it before changing anything: the handler may run twice. */
int lssd_auth_check(lssd_auth *a, sd_bus_message *m, lssd_action action, sd_bus_error *error);
