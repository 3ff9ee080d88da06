/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* D-Bus argument checking of lssd: validation, a{sv} options, Execute steps. */
#include <check.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "daemon-util.h"
#include "daemon/lssd_errors.h"
#include "daemon/lssd_options.h"
#include "daemon/lssd_raw.h"
#include "daemon/lssd_validate.h"

#define ck_assert_invalid_args(e) ck_assert_str_eq((e)->name, SD_BUS_ERROR_INVALID_ARGS)
#define ck_assert_message_has(e, s)                                                                 \
        ck_assert_msg(strstr((e)->message, (s)) != NULL, "'%s' not in message '%s'", (s), (e)->message)

START_TEST(validate_node_id) {
        sd_bus_error e = SD_BUS_ERROR_NULL;
        ck_assert_int_eq(lssd_validate_node_id("node_id", 1, &e), 0);
        ck_assert_int_eq(lssd_validate_node_id("node_id", 127, &e), 0);
        ck_assert(!sd_bus_error_is_set(&e));

        ck_assert_int_eq(lssd_validate_node_id("node_id", 0, &e), -EINVAL);
        ck_assert_invalid_args(&e);
        ck_assert_message_has(&e, "node_id 0");
        sd_bus_error_free(&e);

        ck_assert_int_lt(lssd_validate_node_id("node_id", 128, &e), 0);
        ck_assert_message_has(&e, "128");
        sd_bus_error_free(&e);

        /* 0xFF unconfigures: only the raw service may send it */
        ck_assert_int_lt(lssd_validate_node_id("node_id", 255, &e), 0);
        sd_bus_error_free(&e);
        ck_assert_int_eq(lssd_validate_raw_node_id("node_id", 255, &e), 0);
        ck_assert_int_eq(lssd_validate_raw_node_id("node_id", 64, &e), 0);
        ck_assert_int_lt(lssd_validate_raw_node_id("node_id", 0, &e), 0);
        ck_assert_message_has(&e, "node_id 0");
        sd_bus_error_free(&e);
        ck_assert_int_lt(lssd_validate_raw_node_id("node_id", 200, &e), 0);
        ck_assert_message_has(&e, "200");
        sd_bus_error_free(&e);
}
END_TEST

START_TEST(validate_bit_timing) {
        sd_bus_error e = SD_BUS_ERROR_NULL;
        for (unsigned i = 0; i <= 9; i++)
                ck_assert_int_eq(lssd_validate_bit_timing(0, (uint8_t) i, &e), 0);
        ck_assert_int_eq(lssd_validate_bit_timing(128, 0, &e), 0);
        ck_assert_int_eq(lssd_validate_bit_timing(255, 255, &e), 0);
        ck_assert(!sd_bus_error_is_set(&e));

        ck_assert_int_lt(lssd_validate_bit_timing(0, 10, &e), 0);
        ck_assert_invalid_args(&e);
        ck_assert_message_has(&e, "index 10");
        sd_bus_error_free(&e);

        ck_assert_int_lt(lssd_validate_bit_timing(1, 0, &e), 0);
        ck_assert_message_has(&e, "table 1");
        sd_bus_error_free(&e);
        ck_assert_int_lt(lssd_validate_bit_timing(127, 0, &e), 0);
        ck_assert_message_has(&e, "table 127");
        sd_bus_error_free(&e);
}
END_TEST

START_TEST(validate_misc) {
        sd_bus_error e = SD_BUS_ERROR_NULL;
        ck_assert_int_eq(lssd_validate_bitrate("bitrate", 250000, &e), 0);
        ck_assert_int_eq(lssd_validate_bitrate("bitrate", 1000000, &e), 0);
        ck_assert_int_lt(lssd_validate_bitrate("bitrate", 0, &e), 0);
        ck_assert_message_has(&e, "bitrate 0");
        sd_bus_error_free(&e);
        ck_assert_int_lt(lssd_validate_bitrate("bitrate", 250001, &e), 0);
        ck_assert_message_has(&e, "250001");
        sd_bus_error_free(&e);

        ck_assert_int_eq(lssd_validate_mode("mode", 0, &e), 0);
        ck_assert_int_eq(lssd_validate_mode("mode", 1, &e), 0);
        ck_assert_int_lt(lssd_validate_mode("mode", 2, &e), 0);
        ck_assert_message_has(&e, "mode 2");
        sd_bus_error_free(&e);

        ck_assert_int_eq(lssd_validate_range("rev_lo", 5, "rev_hi", 5, &e), 0);
        ck_assert_int_lt(lssd_validate_range("rev_lo", 6, "rev_hi", 5, &e), 0);
        ck_assert_message_has(&e, "rev_lo 0x00000006");
        sd_bus_error_free(&e);

        ck_assert_int_eq(lssd_validate_ifname("interface", "can0", &e), 0);
        ck_assert_int_eq(lssd_validate_ifname("interface", "vcan-1.2", &e), 0);
        const char *bad[] = { "", "a/b", "a:b", "a b", ".", "..", "0123456789abcdef", "tab\t" };
        for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
                ck_assert_int_lt(lssd_validate_ifname("interface", bad[i], &e), 0);
                ck_assert_invalid_args(&e);
                ck_assert_message_has(&e, "interface");
                sd_bus_error_free(&e);
        }
        /* a long name is quoted shortened, never whole */
        char longname[200];
        memset(longname, 'x', sizeof(longname) - 1);
        longname[sizeof(longname) - 1] = 0;
        ck_assert_int_lt(lssd_validate_ifname("interface", longname, &e), 0);
        ck_assert_message_has(&e, "...");
        ck_assert_uint_lt(strlen(e.message), 150);
        sd_bus_error_free(&e);
}
END_TEST

START_TEST(options_scan) {
        sd_bus *bus = test_bus_new();
        sd_bus_message *m = NULL;
        sd_bus_error e = SD_BUS_ERROR_NULL;
        lssd_scan_options o;

        test_message(bus, m, "a{sv}", 0);
        ck_assert_int_eq(lssd_scan_options_read(m, &o, &e), 0);
        ck_assert(!o.has_vendor && !o.has_product);
        ck_assert(o.sdo); /* SDO discovery unless turned off */
        m = sd_bus_message_unref(m);

        test_message(bus, m, "a{sv}", 1, LSSD_SCAN_OPTION_SDO, "b", 0);
        ck_assert_int_eq(lssd_scan_options_read(m, &o, &e), 0);
        ck_assert(!o.sdo);
        m = sd_bus_message_unref(m);

        /* sdo is a b */
        test_message(bus, m, "a{sv}", 1, LSSD_SCAN_OPTION_SDO, "u", 0u);
        ck_assert_int_lt(lssd_scan_options_read(m, &o, &e), 0);
        ck_assert_invalid_args(&e);
        ck_assert_message_has(&e, "'b', not 'u'");
        sd_bus_error_free(&e);
        m = sd_bus_message_unref(m);

        test_message(bus, m, "a{sv}", 2, "vendor", "u", 0xECu, "product", "u", 0x1234u);
        ck_assert_int_eq(lssd_scan_options_read(m, &o, &e), 0);
        ck_assert(o.has_vendor && o.has_product);
        ck_assert_uint_eq(o.vendor, 0xEC);
        ck_assert_uint_eq(o.product, 0x1234);
        m = sd_bus_message_unref(m);

        /* half a pair is refused */
        test_message(bus, m, "a{sv}", 1, "vendor", "u", 0xECu);
        ck_assert_int_lt(lssd_scan_options_read(m, &o, &e), 0);
        ck_assert_invalid_args(&e);
        ck_assert_message_has(&e, "'vendor'");
        sd_bus_error_free(&e);
        m = sd_bus_message_unref(m);

        /* unknown key */
        test_message(bus, m, "a{sv}", 1, "vendr", "u", 1u);
        ck_assert_int_lt(lssd_scan_options_read(m, &o, &e), 0);
        ck_assert_invalid_args(&e);
        ck_assert_message_has(&e, "Unknown option 'vendr' in argument 'options'");
        sd_bus_error_free(&e);
        m = sd_bus_message_unref(m);

        /* wrong variant type */
        test_message(bus, m, "a{sv}", 2, "vendor", "s", "0xEC", "product", "u", 1u);
        ck_assert_int_lt(lssd_scan_options_read(m, &o, &e), 0);
        ck_assert_invalid_args(&e);
        ck_assert_message_has(&e, "'vendor'");
        ck_assert_message_has(&e, "'u', not 's'");
        sd_bus_error_free(&e);
        m = sd_bus_message_unref(m);

        /* a key twice */
        test_message(bus, m, "a{sv}", 3, "vendor", "u", 1u, "product", "u", 1u, "vendor", "u", 2u);
        ck_assert_int_lt(lssd_scan_options_read(m, &o, &e), 0);
        ck_assert_message_has(&e, "given twice");
        sd_bus_error_free(&e);
        m = sd_bus_message_unref(m);

        test_bus_free(bus);
}
END_TEST

START_TEST(options_assign) {
        sd_bus *bus = test_bus_new();
        sd_bus_message *m = NULL;
        sd_bus_error e = SD_BUS_ERROR_NULL;
        lssd_assign_options o;

        test_message(bus, m, "a{sv}", 0);
        ck_assert_int_eq(lssd_assign_options_read(m, &o, &e), 0);
        ck_assert(o.store);  /* default true */
        ck_assert(o.verify); /* default true */
        m = sd_bus_message_unref(m);

        test_message(bus, m, "a{sv}", 2, "store", "b", 0, "verify", "b", 0);
        ck_assert_int_eq(lssd_assign_options_read(m, &o, &e), 0);
        ck_assert(!o.store);
        ck_assert(!o.verify);
        m = sd_bus_message_unref(m);

        test_message(bus, m, "a{sv}", 1, "store", "u", 1u);
        ck_assert_int_lt(lssd_assign_options_read(m, &o, &e), 0);
        ck_assert_invalid_args(&e);
        ck_assert_message_has(&e, "'store'");
        sd_bus_error_free(&e);
        m = sd_bus_message_unref(m);

        /* methods without options refuse any */
        test_message(bus, m, "a{sv}", 1, "store", "b", 1);
        ck_assert_int_lt(lssd_no_options_read(m, &e), 0);
        ck_assert_message_has(&e, "Unknown option 'store'");
        sd_bus_error_free(&e);
        m = sd_bus_message_unref(m);

        test_bus_free(bus);
}
END_TEST

START_TEST(raw_args) {
        sd_bus *bus = test_bus_new();
        sd_bus_message *m = NULL;
        sd_bus_error e = SD_BUS_ERROR_NULL;
        lssd_raw_step s;

        ck_assert_int_eq(lssd_raw_op_from_string("ConfigureNodeId"), LSSD_RAW_CONFIGURE_NODE_ID);
        ck_assert_int_eq(lssd_raw_op_from_string("configurenodeid"), -EINVAL);
        ck_assert_int_eq(lssd_raw_op_from_string(NULL), -EINVAL);
        for (int i = 0; i < _LSSD_RAW_OP_MAX; i++)
                ck_assert_int_eq(lssd_raw_op_from_string(lssd_raw_op_to_string((lssd_raw_op) i)), i);

        test_message(bus, m, "y", (uint8_t) 255);
        ck_assert_int_eq(lssd_raw_step_read_args(m, LSSD_RAW_CONFIGURE_NODE_ID, &s, &e), 0);
        ck_assert_uint_eq(s.node_id, 255);
        m = sd_bus_message_unref(m);

        test_message(bus, m, "y", (uint8_t) 128);
        ck_assert_int_lt(lssd_raw_step_read_args(m, LSSD_RAW_CONFIGURE_NODE_ID, &s, &e), 0);
        ck_assert_invalid_args(&e);
        ck_assert_message_has(&e, "node_id 128");
        sd_bus_error_free(&e);
        m = sd_bus_message_unref(m);

        test_message(bus, m, "uuuuuu", 1u, 2u, 10u, 3u, 0u, 5u);
        ck_assert_int_lt(lssd_raw_step_read_args(m, LSSD_RAW_IDENTIFY_REMOTE_SLAVES, &s, &e), 0);
        ck_assert_message_has(&e, "rev_lo");
        sd_bus_error_free(&e);
        m = sd_bus_message_unref(m);

        test_message(bus, m, "a{sv}", 2, "vendor", "u", 0xECu, "serial", "u", 0x80000001u);
        ck_assert_int_eq(lssd_raw_step_read_args(m, LSSD_RAW_FASTSCAN, &s, &e), 0);
        ck_assert_uint_eq(s.known.known_bits[LSS_FIELD_VENDOR], 32);
        ck_assert_uint_eq(s.known.known_bits[LSS_FIELD_PRODUCT], 0);
        ck_assert_uint_eq(s.known.known_bits[LSS_FIELD_SERIAL], 32);
        ck_assert_uint_eq(s.known.value.serial, 0x80000001u);
        m = sd_bus_message_unref(m);

        test_message(bus, m, "a{sv}", 1, "node_id", "y", (uint8_t) 1);
        ck_assert_int_lt(lssd_raw_step_read_args(m, LSSD_RAW_FASTSCAN, &s, &e), 0);
        ck_assert_message_has(&e, "Unknown option 'node_id' in argument 'known'");
        sd_bus_error_free(&e);
        m = sd_bus_message_unref(m);

        test_bus_free(bus);
}
END_TEST

START_TEST(execute_steps) {
        sd_bus *bus = test_bus_new();
        sd_bus_message *m = NULL;
        sd_bus_error e = SD_BUS_ERROR_NULL;
        lssd_raw_step *steps = NULL;
        size_t n = 0;

        test_message(bus, m, "a(sv)", 5, "SwitchModeSelective", "(uuuu)", 1u, 2u, 3u, 4u, "ConfigureNodeId", "y",
                     (uint8_t) 5, "StoreConfiguration", "b", 1, "ConfigureBitTiming", "(yy)", (uint8_t) 0,
                     (uint8_t) 3, "Fastscan", "a{sv}", 1, "product", "u", 7u);
        ck_assert_int_eq(lssd_execute_steps_read(m, &steps, &n, &e), 0);
        ck_assert_uint_eq(n, 5);
        ck_assert_int_eq(steps[0].op, LSSD_RAW_SWITCH_MODE_SELECTIVE);
        ck_assert_uint_eq(steps[0].id.serial, 4);
        ck_assert_int_eq(steps[1].op, LSSD_RAW_CONFIGURE_NODE_ID);
        ck_assert_uint_eq(steps[1].node_id, 5);
        ck_assert_int_eq(steps[2].op, LSSD_RAW_STORE_CONFIGURATION);
        ck_assert_uint_eq(steps[3].bit_timing.index, 3);
        ck_assert_uint_eq(steps[4].known.value.product, 7);
        ck_assert_uint_eq(steps[4].known.known_bits[LSS_FIELD_PRODUCT], 32);
        free(steps);
        steps = NULL;
        m = sd_bus_message_unref(m);

        /* unknown step */
        test_message(bus, m, "a(sv)", 2, "InquireNodeId", "b", 1, "Reboot", "b", 1);
        ck_assert_int_lt(lssd_execute_steps_read(m, &steps, &n, &e), 0);
        ck_assert_invalid_args(&e);
        ck_assert_message_has(&e, "steps[1]");
        ck_assert_message_has(&e, "'Reboot'");
        sd_bus_error_free(&e);
        ck_assert_ptr_null(steps);
        m = sd_bus_message_unref(m);

        /* several arguments need a struct */
        test_message(bus, m, "a(sv)", 1, "SwitchModeSelective", "u", 1u);
        ck_assert_int_lt(lssd_execute_steps_read(m, &steps, &n, &e), 0);
        ck_assert_invalid_args(&e);
        ck_assert_message_has(&e, "steps[0] (SwitchModeSelective)");
        ck_assert_message_has(&e, "'(uuuu)', not 'u'");
        sd_bus_error_free(&e);
        m = sd_bus_message_unref(m);

        /* a bad value inside names the step and the argument */
        test_message(bus, m, "a(sv)", 2, "SwitchModeGlobal", "y", (uint8_t) 1, "ConfigureNodeId", "y", (uint8_t) 0);
        ck_assert_int_lt(lssd_execute_steps_read(m, &steps, &n, &e), 0);
        ck_assert_invalid_args(&e);
        ck_assert_message_has(&e, "steps[1] (ConfigureNodeId): Invalid node_id 0");
        sd_bus_error_free(&e);
        m = sd_bus_message_unref(m);

        test_message(bus, m, "a(sv)", 1, "ConfigureBitTiming", "(yy)", (uint8_t) 0, (uint8_t) 12);
        ck_assert_int_lt(lssd_execute_steps_read(m, &steps, &n, &e), 0);
        ck_assert_message_has(&e, "steps[0] (ConfigureBitTiming): Invalid index 12");
        sd_bus_error_free(&e);
        m = sd_bus_message_unref(m);

        test_message(bus, m, "a(sv)", 1, "Fastscan", "a{sv}", 1, "vendor", "s", "x");
        ck_assert_int_lt(lssd_execute_steps_read(m, &steps, &n, &e), 0);
        ck_assert_message_has(&e, "steps[0] (Fastscan)");
        ck_assert_message_has(&e, "argument 'steps[0]'");
        sd_bus_error_free(&e);
        m = sd_bus_message_unref(m);

        test_bus_free(bus);
}
END_TEST

START_TEST(execute_limit) {
        sd_bus *bus = test_bus_new();
        sd_bus_message *m = NULL;
        sd_bus_error e = SD_BUS_ERROR_NULL;
        lssd_raw_step *steps = NULL;
        size_t n = 0;

        for (unsigned count = LSSD_EXECUTE_STEPS_MAX; count <= LSSD_EXECUTE_STEPS_MAX + 1; count++) {
                ck_assert_int_ge(sd_bus_message_new_method_call(bus, &m, LSSD_BUS_NAME, "/x", LSSD_BUS_IFACE,
                                                                "Execute"),
                                 0);
                ck_assert_int_ge(sd_bus_message_open_container(m, 'a', "(sv)"), 0);
                for (unsigned i = 0; i < count; i++)
                        ck_assert_int_ge(sd_bus_message_append(m, "(sv)", "InquireNodeId", "b", 1), 0);
                ck_assert_int_ge(sd_bus_message_close_container(m), 0);
                ck_assert_int_ge(sd_bus_message_seal(m, 1, 0), 0);
                ck_assert_int_ge(sd_bus_message_rewind(m, 1), 0);

                int r = lssd_execute_steps_read(m, &steps, &n, &e);
                if (count <= LSSD_EXECUTE_STEPS_MAX) {
                        ck_assert_int_eq(r, 0);
                        ck_assert_uint_eq(n, count);
                        free(steps);
                        steps = NULL;
                } else {
                        ck_assert_int_lt(r, 0);
                        ck_assert_str_eq(e.name, LSSD_ERROR_LIMITS_EXCEEDED);
                        sd_bus_error_free(&e);
                }
                m = sd_bus_message_unref(m);
        }
        test_bus_free(bus);
}
END_TEST

/* Results as they go back: plain values for the methods, variants for Execute. */
START_TEST(raw_results) {
        sd_bus *bus = test_bus_new();
        sd_bus_message *m = NULL;
        lss_result r = { .status = LSS_E_NO_RESPONSE };
        lssd_raw_step sel = { .op = LSSD_RAW_SWITCH_MODE_SELECTIVE };
        lssd_raw_step store = { .op = LSSD_RAW_STORE_CONFIGURATION };
        lssd_raw_step inq = { .op = LSSD_RAW_INQUIRE_IDENTITY };
        int found;

        /* nobody answering a selective switch is the answer false */
        ck_assert(lssd_raw_step_succeeded(&sel, &r));
        ck_assert(!lssd_raw_step_succeeded(&store, &r));
        ck_assert(!lssd_raw_step_succeeded(&inq, &r));

        ck_assert_int_ge(sd_bus_message_new_method_call(bus, &m, "a.b", "/x", "a.b", "M"), 0);
        ck_assert_int_ge(lssd_raw_step_append_result(&sel, &r, m, false), 0);
        ck_assert_int_ge(lssd_raw_step_append_result(&store, &r, m, false), 0); /* nothing */
        ck_assert_int_ge(sd_bus_message_open_container(m, 'a', "v"), 0);
        ck_assert_int_ge(lssd_raw_step_append_result(&store, &r, m, true), 0); /* b true */
        r = (lss_result) { .status = LSS_OK, .id = { 1, 2, 3, 4 } };
        ck_assert_int_ge(lssd_raw_step_append_result(&inq, &r, m, true), 0);
        ck_assert_int_ge(sd_bus_message_close_container(m), 0);
        ck_assert_int_ge(sd_bus_message_seal(m, 1, 0), 0);
        ck_assert_int_ge(sd_bus_message_rewind(m, 1), 0);
        ck_assert_str_eq(sd_bus_message_get_signature(m, 1), "bav");

        uint32_t v, p, rev, s;
        int t;
        ck_assert_int_ge(sd_bus_message_read(m, "b", &found), 0);
        ck_assert(!found);
        ck_assert_int_ge(sd_bus_message_enter_container(m, 'a', "v"), 0);
        ck_assert_int_ge(sd_bus_message_read(m, "v", "b", &t), 0);
        ck_assert(t);
        ck_assert_int_ge(sd_bus_message_read(m, "v", "(uuuu)", &v, &p, &rev, &s), 0);
        ck_assert_uint_eq(v, 1);
        ck_assert_uint_eq(s, 4);
        sd_bus_message_unref(m);
        test_bus_free(bus);
}
END_TEST

static Suite *suite(void) {
        Suite *s = suite_create("daemon-args");
        TCase *tc = tcase_create("core");
        tcase_add_test(tc, validate_node_id);
        tcase_add_test(tc, validate_bit_timing);
        tcase_add_test(tc, validate_misc);
        tcase_add_test(tc, options_scan);
        tcase_add_test(tc, options_assign);
        tcase_add_test(tc, raw_args);
        tcase_add_test(tc, execute_steps);
        tcase_add_test(tc, execute_limit);
        tcase_add_test(tc, raw_results);
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
