#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""A Scan leaves a running plant as it was (issue 39, point 1), on vcan0 with
lss-sim, candump as the witness and lssd at its default timing.
`scan_untouched.py NAME`:

  compliant  8 non-configured and 2 configured `generic` slaves: the Scan
             finds all 10 and puts no NMT command (COB 000), no Configure
             Node-ID (7E5#11...) and no boot-up (0x701-0x77F) on the bus;
             every slave's state file ends as it began
  bent       4 non-configured `generic` and 2 non-configured `canopennode`
             slaves: all 6 found, at most 2 Configure Node-ID requests other
             than 255 (the CANopenNode slaves set aside), every slave back
             at 255 and in waiting"""

import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bitrate import expect, expect_eq  # noqa: E402
from lssdtest import BUS_IFACE, Env, Skip, Slave, bus_path, configure_node_ids, log, run  # noqa: E402

B0 = bus_path('vcan0')
CONFIG = 'buses = ( { interface = "vcan0"; bitrate = 125000; } );\n'
CS_CONFIGURE_NODE_ID = 0x11
STATE_KEYS = ('active_node_id', 'pending_node_id', 'stored_node_id', 'lss_state', 'nmt_state')


def states(env, slaves):
    return {s.serial: {k: env.slave_state('vcan0', s.serial).get(k) for k in STATE_KEYS} for s in slaves}


def scan(slaves):
    """Scan the bus; returns (env's frames during the Scan, states before, after)."""
    with Env({'vcan0': slaves}, config=CONFIG, candump=True) as env:
        if not env.real:
            raise Skip('the checks read candump and lss-sim state files')
        before = states(env, slaves)
        start = len(env.frames('vcan0'))
        found = env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)[0]
        expect_eq(sorted(tuple(x) for x in found), sorted(s.identity + (s.node_id,) for s in slaves), 'Scan result')
        time.sleep(0.5)  # the Scan's last frames reach candump
        frames = env.frames('vcan0')[start:]
        return frames, before, states(env, slaves)


def test_compliant():
    slaves = [Slave(0xEC, 0x1234, 1, 0x100 + i) for i in range(8)]
    slaves += [Slave(0x9A, 3, 1, 0x200 + i, 20 + i) for i in range(2)]
    frames, before, after = scan(slaves)
    nmt = [f for f in frames if f[1] == 0x000]
    configure = [f for f in frames if f[1] == 0x7E5 and f[2][:1] == bytes([CS_CONFIGURE_NODE_ID])]
    bootups = [f for f in frames if 0x701 <= f[1] <= 0x77F]
    log('%d frames on the bus during the Scan' % len(frames))
    expect_eq(nmt, [], 'NMT commands')
    expect_eq(configure, [], 'Configure Node-ID requests')
    expect_eq(bootups, [], 'boot-ups')
    expect_eq(after, before, 'slave states')


def test_bent():
    slaves = [Slave(0xEC, 0x1234, 1, 0x100 + i) for i in range(4)]
    slaves += [Slave(0x55, 0x1, 2, 0x500 + i, profile='canopennode') for i in range(2)]
    frames, before, after = scan(slaves)
    temporary = [n for n in configure_node_ids(frames) if n != 255]
    log('temporary node-IDs on the bus: %r' % temporary)
    expect(len(temporary) <= 2, 'at most 2 Configure Node-ID other than 255: %r' % temporary)
    for s in slaves:
        expect_eq((after[s.serial]['active_node_id'], after[s.serial]['pending_node_id'],
                   after[s.serial]['lss_state']), ('255', '255', 'waiting'), 'state of %x' % s.serial)


if __name__ == '__main__':
    run({'compliant': test_compliant, 'bent': test_bent})
