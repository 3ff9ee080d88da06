/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Who may send LSS frames: root, user `lssd` and members of group `lssd`.
 * The bus policy (dbus/org.lssd.LSS1.conf) says the same; the daemon checks
 * again from credentials the bus vouches for (defence in depth). Credentials
 * sd-bus "augmented" from /proc are never trusted: they describe whatever
 * the sender's PID is now, not who sent the message. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <sys/types.h>
#include <systemd/sd-bus.h>

#define LSSD_GROUP "lssd"
#define LSSD_USER  "lssd"

typedef struct lssd_auth {
        bool have_uid, have_gid; /* false: no such user / group on this system */
        uid_t uid;               /* of user lssd */
        gid_t gid;               /* of group lssd */
} lssd_auth;

/* Looks up user and group `lssd` (absent = root only). */
void lssd_auth_init(lssd_auth *a);

/* The decision, from verified credentials. gids may be NULL when the bus
 * could not tell the groups (then only the user counts). */
bool lssd_auth_allowed(const lssd_auth *a, uid_t euid, const gid_t *gids, size_t n_gids);

/* The decision from the sender's credentials `creds` (EUID wanted). An EUID
 * sd-bus augmented from /proc is refused whoever it names. `m` is the
 * message the credentials came with, used only to ask the bus for the
 * sender's groups when the user alone is not enough; NULL means no groups.
 * Returns as lssd_auth_check(). */
int lssd_auth_check_creds(const lssd_auth *a, sd_bus_creds *creds, sd_bus_message *m, sd_bus_error *error);

/* Checks the sender of `m`: fetches its credentials and decides with
 * lssd_auth_check_creds(). 0 if allowed; otherwise sets
 * org.freedesktop.DBus.Error.AccessDenied and returns -EACCES (or another
 * negative errno when the credentials could not be read). */
int lssd_auth_check(const lssd_auth *a, sd_bus_message *m, sd_bus_error *error);
