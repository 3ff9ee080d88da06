/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <check.h>
#include <stdlib.h>
#include <string.h>

#include "lss/lss_autoassign.h"
#include "lss/lss_proto.h"

static void expect_bytes(const lss_frame *f, uint32_t id, const uint8_t *b, unsigned len) {
        ck_assert_uint_eq(f->id, id);
        ck_assert_uint_eq(f->len, len);
        ck_assert_uint_eq(f->flags, 0);
        ck_assert_mem_eq(f->data, b, len);
}

/* The decoded seed example "set node-ID 0x44 and store". */
START_TEST(seed_node_id_example) {
        lss_frame f;
        lss_encode_switch_global(&f, LSS_MODE_CONFIGURATION);
        expect_bytes(&f, 0x7E5, (const uint8_t[]){ 0x04, 0x01, 0, 0, 0, 0, 0, 0 }, 8);
        lss_encode_configure_node_id(&f, 0x44);
        expect_bytes(&f, 0x7E5, (const uint8_t[]){ 0x11, 0x44, 0, 0, 0, 0, 0, 0 }, 8);
        lss_encode_store(&f);
        expect_bytes(&f, 0x7E5, (const uint8_t[]){ 0x17, 0, 0, 0, 0, 0, 0, 0 }, 8);
        lss_encode_switch_global(&f, LSS_MODE_WAITING);
        expect_bytes(&f, 0x7E5, (const uint8_t[]){ 0x04, 0x00, 0, 0, 0, 0, 0, 0 }, 8);
        bootup_encode(&f, 0x44);
        expect_bytes(&f, 0x744, (const uint8_t[]){ 0x00 }, 1);
        uint8_t nid = 0, st = 1;
        ck_assert(bootup_decode(&f, &nid, &st));
        ck_assert_uint_eq(nid, 0x44);
        ck_assert_uint_eq(st, 0);
}
END_TEST

/* The decoded seed example "set 500 kbit/s". */
START_TEST(seed_bit_rate_example) {
        lss_frame f;
        lss_encode_configure_bit_timing(&f, 0, (uint8_t) lss_bit_timing_index(500000));
        expect_bytes(&f, 0x7E5, (const uint8_t[]){ 0x13, 0x00, 0x02, 0, 0, 0, 0, 0 }, 8);
        lss_encode_activate_bit_timing(&f, 16);
        expect_bytes(&f, 0x7E5, (const uint8_t[]){ 0x15, 0x10, 0x00, 0, 0, 0, 0, 0 }, 8);
}
END_TEST

START_TEST(encoders) {
        lss_frame f;
        lss_encode_switch_selective(&f, LSS_FIELD_SERIAL, 0x80002468u);
        expect_bytes(&f, 0x7E5, (const uint8_t[]){ 0x43, 0x68, 0x24, 0x00, 0x80, 0, 0, 0 }, 8);
        lss_encode_fastscan(&f, 0x12345678u, 31, 2, 3);
        expect_bytes(&f, 0x7E5, (const uint8_t[]){ 0x51, 0x78, 0x56, 0x34, 0x12, 31, 2, 3 }, 8);
        lss_encode_identify_remote(&f, 5, 0x2468);
        expect_bytes(&f, 0x7E5, (const uint8_t[]){ 0x4B, 0x68, 0x24, 0, 0, 0, 0, 0 }, 8);
        lss_encode_inquire(&f, LSS_FIELD_COUNT);
        ck_assert_uint_eq(f.data[0], 0x5E);
        lss_encode_inquire(&f, LSS_FIELD_REVISION);
        ck_assert_uint_eq(f.data[0], 0x5C);
        lss_encode_identify_non_configured(&f);
        ck_assert_uint_eq(f.data[0], 0x4C);
        nmt_encode(&f, NMT_CS_RESET_COMMUNICATION, 5);
        expect_bytes(&f, 0x000, (const uint8_t[]){ 0x82, 0x05 }, 2);
        uint8_t cs, nid;
        ck_assert(nmt_decode(&f, &cs, &nid));
        ck_assert_uint_eq(cs, 0x82);
        ck_assert_uint_eq(nid, 5);
}
END_TEST

START_TEST(response_acceptance) {
        lss_frame f;
        lss_frame_response(&f, LSS_CS_IDENTIFY_SLAVE);
        ck_assert(lss_is_response(&f));
        ck_assert(!lss_is_request(&f));
        f.flags = LSS_FRAME_EFF;
        ck_assert(!lss_is_response(&f));
        f.flags = LSS_FRAME_RTR;
        ck_assert(!lss_is_response(&f));
        f.flags = LSS_FRAME_FD;
        ck_assert(!lss_is_response(&f));
        f.flags = 0;
        f.len = 4;
        ck_assert(!lss_is_response(&f));
        f.len = 8;
        f.id = 0x7E3;
        ck_assert(!lss_is_response(&f));
        ck_assert(!lss_is_foreign_request(&f));
        /* a frame at the master's identifier that is not our echo: another
         * master's, whatever its DLC; our echo, look-alikes and answers are not */
        lss_encode_inquire(&f, LSS_FIELD_VENDOR);
        ck_assert(lss_is_foreign_request(&f));
        f.len = 2;
        ck_assert(lss_is_foreign_request(&f));
        f.flags = LSS_FRAME_ECHO;
        ck_assert(!lss_is_foreign_request(&f));
        f.flags = LSS_FRAME_EFF;
        ck_assert(!lss_is_foreign_request(&f));
        f.flags = LSS_FRAME_RTR;
        ck_assert(!lss_is_foreign_request(&f));
        lss_frame_response(&f, LSS_CS_INQUIRE_VENDOR);
        ck_assert(!lss_is_foreign_request(&f));
        bootup_encode(&f, 0x7F);
        ck_assert(bootup_decode(&f, NULL, NULL));
        f.id = 0x700;
        ck_assert(!bootup_decode(&f, NULL, NULL));
        f.id = 0x780;
        ck_assert(!bootup_decode(&f, NULL, NULL));
}
END_TEST

START_TEST(helpers) {
        ck_assert(!lss_node_id_valid(0));
        ck_assert(lss_node_id_valid(1));
        ck_assert(lss_node_id_valid(127));
        ck_assert(!lss_node_id_valid(128));
        ck_assert(!lss_node_id_valid(0xFF));
        ck_assert_int_eq(lss_bit_timing_index(125000), 4);
        ck_assert_int_eq(lss_bit_timing_index(100000), 5);
        ck_assert_int_eq(lss_bit_timing_index(123), -1);
        ck_assert_uint_eq(lss_bit_timing_rate(0), 1000000);
        ck_assert_uint_eq(lss_bit_timing_rate(9), 0);
        lss_identity a = { 1, 2, 3, 4 }, b = a;
        ck_assert(lss_identity_equal(&a, &b));
        lss_identity_set_field(&b, LSS_FIELD_SERIAL, 5);
        ck_assert_int_lt(lss_identity_compare(&a, &b), 0);
        ck_assert_uint_eq(lss_identity_field(&b, LSS_FIELD_SERIAL), 5);
        ck_assert_uint_eq(lss_get_u32((const uint8_t[]){ 0xFF, 0xFF, 0xFF, 0xFF }), 0xFFFFFFFFu);
        char buf[40];
        lss_frame f;
        lss_encode_switch_global(&f, LSS_MODE_CONFIGURATION);
        ck_assert_str_eq(lss_frame_format(&f, buf, sizeof(buf)), "7E5#0401000000000000");
}
END_TEST

/* The map-matching rule (lss_identity_matches, its one home): vendor,
 * product and serial always count; the revision only when the entry has
 * one. The autoassign map, the config lookup and the daemon all use it. */
START_TEST(map_matching_rule) {
        const lss_identity entry = { .vendor = 0xEC, .product = 0x1234, .revision = 0x10002, .serial = 0x80002468 };
        lss_identity id = entry;

        ck_assert(lss_identity_matches(&entry, true, &id));
        ck_assert(lss_identity_matches(&entry, false, &id));
        /* another revision: only an entry without revision names it */
        id.revision = 0x20001;
        ck_assert(!lss_identity_matches(&entry, true, &id));
        ck_assert(lss_identity_matches(&entry, false, &id));
        /* an entry without revision keeps whatever revision field it has: 0 matches any too */
        const lss_identity zero_rev = { .vendor = 0xEC, .product = 0x1234, .revision = 0, .serial = 0x80002468 };
        ck_assert(lss_identity_matches(&zero_rev, false, &id));
        ck_assert(!lss_identity_matches(&zero_rev, true, &id));
        /* vendor, product, serial: each one that differs is another device, revision or not */
        for (unsigned f = 0; f < LSS_FIELD_COUNT; f++) {
                if (f == LSS_FIELD_REVISION)
                        continue;
                id = entry;
                lss_identity_set_field(&id, f, lss_identity_field(&entry, f) + 1);
                ck_assert_msg(!lss_identity_matches(&entry, true, &id), "field %u", f);
                ck_assert_msg(!lss_identity_matches(&entry, false, &id), "field %u", f);
        }
        /* the autoassign map's entries follow the same rule */
        lss_map_entry e = { .id = entry, .revision_known = false, .node_id = 5 };
        id = entry;
        id.revision = 7;
        ck_assert(lss_map_entry_matches(&e, &id));
        e.revision_known = true;
        ck_assert(!lss_map_entry_matches(&e, &id));
        id.revision = entry.revision;
        ck_assert(lss_map_entry_matches(&e, &id));
}
END_TEST

/* Bit counts of known frames (stuffing computed on the real bit stream). */
START_TEST(frame_bits) {
        lss_frame f;
        lss_encode_switch_global(&f, LSS_MODE_WAITING);
        unsigned bits = can_frame_bits(&f);
        /* 8-byte standard frame: 108 bits + IFS 3 unstuffed, stuffing at most 24 */
        ck_assert_uint_ge(bits, 111);
        ck_assert_uint_le(bits, 111 + 24);
        bootup_encode(&f, 0x44);
        ck_assert_uint_ge(can_frame_bits(&f), 55);
        ck_assert_uint_le(can_frame_bits(&f), 55 + 10);
        /* all-zero data stuffs heavily, more than alternating data */
        lss_frame z, a;
        lss_frame_request(&z, 0);
        lss_frame_request(&a, 0x55);
        memset(a.data, 0x55, 8);
        ck_assert_uint_gt(can_frame_bits(&z), can_frame_bits(&a));
}
END_TEST

int main(void) {
        Suite *s = suite_create("proto");
        TCase *tc = tcase_create("core");
        tcase_add_test(tc, seed_node_id_example);
        tcase_add_test(tc, seed_bit_rate_example);
        tcase_add_test(tc, encoders);
        tcase_add_test(tc, response_acceptance);
        tcase_add_test(tc, helpers);
        tcase_add_test(tc, map_matching_rule);
        tcase_add_test(tc, frame_bits);
        suite_add_tcase(s, tc);
        SRunner *sr = srunner_create(s);
        srunner_run_all(sr, CK_NORMAL);
        int failed = srunner_ntests_failed(sr);
        srunner_free(sr);
        return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
