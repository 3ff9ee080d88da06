/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <grp.h>
#include <pwd.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_auth.h"

void lssd_auth_init(lssd_auth *a) {
        *a = (lssd_auth) { 0 };
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

bool lssd_auth_allowed(const lssd_auth *a, uid_t euid, const gid_t *gids, size_t n_gids) {
        if (euid == 0)
                return true;
        if (a->have_uid && euid == a->uid)
                return true;
        if (a->have_gid && gids)
                for (size_t i = 0; i < n_gids; i++)
                        if (gids[i] == a->gid)
                                return true;
        return false;
}

/* The groups the bus daemon recorded when the sender connected
 * (GetConnectionCredentials "UnixGroupIDs", from SO_PEERGROUPS). sd-bus would
 * only augment these from /proc, which is not proof. Returns the number of
 * groups (0 when the bus does not say) with a malloc'ed array in *ret. */
static int sender_groups(sd_bus_message *m, gid_t **ret) {
        sd_bus *bus = sd_bus_message_get_bus(m);
        const char *sender = sd_bus_message_get_sender(m);
        sd_bus_message *reply = NULL;
        gid_t *gids = NULL;
        size_t n = 0;
        int r;

        *ret = NULL;
        if (!sender)
                return 0;

        r = sd_bus_call_method(bus, "org.freedesktop.DBus", "/org/freedesktop/DBus", "org.freedesktop.DBus",
                               "GetConnectionCredentials", NULL, &reply, "s", sender);
        if (r < 0)
                return r;

        r = sd_bus_message_enter_container(reply, 'a', "{sv}");
        if (r < 0)
                goto finish;
        while ((r = sd_bus_message_enter_container(reply, 'e', "sv")) > 0) {
                const char *key;
                r = sd_bus_message_read_basic(reply, 's', &key);
                if (r < 0)
                        goto finish;
                if (strcmp(key, "UnixGroupIDs") == 0 && !gids) {
                        const void *p;
                        size_t size;
                        r = sd_bus_message_enter_container(reply, 'v', "au");
                        if (r < 0)
                                goto finish;
                        r = sd_bus_message_read_array(reply, 'u', &p, &size);
                        if (r < 0)
                                goto finish;
                        n = size / sizeof(uint32_t);
                        gids = calloc(n ? n : 1, sizeof(gid_t));
                        if (!gids) {
                                r = -ENOMEM;
                                goto finish;
                        }
                        for (size_t i = 0; i < n; i++) {
                                uint32_t g;
                                memcpy(&g, (const uint8_t *) p + i * sizeof(uint32_t), sizeof(g));
                                gids[i] = (gid_t) g;
                        }
                        r = sd_bus_message_exit_container(reply);
                } else
                        r = sd_bus_message_skip(reply, "v");
                if (r < 0)
                        goto finish;
                r = sd_bus_message_exit_container(reply);
                if (r < 0)
                        goto finish;
        }
        if (r < 0)
                goto finish;
        r = sd_bus_message_exit_container(reply);

finish:
        sd_bus_message_unref(reply);
        if (r < 0) {
                free(gids);
                return r;
        }
        *ret = gids;
        return (int) n;
}

int lssd_auth_check_creds(const lssd_auth *a, sd_bus_creds *creds, sd_bus_message *m, sd_bus_error *error) {
        gid_t *gids = NULL;
        uid_t euid;
        int r, n = 0;

        /* EUID comes from the bus (SO_PEERCRED at connect time); refuse it if
         * sd-bus had to read it from /proc instead */
        if (sd_bus_creds_get_augmented_mask(creds) & SD_BUS_CREDS_EUID)
                return sd_bus_error_set(error, SD_BUS_ERROR_ACCESS_DENIED,
                                        "The bus did not vouch for the caller's user ID");
        r = sd_bus_creds_get_euid(creds, &euid);
        if (r < 0)
                return r;

        if (lssd_auth_allowed(a, euid, NULL, 0))
                return 0;

        if (a->have_gid && m) {
                n = sender_groups(m, &gids);
                if (n > 0 && lssd_auth_allowed(a, euid, gids, (size_t) n)) {
                        free(gids);
                        return 0;
                }
                free(gids);
        }

        return sd_bus_error_setf(error, SD_BUS_ERROR_ACCESS_DENIED,
                                 "Sending LSS frames needs root or membership in group '%s' (caller's UID %u)",
                                 LSSD_GROUP, (unsigned) euid);
}

int lssd_auth_check(const lssd_auth *a, sd_bus_message *m, sd_bus_error *error) {
        sd_bus_creds *creds = NULL;
        int r;

        r = sd_bus_query_sender_creds(m, SD_BUS_CREDS_EUID, &creds);
        if (r < 0)
                return r;
        r = lssd_auth_check_creds(a, creds, m, error);
        sd_bus_creds_unref(creds);
        return r;
}
