#!/usr/bin/env python3
"""Slaves that bend CiA 305, on real SocketCAN with candump as the witness:
CANopenNode v4 slaves (lss-sim's canopennode profile answers every Fastscan
in configuration state), a slave that answers every Fastscan request,
devices that cannot store, and a raw Fastscan nobody answers. Every pass
ends; nothing unconfirmed is reported; Scan leaves the bus as it found it.

Run as: bent.py NAME (see TESTS). The faults live in lss-sim: on lssd
--simulate these tests skip."""
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import dbusmini  # noqa: E402
from autoassign import all_waiting, config, slave_ids  # noqa: E402
from ctl import Ctl  # noqa: E402
from lssdtest import BUS_IFACE, ERR, SERVICE, Env, Skip, Slave, auto_assign, bus_path, run  # noqa: E402

B0 = bus_path('vcan0')
V, P, R = 0x1F, 0x77, 4
CS_FASTSCAN = 0x51


def expect(cond, what):
    if not cond:
        raise AssertionError(what)


def expect_eq(got, want, what):
    if got != want:
        raise AssertionError('%s: got %r, want %r' % (what, got, want))


def real_env(slaves, cfg, **kw):
    env = Env({'vcan0': slaves}, config=cfg, candump=True, **kw)
    if not env.real:
        raise Skip('the slaves bend CiA 305 inside lss-sim')
    return env


def name(s):
    return '%08x:%08x:%08x:%08x' % s.identity


def timed(env, what, fn):
    t = time.monotonic()
    out = fn()
    env.step('%s took %.2f s' % (what, time.monotonic() - t))
    return out


def untouched(env, slaves):
    return all(slave_ids(env, 'vcan0', [s])[s.serial] == (255, 255) and
               env.slave_state('vcan0', s.serial).get('pending_node_id') == '255' for s in slaves)


def test_canopennode():
    slaves = [Slave(V, P, R, 0xC0DE0000 + i) for i in range(5)]
    four, extra = slaves[:4], slaves[4]
    cfg = config('vcan0', [], unknown='pool', pool=[20, 40])
    with real_env(four, cfg, sim_args=['--profile', 'canopennode']) as env:
        # Scan finds all four and leaves them as they were
        found = timed(env, 'Scan of 4 CANopenNode slaves', lambda: env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)[0])
        expect_eq(sorted(tuple(x) for x in found), sorted(s.identity + (255,) for s in four), 'Scan')
        expect(untouched(env, four), 'Scan left a node-ID behind: %r' % slave_ids(env, 'vcan0', four))
        expect(all_waiting(env, 'vcan0', four), 'Scan left a slave in configuration')
        log = env.lssd_output()
        for s in four:
            expect('Scan set %s aside' % name(s) in log, 'no journal line for the set-aside %s' % name(s))
        # each was set aside with a volatile node-ID and given 255 back
        # (asked again right after itself, its answer stalled, is one: CI 2026-12-02)
        nodes = env.configure_node_ids('vcan0')
        expect_eq(nodes.count(255), 4, 'Configure Node-ID 255 of the give-back (%r)' % nodes)
        expect(not any(f[1] == 0x7E5 and f[2][0] == 0x17 for f in env.lss_frames('vcan0')), 'Scan stored something')

        # blind AutoAssign from the pool: every one gets a node-ID
        start = len(env.lss_frames('vcan0'))
        changes, outcomes, result = timed(env, 'blind AutoAssign of 4', lambda: auto_assign(env))
        expect_eq(result, 'done', 'blind AutoAssign result')
        expect_eq(sorted(o[0] for o in outcomes.values()), ['pool'] * 4, 'blind AutoAssign outcomes')
        ids = slave_ids(env, 'vcan0', four)
        got = {c[3]: c[5] for c in changes}
        expect_eq(ids, {s: (n, n) for s, n in got.items()}, 'the slaves have what the reply says')
        expect(len(set(got.values())) == 4 and all(20 <= n <= 40 for n in got.values()), 'pool node-IDs %r' % got)
        # each takes its pool node-ID the moment it is found: one Configure
        # Node-ID each, none set aside with a temporary node-ID and given 255 back
        nodes = env.configure_node_ids('vcan0', start)
        expect_eq(sorted(nodes), sorted(got.values()), 'Configure Node-ID requests of the blind AutoAssign')
        expect(all_waiting(env, 'vcan0', four), 'AutoAssign left a slave in configuration')
        env.alive()

    # mapped by serial, with one unmapped non-configured slave more: reported, left alone
    cfg = config('vcan0', [(s.serial, 10 + i) for i, s in enumerate(four)], vendor=hex(V), product=hex(P),
                 unknown='ignore')
    with real_env(slaves, cfg, sim_args=['--profile', 'canopennode']) as env:
        changes, outcomes, result = timed(env, 'mapped AutoAssign of 4 + 1', lambda: auto_assign(env))
        expect_eq(result, 'done', 'mapped AutoAssign result')
        expect_eq(outcomes[extra.serial][0], 'unknown', 'the unmapped slave')
        expect_eq(slave_ids(env, 'vcan0', four), {s.serial: (10 + i, 10 + i) for i, s in enumerate(four)},
                  'mapped slaves')
        expect(untouched(env, [extra]), 'the unmapped slave was changed: %r' % slave_ids(env, 'vcan0', [extra]))
        env.alive()


def test_fastscan_any():
    # the worst case: one slave answers every Fastscan request in every state
    others = [Slave(V, P, R, 0xA0 + i) for i in range(3)]
    bad = Slave(V, P, R, 0xBAD, faults=['fastscan-any'])
    cfg = config('vcan0', [], unknown='pool', pool=[20, 40])
    with real_env(others + [bad], cfg) as env:
        for method in ('Scan', 'AutoAssign'):
            err, msg = timed(env, method + ' with the worst case',
                             lambda: env.call_error(B0, BUS_IFACE, method, 'a{sv}', 0))
            expect_eq(err, ERR + 'Conflict', method + ' error')
            expect(name(bad) in msg, '%s names the slave: %r' % (method, msg))
            expect(untouched(env, others), 'others changed by %s: %r' % (method, slave_ids(env, 'vcan0', others)))
            expect(all_waiting(env, 'vcan0', others + [bad]), 'a slave left in configuration by ' + method)
        expect(name(bad) in env.lssd_output(), 'the journal names the slave')
        env.alive()


def test_cannot_store():
    # a device answers Store Configuration with error 1: assigned, not stored, no failure
    s = Slave(0x9A, 3, 1, 0x5707, faults=['store-unsupported'])
    cfg = config('vcan0', [(s.serial, 12)], vendor='0x9A', product='0x3')
    with real_env([s], cfg) as env:
        ctl = Ctl(env)
        for boot in ('first pass', 'after a power cycle'):
            r = ctl('auto-assign')
            expect_eq(r.rc, 0, 'lssctl auto-assign %s (%r)' % (boot, r.err))
            expect('not stored (device cannot store: storing not supported)' in r.out,
                   'lssctl says it is not stored (%s): %r' % (boot, r.out))
            expect_eq(slave_ids(env, 'vcan0', [s])[s.serial], (12, 255), 'the slave ' + boot)
            env.restart_sim('vcan0', [s])
            expect_eq(slave_ids(env, 'vcan0', [s])[s.serial], (255, 255), 'the slave powered off and on')
        r = ctl('auto-assign', '--json')
        got = [x for x in json.loads(r.out) if x['serial'] == s.serial]
        expect_eq([(x['outcome'], x['detail']) for x in got],
                  [('assigned', 'not stored (device cannot store: storing not supported)')], '--json')
        env.alive()


def test_raw_fastscan_nobody():
    with real_env([], None) as env:
        holder = env.connect()
        holder.call(SERVICE, B0, BUS_IFACE, 'Acquire', '', [], timeout=60)
        try:
            holder.call(SERVICE, B0, BUS_IFACE, 'Fastscan', 'a{sv}', [{}], timeout=60)
            raise AssertionError('Fastscan with nobody on the bus succeeded')
        except dbusmini.DBusError as e:
            expect_eq(e.name, ERR + 'NotFound', 'Fastscan with nobody')
            expect('no device' in e.message, 'Fastscan error: %r' % e.message)
        expect(any(f[1] == 0x7E5 and f[2][0] == CS_FASTSCAN for f in env.lss_frames('vcan0')),
               'no Fastscan request on the wire')
        holder.call(SERVICE, B0, BUS_IFACE, 'Release', '', [], timeout=60)
        env.alive()


TESTS = {
    'canopennode': test_canopennode,
    'fastscan-any': test_fastscan_any,
    'cannot-store': test_cannot_store,
    'raw-fastscan-nobody': test_raw_fastscan_nobody,
}

if __name__ == '__main__':
    sys.exit(run(TESTS))
