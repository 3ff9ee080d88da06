/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* lssd's pure pieces: job queue bounds and order, scan bookkeeping, device
 * states, object paths, the authorization decision, --sim-slave parsing. */
#include <check.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_auth.h"
#include "daemon/lssd_device.h"
#include "daemon/lssd_job_queue.h"
#include "daemon/lssd_path.h"
#include "simbus/simbus.h"

static lssd_job *job(lssd_job_type t) {
        lssd_job *j = NULL;
        ck_assert_int_eq(lssd_job_new(t, NULL, &j), 0);
        return j;
}

START_TEST(queue_bounds) {
        lssd_job_queue q;
        lssd_job *jobs[5];
        lssd_job_queue_init(&q, 3);

        ck_assert_ptr_null(lssd_job_queue_pop(&q));
        for (unsigned i = 0; i < 3; i++) {
                jobs[i] = job(LSSD_JOB_SCAN);
                ck_assert_int_eq(lssd_job_queue_push(&q, jobs[i], false), 0);
        }
        ck_assert_uint_eq(q.n, 3);

        /* full for callers ... */
        jobs[3] = job(LSSD_JOB_SCAN);
        ck_assert_int_eq(lssd_job_queue_push(&q, jobs[3], false), -ENOBUFS);
        ck_assert_uint_eq(q.n, 3);
        /* ... never for the daemon's own switch to waiting */
        jobs[4] = job(LSSD_JOB_RESET);
        ck_assert_int_eq(lssd_job_queue_push(&q, jobs[4], true), 0);
        ck_assert_uint_eq(q.n, 4);

        /* FIFO */
        for (unsigned i = 0; i < 3; i++)
                ck_assert_ptr_eq(lssd_job_queue_pop(&q), jobs[i]);
        ck_assert_ptr_eq(lssd_job_queue_pop(&q), jobs[4]);
        ck_assert_ptr_null(lssd_job_queue_pop(&q));
        ck_assert_uint_eq(q.n, 0);
        ck_assert_ptr_null(q.head);
        ck_assert_ptr_null(q.tail);

        /* room again */
        ck_assert_int_eq(lssd_job_queue_push(&q, jobs[3], false), 0);
        ck_assert_ptr_eq(lssd_job_queue_pop(&q), jobs[3]);

        for (unsigned i = 0; i < 5; i++)
                lssd_job_free(jobs[i]);
}
END_TEST

START_TEST(queue_front_and_remove) {
        lssd_job_queue q;
        lssd_job *a = job(LSSD_JOB_SCAN), *b = job(LSSD_JOB_ASSIGN), *c = job(LSSD_JOB_EXECUTE),
                 *r = job(LSSD_JOB_RESET);
        lssd_job_queue_init(&q, 8);

        ck_assert_int_eq(lssd_job_queue_push(&q, a, false), 0);
        ck_assert_int_eq(lssd_job_queue_push(&q, b, false), 0);
        ck_assert_int_eq(lssd_job_queue_push(&q, c, false), 0);
        lssd_job_queue_push_front(&q, r);
        ck_assert_uint_eq(q.n, 4);

        lssd_job_queue_remove(&q, b); /* middle */
        ck_assert_uint_eq(q.n, 3);
        lssd_job_queue_remove(&q, c); /* tail */
        ck_assert_ptr_eq(q.tail, a);

        ck_assert_ptr_eq(lssd_job_queue_pop(&q), r);
        ck_assert_ptr_eq(lssd_job_queue_pop(&q), a);
        ck_assert_ptr_null(lssd_job_queue_pop(&q));

        /* push_front on an empty queue */
        lssd_job_queue_push_front(&q, b);
        ck_assert_ptr_eq(q.head, b);
        ck_assert_ptr_eq(q.tail, b);
        ck_assert_ptr_eq(lssd_job_queue_pop(&q), b);

        ck_assert_str_eq(lssd_job_name(a), "Scan");
        ck_assert_str_eq(lssd_job_name(b), "AssignNodeId");
        ck_assert_str_eq(lssd_job_name(c), "Execute");
        ck_assert_str_eq(lssd_job_name(r), "Reset");
        lssd_job_free(a);
        lssd_job_free(b);
        lssd_job_free(c);
        lssd_job_free(r);
        ck_assert_ptr_null(lssd_job_free(NULL));
}
END_TEST

START_TEST(scan_bookkeeping) {
        lssd_job *j = job(LSSD_JOB_SCAN);
        ck_assert_int_eq(lssd_job_add_pair(j, 0xEC, 0x1234), 1);
        ck_assert_int_eq(lssd_job_add_pair(j, 0xEC, 0x1234), 0);
        ck_assert_int_eq(lssd_job_add_pair(j, 0xEC, 0x1235), 1);
        ck_assert_uint_eq(j->n_pairs, 2);

        lss_device d = { .id = { 0xEC, 0x1234, 1, 0x1276 }, .node_id = 0xFF };
        ck_assert_int_eq(lssd_job_add_found(j, &d), 1);
        d.node_id = 5; /* slowscan knows better than fastscan */
        ck_assert_int_eq(lssd_job_add_found(j, &d), 0);
        ck_assert_uint_eq(j->n_found, 1);
        ck_assert_uint_eq(j->found[0].dev.node_id, 5);
        ck_assert_uint_eq(j->found[0].by, LSSD_FOUND_LSS);
        /* SDO at another node-ID: found that way too, the LSS answer stays */
        d.node_id = 9;
        ck_assert_int_eq(lssd_job_add_found_by(j, &d, LSSD_FOUND_SDO), 0);
        ck_assert_uint_eq(j->found[0].dev.node_id, 5);
        ck_assert_uint_eq(j->found[0].by, LSSD_FOUND_LSS | LSSD_FOUND_SDO);
        d.id.serial++;
        ck_assert_int_eq(lssd_job_add_found_by(j, &d, LSSD_FOUND_SDO), 1);
        ck_assert_uint_eq(j->n_found, 2);
        /* found by SDO, then confirmed through LSS: the LSS answer counts */
        d.node_id = 10;
        ck_assert_int_eq(lssd_job_add_found(j, &d), 0);
        ck_assert_uint_eq(j->found[1].dev.node_id, 10);
        ck_assert_uint_eq(j->found[1].by, LSSD_FOUND_LSS | LSSD_FOUND_SDO);

        /* a raw job is named after its service */
        lssd_job *raw = job(LSSD_JOB_RAW);
        raw->steps = calloc(1, sizeof(*raw->steps));
        ck_assert_ptr_nonnull(raw->steps);
        raw->steps[0].op = LSSD_RAW_INQUIRE_NODE_ID;
        raw->n_steps = 1;
        ck_assert_str_eq(lssd_job_name(raw), "InquireNodeId");
        lssd_job_free(raw);
        lssd_job_free(j);
}
END_TEST

START_TEST(device_states) {
        /* node_id, mapped, missing, conflict, assigned, pooled, pending_reset */
        ck_assert_str_eq(lssd_device_state(5, 5, true, false, false, false, false), "missing");
        ck_assert_str_eq(lssd_device_state(0xFF, 5, false, false, false, false, false), "non-configured");
        ck_assert_str_eq(lssd_device_state(0xFF, 0, false, true, false, false, false), "non-configured");
        ck_assert_str_eq(lssd_device_state(5, 0, false, true, false, false, false), "conflict");
        ck_assert_str_eq(lssd_device_state(5, 5, false, true, true, false, false), "conflict");
        ck_assert_str_eq(lssd_device_state(5, 5, false, false, false, false, false), "assigned");
        ck_assert_str_eq(lssd_device_state(6, 5, false, false, false, false, false), "mismatch");
        ck_assert_str_eq(lssd_device_state(6, 5, false, false, true, false, false), "mismatch");
        ck_assert_str_eq(lssd_device_state(6, 0, false, false, false, false, false), "configured");
        ck_assert_str_eq(lssd_device_state(6, 0, false, false, true, false, false), "assigned");
        ck_assert_str_eq(lssd_device_state(6, 0, false, false, true, true, false), "pool");
        ck_assert_str_eq(lssd_device_state(6, 0, false, true, true, true, false), "conflict");
        /* it holds the node-ID lssd gave it for its next reset: before all but missing */
        ck_assert_str_eq(lssd_device_state(6, 6, false, true, true, false, true), "pending-reset");
        ck_assert_str_eq(lssd_device_state(6, 0, false, false, true, true, true), "pending-reset");
        ck_assert_str_eq(lssd_device_state(6, 6, true, false, true, false, true), "missing");
}
END_TEST

START_TEST(paths) {
        char *p = NULL;
        ck_assert_int_eq(lssd_bus_path("can0", &p), 0);
        ck_assert_str_eq(p, "/org/lssd/LSS1/buses/can0");
        free(p);
        ck_assert_int_eq(lssd_bus_path("vcan1", &p), 0);
        ck_assert_str_eq(p, "/org/lssd/LSS1/buses/vcan1");
        free(p);
        /* everything but letters and digits is escaped */
        ck_assert_int_eq(lssd_bus_path("can-1.x_y", &p), 0);
        ck_assert_str_eq(p, "/org/lssd/LSS1/buses/can_2d1_2ex_5fy");
        free(p);

        lss_identity id = { 0xEC, 0x1234, 0x00010002, 0x80002468 };
        ck_assert_int_eq(lssd_device_path("can0", &id, &p), 0);
        ck_assert_str_eq(p, "/org/lssd/LSS1/buses/can0/devices/000000ec_00001234_00010002_80002468");
        free(p);
        id = (lss_identity) { 0xFFFFFFFF, 0, 0xABCDEF01, 0xFFFFFFFF };
        ck_assert_int_eq(lssd_device_path("can0", &id, &p), 0);
        ck_assert_str_eq(p, "/org/lssd/LSS1/buses/can0/devices/ffffffff_00000000_abcdef01_ffffffff");

        lss_identity back;
        ck_assert_int_eq(lssd_device_name_parse(strrchr(p, '/') + 1, &back), 0);
        ck_assert(lss_identity_equal(&id, &back));
        free(p);

        ck_assert_int_eq(lssd_device_name_parse("000000EC_00001234_00010002_80002468", &back), -EINVAL);
        ck_assert_int_eq(lssd_device_name_parse("000000ec_00001234_00010002_8000246", &back), -EINVAL);
        ck_assert_int_eq(lssd_device_name_parse("000000ec-00001234_00010002_80002468", &back), -EINVAL);
        ck_assert_int_eq(lssd_device_name_parse("000000ec_00001234_00010002_80002468_", &back), -EINVAL);
        ck_assert_int_eq(lssd_device_name_parse("", &back), -EINVAL);
        ck_assert_int_eq(lssd_device_name_parse(NULL, &back), -EINVAL);
}
END_TEST

START_TEST(auth_decision) {
        lssd_auth none = { 0 };
        lssd_auth both = { .have_uid = true, .have_gid = true, .uid = 990, .gid = 991 };
        const gid_t member[] = { 100, 991 }, other[] = { 100, 990 };

        /* no user or group lssd: root only */
        ck_assert(lssd_auth_allowed(&none, 0, NULL, 0));
        ck_assert(!lssd_auth_allowed(&none, 1000, member, 2));
        ck_assert(!lssd_auth_allowed(&none, 990, NULL, 0));

        ck_assert(lssd_auth_allowed(&both, 0, NULL, 0));
        ck_assert(lssd_auth_allowed(&both, 990, NULL, 0));
        ck_assert(lssd_auth_allowed(&both, 1000, member, 2));
        ck_assert(!lssd_auth_allowed(&both, 1000, other, 2));
        ck_assert(!lssd_auth_allowed(&both, 1000, NULL, 0));
        ck_assert(!lssd_auth_allowed(&both, 65534, member, 1));
}
END_TEST

START_TEST(sim_slave_spec) {
        char ifname[16];
        lss_identity id;
        uint8_t node;
        simbus_profile co;
        ck_assert_int_eq(simbus_slave_parse("vcan0:0xEC:0x1234:1:0x80001276", ifname, &id, &node, &co), 0);
        ck_assert_str_eq(ifname, "vcan0");
        ck_assert_uint_eq(id.vendor, 0xEC);
        ck_assert_uint_eq(id.serial, 0x80001276u);
        ck_assert_uint_eq(node, 0xFF);
        ck_assert_int_eq(simbus_slave_parse("sim:1:2:3:4:127", ifname, &id, &node, &co), 0);
        ck_assert_uint_eq(node, 127);
        ck_assert_int_eq(simbus_slave_parse("sim:1:2:3:4:255", ifname, &id, &node, &co), 0);
        ck_assert_uint_eq(node, 0xFF);
        ck_assert_int_eq(co, SIMBUS_PLAIN);
        /* a CANopenNode v4 device */
        ck_assert_int_eq(simbus_slave_parse("sim:1:2:3:4:0xff:canopennode", ifname, &id, &node, &co), 0);
        ck_assert_uint_eq(node, 0xFF);
        ck_assert_int_eq(co, SIMBUS_CANOPENNODE);
        /* the same answering Configure Bit Timing; one without selective switch */
        ck_assert_int_eq(simbus_slave_parse("sim:1:2:3:4:9:canopennode-bitrate", ifname, &id, &node, &co), 0);
        ck_assert_int_eq(co, SIMBUS_CANOPENNODE_BITRATE);
        ck_assert_int_eq(simbus_slave_parse("sim:1:2:3:4:9:no-selective-switch", ifname, &id, &node, &co), 0);
        ck_assert_int_eq(co, SIMBUS_NO_SELECTIVE_SWITCH);
        /* a device on lely-core's LSS slave */
        ck_assert_int_eq(simbus_slave_parse("sim:1:2:3:4:5:lely", ifname, &id, &node, &co), 0);
        ck_assert_int_eq(co, SIMBUS_LELY);
        lss_slave_faults f;
        simbus_profile_faults(SIMBUS_LELY, &f);
        ck_assert(f.lely_lss && f.miss_activation && !f.canopennode_lss);
        ck_assert_uint_eq(f.bit_index_unsupported, UINT32_MAX);
        simbus_profile_faults(SIMBUS_CANOPENNODE, &f);
        ck_assert(f.canopennode_lss && f.bit_timing_silent && !f.lely_lss);
        ck_assert(strstr(SIMBUS_PROFILES, "lely"));
        ck_assert_int_eq(simbus_slave_parse("sim:1:2:3:4:5:plain", ifname, &id, &node, &co), -EINVAL);
        ck_assert_int_eq(simbus_slave_parse("sim:1:2:3:4:5:canopennode:x", ifname, &id, &node, &co), -EINVAL);
        ck_assert_int_eq(simbus_slave_parse("sim:1:2:3:4:0", ifname, &id, &node, &co), -EINVAL);
        ck_assert_int_eq(simbus_slave_parse("sim:1:2:3", ifname, &id, &node, &co), -EINVAL);
        ck_assert_int_eq(simbus_slave_parse("sim:1:2:3:4:5:6", ifname, &id, &node, &co), -EINVAL);
        ck_assert_int_eq(simbus_slave_parse("sim:1:2:3:0x100000000", ifname, &id, &node, &co), -EINVAL);
        ck_assert_int_eq(simbus_slave_parse("sim:1:2:3:-1", ifname, &id, &node, &co), -EINVAL);
        ck_assert_int_eq(simbus_slave_parse("0123456789abcdef:1:2:3:4", ifname, &id, &node, &co), -EINVAL);
}
END_TEST

/* --sim-foreign-master IFACE:AFTER[:COUNT[:PERIOD_MS]] */
START_TEST(sim_foreign_spec) {
        simbus_foreign f;
        ck_assert_int_eq(simbus_foreign_parse("vcan0:150", &f), 0);
        ck_assert_str_eq(f.ifname, "vcan0");
        ck_assert_uint_eq(f.after, 150);
        ck_assert_uint_eq(f.count, 1);
        ck_assert_uint_eq(f.period_ms, 100);
        ck_assert_int_eq(simbus_foreign_parse("sim:0:20:0x32", &f), 0);
        ck_assert_uint_eq(f.after, 0);
        ck_assert_uint_eq(f.count, 20);
        ck_assert_uint_eq(f.period_ms, 50);
        ck_assert_int_eq(f.after_cs, 0);
        /* at lssd's first Activate Bit Timing */
        ck_assert_int_eq(simbus_foreign_parse("sim:@0x15", &f), 0);
        ck_assert_int_eq(f.after_cs, 0x15);
        ck_assert_int_eq(simbus_foreign_parse("sim:@256", &f), -EINVAL);
        ck_assert_int_eq(simbus_foreign_parse("sim:@0", &f), -EINVAL);
        ck_assert_int_eq(simbus_foreign_parse("sim:@", &f), -EINVAL);
        ck_assert_int_eq(simbus_foreign_parse("sim", &f), -EINVAL);
        ck_assert_int_eq(simbus_foreign_parse("sim:1:0", &f), -EINVAL);
        ck_assert_int_eq(simbus_foreign_parse("sim:1:1:0", &f), -EINVAL);
        ck_assert_int_eq(simbus_foreign_parse("sim:1:1:60001", &f), -EINVAL);
        ck_assert_int_eq(simbus_foreign_parse("sim:-1", &f), -EINVAL);
        ck_assert_int_eq(simbus_foreign_parse("sim:1:2:3:4", &f), -EINVAL);
        ck_assert_int_eq(simbus_foreign_parse("0123456789abcdef:1", &f), -EINVAL);
        ck_assert_int_eq(simbus_foreign_parse(NULL, &f), -EINVAL);
}
END_TEST

static Suite *suite(void) {
        Suite *s = suite_create("daemon-queue");
        TCase *tc = tcase_create("core");
        tcase_add_test(tc, queue_bounds);
        tcase_add_test(tc, queue_front_and_remove);
        tcase_add_test(tc, scan_bookkeeping);
        tcase_add_test(tc, device_states);
        tcase_add_test(tc, paths);
        tcase_add_test(tc, auth_decision);
        tcase_add_test(tc, sim_slave_spec);
        tcase_add_test(tc, sim_foreign_spec);
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
