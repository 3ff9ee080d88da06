#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Devices on Lely's LSS slave (lss-sim profile lely: a configured node-ID
takes effect only at NMT Reset Communication or Reset Node, Fastscan
answered in waiting whatever the node-ID, 13 01 without a rate hook), on
vcan0 with candump as the witness and lssd at its default timing (no
lss_timeout_ms in the configuration). `lely.py NAME`:

  pool         blind AutoAssign, pool 71..90, of four: each a node-ID of its
               own, "in effect after the device's next reset"; a broadcast
               reset boots them there, and the next pass finds them unchanged
  mapped       a map of full identities (61..64), and one configured device
               re-addressed (30 -> 65): assigned, pending their reset, the
               configured one at once; after the plant's reset, unchanged
  mapped-reset a map of full identities (61..64) with reset_after_pass: lssd
               resets the bus once and verifies every device by its boot-up
  scan         blind Scan of four non-configured and four configured (10..13):
               each found once with its identity and node-ID, nothing stored
  mixed        lely, canopennode and plain slaves, configured and not: Scan
               finds each once, a blind AutoAssign gives each non-configured
               one a pool node-ID of its own
  bitrate      SetBitrate with four Lely devices (two configured) beside a
               plain one: the first Lely device answers 13 01, the change is
               refused, naming it, before anything changes"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from autoassign import all_waiting  # noqa: E402
from bitrate import expect, expect_eq  # noqa: E402
from lssdtest import BUS_IFACE, DEVICE_IFACE, ERR, Env, Skip, Slave, auto_assign, bus_path, device_path, run  # noqa: E402

B0 = bus_path('vcan0')
V, P, R = 0x1A2, 0xB0B, 0x10002
LELY = [Slave(V, P, R, s, profile='lely') for s in (0x11, 0x22, 0x33, 0x44)]
PENDING = "in effect after the device's next reset"
CS_CONFIGURE_NODE_ID, CS_STORE = 0x11, 0x17


def config(devices=(), **keys):
    """One bus on vcan0 at lssd's default timing: no lss_timeout_ms."""
    def value(v):
        if isinstance(v, bool):
            return 'true' if v else 'false'
        if isinstance(v, list):
            return '[%s]' % ', '.join(str(x) for x in v)
        return '"%s"' % v if isinstance(v, str) else str(v)
    lines = ['buses = ( {', '  interface = "vcan0";']
    lines += ['  %s = %s;' % (k, value(v)) for k, v in keys.items()]
    lines.append('  devices = ( %s );' % ', '.join(
        '{ vendor = 0x%x; product = 0x%x; revision = 0x%x; serial = 0x%x; node_id = %d; }' % (s.identity + (n,))
        for s, n in devices))
    lines.append('} );')
    return '\n'.join(lines) + '\n'


def lely_env(slaves, cfg):
    env = Env({'vcan0': slaves}, config=cfg, candump=True)
    if not env.real:
        raise Skip('the profile lives in lss-sim and in lssd --simulate alike; these checks read its state files')
    return env


def state(env, s):
    st = env.slave_state('vcan0', s.serial)
    return tuple(int(st[k]) for k in ('active_node_id', 'pending_node_id', 'stored_node_id'))


def no_node_id_shared(env, slaves):
    """No node-ID held (active, pending or stored) by two slaves."""
    owner = {}
    for s in slaves:
        for n in set(state(env, s)) - {255}:
            expect(owner.setdefault(n, s.serial) == s.serial,
                   'slaves %x and %x both hold node-ID %d' % (owner[n], s.serial, n))


def requests(env, cs, start=0):
    return [f[2] for f in env.lss_frames('vcan0')[start:] if f[1] == 0x7E5 and f[2][0] == cs]


def bootups(env, start=0):
    return sorted(f[1] - 0x700 for f in env.frames('vcan0')[start:] if 0x701 <= f[1] <= 0x77F and f[2] == b'\0')


def device_state(env, s):
    return env.get(device_path('vcan0', *s.identity), DEVICE_IFACE, 'State')


def test_pool():
    with lely_env(LELY, config(unknown='pool', pool=[71, 90])) as env:
        changes, outcomes, result = auto_assign(env)
        expect_eq(result, 'done', 'result (a device pending its reset is no failure)')
        given = {}
        for s in LELY:
            kind, old, new, detail = outcomes[s.serial]
            expect_eq((kind, old), ('pool', 255), 'outcome of %x (%s)' % (s.serial, detail))
            expect(PENDING in detail, 'the detail says it: %r' % detail)
            expect_eq(state(env, s), (255, new, new), 'state of %x' % s.serial)
            expect_eq(device_state(env, s), 'pending-reset', 'State of %x' % s.serial)
            given[s.serial] = new
        expect_eq(len(set(given.values())), 4, 'four node-IDs %r' % given)
        no_node_id_shared(env, LELY)
        # one Configure Node-ID of the pool per device (before: 71 into each of the four)
        # (the same Configure asked again before another selection is one:
        # a silent or stalled answer is asked again, CI 2026-12-02)
        pool_ids = sorted(n for n in env.configure_node_ids('vcan0') if 71 <= n <= 90)
        expect_eq(pool_ids, sorted(given.values()), 'Configure Node-ID to the pool on the wire')
        expect(all_waiting(env, 'vcan0', LELY), 'a slave left in configuration')
        expect(PENDING in env.lssd_output(), 'the journal says it')

        # the plant's own reset makes it true; the next pass finds them there
        start = len(env.frames('vcan0'))
        os.system('cansend vcan0 000#8200')
        env.wait_until(lambda: len(bootups(env, start)) == 4, what='four boot-ups after the reset')
        expect_eq(bootups(env, start), sorted(given.values()), 'boot-ups at the node-IDs given')
        for s in LELY:
            expect_eq(device_state(env, s), 'pool', 'State of %x after its boot-up' % s.serial)
        start = len(env.lss_frames('vcan0'))
        changes, outcomes, result = auto_assign(env)
        expect_eq(result, 'done', 'second pass')
        # configured and not in the map now: left alone where they are
        expect_eq({k: o[:3] for k, o in outcomes.items()}, {s.serial: ('unknown', n, n) for s, n in
                                                            ((s, given[s.serial]) for s in LELY)}, 'second pass')
        expect_eq(requests(env, CS_CONFIGURE_NODE_ID, start) + requests(env, CS_STORE, start), [],
                  'the second pass configured or stored something')
        env.alive()


def test_mapped():
    moved = Slave(V, P, R, 0x55, 30, profile='lely')
    mapped = [(s, 61 + i) for i, s in enumerate(LELY)] + [(moved, 65)]
    slaves = LELY + [moved]
    with lely_env(slaves, config(mapped)) as env:
        changes, outcomes, result = auto_assign(env)
        expect_eq(result, 'done', 'result (a device pending its reset is no failure)')
        for s, n in mapped[:4]:
            kind, old, new, detail = outcomes[s.serial]
            expect_eq((kind, old, new), ('assigned', 255, n), 'outcome of %x (%s)' % (s.serial, detail))
            expect(PENDING in detail, 'the detail says it: %r' % detail)
            expect_eq(state(env, s), (255, n, n), 'state of %x' % s.serial)
            expect_eq(device_state(env, s), 'pending-reset', 'State of %x' % s.serial)
        # a configured device takes its new node-ID at the NMT Reset Communication on its old one
        kind, old, new, detail = outcomes[moved.serial]
        expect_eq((kind, old, new, detail), ('assigned', 30, 65, ''), 'the configured device')
        expect_eq(state(env, moved), (65, 65, 65), 'state of the configured device')

        # a pass before the reset changes nothing and still says pending
        start = len(env.lss_frames('vcan0'))
        changes, outcomes, result = auto_assign(env)
        expect_eq(result, 'done', 'second pass')
        expect_eq(requests(env, CS_CONFIGURE_NODE_ID, start) + requests(env, CS_STORE, start), [],
                  'the second pass configured or stored something')
        expect_eq(sorted(device_state(env, s) for s, n in mapped[:4]), ['pending-reset'] * 4, 'States before the reset')

        # the plant's reset makes it true; the next pass finds them unchanged
        start = len(env.frames('vcan0'))
        os.system('cansend vcan0 000#8200')
        env.wait_until(lambda: len(bootups(env, start)) == 5, what='five boot-ups after the reset')
        expect_eq(bootups(env, start), [61, 62, 63, 64, 65], 'boot-ups')
        expect_eq(sorted(device_state(env, s) for s, n in mapped), ['assigned'] * 5, 'States after the boot-ups')
        changes, outcomes, result = auto_assign(env)
        expect_eq(result, 'done', 'third pass')
        expect_eq(sorted(o[:3] for o in outcomes.values()), [('unchanged', n, n) for n in range(61, 66)],
                  'third pass')
        env.alive()


def test_mapped_reset():
    mapped = [(s, 61 + i) for i, s in enumerate(LELY)]
    with lely_env(LELY, config(mapped, reset_after_pass=True)) as env:
        start = len(env.frames('vcan0'))
        changes, outcomes, result = auto_assign(env)
        expect_eq(result, 'done', 'result')
        for s, n in mapped:
            kind, old, new, detail = outcomes[s.serial]
            expect_eq((kind, old, new), ('assigned', 255, n), 'outcome of %x (%s)' % (s.serial, detail))
            expect(PENDING not in detail, 'verified by its boot-up: %r' % detail)
            expect_eq(state(env, s), (n, n, n), 'state of %x' % s.serial)
        resets = [f for f in env.frames('vcan0')[start:] if f[1] == 0 and f[2] == b'\x82\x00']
        expect_eq(len(resets), 1, 'one broadcast NMT Reset Communication')
        expect_eq(bootups(env, start), [61, 62, 63, 64], 'boot-ups')
        env.alive()


def scanned(env):
    found = env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)[0]
    return sorted(tuple(x) for x in found)


def test_scan():
    configured = [Slave(V, P, R, 0x100 + i, 10 + i, profile='lely') for i in range(4)]
    slaves = LELY + configured
    with lely_env(slaves, config()) as env:
        before = {s.serial: state(env, s) for s in slaves}
        found = scanned(env)
        expect_eq(found, sorted(s.identity + (s.node_id,) for s in slaves), 'Scan')
        expect_eq({s.serial: state(env, s) for s in slaves}, before, 'the slaves as the Scan found them')
        expect_eq(requests(env, CS_STORE), [], 'Scan stored something')
        expect(all_waiting(env, 'vcan0', slaves), 'a slave left in configuration')
        expect('does not follow CiA 305' not in env.lssd_output(), 'no slave named misbehaving')
        env.alive()


def test_mixed():
    slaves = [Slave(V, P, R, 0x11, profile='lely'), Slave(V, P, R, 0x12, 20, profile='lely'),
              Slave(0x5005, 0x11, 1, 0x55, profile='canopennode'), Slave(0x5005, 0x11, 1, 0x56, profile='canopennode'),
              Slave(0x9A, 3, 1, 0x77), Slave(0x9A, 3, 1, 0x78, 21)]
    with lely_env(slaves, config(unknown='pool', pool=[71, 90])) as env:
        expect_eq(scanned(env), sorted(s.identity + (s.node_id,) for s in slaves), 'Scan')
        expect('does not follow CiA 305' not in env.lssd_output(), 'no slave named misbehaving')
        changes, outcomes, result = auto_assign(env)
        expect_eq(result, 'done', 'result %r' % outcomes)
        for s in slaves:
            if s.node_id != 255:
                # a configured device not in the map is left alone (a compliant one does not even
                # answer Fastscan: no outcome)
                expect(outcomes.get(s.serial, ('unknown', s.node_id, s.node_id))[:3] ==
                       ('unknown', s.node_id, s.node_id), 'configured %x left alone: %r' % (s.serial, outcomes))
                expect_eq(state(env, s), (s.node_id,) * 3, 'state of %x' % s.serial)
                continue
            kind, old, new, detail = outcomes[s.serial]
            expect_eq(kind, 'pool', 'outcome of %x (%s)' % (s.serial, detail))
            active, pending, stored = state(env, s)
            expect_eq((pending, stored), (new, new), 'state of %x' % s.serial)
            expect_eq(active, 255 if s.profile == 'lely' else new, 'in effect: %x' % s.serial)
        no_node_id_shared(env, slaves)
        expect(all_waiting(env, 'vcan0', slaves), 'a slave left in configuration')
        env.alive()


def test_bitrate():
    lely = [Slave(V, P, R, 0x12 + i, 22 + i if i < 2 else 0xFF, profile='lely') for i in range(4)]
    slaves = [Slave(0x9A, 3, 1, 0x77, 21)] + lely
    with lely_env(slaves, config(bitrate_change=True)) as env:
        name, msg = env.call_error(B0, BUS_IFACE, 'SetBitrate', 'uqa{sv}', 250000, 16, 0)
        expect_eq(name, ERR + 'Rejected', 'SetBitrate with Lely devices: ' + msg)
        expect(any('%08x:%08x:%08x:%08x' % s.identity in msg for s in lely), 'a Lely device is named: ' + msg)
        expect_eq([f for f in env.lss_frames('vcan0') if f[1] == 0x7E5 and f[2][0] == 0x15], [],
                  'no Activate Bit Timing on the wire')
        for s in slaves:
            expect_eq(env.slave_state('vcan0', s.serial)['bit_timing_index'], '4', 'bit timing of %x' % s.serial)
        env.alive()


TESTS = {'pool': test_pool, 'mapped': test_mapped, 'mapped-reset': test_mapped_reset, 'scan': test_scan, 'mixed': test_mixed,
         'bitrate': test_bitrate}

if __name__ == '__main__':
    sys.exit(run(TESTS))
