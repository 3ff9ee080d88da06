/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The simulation's pseudo-random numbers (slave jitter and frame loss,
 * lss-sim --random, the tests' made-up identities): splitmix64, small, good
 * enough, and deterministic for a given seed. */
#pragma once

#include <stdint.h>

static inline uint64_t sim_random_next(uint64_t *state) {
        uint64_t z = (*state += UINT64_C(0x9E3779B97F4A7C15));
        z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
        z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
        return z ^ (z >> 31);
}

/* The seed of slave number `index` (0, 1, ...) of a bus or simulator seeded
 * with `seed`: one stream per slave, so adding a slave changes no other's. */
static inline uint64_t sim_random_slave_seed(uint64_t seed, uint64_t index) {
        return seed ^ (UINT64_C(0x9E3779B97F4A7C15) * (index + 1));
}
