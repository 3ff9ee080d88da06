#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""AutoAssign's reading of object 1018h by SDO (issue 18), end to end:
`autoassign_sdo.py NAME` runs one scenario (meson test per name). The
helpers are autoassign.py's."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from autoassign import all_waiting, assigning_configures, config, configure_or_store, dev, expect, expect_eq, slave_ids  # noqa: E402
from lssdtest import DEVICE_IFACE, Env, Slave, auto_assign, run  # noqa: E402

# ---- devices without identify services (CANopenNode), map without revisions (issue 18) ----

CO_V, CO_P = 0x5005, 0x11
CO_A = Slave(CO_V, CO_P, 0x20003, 0xC0A, 40, profile='canopennode')  # mapped to 5, configured with 40
CO_B = Slave(CO_V, CO_P, 0x20004, 0xC0B, profile='canopennode')      # mapped to 6, non-configured
CO_MAP = [(CO_A.serial, 5), (CO_B.serial, 6)]


def sdo_1018_requests(frames):
    """The node-IDs of the master's SDO upload requests of 1018h."""
    return [f[1] - 0x600 for f in frames if 0x601 <= f[1] <= 0x67F and f[2][1:3] == b'\x18\x10']


def test_canopennode_no_revision():
    """A map without revisions, CANopenNode-like devices (no identify
    remote): the one configured at another node-ID is found by reading 1018h
    by SDO and moved, the non-configured one by fastscan. A second pass
    changes nothing."""
    cfg = config('vcan0', CO_MAP, vendor=hex(CO_V), product=hex(CO_P))
    with Env({'vcan0': [CO_A, CO_B]}, config=cfg, candump=True) as env:
        got, outcomes, result = auto_assign(env)
        expect_eq({k: v[:3] for k, v in outcomes.items()},
                  {CO_A.serial: ('assigned', 40, 5), CO_B.serial: ('assigned', 255, 6)}, 'AutoAssign outcomes')
        expect_eq(result, 'done', 'AutoAssign result')
        for s, node in ((CO_A, 5), (CO_B, 6)):
            p = dev('vcan0', s)
            expect_eq((env.get(p, DEVICE_IFACE, 'State'), env.get(p, DEVICE_IFACE, 'NodeId')), ('assigned', node),
                      'State, NodeId of %x' % s.serial)
        if env.real:
            expect_eq(slave_ids(env, 'vcan0', [CO_A, CO_B]), {CO_A.serial: (5, 5), CO_B.serial: (6, 6)},
                      'slaves after the pass')
            expect(all_waiting(env, 'vcan0', [CO_A, CO_B]), 'slaves left in configuration')
            frames = env.frames('vcan0')
            expect_eq(sorted(assigning_configures(frames)), [5, 6], 'Configure Node-ID requests')
            asked = sdo_1018_requests(frames)
            expect(40 in asked and set(range(1, 128)) <= set(asked), 'SDO 1018h read at 1..127: %r' % sorted(set(asked)))
            # it reads: every SDO request of the master is an upload (0x40)
            sdo = [f for f in frames if 0x601 <= f[1] <= 0x67F]
            expect(all(f[2][0] == 0x40 for f in sdo), 'SDO requests other than uploads: %r' %
                   [f for f in sdo if f[2][0] != 0x40][:3])
            expect((0, b'\x82\x28') in [(f[1], f[2]) for f in frames], 'NMT Reset Communication to the old ID 40')
            for node in (5, 6):
                expect(any(f[1] == 0x700 + node and f[2] == b'\x00' for f in frames), 'boot-up of node %d' % node)
            n = len(frames)

        _, outcomes, result = auto_assign(env)
        expect_eq({k: v[:3] for k, v in outcomes.items()},
                  {CO_A.serial: ('unchanged', 5, 5), CO_B.serial: ('unchanged', 6, 6)}, 'second pass')
        expect_eq(result, 'done', 'second AutoAssign result')
        if env.real:
            expect_eq(configure_or_store(env.frames('vcan0')[n:]), [], '0x11/0x17 frames in the second pass')
        env.alive()


TESTS = {
    'canopennode-no-revision': test_canopennode_no_revision,
}

if __name__ == '__main__':
    sys.exit(run(TESTS))
