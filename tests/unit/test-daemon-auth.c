/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The authorization decision: who may send, and that an EUID sd-bus read
 * from /proc (augmented) is refused even when it names root. */
#include <check.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "daemon/lssd_auth.h"

/* Allows exactly the test's own EUID (root or not), so that only the
 * source of the credentials can make the check refuse. */
static lssd_auth auth_for_self(void) {
        return (lssd_auth) { .have_uid = true, .uid = geteuid() };
}

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

/* sd_bus_creds_new_from_pid() reads everything from /proc: the EUID is
 * augmented. It is our own (root when the tests run as root), one that
 * lssd_auth_allowed() accepts, and still the check refuses it. */
START_TEST(augmented_euid_refused) {
        lssd_auth a = auth_for_self();
        sd_bus_creds *creds = NULL;
        sd_bus_error error = SD_BUS_ERROR_NULL;
        uid_t euid = (uid_t) -1;

        ck_assert_int_ge(sd_bus_creds_new_from_pid(&creds, 0, SD_BUS_CREDS_EUID), 0);
        ck_assert(sd_bus_creds_get_augmented_mask(creds) & SD_BUS_CREDS_EUID);
        ck_assert_int_eq(sd_bus_creds_get_euid(creds, &euid), 0);
        ck_assert_uint_eq(euid, geteuid());
        ck_assert(lssd_auth_allowed(&a, euid, NULL, 0));
        if (euid == 0) {
                lssd_auth none = { 0 };
                ck_assert(lssd_auth_allowed(&none, euid, NULL, 0));
                ck_assert_int_eq(lssd_auth_check_creds(&none, creds, NULL, &error), -EACCES);
                ck_assert(sd_bus_error_has_name(&error, SD_BUS_ERROR_ACCESS_DENIED));
                sd_bus_error_free(&error);
        }

        ck_assert_int_eq(lssd_auth_check_creds(&a, creds, NULL, &error), -EACCES);
        ck_assert(sd_bus_error_has_name(&error, SD_BUS_ERROR_ACCESS_DENIED));
        ck_assert_int_eq(sd_bus_error_get_errno(&error), EACCES);

        sd_bus_error_free(&error);
        sd_bus_creds_unref(creds);
}
END_TEST

/* The control: the same EUID vouched for by the peer socket (SO_PEERCRED on
 * a direct connection, nothing read from /proc) passes. */
START_TEST(vouched_euid_allowed) {
        lssd_auth a = auth_for_self(), none = { 0 };
        sd_bus *server = NULL, *client = NULL;
        sd_bus_creds *creds = NULL;
        sd_bus_error error = SD_BUS_ERROR_NULL;
        sd_id128_t id;
        uid_t euid = (uid_t) -1;
        int fds[2];

        ck_assert_int_eq(socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0, fds), 0);
        ck_assert_int_ge(sd_id128_randomize(&id), 0);
        ck_assert_int_ge(sd_bus_new(&server), 0);
        ck_assert_int_ge(sd_bus_set_fd(server, fds[0], fds[0]), 0);
        ck_assert_int_ge(sd_bus_set_server(server, 1, id), 0);
        ck_assert_int_ge(sd_bus_start(server), 0);
        ck_assert_int_ge(sd_bus_new(&client), 0);
        ck_assert_int_ge(sd_bus_set_fd(client, fds[1], fds[1]), 0);
        ck_assert_int_ge(sd_bus_start(client), 0);

        ck_assert_int_ge(sd_bus_get_owner_creds(client, SD_BUS_CREDS_EUID, &creds), 0);
        ck_assert_uint_eq(sd_bus_creds_get_augmented_mask(creds), 0);
        ck_assert_int_eq(sd_bus_creds_get_euid(creds, &euid), 0);
        ck_assert_uint_eq(euid, geteuid());

        ck_assert_int_eq(lssd_auth_check_creds(&a, creds, NULL, &error), 0);
        ck_assert(!sd_bus_error_is_set(&error));

        /* nobody but root without user/group lssd */
        if (euid == 0)
                ck_assert_int_eq(lssd_auth_check_creds(&none, creds, NULL, &error), 0);
        else {
                ck_assert_int_eq(lssd_auth_check_creds(&none, creds, NULL, &error), -EACCES);
                ck_assert(sd_bus_error_has_name(&error, SD_BUS_ERROR_ACCESS_DENIED));
        }

        sd_bus_error_free(&error);
        sd_bus_creds_unref(creds);
        /* no flush: the handshake never ran, so a flush would wait for it */
        sd_bus_close_unref(client);
        sd_bus_close_unref(server);
}
END_TEST

/* Credentials without an EUID are an error, not a decision. */
START_TEST(missing_euid) {
        lssd_auth a = auth_for_self();
        sd_bus_creds *creds = NULL;
        sd_bus_error error = SD_BUS_ERROR_NULL;

        ck_assert_int_ge(sd_bus_creds_new_from_pid(&creds, 0, SD_BUS_CREDS_PID), 0);
        ck_assert(!(sd_bus_creds_get_mask(creds) & SD_BUS_CREDS_EUID));
        ck_assert_int_eq(lssd_auth_check_creds(&a, creds, NULL, &error), -ENODATA);
        ck_assert(!sd_bus_error_is_set(&error));

        sd_bus_creds_unref(creds);
}
END_TEST

static Suite *suite(void) {
        Suite *s = suite_create("daemon-auth");
        TCase *tc = tcase_create("core");
        tcase_add_test(tc, allowed_root);
        tcase_add_test(tc, allowed_other_uid);
        tcase_add_test(tc, allowed_user_lssd);
        tcase_add_test(tc, allowed_group_member);
        tcase_add_test(tc, augmented_euid_refused);
        tcase_add_test(tc, vouched_euid_allowed);
        tcase_add_test(tc, missing_euid);
        suite_add_tcase(s, tc);
        return s;
}

int main(void) {
        SRunner *sr = srunner_create(suite());
        srunner_run_all(sr, CK_NORMAL);
        int failed = srunner_ntests_failed(sr);
        srunner_free(sr);
        return failed == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
