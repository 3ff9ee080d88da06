#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""D-Bus load on lssd: K concurrent Properties.Get and J concurrent queued
Execute([SwitchModeSelective, InquireNodeId]) jobs, each from its own client
connection; p50/p99 latency from send to reply, and every call must be
answered (a lost call fails the bench).

    dbus-load.py [--gets 1000] [--jobs 200] [--queue-size N]...

Runs on the host against `lssd --simulate` (in-memory bus with simulated
slaves answering after 0.5 ms, in real time): the D-Bus side, the job queue
and the engine are lssd's own code; only the CAN socket is replaced.
A private dbus-daemon with the real policy file, its connection limits raised
for 1000+ clients. All requests are written first, then the replies are read
with epoll in one thread, so the client does not queue them itself."""

import argparse
import os
import resource
import selectors
import socket
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchlib as bl  # noqa: E402

os.environ['LSSD_TEST_BACKEND'] = 'simulate'
os.environ.setdefault('LSSD_LOG_LEVEL', 'info')
import dbusmini  # noqa: E402
from lssdtest import BUS_IFACE, DEVICE_IFACE, MANAGER, MANAGER_IFACE, SERVICE, Env, Slave, bus_path, device_path  # noqa: E402

IFNAME = 'vcan0'
LIMITS = ''.join('<limit name="%s">%d</limit>' % kv for kv in (
    ('max_completed_connections', 8192), ('max_connections_per_user', 8192),
    ('max_incomplete_connections', 1024), ('max_pending_service_starts', 8192)))


class LoadEnv(Env):
    """Env whose private system bus admits thousands of clients."""

    def bus_config_extra(self):
        return super().bus_config_extra() + LIMITS


def connect(address):
    sock_path = address.split('path=', 1)[1].split(',')[0]
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.connect(sock_path)
    s.sendall(b'\0AUTH EXTERNAL ' + str(os.geteuid()).encode().hex().encode() + b'\r\nBEGIN\r\n')
    hello = dbusmini.Message(dbusmini.METHOD_CALL, 1, 0, {1: '/org/freedesktop/DBus', 2: 'org.freedesktop.DBus',
                                                          3: 'Hello', 6: 'org.freedesktop.DBus'})
    buf = b''
    while b'\r\n' not in buf:
        chunk = s.recv(4096)
        if not chunk:
            raise ConnectionError('bus closed the connection during authentication')
        buf += chunk
    if not buf.startswith(b'OK'):
        raise ConnectionError('authentication failed: %r' % buf)
    s.sendall(hello.encode())
    data = buf.split(b'\r\n', 1)[1]
    while True:
        msg, used = dbusmini._parse(data)
        if msg:
            data = data[used:]
            if msg.type == dbusmini.METHOD_RETURN and msg.reply_serial == 1:
                break
            continue
        chunk = s.recv(65536)
        if not chunk:
            raise ConnectionError('bus closed the connection after Hello')
        data += chunk
    s.setblocking(False)
    return s, data


def storm(address, messages, timeout):
    """One connection per message; all sent, then replies read. Returns
    (latencies in s, {error name: count}, replies, lost)."""
    conns = []
    for m in messages:
        conns.append(connect(address))
    sel = selectors.DefaultSelector()
    state = {}
    for (s, rest), m in zip(conns, messages):
        state[s] = {'buf': rest, 'msg': m}
    t_send = {}
    for (s, _), m in zip(conns, messages):
        data = m.encode()
        t_send[s] = time.monotonic()
        s.setblocking(True)
        s.sendall(data)
        s.setblocking(False)
        sel.register(s, selectors.EVENT_READ)
    lat, errors, replies = [], {}, []
    pending = set(state)
    deadline = time.monotonic() + timeout
    while pending and time.monotonic() < deadline:
        for key, _ in sel.select(timeout=0.5):
            s = key.fileobj
            now = time.monotonic()
            try:
                chunk = s.recv(65536)
            except BlockingIOError:
                continue
            st = state[s]
            st['buf'] += chunk
            while True:
                msg, used = dbusmini._parse(st['buf'])
                if not msg:
                    break
                st['buf'] = st['buf'][used:]
                if msg.type in (dbusmini.METHOD_RETURN, dbusmini.ERROR) and msg.reply_serial == st['msg'].serial:
                    lat.append(now - t_send[s])
                    if msg.type == dbusmini.ERROR:
                        errors[msg.error_name] = errors.get(msg.error_name, 0) + 1
                    replies.append((st['msg'], msg))
                    pending.discard(s)
                    sel.unregister(s)
            if not chunk and s in pending:
                pending.discard(s)
                sel.unregister(s)
    for s, _ in conns:
        s.close()
    return lat, errors, replies, len(pending)


def call_msg(path, iface, member, sig='', body=()):
    return dbusmini.Message(dbusmini.METHOD_CALL, 2, 0, {1: path, 2: iface, 3: member, 6: SERVICE}, sig, body)


def stats(lat, errors, lost, n):
    ms = [x * 1000 for x in lat]
    return {'calls': n, 'answered': len(lat), 'lost': lost, 'errors': errors,
            'p50_ms': bl.percentile(ms, 50), 'p99_ms': bl.percentile(ms, 99), 'max_ms': max(ms) if ms else None}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--gets', type=int, default=1000)
    ap.add_argument('--jobs', type=int, default=200)
    ap.add_argument('--queue-size', type=int, action='append', default=None,
                    help='lssd --queue-size for the jobs run (repeatable; default: lssd default, then 256)')
    a = ap.parse_args()
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    need = max(a.gets, a.jobs) + 256
    if soft < need:
        resource.setrlimit(resource.RLIMIT_NOFILE, (min(max(need, soft), hard), hard))
    slaves = [Slave(bl.VENDOR, bl.PRODUCT, 1, 0x1000 + i, 10 + i) for i in range(8)]
    out = {'backend': 'lssd --simulate on the host (in-memory bus, slaves answer after 0.5 ms)'}
    failures = []
    for qs in (a.queue_size or [0, 256]):
        args = ['--queue-size', str(qs)] if qs else []
        with LoadEnv({IFNAME: slaves}, lssd_args=args) as env:
            run = {'queue_size': qs or 'default (128)'}
            if 'gets' not in out:
                props = [(MANAGER, MANAGER_IFACE, 'Version'), (bus_path(IFNAME), BUS_IFACE, 'State'),
                         (bus_path(IFNAME), BUS_IFACE, 'QueueLength')]
                # device objects exist once a scan saw them (configured ones: with vendor/product)
                env.call(bus_path(IFNAME), BUS_IFACE, 'Scan', 'a{sv}', 2, 'vendor', 'u', bl.VENDOR,
                         'product', 'u', bl.PRODUCT)
                props.append((device_path(IFNAME, *slaves[0].identity), DEVICE_IFACE, 'NodeId'))
                msgs = [call_msg(p, 'org.freedesktop.DBus.Properties', 'Get', 'ss', [i, n])
                        for p, i, n in (props[k % len(props)] for k in range(a.gets))]
                t0 = time.monotonic()
                lat, errors, _, lost = storm(env.address, msgs, 60)
                out['gets'] = dict(stats(lat, errors, lost, a.gets), wall_s=time.monotonic() - t0)
                bl.log('Properties.Get x%d: %r' % (a.gets, out['gets']))
                if lost or errors:
                    failures.append('Properties.Get: %d lost, errors %r' % (lost, errors))
            msgs = []
            for k in range(a.jobs):
                s = slaves[k % len(slaves)]
                msgs.append(call_msg(bus_path(IFNAME), BUS_IFACE, 'Execute', 'a(sv)', [[
                    ('SwitchModeSelective', ('(uuuu)', s.identity)), ('InquireNodeId', ('b', True))]]))
            t0 = time.monotonic()
            lat, errors, replies, lost = storm(env.address, msgs, 300)
            wrong = 0
            for m, r in replies:
                if r.type == dbusmini.METHOD_RETURN:
                    ident = m.body[0][0][1][1]
                    want = [('b', True), ('y', next(x.node_id for x in slaves if x.identity == tuple(ident)))]
                    wrong += r.body[0] != want
            run.update(stats(lat, errors, lost, a.jobs), wrong_answers=wrong, wall_s=time.monotonic() - t0)
            bl.log('Execute jobs x%d, queue %s: %r' % (a.jobs, run['queue_size'], run))
            if lost or wrong:
                failures.append('jobs (queue %s): %d lost, %d wrong answers' % (run['queue_size'], lost, wrong))
            out.setdefault('jobs', []).append(run)
            env.alive()
    bl.save('dbus-load', out)
    if failures:
        bl.log('!!!! D-Bus load FAILS: ' + '; '.join(failures))
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
