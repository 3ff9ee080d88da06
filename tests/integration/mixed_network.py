#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""The mixed network of issue 38 at lssd's default timing (no lss_timeout_ms
in the configuration), on vcan0 with lss-sim: configured `generic` slaves of
three vendors (nodes 20..22), two non-configured ones of a vendor not in the
map, and a configured CANopenNode v4 slave (node 23) that the map moves to 30.
`mixed_network.py NAME`:

  rounds   LSSD_TEST_ROUNDS rounds (default 1), fresh slaves each: Scan
           finds all 6 with their identities and node-IDs; AutoAssign
           (unknown = "ignore") moves 0x5001 to 30 and touches nothing else;
           SetBitrate 250000 (50 ms delay) switches all 6 to bit timing
           index 3 and stores it
  loaded   the same with a spinning process on every CPU (LSSD_TEST_ROUNDS,
           default 1)"""

import multiprocessing
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from autoassign import all_waiting  # noqa: E402
from bitrate import expect, expect_eq  # noqa: E402
from lssdtest import BUS_IFACE, Env, Skip, Slave, auto_assign, bus_path, log, run  # noqa: E402

B0 = bus_path('vcan0')
CONFIGURED = [Slave(0x11, 0x1, 0x1, 0x1101, 20), Slave(0x22, 0x2, 0x3, 0x2202, 21), Slave(0x33, 0x7, 0x1, 0x3303, 22)]
UNKNOWN = [Slave(0x44, 0x4, 0x1, 0x4404), Slave(0x44, 0x4, 0x1, 0x4405)]
MOVED = Slave(0x55, 0x1, 0x2, 0x5001, 23, profile='canopennode-bitrate')
SLAVES = CONFIGURED + UNKNOWN + [MOVED]
CONFIG = """buses = ( {
  interface = "vcan0";
  bitrate = 125000;
  bitrate_change = true;
  unknown = "ignore";
  devices = ( { vendor = 0x55; product = 0x1; serial = 0x5001; node_id = 30; } );
} );
"""


def node_ids(env):
    return {s.serial: int(env.slave_state('vcan0', s.serial)['active_node_id']) for s in SLAVES}


def one_round(n):
    with Env({'vcan0': SLAVES}, config=CONFIG, sim_args=['--bitrate', '125000'], candump=True) as env:
        if not env.real:
            raise Skip('the checks read lss-sim state files')
        env.step('round %d: Scan' % n)
        found = env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)[0]
        expect_eq(sorted(tuple(x) for x in found), sorted(s.identity + (s.node_id,) for s in SLAVES),
                  'Scan of round %d' % n)
        before = node_ids(env)

        env.step('round %d: AutoAssign' % n)
        changes, outcomes, result = auto_assign(env)
        expect_eq(result, 'done', 'AutoAssign of round %d (%r)' % (n, outcomes))
        expect_eq([c[3:] for c in changes], [[0x5001, 23, 30]], 'AutoAssign changes of round %d' % n)
        expect_eq(node_ids(env), {**before, 0x5001: 30}, 'node-IDs after AutoAssign, round %d' % n)
        expect(all_waiting(env, 'vcan0', SLAVES), 'a slave left in configuration')

        env.step('round %d: SetBitrate 250000' % n)
        reply = env.call(B0, BUS_IFACE, 'SetBitrate', 'uqa{sv}', 250000, 50, 0)[0]
        # store is on (the default): each switched and stored
        expect_eq(sorted((tuple(d[:4]), d[4]) for d in reply), sorted((s.identity, 'stored') for s in SLAVES),
                  'SetBitrate reply of round %d' % n)
        for s in SLAVES:
            expect_eq(int(env.slave_state('vcan0', s.serial)['bit_timing_index']), 3,
                      'bit timing index of %x, round %d' % (s.serial, n))
        env.alive()


def rounds():
    for n in range(1, int(os.environ.get('LSSD_TEST_ROUNDS', '1')) + 1):
        one_round(n)
        log('round %d right' % n)


def spin():
    while True:
        pass


def test_rounds():
    rounds()


def test_loaded():
    spinners = [multiprocessing.Process(target=spin, daemon=True) for _ in range(os.cpu_count() or 1)]
    for p in spinners:
        p.start()
    try:
        rounds()
    finally:
        for p in spinners:
            p.terminate()


if __name__ == '__main__':
    run({'rounds': test_rounds, 'loaded': test_loaded})
