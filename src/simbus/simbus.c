/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "simbus/simbus.h"
#include "sim/membus.h"
#include "util/time_util.h"

struct simbus {
        membus *bus;
        uint64_t t0; /* CLOCK_MONOTONIC µs at virtual time 0 */
        uint64_t requests;       /* LSS requests the master wrote */
        simbus_foreign foreign;  /* another master, once `requests` reaches its `after` */
        bool foreign_armed;
};

static uint64_t monotonic_us(void) {
        return clock_now_us(CLOCK_MONOTONIC);
}

/* Run the simulation up to the real present. */
static void catch_up(simbus *s) {
        uint64_t now = monotonic_us();
        if (now > s->t0 && now - s->t0 > membus_now(s->bus))
                membus_advance(s->bus, now - s->t0);
}

/* The other master starts: its requests, `period_ms` apart from now. */
static void foreign_start(simbus *s) {
        lss_frame f = { .id = LSS_COB_MASTER, .len = 8,
                        .data = { LSS_CS_INQUIRE_VENDOR, 0xF0, 0xF0, 0xF0, 0xF0, 0xF0, 0xF0, 0xF0 } };
        for (unsigned k = 0; k < s->foreign.count; k++)
                membus_inject(s->bus, &f, membus_now(s->bus) + (uint64_t) k * s->foreign.period_ms * 1000u);
        s->foreign_armed = false;
}

static int sim_send(void *impl, const lss_frame *f) {
        simbus *s = impl;
        catch_up(s);
        membus_master_send(s->bus, f);
        if (!lss_is_request(f))
                return 0;
        s->requests++;
        if (s->foreign_armed && (s->foreign.after_cs ? f->data[0] == s->foreign.after_cs :
                                                            s->requests >= s->foreign.after))
                foreign_start(s);
        return 0;
}

void simbus_add_foreign(simbus *s, const simbus_foreign *f) {
        catch_up(s);
        s->foreign = *f;
        s->foreign_armed = f->count > 0;
        if (s->foreign_armed && !f->after_cs && f->after <= s->requests)
                foreign_start(s);
}

struct membus *simbus_bus(simbus *s) {
        catch_up(s);
        return s->bus;
}


static int sim_recv(void *impl, lss_frame *f, uint64_t *rx_us) {
        simbus *s = impl;
        uint64_t t;
        catch_up(s);
        if (!membus_master_recv(s->bus, f, &t))
                return 0;
        *rx_us = t + s->t0;
        return 1;
}

static int sim_get_fd(void *impl) {
        return -1;
}

static uint64_t sim_now(void *impl) {
        return monotonic_us();
}

static void sim_close(void *impl) {
        simbus *s = impl;
        if (!s)
                return;
        membus_free(s->bus);
        free(s);
}

/* SetBitrate: the simulated host controller follows at once. */
static int sim_retune_start(void *impl, uint32_t bitrate, lss_retune_wait *wait) {
        simbus *s = impl;
        catch_up(s);
        membus_set_bitrate(s->bus, bitrate);
        return 1;
}

static uint64_t sim_next_event(void *impl) {
        simbus *s = impl;
        uint64_t t = membus_next_event(s->bus);
        return t == UINT64_MAX ? UINT64_MAX : t + s->t0;
}

static const lss_transport_ops sim_ops = {
        .kind = "simulated",
        .send = sim_send,
        .recv = sim_recv,
        .get_fd = sim_get_fd,
        .now = sim_now,
        .next_event = sim_next_event,
        .retune_start = sim_retune_start,
        .close = sim_close,
};

/* LSSD_SIM_TRACE=1: every frame on the simulated wire to stderr, candump style. */
static void trace_frame(void *ud, const lss_frame *f, uint64_t t_us) {
        const simbus *s = ud;
        char buf[64];
        fprintf(stderr, "(%" PRIu64 ".%06" PRIu64 ") sim %s\n", (t_us + s->t0) / 1000000u, (t_us + s->t0) % 1000000u,
                lss_frame_format(f, buf, sizeof(buf)));
}

int simbus_new(uint32_t bitrate, simbus **ret) {
        simbus *s = calloc(1, sizeof(*s));
        if (!s)
                return -ENOMEM;
        s->bus = membus_new(bitrate);
        if (!s->bus) {
                free(s);
                return -ENOMEM;
        }
        s->t0 = monotonic_us();
        /* identical answers that wait for the wire together go out as one frame, as on CAN */
        membus_set_merge_identical(s->bus, true);
        if (getenv("LSSD_SIM_TRACE"))
                membus_set_trace(s->bus, trace_frame, s);
        *ret = s;
        return 0;
}

void simbus_profile_faults(simbus_profile profile, lss_slave_faults *f) {
        switch (profile) {
        case SIMBUS_CANOPENNODE:
        case SIMBUS_CANOPENNODE_BITRATE:
                lss_slave_faults_canopennode(f);
                f->bit_timing_silent = profile == SIMBUS_CANOPENNODE;
                break;
        case SIMBUS_LELY:
                lss_slave_faults_lely(f);
                break;
        case SIMBUS_NO_SELECTIVE_SWITCH:
                lss_slave_faults_default(f);
                f->ignore_cs = LSS_CS_SWITCH_SEL_VENDOR;
                break;
        default:
                lss_slave_faults_default(f);
                break;
        }
}

int simbus_add_slave(simbus *s, const lss_identity *id, uint8_t node_id, simbus_profile profile) {
        lss_slave_faults faults;
        simbus_profile_faults(profile, &faults);
        /* a little latency, as real slaves have */
        faults.latency_us = 500;
        catch_up(s);
        size_t i = membus_add_slave(s->bus, id, node_id, &faults);
        if (i == SIZE_MAX)
                return -ENOMEM;
        /* The slaves were running before lssd started, as on a machine whose
         * devices boot faster than it: their power-on boot-up is not on the
         * bus lssd sees (one would look like a pending ID taken at lssd's
         * switch to waiting, see lssd_bus.h). */
        lss_slave *sl = membus_slave(s->bus, i);
        lss_slave_emit_fn emit = sl->emit;
        sl->emit = NULL;
        lss_slave_power_on(sl, membus_now(s->bus));
        sl->emit = emit;
        return 0;
}

void simbus_transport(simbus *s, lss_transport *ret) {
        *ret = (lss_transport) { .ops = &sim_ops, .impl = s };
}

static int parse_u32(const char *s, uint32_t *ret) {
        char *end;
        errno = 0;
        unsigned long long v = strtoull(s, &end, 0);
        if (errno || end == s || *end || v > UINT32_MAX || s[0] == '-')
                return -EINVAL;
        *ret = (uint32_t) v;
        return 0;
}

/* spec's ':'-separated fields into buf (of `size`): their count, or -1 when
 * spec is too long, has more than `max` fields or an interface name too
 * long for one (the first field). */
static int split_spec(const char *spec, char *buf, size_t size, char **fields, size_t max) {
        size_t n = 0;
        if (!spec || strlen(spec) >= size)
                return -1;
        strcpy(buf, spec);
        for (char *p = buf, *save = NULL, *t; n <= max && (t = strtok_r(p, ":", &save)); p = NULL)
                if (n < max)
                        fields[n++] = t;
                else
                        return -1;
        return n > 0 && strlen(fields[0]) <= 15 ? (int) n : -1;
}

static int parse_in(const char *s, uint32_t lo, uint32_t hi, unsigned *ret) {
        uint32_t v;
        if (parse_u32(s, &v) < 0 || v < lo || v > hi)
                return -EINVAL;
        *ret = v;
        return 0;
}

int simbus_foreign_parse(const char *spec, simbus_foreign *ret) {
        char buf[64], *fields[4];
        int n = split_spec(spec, buf, sizeof(buf), fields, 4);
        if (n < 2)
                return -EINVAL;
        simbus_foreign f = { .count = 1, .period_ms = 100 };
        unsigned cs;
        if (fields[1][0] == '@') {
                if (parse_in(fields[1] + 1, 1, 255, &cs) < 0)
                        return -EINVAL;
                f.after_cs = (int) cs;
        } else if (parse_in(fields[1], 0, 1000000, &f.after) < 0)
                return -EINVAL;
        if ((n > 2 && parse_in(fields[2], 1, 100000, &f.count) < 0) ||
            (n > 3 && parse_in(fields[3], 1, 60000, &f.period_ms) < 0))
                return -EINVAL;
        strcpy(f.ifname, fields[0]);
        *ret = f;
        return 0;
}

static const char *const profile_names[] = {
        [SIMBUS_CANOPENNODE] = "canopennode",
        [SIMBUS_CANOPENNODE_BITRATE] = "canopennode-bitrate",
        [SIMBUS_NO_SELECTIVE_SWITCH] = "no-selective-switch",
        [SIMBUS_LELY] = "lely",
};

static int parse_profile(const char *name, simbus_profile *ret) {
        for (size_t i = 1; i < sizeof(profile_names) / sizeof(profile_names[0]); i++)
                if (strcmp(name, profile_names[i]) == 0) {
                        *ret = (simbus_profile) i;
                        return 0;
                }
        return -EINVAL;
}

int simbus_slave_parse(const char *spec, char ifname[16], lss_identity *id, uint8_t *node_id,
                       simbus_profile *profile) {
        char buf[128], *fields[7];
        int n = split_spec(spec, buf, sizeof(buf), fields, 7);
        if (n < 5)
                return -EINVAL;
        *profile = SIMBUS_PLAIN;
        if (n == 7 && parse_profile(fields[6], profile) < 0)
                return -EINVAL;
        if (n == 7)
                n = 6;

        uint32_t v[5] = { 0, 0, 0, 0, LSS_NODE_ID_UNCONFIGURED };
        for (int i = 1; i < n; i++)
                if (parse_u32(fields[i], &v[i - 1]) < 0)
                        return -EINVAL;
        if (v[4] != LSS_NODE_ID_UNCONFIGURED && !lss_node_id_valid(v[4]))
                return -EINVAL;

        strcpy(ifname, fields[0]);
        *id = (lss_identity) { .vendor = v[0], .product = v[1], .revision = v[2], .serial = v[3] };
        *node_id = (uint8_t) v[4];
        return 0;
}
