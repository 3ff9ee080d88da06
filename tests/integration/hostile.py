#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Hostile and heavy clients: `hostile.py NAME` runs one (meson test per name).

Floods from one connection and from many, a client that queues a job and
leaves, a holder that never lets go, 10,000 jobs with lssd's fds and memory
watched, and argument values that make lssd quote odd text in its errors.
Every call must get a reply or a D-Bus error and lssd must stay up."""

import json
import os
import subprocess
import sys
import threading
import time
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import dbusmini  # noqa: E402
from lssdtest import (ACCESS_DENIED, BUS_IFACE, DEVICE_IFACE, ERR, INVALID_ARGS, MANAGER, MANAGER_IFACE,  # noqa: E402
                      SERVICE, SOURCE_ROOT, Env, Skip, Slave, bus_path, device_path, log, run)

B0 = bus_path('vcan0')
SLAVES = [Slave(0x9A, 3, 1, 100 + i, 10 + i) for i in range(4)]
# errors a flooded lssd (or the bus daemon in front of it) may answer with
LIMIT_ERRORS = (ERR + 'LimitsExceeded', 'org.freedesktop.DBus.Error.LimitsExceeded')


def expect(cond, what):
    if not cond:
        raise AssertionError(what)


def expect_eq(got, want, what):
    if got != want:
        raise AssertionError('%s: got %r, want %r' % (what, got, want))


def select_inquire(s):
    return [[('SwitchModeSelective', ('(uuuu)', s.identity)), ('InquireNodeId', ('b', True))]]


def pipelined(c, calls, timeout=600):
    """Sends every call before reading any reply; returns results (reply body or DBusError) in order."""
    serials = [c.send(SERVICE, *call) for call in calls]
    out = []
    for s in serials:
        try:
            out.append(c.wait_reply(s, timeout))
        except dbusmini.DBusError as e:
            out.append(e)
    return out


def flood_calls(n, k=0):
    """n calls of every kind: jobs, property reads, bad arguments, a raw call without holding."""
    calls = []
    for i in range(n):
        s = SLAVES[(k + i) % len(SLAVES)]
        kind = i % 5
        if kind in (0, 1):
            calls.append((B0, BUS_IFACE, 'Execute', 'a(sv)', select_inquire(s)))
        elif kind == 2:
            calls.append((B0, 'org.freedesktop.DBus.Properties', 'Get', 'ss', [BUS_IFACE, 'State']))
        elif kind == 3:
            calls.append((B0, BUS_IFACE, 'Execute', 'a(sv)', [[('ConfigureNodeId', ('y', 0))]]))
        else:
            calls.append((B0, BUS_IFACE, 'InquireNodeId', '', []))
    return calls


def judge(results, n, k=0):
    """Failures: answers that are neither the right reply nor an expected error."""
    bad, limited, timing = [], 0, 0
    for i, r in enumerate(results):
        s = SLAVES[(k + i) % len(SLAVES)]
        kind = i % 5
        if isinstance(r, dbusmini.DBusError) and r.name in LIMIT_ERRORS:
            limited += 1
            continue
        if kind in (0, 1):
            if r == [[('b', True), ('y', s.node_id)]]:
                continue
            if r == [[('b', False), ('y', s.node_id)]] or (isinstance(r, dbusmini.DBusError) and
                                                            r.name == ERR + 'NoResponse'):
                timing += 1  # a loaded host: late answer, not a wrong one
                continue
        elif kind == 2 and not isinstance(r, dbusmini.DBusError):
            continue
        elif kind == 3 and isinstance(r, dbusmini.DBusError) and r.name == INVALID_ARGS:
            continue
        elif kind == 4 and isinstance(r, dbusmini.DBusError) and r.name == ERR + 'NotHeld':
            continue
        bad.append('call %d (kind %d): %r' % (i, kind, r))
    return bad, limited, timing


def lssd_usage(env):
    """(open fds, VmRSS in KiB) of lssd."""
    pid = env.lssd.pid
    fds = len(os.listdir('/proc/%d/fd' % pid))
    rss = 0
    with open('/proc/%d/status' % pid) as f:
        for line in f:
            if line.startswith('VmRSS:'):
                rss = int(line.split()[1])
    return fds, rss


def sanitized(env):
    """lssd runs under ASan or valgrind: RSS says nothing about leaks (quarantine, shadow memory)."""
    if os.environ.get('LSSD_TEST_WRAPPER'):
        return True
    try:
        with open('/proc/%d/maps' % env.lssd.pid) as f:
            maps = f.read()
    except OSError:
        return False
    return 'libasan' in maps or 'libubsan' in maps or '__asan' in maps


def test_flood_one():
    """1000 calls from one connection, all sent before any reply is read."""
    n = 1000
    with Env({'vcan0': SLAVES}) as env:
        c = env.connect()
        t = time.monotonic()
        results = pipelined(c, flood_calls(n))
        bad, limited, timing = judge(results, n)
        log('%d calls answered in %.1f s: %d refused for limits, %d timing misses, %d wrong' %
            (len(results), time.monotonic() - t, limited, timing, len(bad)))
        expect(not bad, 'wrong answers: %s' % bad[:5])
        expect(timing <= n // 50, 'too many timing misses: %d' % timing)
        env.alive()
        expect_eq(env.get(B0, BUS_IFACE, 'QueueLength'), 0, 'queue empty afterwards')
        expect_eq(env.get(B0, BUS_IFACE, 'State'), 'idle', 'State afterwards')


def test_flood_many():
    """100 connections, 10 pipelined calls each, all at once."""
    clients, calls = 100, 10
    with Env({'vcan0': SLAVES}) as env:
        bad, errors = [], []
        counts = [0, 0, 0]
        lock = threading.Lock()
        barrier = threading.Barrier(clients)

        def client(k):
            try:
                c = dbusmini.Connection(env.address)
                try:
                    barrier.wait(60)
                    results = pipelined(c, flood_calls(calls, k))
                finally:
                    c.close()
                b, limited, timing = judge(results, calls, k)
                with lock:
                    bad.extend('client %d %s' % (k, x) for x in b)
                    counts[0] += len(results)
                    counts[1] += limited
                    counts[2] += timing
            except Exception as e:  # noqa: BLE001
                with lock:
                    errors.append('client %d: %r' % (k, e))

        t = time.monotonic()
        threads = [threading.Thread(target=client, args=(k,)) for k in range(clients)]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        log('%d calls answered in %.1f s: %d refused for limits, %d timing misses' %
            (counts[0], time.monotonic() - t, counts[1], counts[2]))
        expect(not errors, 'client errors: %s' % errors[:3])
        expect(not bad, 'wrong answers: %s' % bad[:5])
        expect_eq(counts[0], clients * calls, 'calls answered')
        expect(counts[2] <= clients * calls // 50, 'too many timing misses: %d' % counts[2])
        env.alive()
        expect_eq(env.get(B0, BUS_IFACE, 'QueueLength'), 0, 'queue empty afterwards')


def test_job_then_disconnect():
    """Clients queue jobs and close their connection before the replies: lssd runs them, drops the
    replies, and serves the next client."""
    with Env({'vcan0': SLAVES}) as env:
        for _ in range(20):
            c = dbusmini.Connection(env.address)
            c.send(SERVICE, B0, BUS_IFACE, 'Scan', 'a{sv}', [[]])
            for s in SLAVES:
                c.send(SERVICE, B0, BUS_IFACE, 'Execute', 'a(sv)', select_inquire(s))
            c.close()
        # a holder that leaves in the middle of its raw call
        c = dbusmini.Connection(env.address)
        c.call(SERVICE, B0, BUS_IFACE, 'Acquire')
        c.send(SERVICE, B0, BUS_IFACE, 'SwitchModeGlobal', 'y', [1])
        c.send(SERVICE, B0, BUS_IFACE, 'InquireNodeId')
        c.close()
        env.wait_until(lambda: env.get(B0, BUS_IFACE, 'State') == 'idle', timeout=120, what='bus idle again')
        s = SLAVES[0]
        r = env.call(B0, BUS_IFACE, 'Execute', 'a(sv)', '2', 'SwitchModeSelective', '(uuuu)', *s.identity,
                     'InquireNodeId', 'b', 'true')
        expect_eq([v['data'] for v in r[0]], [True, s.node_id], 'next client served')
        if env.real:
            env.wait_until(lambda: all(env.slave_state('vcan0', x.serial)['lss_state'] == 'waiting' for x in SLAVES),
                           what='slaves back in waiting')
        env.alive()


def test_idle_holder():
    """A live holder that sends nothing keeps the bus (documented policy): everyone else gets Busy,
    reads still work; it is released the moment its connection goes."""
    with Env({'vcan0': SLAVES}) as env:
        holder = dbusmini.Connection(env.address)
        holder.call(SERVICE, B0, BUS_IFACE, 'Acquire')
        time.sleep(3)  # idle, longer than any job
        for _ in range(3):
            name, _ = env.call_error(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)
            expect_eq(name, ERR + 'Busy', 'Scan while another holds the bus')
        name, msg = env.call_error(B0, BUS_IFACE, 'Acquire')
        expect_eq(name, ERR + 'Busy', 'Acquire while another holds the bus')
        expect(holder.unique_name in msg, 'Busy names the holder: ' + msg)
        expect_eq(env.get(B0, BUS_IFACE, 'State'), 'busy', 'State while held')
        # the holder is still served
        expect_eq(holder.call(SERVICE, B0, BUS_IFACE, 'SwitchModeGlobal', 'y', [0]), [], 'holder served')
        holder.close()
        env.wait_until(lambda: env.get(B0, BUS_IFACE, 'State') == 'idle', what='released on disconnect')
        env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)
        env.alive()


def test_many_jobs():
    """10,000 jobs: lssd's open fds come back to the same count and its memory stays bounded."""
    total = int(os.environ.get('LSSD_TEST_JOBS', '10000'))
    batch = 100  # below the queue bound and the bus daemon's pending-reply limit
    with Env({'vcan0': SLAVES}) as env:
        c = env.connect()

        def jobs(n):
            done = 0
            while done < n:
                k = min(batch, n - done)
                calls = []
                for i in range(k):
                    if i % 10 == 0:
                        calls.append((B0, BUS_IFACE, 'Execute', 'a(sv)', select_inquire(SLAVES[i % len(SLAVES)])))
                    else:
                        calls.append((B0, BUS_IFACE, 'Execute', 'a(sv)', [[('SwitchModeGlobal', ('y', 0))]]))
                # every job succeeds: the switches queued ahead on the wire
                # are no answer latency (a NoResponse here was lssd's timing)
                for r in pipelined(c, calls):
                    expect(not isinstance(r, dbusmini.DBusError), 'job failed: %r' % r)
                done += k

        jobs(500)  # warm up: allocator pools, sd-bus buffers
        fds0, rss0 = lssd_usage(env)
        t = time.monotonic()
        jobs(total)
        fds1, rss1 = lssd_usage(env)
        log('%d jobs in %.1f s; fds %d -> %d, VmRSS %d -> %d KiB' % (total, time.monotonic() - t, fds0, fds1,
                                                                    rss0, rss1))
        expect_eq(fds1, fds0, 'open fds after %d jobs' % total)
        if sanitized(env):
            log('lssd is sanitized: memory is checked by its leak checker at exit, not by RSS')
        else:
            expect(rss1 - rss0 < 2048, 'VmRSS grew by %d KiB over %d jobs' % (rss1 - rss0, total))
        env.alive()


def test_odd_text():
    """Arguments lssd quotes in its errors: long, multi-byte, control characters. Every error
    reply must still be valid (an unsendable reply would cost lssd its bus connection)."""
    with Env({'vcan0': SLAVES[:1]}) as env:
        c = env.connect()
        names = ['a' * n + '\u00e5' + 'b' * 3 for n in range(40, 52)]
        names += ['\u20ac' * 30, '\U0001F600' * 20, 'x\ty\x01z', '\u00e5' * 200, 'n' * 5000]
        for name in names:
            for path, iface, method, sig, body in [
                    (B0, BUS_IFACE, 'Execute', 'a(sv)', [[(name, ('y', 1))]]),
                    (B0, BUS_IFACE, 'Scan', 'a{sv}', [{name: ('u', 1)}]),
                    (B0, BUS_IFACE, 'AutoAssign', 'a{sv}', [{name: ('b', True)}]),
                    (MANAGER, MANAGER_IFACE, 'GetBus', 's', [name])]:
                try:
                    c.call(SERVICE, path, iface, method, sig, body, timeout=30)
                    raise AssertionError('%s(%r) succeeded' % (method, name))
                except dbusmini.DBusError as e:
                    expect(e.name in (INVALID_ARGS, ERR + 'NotFound'), '%s(%r): %s' % (method, name, e.name))
                except (TimeoutError, ConnectionError) as e:
                    raise AssertionError('%s(%r): no answer (%r)' % (method, name, e))
        env.alive()


def test_watchdog():
    """A hang: lssd pings the watchdog (WATCHDOG=1) only while its event loop runs. Stopped (SIGSTOP,
    as a hang looks from outside) it goes silent, which is what makes systemd (WatchdogSec=, Restart=
    on-failure in lssd.service) kill and restart it; it pings again when it runs again."""
    import signal
    os.environ['WATCHDOG_USEC'] = '1000000'
    os.environ.pop('WATCHDOG_PID', None)
    try:
        with Env({'vcan0': SLAVES[:1]}, notify=True) as env:
            def pings():
                return sum(1 for m in env.notify_msgs if m.get('WATCHDOG') == '1')

            def collect(seconds):
                end = time.monotonic() + seconds
                try:
                    env.notify_wait(lambda m: False, timeout=seconds)
                except AssertionError:
                    pass
                expect(time.monotonic() >= end - 0.1, 'collect')

            collect(3)
            n0 = pings()
            expect(n0 >= 3, 'WATCHDOG=1 every half period while running: %d in 3 s' % n0)
            env.lssd.send_signal(signal.SIGSTOP)
            try:
                time.sleep(0.2)
                n1 = pings()
                collect(3)
                expect_eq(pings(), n1, 'pings while hung')
            finally:
                env.lssd.send_signal(signal.SIGCONT)
            collect(2)
            expect(pings() >= n1 + 2, 'pings again after SIGCONT')
            env.alive()
    finally:
        os.environ.pop('WATCHDOG_USEC', None)
    unit = open(os.path.join(SOURCE_ROOT, 'systemd', 'lssd.service.in')).read()
    for line in ('WatchdogSec=', 'Restart=on-failure', 'Type=notify'):
        expect(line in unit, 'lssd.service has %s' % line)


# ---- the policy, member by member ----

# what the policy lets everyone call (besides Introspectable, Peer, Properties.Get/GetAll, ObjectManager)
OPEN_MEMBERS = {(MANAGER_IFACE, 'GetBus')}
# no-ops that answer before any check when there is nothing to do (nothing is sent, nothing changes)
NOOP_WHEN_IDLE = {(BUS_IFACE, 'Cancel'), (BUS_IFACE, 'Release')}
# valid arguments where the generic defaults would be refused before the credential check
VALID_ARGS = {'SetBitrate': [250000, 10, {}], 'ConfigureBitTiming': [0, 2]}


def default_value(sig):
    """A well-formed argument of type sig."""
    if sig in 'ynqiuxt':
        return 1
    if sig == 'b':
        return True
    if sig == 'd':
        return 0.5
    if sig in ('ao', 'as'):
        return []
    if sig == 'o':
        return '/'
    if sig == 's':
        return 'vcan0'
    if sig == 'a{sv}':
        return {}
    if sig == 'a(sv)':
        return [('InquireNodeId', ('b', True))]
    if sig == '(ttssa{su})':
        return (1, 1, 'boot', 'done', {})
    if sig == '(btts)':
        return (False, 0, 0, '')
    raise ValueError('no default for ' + sig)


def interface_members():
    """(interface, method, in-signature list) of every method, and (interface, property) of every
    property, from dbus/*.xml: a member added there is covered here."""
    methods, props = [], []
    d = os.path.join(SOURCE_ROOT, 'dbus')
    for name in sorted(os.listdir(d)):
        if not name.endswith('.xml'):
            continue
        for iface in ET.parse(os.path.join(d, name)).getroot().iter('interface'):
            for m in iface.iter('method'):
                sigs = [a.get('type') for a in m.iter('arg') if a.get('direction', 'in') == 'in']
                methods.append((iface.get('name'), m.get('name'), sigs))
            for pr in iface.iter('property'):
                props.append((iface.get('name'), pr.get('name'), pr.get('type')))
    return methods, props


def member_calls():
    """Child process (run as nobody): calls every member once, prints {key: error name or "ok"}."""
    objects = json.loads(sys.argv[2])
    methods, props = interface_members()
    c = dbusmini.Connection()
    out = {}
    for iface, method, sigs in methods:
        args = VALID_ARGS.get(method) or [default_value(t) for t in sigs]
        try:
            c.call(SERVICE, objects[iface], iface, method, ''.join(sigs), args, timeout=60)
            out['%s.%s' % (iface, method)] = 'ok'
        except dbusmini.DBusError as e:
            out['%s.%s' % (iface, method)] = e.name
    for iface, prop, sig in props:
        try:
            c.call(SERVICE, objects[iface], 'org.freedesktop.DBus.Properties', 'Set', 'ssv',
                   [iface, prop, (sig, default_value(sig))], timeout=60)
            out['Set %s.%s' % (iface, prop)] = 'ok'
        except dbusmini.DBusError as e:
            out['Set %s.%s' % (iface, prop)] = e.name
        try:
            c.call(SERVICE, objects[iface], 'org.freedesktop.DBus.Properties', 'Get', 'ss', [iface, prop], timeout=60)
            out['Get %s.%s' % (iface, prop)] = 'ok'
        except dbusmini.DBusError as e:
            out['Get %s.%s' % (iface, prop)] = e.name
    print(json.dumps(out))


def policy_every_member(open_policy):
    if os.geteuid() != 0:
        raise Skip('acting as another user needs root')
    s = SLAVES[0]
    with Env({'vcan0': [s]}, lssd_policy_override=open_policy) as env:
        env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 2, 'vendor', 'u', s.vendor, 'product', 'u', s.product)
        objects = {MANAGER_IFACE: MANAGER, BUS_IFACE: B0,
                   DEVICE_IFACE: device_path('vcan0', *s.identity)}
        p = subprocess.run(['setpriv', '--reuid=nobody', '--regid=nogroup', '--clear-groups', sys.executable,
                            os.path.abspath(__file__), '_member-calls', json.dumps(objects)],
                           capture_output=True, text=True, timeout=600,
                           env=dict(os.environ, DBUS_SYSTEM_BUS_ADDRESS=env.address))
        assert p.returncode == 0, 'member calls as nobody failed: %s' % p.stderr[-2000:]
        got = json.loads(p.stdout)
        methods, props = interface_members()
        expect(len(methods) >= 22, 'found only %d methods in dbus/*.xml' % len(methods))
        wrong = []
        for iface, method, _ in methods:
            r = got['%s.%s' % (iface, method)]
            if (iface, method) in OPEN_MEMBERS:
                ok = r == 'ok'
            elif (iface, method) in NOOP_WHEN_IDLE:
                ok = r in ('ok', ACCESS_DENIED)
            else:
                ok = r == ACCESS_DENIED
            if not ok:
                wrong.append('%s.%s -> %s' % (iface, method, r))
        for iface, prop, _ in props:
            # Set: denied by the policy, or refused by sd-bus (read-only property) when the policy is open
            if got['Set %s.%s' % (iface, prop)] not in (ACCESS_DENIED, 'org.freedesktop.DBus.Error.PropertyReadOnly'):
                wrong.append('Set %s.%s -> %s' % (iface, prop, got['Set %s.%s' % (iface, prop)]))
            if got['Get %s.%s' % (iface, prop)] != 'ok':
                wrong.append('Get %s.%s -> %s' % (iface, prop, got['Get %s.%s' % (iface, prop)]))
        log('%d methods and %d properties called as nobody (%s policy)' %
            (len(methods), len(props), 'open' if open_policy else 'real'))
        expect(not wrong, 'as nobody: ' + '; '.join(wrong))
        # the policy lets every call through (as hostnamed's) and lssd refused them all (no polkit on
        # this bus: root and group lssd only): no job ran for nobody
        expect('by :' not in env.lssd_output().split('Scan finished')[-1], 'lssd ran a job for nobody')
        expect_eq(env.get(B0, BUS_IFACE, 'State'), 'idle', 'nothing happened')
        env.alive()


TESTS = {
    'flood-one': test_flood_one,
    'flood-many': test_flood_many,
    'job-then-disconnect': test_job_then_disconnect,
    'idle-holder': test_idle_holder,
    'many-jobs': test_many_jobs,
    'odd-text': test_odd_text,
    'watchdog': test_watchdog,
    'policy-every-member': lambda: policy_every_member(False),
    'daemon-checks-every-member': lambda: policy_every_member(True),
}

if __name__ == '__main__':
    if sys.argv[1:2] == ['_member-calls']:
        member_calls()
        sys.exit(0)
    sys.exit(run(TESTS))
