/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Helpers shared by the engine tests: buses of random slaves, driving. */
#pragma once

#include <check.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lss/lss_master.h"
#include "sim/lss_drive.h"
#include "sim/membus.h"
#include "sim/sim_random.h"

#define SECOND 1000000ull

/* n slaves with random, distinct identities; vendor/product fixed if nonzero. */
static inline membus *bus_random(size_t n, uint64_t seed, uint32_t vendor, uint32_t product,
                                 const lss_slave_faults *faults) {
        membus *b = membus_new(125000);
        ck_assert_ptr_nonnull(b);
        for (size_t i = 0; i < n; i++) {
                lss_identity id = {
                        .vendor = vendor ? vendor : (uint32_t) sim_random_next(&seed),
                        .product = product ? product : (uint32_t) sim_random_next(&seed),
                        .revision = (uint32_t) sim_random_next(&seed),
                        .serial = (uint32_t) sim_random_next(&seed),
                };
                membus_add_slave(b, &id, LSS_NODE_ID_UNCONFIGURED, faults);
        }
        return b;
}

static inline lss_slave_faults faults_latency(uint32_t latency_us, uint32_t jitter_us) {
        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.latency_us = latency_us;
        f.jitter_us = jitter_us;
        return f;
}

/* lss_master_set_taken_check() over a table of 128 node-IDs (userdata) */
static inline bool taken_in_table(void *userdata, uint8_t node_id, const lss_identity *id) {
        (void) id;
        return ((const bool *) userdata)[node_id];
}

/* The failure's codes: which service failed and why (lss_result), the
 * daemon's classification; never read from the message. */
#define expect_failed_at(r, service, why) \
        ck_assert_msg((r)->failed_service == (service) && (r)->reason == (why), \
                      "failed at %s (%s), want %s (%s): %s", lss_service_name((r)->failed_service), \
                      lss_reason_name((r)->reason), lss_service_name(service), lss_reason_name(why), (r)->message)

static inline lss_master *master_default(void) {
        lss_timing_config c;
        lss_timing_config_default(&c);
        lss_master *m = lss_master_new(&c);
        ck_assert_ptr_nonnull(m);
        return m;
}

static inline const lss_result *run(lss_master *m, membus *b) {
        return lss_drive(m, b, 600 * SECOND, NULL, NULL);
}

/* Every frame on the wire, in order: membus_set_trace(b, wire_trace_cb, tr),
 * tr from calloc (it is large). */
#define WIRE_TRACE_MAX 20000
typedef struct wire_trace {
        lss_frame f[WIRE_TRACE_MAX];
        uint64_t t[WIRE_TRACE_MAX];
        size_t n;
} wire_trace;

static inline void wire_trace_cb(void *ud, const lss_frame *f, uint64_t t_us) {
        wire_trace *tr = ud;
        if (tr->n < WIRE_TRACE_MAX) {
                tr->f[tr->n] = *f;
                tr->t[tr->n] = t_us;
                tr->n++;
        }
}

static inline bool all_waiting(membus *b) {
        for (size_t i = 0; i < membus_slave_count(b); i++)
                if (membus_slave(b, i)->st.configuration)
                        return false;
        return true;
}

/* Every device in the result is a real slave of the bus, each at most once. */
static inline void assert_devices_real(membus *b, const lss_result *r) {
        for (size_t i = 0; i < r->n_devices; i++) {
                lss_slave *s = membus_find(b, &r->devices[i].id);
                ck_assert_msg(s != NULL, "device %zu (%08x:%08x:%08x:%08x) is not on the bus", i,
                              r->devices[i].id.vendor, r->devices[i].id.product, r->devices[i].id.revision,
                              r->devices[i].id.serial);
                ck_assert_uint_eq(r->devices[i].node_id, s->st.active_node_id);
                for (size_t j = 0; j < i; j++)
                        ck_assert(!lss_identity_equal(&r->devices[i].id, &r->devices[j].id));
        }
}

/* A loaded host, seed by seed: each slave's answers 20, 50, 100 or 200 ms
 * late (by seed) on `ppm` per million of them; a stall holds back the
 * slave's later answers too (one transmit queue). */
/* Seeds of a run over stalls: under valgrind (meson test --setup valgrind,
 * which checks memory) a twentieth of them. */
#define STALL_SEEDS(n) (getenv("LSSD_TEST_UNDER_VALGRIND") ? (n) / 20u : (n))

static inline uint32_t stall_us_of(uint64_t seed) {
        static const uint32_t stall_us[] = { 20000, 50000, 100000, 200000 };
        return stall_us[seed % 4];
}

static inline void faults_stall(lss_slave_faults *f, uint64_t seed, uint32_t ppm) {
        f->spike_us = stall_us_of(seed);
        f->spike_ppm = ppm;
}

/* A seed's failure over stalls: said on stderr (the seed and its stall, so
 * that it can be traced) and counted; the test asserts the count at the end. */
static inline void stall_failed(unsigned *failed, uint64_t seed, const lss_slave_faults *f, const char *what) {
        fprintf(stderr, "seed %u (%u ms stalls): %s\n", (unsigned) seed, (unsigned) (f->spike_us / 1000), what);
        (*failed)++;
}

/* ... a result that should hold all `n` slaves of the bus: OK, each real;
 * every slave ends in waiting. */
static inline void stall_expect_found(unsigned *failed, uint64_t seed, const lss_slave_faults *f, membus *b,
                                      const lss_result *r, size_t n) {
        if (r->status != LSS_OK || r->n_devices != n) {
                char what[500];
                snprintf(what, sizeof(what), "%zu of %zu found: %s", r->n_devices, n, r->message);
                stall_failed(failed, seed, f, what);
        } else {
                assert_devices_real(b, r);
        }
        lss_drive_idle(b, 300000);
        ck_assert(all_waiting(b));
}

/* What lss_master_set_found() announced, and when (virtual time, LSS
 * requests on the bus so far). Every announcement must be a real slave of
 * the bus, announced once. */
#define FOUND_LOG_MAX 256
typedef struct found_log {
        membus *bus;
        size_t n;
        lss_device dev[FOUND_LOG_MAX];
        uint64_t at[FOUND_LOG_MAX], requests[FOUND_LOG_MAX];
} found_log;

static inline void found_log_cb(void *ud, const lss_device *d) {
        found_log *l = ud;
        ck_assert_msg(membus_find(l->bus, &d->id) != NULL,
                      "announced %08x:%08x:%08x:%08x, which is not on the bus", d->id.vendor, d->id.product,
                      d->id.revision, d->id.serial);
        for (size_t i = 0; i < l->n; i++)
                ck_assert_msg(!lss_identity_equal(&l->dev[i].id, &d->id), "%08x announced twice", d->id.serial);
        ck_assert_uint_lt(l->n, FOUND_LOG_MAX);
        l->dev[l->n] = *d;
        l->at[l->n] = membus_now(l->bus);
        l->requests[l->n] = membus_get_stats(l->bus)->lss_requests;
        l->n++;
}

static inline void found_log_start(found_log *l, lss_master *m, membus *b) {
        memset(l, 0, sizeof(*l));
        l->bus = b;
        lss_master_set_found(m, found_log_cb, l);
}

/* Each result device was announced, with its node-ID, before the end
 * (`end`: the virtual time the operation ended); when `exact`, nothing else
 * was. */
static inline void found_log_check(const found_log *l, const lss_result *r, uint64_t end, bool exact) {
        for (size_t i = 0; i < r->n_devices; i++) {
                size_t k = 0;
                while (k < l->n && !lss_identity_equal(&l->dev[k].id, &r->devices[i].id))
                        k++;
                ck_assert_msg(k < l->n, "result device %08x not announced", r->devices[i].id.serial);
                ck_assert_uint_eq(l->dev[k].node_id, r->devices[i].node_id);
                ck_assert_uint_lt(l->at[k], end);
        }
        if (exact)
                ck_assert_uint_eq(l->n, r->n_devices);
}

static inline int run_suite(Suite *s) {
        SRunner *sr = srunner_create(s);
        srunner_run_all(sr, CK_NORMAL);
        int failed = srunner_ntests_failed(sr);
        srunner_free(sr);
        return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
