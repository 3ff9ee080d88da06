/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Helpers for the daemon unit tests: sd-bus messages without a bus daemon. */
#pragma once

#include <check.h>
#include <sys/socket.h>
#include <systemd/sd-bus.h>
#include <unistd.h>

#include "names/lssd_names.h"

/* An sd_bus on one end of a socketpair: enough to build and read messages. */
static inline sd_bus *test_bus_new(void) {
        sd_bus *bus = NULL;
        int sp[2];
        ck_assert_int_eq(socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sp), 0);
        ck_assert_int_ge(sd_bus_new(&bus), 0);
        ck_assert_int_ge(sd_bus_set_fd(bus, sp[0], sp[0]), 0);
        ck_assert_int_ge(sd_bus_start(bus), 0);
        close(sp[1]);
        return bus;
}

static inline void test_bus_free(sd_bus *bus) {
        sd_bus_close_unref(bus);
}

/* A method call with `types`/args appended, sealed and rewound for reading. */
#define test_message(bus, m, types, ...)                                                                         \
        do {                                                                                                     \
                ck_assert_int_ge(sd_bus_message_new_method_call((bus), &(m), LSSD_BUS_NAME,                       \
                                                                LSSD_BUSES_PATH "/can0", LSSD_BUS_IFACE,          \
                                                                "Test"),                                         \
                                 0);                                                                             \
                ck_assert_int_ge(sd_bus_message_append((m), (types), __VA_ARGS__), 0);                          \
                ck_assert_int_ge(sd_bus_message_seal((m), 1, 0), 0);                                             \
                ck_assert_int_ge(sd_bus_message_rewind((m), 1), 0);                                              \
        } while (0)

/* main() of a unit test: runs the suite, exit status for meson. */
static inline int test_run_suite(Suite *s) {
        SRunner *sr = srunner_create(s);
        srunner_run_all(sr, CK_NORMAL);
        int failed = srunner_ntests_failed(sr);
        srunner_free(sr);
        return failed == 0 ? 0 : 1;
}
