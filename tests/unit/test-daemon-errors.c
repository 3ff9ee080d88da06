/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* lssd's one error map: names, errno mapping, engine results to bus errors. */
#include <check.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_errors.h"

static const char *const contract_names[] = {
        "org.lssd.LSS1.Error.NoResponse", "org.lssd.LSS1.Error.Rejected", "org.lssd.LSS1.Error.Busy",
        "org.lssd.LSS1.Error.BusDown",    "org.lssd.LSS1.Error.BusOff",   "org.lssd.LSS1.Error.NotFound",
        "org.lssd.LSS1.Error.Conflict",   "org.lssd.LSS1.Error.Cancelled", "org.lssd.LSS1.Error.NotSupported",
        "org.lssd.LSS1.Error.LimitsExceeded", "org.lssd.LSS1.Error.PermissionDenied",
        "org.lssd.LSS1.Error.NotHeld", "org.lssd.LSS1.Error.ForeignMaster",
};

/* Every name of the v1 contract is in the map, once, with its own errno. */
START_TEST(map_complete) {
        size_t n = 0;
        for (const sd_bus_error_map *m = lssd_error_map; m->name; m++, n++) {
                ck_assert_msg(strncmp(m->name, LSSD_ERROR_PREFIX, strlen(LSSD_ERROR_PREFIX)) == 0, "%s", m->name);
                ck_assert_int_gt(m->code, 0);
                for (const sd_bus_error_map *o = lssd_error_map; o != m; o++) {
                        ck_assert_str_ne(o->name, m->name);
                        ck_assert_int_ne(o->code, m->code);
                }
        }
        ck_assert_uint_eq(n, sizeof(contract_names) / sizeof(contract_names[0]));
        for (size_t i = 0; i < n; i++) {
                bool found = false;
                for (const sd_bus_error_map *m = lssd_error_map; m->name; m++)
                        found = found || strcmp(m->name, contract_names[i]) == 0;
                ck_assert_msg(found, "%s missing", contract_names[i]);
        }
}
END_TEST

/* With the map added, a client gets errno values back from the names. */
START_TEST(map_round_trip) {
        ck_assert_int_ge(sd_bus_error_add_map(lssd_error_map), 0);
        for (const sd_bus_error_map *m = lssd_error_map; m->name; m++) {
                sd_bus_error e = SD_BUS_ERROR_NULL;
                int r = sd_bus_error_set(&e, m->name, "x");
                ck_assert_int_eq(r, -m->code);
                ck_assert_int_eq(sd_bus_error_get_errno(&e), m->code);
                sd_bus_error_free(&e);
        }
}
END_TEST

START_TEST(status_names) {
        ck_assert_ptr_null(lssd_status_to_error_name(LSS_OK));
        ck_assert_str_eq(lssd_status_to_result(LSS_OK), "done");
        for (int s = LSS_E_NO_RESPONSE; s <= LSS_E_FOREIGN_MASTER; s++) {
                const char *name = lssd_status_to_error_name((enum lss_status) s);
                ck_assert_ptr_nonnull(name);
                ck_assert_ptr_nonnull(lssd_status_to_result((enum lss_status) s));
                ck_assert_str_ne(lssd_status_to_result((enum lss_status) s), "done");
        }
        ck_assert_str_eq(lssd_status_to_error_name(LSS_E_NO_RESPONSE), LSSD_ERROR_NO_RESPONSE);
        ck_assert_str_eq(lssd_status_to_error_name(LSS_E_REJECTED), LSSD_ERROR_REJECTED);
        ck_assert_str_eq(lssd_status_to_error_name(LSS_E_CONFLICT), LSSD_ERROR_CONFLICT);
        ck_assert_str_eq(lssd_status_to_error_name(LSS_E_NOT_FOUND), LSSD_ERROR_NOT_FOUND);
        ck_assert_str_eq(lssd_status_to_error_name(LSS_E_BUS_DOWN), LSSD_ERROR_BUS_DOWN);
        ck_assert_str_eq(lssd_status_to_error_name(LSS_E_BUS_OFF), LSSD_ERROR_BUS_OFF);
        ck_assert_str_eq(lssd_status_to_error_name(LSS_E_CANCELLED), LSSD_ERROR_CANCELLED);
        ck_assert_str_eq(lssd_status_to_error_name(LSS_E_INVALID), SD_BUS_ERROR_INVALID_ARGS);
        ck_assert_str_eq(lssd_status_to_result(LSS_E_CANCELLED), "cancelled");
        ck_assert_str_eq(lssd_status_to_error_name(LSS_E_FOREIGN_MASTER), LSSD_ERROR_FOREIGN_MASTER);
        ck_assert_str_eq(lssd_status_to_result(LSS_E_FOREIGN_MASTER), "foreign-master");
        /* out of range: still a name, never NULL */
        ck_assert_ptr_nonnull(lssd_status_to_error_name((enum lss_status) 1000));
        ck_assert_ptr_nonnull(lssd_status_to_result((enum lss_status) 1000));
}
END_TEST

START_TEST(rejected_message) {
        sd_bus_error e = SD_BUS_ERROR_NULL;
        lss_result r = { .status = LSS_E_REJECTED, .err = 1, .spec = 0 };
        strcpy(r.message, "Configure Node-ID rejected by the slave: error 1, spec 0");

        lssd_error_from_result(&e, &r, LSS_SERVICE_CONFIGURE_NODE_ID, NULL);
        ck_assert_str_eq(e.name, LSSD_ERROR_REJECTED);
        ck_assert_str_eq(e.message,
                         "Configure Node-ID rejected by the slave: error 1 (node-ID out of range), spec 0");
        sd_bus_error_free(&e);

        r.err = 2;
        lssd_error_from_result(&e, &r, LSS_SERVICE_STORE, "steps[3] (StoreConfiguration): ");
        ck_assert_str_eq(e.message, "steps[3] (StoreConfiguration): Store Configuration rejected by the slave: "
                                    "error 2 (storage media access error), spec 0");
        sd_bus_error_free(&e);

        r.err = 255;
        r.spec = 0x42;
        lssd_error_from_result(&e, &r, LSS_SERVICE_CONFIGURE_BIT_TIMING, NULL);
        ck_assert_str_eq(e.message,
                         "Configure Bit Timing rejected by the slave: error 255 (manufacturer-specific), spec 66");
        sd_bus_error_free(&e);

        ck_assert_str_eq(lssd_lss_error_meaning(LSS_SERVICE_CONFIGURE_BIT_TIMING, 1), "bit rate not supported");
        ck_assert_str_eq(lssd_lss_error_meaning(LSS_SERVICE_STORE, 1), "store not supported");
        ck_assert_str_eq(lssd_lss_error_meaning(LSS_SERVICE_CONFIGURE_NODE_ID, 7), "reserved");
        ck_assert_str_eq(lssd_lss_error_meaning(LSS_SERVICE_NONE, 7), "reserved");
}
END_TEST

/* Which service a rejection is about comes from the engine's code
 * (lss_result.failed_service), never from its message: a store refusal
 * gets the store meanings whatever the text says, and a service that
 * answers without error codes keeps the engine's message. */
START_TEST(rejected_by_code) {
        sd_bus_error e = SD_BUS_ERROR_NULL;
        lss_result r = { .status = LSS_E_REJECTED, .err = 2, .failed_service = LSS_SERVICE_STORE,
                         .reason = LSS_REASON_REFUSED };
        strcpy(r.message, "Configure Node-ID 5 went fine, then the slave refused");
        lssd_error_from_result(&e, &r, r.failed_service, NULL);
        ck_assert_str_eq(e.name, LSSD_ERROR_REJECTED);
        ck_assert_str_eq(e.message, "Store Configuration rejected by the slave: error 2 (storage media access error), "
                                    "spec 0");
        sd_bus_error_free(&e);

        r.failed_service = LSS_SERVICE_CONFIGURE_NODE_ID;
        r.err = 1;
        strcpy(r.message, "Store Configuration: anything");
        lssd_error_from_result(&e, &r, r.failed_service, NULL);
        ck_assert_str_eq(e.message, "Configure Node-ID rejected by the slave: error 1 (node-ID out of range), spec 0");
        sd_bus_error_free(&e);

        r.failed_service = LSS_SERVICE_SWITCH_SELECTIVE;
        lssd_error_from_result(&e, &r, r.failed_service, NULL);
        ck_assert_str_eq(e.message, "Store Configuration: anything");
        sd_bus_error_free(&e);
}
END_TEST

START_TEST(other_results) {
        sd_bus_error e = SD_BUS_ERROR_NULL;
        lss_result r = { .status = LSS_E_NO_RESPONSE };
        strcpy(r.message, "no answer to Configure Node-ID 5");
        int k = lssd_error_from_result(&e, &r, LSS_SERVICE_CONFIGURE_NODE_ID, "Scan: ");
        ck_assert_int_lt(k, 0);
        ck_assert_str_eq(e.name, LSSD_ERROR_NO_RESPONSE);
        ck_assert_str_eq(e.message, "Scan: no answer to Configure Node-ID 5");
        sd_bus_error_free(&e);

        /* no engine message: the short result word */
        r = (lss_result) { .status = LSS_E_CANCELLED };
        lssd_error_from_result(&e, &r, LSS_SERVICE_NONE, NULL);
        ck_assert_str_eq(e.name, LSSD_ERROR_CANCELLED);
        ck_assert_str_eq(e.message, "cancelled");
        sd_bus_error_free(&e);

        /* a rejection without a known service keeps the engine's text */
        r = (lss_result) { .status = LSS_E_REJECTED, .err = 1 };
        strcpy(r.message, "something rejected");
        lssd_error_from_result(&e, &r, LSS_SERVICE_NONE, NULL);
        ck_assert_str_eq(e.name, LSSD_ERROR_REJECTED);
        ck_assert_str_eq(e.message, "something rejected");
        sd_bus_error_free(&e);
}
END_TEST

static Suite *suite(void) {
        Suite *s = suite_create("daemon-errors");
        TCase *tc = tcase_create("core");
        tcase_add_test(tc, map_complete);
        tcase_add_test(tc, map_round_trip);
        tcase_add_test(tc, status_names);
        tcase_add_test(tc, rejected_message);
        tcase_add_test(tc, rejected_by_code);
        tcase_add_test(tc, other_results);
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
