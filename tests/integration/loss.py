#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Frame loss is never a silent miss (issue 38, point 4), on vcan0 with
lss-sim's drop=P and lssd at its default timing (no lss_timeout_ms in the
configuration). `loss.py NAME`:

  pool-drop    16 generic slaves, each losing every frame it receives and
               every frame it sends with probability 0.02 (seeded per
               round); a blind AutoAssign from a pool, 5 rounds, each on
               fresh non-configured slaves and a fresh lssd: every slave
               ends with its pool node-ID in at least 4 rounds, and no
               round replies "done" while a slave is left non-configured"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bitrate import expect  # noqa: E402
from lely import config  # noqa: E402
from lssdtest import Env, Skip, Slave, auto_assign, log, run  # noqa: E402

V, P, R = 0x1A2, 0xC0C, 0x10001
SLAVES = [Slave(V, P, R, 0x7100 + 0x1357 * i, profile='generic') for i in range(16)]
DROP = '0.02'
ROUNDS = 5
POOL = [1, 64]


def one_round(seed):
    """{serial: node-ID it got from the pool, verified on the slave} and the reply."""
    args = ['--fault', 'drop=' + DROP, '--seed', str(seed)]
    with Env({'vcan0': SLAVES}, config=config(unknown='pool', pool=POOL), sim_args=args) as env:
        if not env.real:
            raise Skip("drop is lss-sim's")
        try:
            changes, outcomes, result = auto_assign(env)
        except AssertionError as e:
            # the pass broke off (an error reply): not "done", and no outcomes
            log('round %d: %s' % (seed, e))
            outcomes, result = {}, 'error'
        active = {s.serial: int(env.slave_state('vcan0', s.serial)['active_node_id']) for s in SLAVES}
        left = sorted('%x' % s for s, n in active.items() if n == 255)
        log('round %d: %s, %d outcomes, non-configured left: %s' % (seed, result, len(outcomes), left or 'none'))
        for serial, o in sorted(outcomes.items()):
            if o[0] != 'pool':
                log('  %x: %s %d -> %d %s' % ((serial,) + o))
        for serial in left:
            st = env.slave_state('vcan0', int(serial, 16))
            log('  %s left: %s, pending %s' % (serial, st.get('lss_state'), st.get('pending_node_id')))
        expect(all(p.poll() is None for p in env.sims.values()), 'round %d: lss-sim exited' % seed)
        expect(result != 'done' or not left, 'round %d replied done with slaves %s non-configured' % (seed, left))
        env.alive()
        return {s: o[2] for s, o in outcomes.items() if o[0] == 'pool' and active.get(s) == o[2]}, result


def test_pool_drop():
    assigned = {s.serial: 0 for s in SLAVES}
    for seed in range(1, ROUNDS + 1):
        got, result = one_round(seed)
        expect(len(set(got.values())) == len(got), 'round %d gave a node-ID twice: %r' % (seed, got))
        for serial in got:
            assigned[serial] += 1
    log('rounds in which each slave was assigned: %s' % ', '.join('%x: %d' % kv for kv in sorted(assigned.items())))
    few = sorted('%x (%d)' % kv for kv in assigned.items() if kv[1] < ROUNDS - 1)
    expect(not few, 'assigned in fewer than %d of %d rounds: %s' % (ROUNDS - 1, ROUNDS, few))


TESTS = {'pool-drop': test_pool_drop}

if __name__ == '__main__':
    sys.exit(run(TESTS))
