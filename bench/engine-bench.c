/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Engine bench on the in-memory bus (virtual time, 125 kbit/s, slaves with
 * 1 ms latency + up to 0.3 ms jitter): frames and bus time to identify and
 * give node-IDs to N non-configured slaves,
 *   (a) blind fastscan, (b) vendor and product known, (c) full identity known,
 * and (d) the blind Scan: one enumeration of every slave (one vendor and
 * product, revision and serial random: the lss-sim set-up of bench/run),
 * (e) AutoAssign with a map of full identities (what lssd runs for one),
 * (f) Scan with vendor and product given (slowscan: identify-remote bisection),
 * (g) AutoAssign with a pool, the map naming vendor and product only (one
 * absent device of that type), (h) AutoAssign with a pool, blind (what lssd
 * runs for bench/autoaddress.py's modes vendor and blind).
 * And the SDO identity discovery of node-IDs 1..127 with N configured devices
 * at 1..N, against the bus floor of its frames.
 * Not a test: prints tables. Correctness is still checked: every slave must
 * end with the node-ID it was reported with, every configured device must be
 * found with its identity, or the bench fails. */
#include <stdio.h>
#include <stdlib.h>

#include "lss/lss_autoassign.h"
#include "lss/lss_master.h"
#include "sim/lss_drive.h"
#include "sim/membus.h"
#include "sim/sim_random.h"

#define BITRATE 125000u
#define LATENCY_US 1000u
#define JITTER_US 300u

enum mode { BLIND, KNOWN_VP, FULL, SCAN, AA_MAPPED, SLOWSCAN, AA_POOL_VP, AA_POOL_BLIND };
static const char *const mode_names[] = { "(a) blind fastscan", "(b) vendor+product known",
                                          "(c) full identity known", "(d) blind Scan (enumerate)",
                                          "(e) AutoAssign, full map", "(f) Scan vendor+product",
                                          "(g) AutoAssign pool, v+p", "(h) AutoAssign pool, blind" };

typedef struct row {
        uint64_t lss_frames, all_frames, busy_us, elapsed_us;
} row;

/* A host that stalls now and then, for trials of the timing rules:
 * ENGINE_BENCH_STALL_PPM answers per million come ENGINE_BENCH_STALL_US late
 * (default none: the tables below are without). */
static void stalls(lss_slave_faults *f) {
        const char *ppm = getenv("ENGINE_BENCH_STALL_PPM"), *us = getenv("ENGINE_BENCH_STALL_US");
        f->spike_ppm = ppm ? (uint32_t) strtoul(ppm, NULL, 10) : 0;
        f->spike_us = us ? (uint32_t) strtoul(us, NULL, 10) : 8000;
}

/* (g), (h): the pool gives every slave a node-ID of its own, each one the
 * slave has and the outcomes report */
static int autoassign_pool(lss_master *m, membus *b, const lss_identity *ids, size_t n, bool vp) {
        /* (g): the map's only entry is an absent device of the slaves' type */
        lss_map_entry absent = { .id = { ids[0].vendor, ids[0].product, 0, 0xA0000000u }, .revision_known = true,
                                 .node_id = 127 };
        lss_autoassign_plan p = { .map = vp ? &absent : NULL, .n_map = vp ? 1 : 0, .unknown = LSS_UNKNOWN_POOL,
                                  .pool_lo = 1, .pool_hi = 64, .store = true };
        lss_master_autoassign(m, &p, membus_now(b));
        const lss_result *r = lss_drive(m, b, 3600ull * 1000000, NULL, NULL);
        size_t n_out, given = 0;
        const lss_outcome *o = lss_master_outcomes(m, &n_out);
        bool seen[128] = { false };
        for (size_t k = 0; k < n_out; k++) {
                const lss_slave *s = membus_find(b, &o[k].id);
                if (!s)
                        continue; /* the absent one */
                if (o[k].kind != LSS_OUTCOME_POOL || s->st.active_node_id != o[k].new_node_id ||
                    seen[o[k].new_node_id])
                        break;
                seen[o[k].new_node_id] = true;
                given++;
        }
        if (given != n || r->status == LSS_E_CANCELLED) {
                fprintf(stderr, "AutoAssign pool of %zu: %zu right: %s\n", n, given, r->message);
                return 1;
        }
        return 0;
}

static int run_case(enum mode mode, size_t n, uint64_t seed, row *out) {
        const size_t n_slaves = n;
        membus *b = membus_new(BITRATE);
        /* identical answers that wait for the wire together merge, as on CAN */
        membus_set_merge_identical(b, true);
        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.latency_us = LATENCY_US;
        f.jitter_us = JITTER_US;
        stalls(&f);
        lss_identity *ids = calloc(n, sizeof(*ids));
        for (size_t i = 0; i < n_slaves; i++) {
                ids[i] = (lss_identity) { 0xEC, 0x1234, (uint32_t) sim_random_next(&seed), (uint32_t) sim_random_next(&seed) };
                membus_add_slave(b, &ids[i], LSS_NODE_ID_UNCONFIGURED, &f);
        }
        lss_master *m = lss_master_new(NULL);
        lss_fastscan_known k = { 0 };
        if (mode == KNOWN_VP) {
                k.value = ids[0];
                k.known_bits[0] = k.known_bits[1] = 32;
        }
        int bad = 0;
        if (mode == SLOWSCAN) {
                lss_identify_range rg = { 0xEC, 0x1234, 0, UINT32_MAX, 0, UINT32_MAX };
                lss_master_slowscan(m, &rg, membus_now(b));
                const lss_result *r = lss_drive(m, b, 3600ull * 1000000, NULL, NULL);
                if (r->status != LSS_OK || r->n_devices != n) {
                        fprintf(stderr, "Scan (slowscan) of %zu: %zu found: %s\n", n, r->n_devices, r->message);
                        bad = 1;
                }
                n = 0;
        }
        if (mode == SCAN) {
                lss_master_enumerate(m, NULL, membus_now(b));
                const lss_result *r = lss_drive(m, b, 3600ull * 1000000, NULL, NULL);
                if (r->status != LSS_OK || r->n_devices != n) {
                        fprintf(stderr, "Scan of %zu: %zu found: %s\n", n, r->n_devices, r->message);
                        bad = 1;
                }
                n = 0;
        }
        if (mode == AA_MAPPED) {
                /* what lssd runs for a map: node-IDs probed, store, boot-ups verified */
                lss_map_entry *map = calloc(n, sizeof(*map));
                for (size_t i = 0; i < n; i++)
                        map[i] = (lss_map_entry) { .id = ids[i], .revision_known = true, .node_id = (uint8_t) (i + 1) };
                lss_autoassign_plan p = { .map = map, .n_map = n, .store = true };
                lss_master_autoassign(m, &p, membus_now(b));
                const lss_result *r = lss_drive(m, b, 3600ull * 1000000, NULL, NULL);
                for (size_t i = 0; i < n; i++) {
                        lss_slave *s = membus_find(b, &ids[i]);
                        if (r->status != LSS_OK || !s || s->st.active_node_id != i + 1) {
                                fprintf(stderr, "AutoAssign: MIS-ASSIGNMENT or failure at node %zu: %s\n", i + 1,
                                        r->message);
                                bad = 1;
                        }
                }
                free(map);
                n = 0;
        }
        if (mode == AA_POOL_VP || mode == AA_POOL_BLIND)
                bad |= autoassign_pool(m, b, ids, n, mode == AA_POOL_VP);
        for (size_t i = 0; i < n && mode != AA_POOL_VP && mode != AA_POOL_BLIND; i++) {
                uint8_t nid = (uint8_t) (i + 1);
                unsigned flags = LSS_ASSIGN_STORE | LSS_ASSIGN_VERIFY;
                if (mode == FULL)
                        lss_master_assign(m, &ids[i], nid, flags, membus_now(b));
                else
                        lss_master_fastscan_assign(m, &k, nid, flags, membus_now(b));
                const lss_result *r = lss_drive(m, b, 3600ull * 1000000, NULL, NULL);
                lss_slave *s = r->status == LSS_OK ? membus_find(b, &r->id) : NULL;
                if (!s || s->st.active_node_id != nid) {
                        fprintf(stderr, "MIS-ASSIGNMENT or failure at node %u: %s\n", nid, r->message);
                        bad = 1;
                }
        }
        const membus_stats *st = membus_get_stats(b);
        out->lss_frames = st->lss_requests + st->lss_responses;
        out->all_frames = st->frames;
        out->busy_us = st->busy_us;
        out->elapsed_us = membus_now(b);
        lss_master_free(m);
        membus_free(b);
        free(ids);
        return bad;
}

/* bits of the SDO requests on the wire (0x601..0x67F: only the master sends them) */
static void count_request_bits(void *ud, const lss_frame *f, uint64_t t_us) {
        (void) t_us;
        if (f->id >= 0x601 && f->id <= 0x67F)
                *(uint64_t *) ud += can_frame_bits(f);
}

/* SDO discovery of 1..127 with n devices at 1..n; the master's frames leave
 * in order (a SocketCAN socket). */
static int run_sdo(size_t n, uint64_t seed) {
        membus *b = membus_new(BITRATE);
        membus_set_master_fifo(b, true);
        uint64_t request_bits = 0;
        membus_set_trace(b, count_request_bits, &request_bits);
        lss_slave_faults f;
        lss_slave_faults_default(&f);
        f.latency_us = LATENCY_US;
        f.jitter_us = JITTER_US;
        for (size_t i = 0; i < n; i++) {
                lss_identity id = { (uint32_t) sim_random_next(&seed), (uint32_t) sim_random_next(&seed), (uint32_t) sim_random_next(&seed),
                                    (uint32_t) sim_random_next(&seed) };
                membus_add_slave(b, &id, (uint8_t) (i + 1), &f);
        }
        lss_master *m = lss_master_new(NULL);
        lss_sdo_discover_params p = { .first = 1, .last = 127 };
        lss_master_sdo_discover(m, &p, membus_now(b));
        const lss_result *r = lss_drive(m, b, 3600ull * 1000000, NULL, NULL);
        int bad = r->status != LSS_OK || r->n_sdo_nodes != n;
        for (size_t i = 0; !bad && i < n; i++) {
                const lss_sdo_node *d = &r->sdo_nodes[i];
                bad = d->node_id != i + 1 || d->known != 0xF || d->conflict ||
                      !lss_identity_equal(&d->id, &membus_slave(b, i)->id);
        }
        if (bad)
                fprintf(stderr, "SDO discovery with %zu devices: wrong result (%s)\n", n, r->message);
        const membus_stats *st = membus_get_stats(b);
        double req_floor_us = (double) request_bits * 1e6 / BITRATE;
        /* lss_drive ends with 2 ms of idle bus */
        double elapsed_ms = (membus_now(b) - 2000) / 1000.0;
        printf("%-26s %4zu %10llu %10llu %12.1f %12.1f %12.1f %9.2fx\n", "SDO 1018h of 1..127", n,
               (unsigned long long) st->master_frames, (unsigned long long) st->frames, req_floor_us / 1000,
               st->busy_us / 1000.0, elapsed_ms, elapsed_ms * 1000 / st->busy_us);
        lss_master_free(m);
        membus_free(b);
        return bad;
}

static double frame_us(const lss_frame *f) {
        return can_frame_bits(f) * 1e6 / BITRATE;
}

int main(void) {
        size_t ns[4] = { 1, 8, 32 };
        int bad = 0;
        lss_frame req, ans;
        lss_encode_fastscan(&req, 0x12345678, 7, 3, 3);
        lss_frame_response(&ans, LSS_CS_IDENTIFY_SLAVE);
        /* the bus floor of one 133-step fastscan: every step needs its request
         * on the wire, the slave's latency and (answered or not, the master
         * cannot know earlier) the time an answer would take */
        double fastscan_floor_us = 133 * (frame_us(&req) + LATENCY_US + frame_us(&ans));

        printf("# engine on the in-memory bus: %u bit/s, slave latency %u us + jitter 0..%u us\n", BITRATE,
               LATENCY_US, JITTER_US);
        lss_slave_faults st;
        lss_slave_faults_default(&st);
        stalls(&st);
        if (st.spike_ppm)
                printf("# stalls: %u of a million answers %u us late (not in the SDO rows)\n", st.spike_ppm,
                       st.spike_us);
        printf("# floor (c) = 10 LSS frames per node; floor (a) = bus floor of a 133-step fastscan = %.1f ms\n",
               fastscan_floor_us / 1000);
        printf("%-26s %4s %10s %10s %12s %12s %10s %10s\n", "case", "N", "LSS frames", "frames/N", "bus time ms",
               "elapsed ms", "ms/node", "vs floor");
        for (int mode = BLIND; mode <= AA_POOL_BLIND; mode++)
                for (size_t i = 0; i < 3u + (mode == SCAN); i++) {
                        row r;
                        if (i == 3)
                                ns[i] = 127; /* (d) also for a full bus, as bench/run's footprint phase */
                        bad |= run_case((enum mode) mode, ns[i], 1000 + ns[i], &r);
                        double per_node = r.elapsed_us / 1000.0 / ns[i];
                        double vs;
                        if (mode == FULL || mode == AA_MAPPED)
                                vs = (double) r.lss_frames / (10.0 * ns[i]);
                        else
                                vs = r.elapsed_us / (double) ns[i] / fastscan_floor_us;
                        printf("%-26s %4zu %10llu %10.1f %12.1f %12.1f %10.2f %9.2fx\n", mode_names[mode], ns[i],
                               (unsigned long long) r.lss_frames, (double) r.lss_frames / ns[i],
                               r.busy_us / 1000.0, r.elapsed_us / 1000.0, per_node, vs);
                }
        printf("# vs floor: (c),(e) LSS frames / 10 per node (target <= 1.5x); (a),(b),(d),(f),(g),(h) elapsed per node / fastscan "
               "floor (target for (a) <= 2x)\n");

        printf("\n# SDO identity discovery (window %u), node-IDs 1..127, N devices at 1..N, same latency\n",
               LSS_SDO_WINDOW_DEFAULT);
        printf("%-26s %4s %10s %10s %12s %12s %12s %10s\n", "case", "N", "requests", "frames", "req floor ms",
               "bus time ms", "elapsed ms", "vs bus");
        const size_t sdo_ns[] = { 0, 8, 32, 127 };
        for (size_t i = 0; i < sizeof(sdo_ns) / sizeof(sdo_ns[0]); i++)
                bad |= run_sdo(sdo_ns[i], 2000 + sdo_ns[i]);
        printf("# req floor: bus time of the requests sent; bus time: of all frames (requests and answers); "
               "vs bus: elapsed / bus time\n");
        if (bad)
                printf("FAILED: mis-assignments or failures (see stderr)\n");
        return bad;
}
