#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""lssd on a real controller driver: the emulated Kvaser PCI (SJA1000) cards
of the VM (tests/vm/run --kvaser), lssd on can0 and lss-sim on can1 of the
same emulated bus. `test-kvaser-faults.py NAME` runs one; SKIPs (77) when
can0/can1 are not there.

  kvaser-scan-assign  Scan, AssignNodeId, Execute through the real driver
  kvaser-enobufs      the tx queue slowed (tbf qdisc) and kept full by cangen:
                      lssd's writes meet ENOBUFS and it still does its jobs
  kvaser-link         ip link set can0 down/up, idle and in the middle of a job"""

import os
import re
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'integration'))
import dbusmini  # noqa: E402
from lssdtest import BUS_IFACE, ERR, SERVICE, Env, Skip, Slave, bus_path, log, run  # noqa: E402

MASTER, SIM = 'can0', 'can1'
B = bus_path(MASTER)
SLAVES = [Slave(0xEC, 0x1234, 1, 0x1276), Slave(0xEC, 0x1234, 1, 0x80002468, 6), Slave(0x9A, 3, 1, 0x55)]
EXPECTED = sorted(s.identity for s in SLAVES)


def expect(cond, what):
    if not cond:
        raise AssertionError(what)


def expect_eq(got, want, what):
    if got != want:
        raise AssertionError('%s: got %r, want %r' % (what, got, want))


class KvaserEnv(Env):
    """lssd serves can0; the slaves (lss-sim) sit on can1, the other card on the same bus."""

    def __init__(self, slaves, **kw):
        # qemu's emulated CAN bus has no wire time: a frame is delivered the
        # moment it is written. lssd drains stale answers by its own frames'
        # echo (tx confirmation), so this works without; 2 ms of slave latency
        # keeps the answers in the order a real wire would give them.
        kw.setdefault('sim_args', ['--latency', '2'])
        super().__init__({MASTER: slaves}, candump=True, **kw)

    def start(self):
        for ifname in (MASTER, SIM):
            if not os.path.exists('/sys/class/net/' + ifname):
                raise Skip('%s is not there (run through tests/vm/run --kvaser)' % ifname)
        if os.geteuid() != 0:
            raise Skip('needs root')
        if os.environ.get('LSSD_TEST_BACKEND') == 'simulate':
            raise Skip('needs the real driver')
        for ifname in (MASTER, SIM):
            ip('link', 'set', ifname, 'up')
        super().start()

    def _start_sim(self, ifname, slaves):
        super()._start_sim(SIM, slaves)


def ip(*args):
    subprocess.run(['ip'] + list(args), check=True, capture_output=True, text=True)


def link_up(ifname):
    subprocess.run(['ip', 'link', 'set', ifname, 'up'], check=False)


def scan(env):
    """Scan with the vendor/product of the configured slaves (slowscan); the others by fastscan."""
    found = sorted(tuple(d[:4]) for d in env.call(B, BUS_IFACE, 'Scan', 'a{sv}', 2, 'vendor', 'u', 0xEC,
                                                   'product', 'u', 0x1234)[0])
    if found != EXPECTED:
        # qemu's SJA1000 on the slave side overruns its receive FIFO: rx errors on can1
        for ifname in (MASTER, SIM):
            log(subprocess.run(['ip', '-statistics', 'link', 'show', ifname], capture_output=True, text=True).stdout)
    if found != EXPECTED and env.want_candump:
        for f in env.frames(MASTER)[:80]:
            log('  %.6f %03X %s' % (f[0], f[1], f[2].hex()))
    return found


def test_scan_assign():
    with KvaserEnv(SLAVES) as env:
        expect_eq(scan(env), EXPECTED, 'Scan over kvaser_pci')
        s = SLAVES[0]
        env.call(B, BUS_IFACE, 'AssignNodeId', 'uuuuya{sv}', *s.identity, 20, 0)
        expect_eq(env.slave_state(SIM, s.serial).get('active_node_id'), '20', 'node-ID assigned')
        r = env.call(B, BUS_IFACE, 'Execute', 'a(sv)', '2', 'SwitchModeSelective', '(uuuu)', *SLAVES[1].identity,
                     'InquireNodeId', 'b', 'true')
        expect_eq([v['data'] for v in r[0]], [True, 6], 'Execute over kvaser_pci')
        expect_eq(env.get(B, BUS_IFACE, 'Bitrate'), 125000, 'Bitrate read from the driver')
        env.alive()


def tc(*args):
    subprocess.run(['tc'] + list(args), check=True, capture_output=True, text=True)


def qdisc_drops(ifname):
    out = subprocess.run(['tc', '-s', 'qdisc', 'show', 'dev', ifname], capture_output=True, text=True).stdout
    m = re.search(r'dropped (\d+)', out)
    return int(m.group(1)) if m else 0


def test_enobufs():
    """The emulated SJA1000 completes a transmission at once, so its 10-frame queue never fills by
    itself: a token-bucket qdisc on can0 makes the tx queue drain at ~300 frames/s and cangen keeps it
    full. Every write that finds it full fails with ENOBUFS (witness: cangen without -i stops on it);
    lssd's writes meet the same and it must still do its jobs."""
    with KvaserEnv(SLAVES) as env:
        subprocess.run(['modprobe', 'sch_tbf'], check=False)
        tc('qdisc', 'replace', 'dev', MASTER, 'root', 'tbf', 'rate', '4kbit', 'burst', '64', 'limit', '64')
        try:
            p = subprocess.run(['cangen', MASTER, '-g', '0', '-I', '123', '-L', '8', '-n', '2000'],
                               capture_output=True, text=True, timeout=60)
            expect(p.returncode != 0 and 'No buffer space' in p.stderr + p.stdout,
                   'cangen meets ENOBUFS on %s: rc %d %r' % (MASTER, p.returncode, p.stderr[-200:]))
            tc('qdisc', 'replace', 'dev', MASTER, 'root', 'tbf', 'rate', '40kbit', 'burst', '64', 'limit', '64')
            flood = subprocess.Popen(['cangen', MASTER, '-g', '1', '-i', '-I', '123', '-L', '8'],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            try:
                time.sleep(0.5)
                d0 = qdisc_drops(MASTER)
                t = time.monotonic()
                found = scan(env)
                log('Scan with the tx queue kept full: %.1f s, %d frames dropped at the queue meanwhile' %
                    (time.monotonic() - t, qdisc_drops(MASTER) - d0))
                expect_eq(found, EXPECTED, 'Scan with the tx queue kept full')
                expect(qdisc_drops(MASTER) > d0, 'the queue overflowed during the Scan')
                env.call(B, BUS_IFACE, 'AssignNodeId', 'uuuuya{sv}', *SLAVES[2].identity, 30, 0)
                expect_eq(env.slave_state(SIM, SLAVES[2].serial).get('active_node_id'), '30',
                          'assigned with the tx queue kept full')
            finally:
                flood.terminate()
                flood.wait(10)
        finally:
            subprocess.run(['tc', 'qdisc', 'del', 'dev', MASTER, 'root'], check=False)
        env.alive()
        expect_eq(env.get(B, BUS_IFACE, 'State'), 'idle', 'State afterwards')


def test_link():
    with KvaserEnv(SLAVES) as env:
        try:
            # idle
            ip('link', 'set', MASTER, 'down')
            env.wait_until(lambda: env.get(B, BUS_IFACE, 'State') == 'down', what='State down')
            name, _ = env.call_error(B, BUS_IFACE, 'Scan', 'a{sv}', 0)
            expect_eq(name, ERR + 'BusDown', 'Scan while can0 is down')
            ip('link', 'set', MASTER, 'up')
            env.wait_until(lambda: env.get(B, BUS_IFACE, 'State') == 'idle', what='State idle after up')
            expect_eq(scan(env), EXPECTED, 'Scan after up')
            # in the middle of a job
            c = dbusmini.Connection(env.address)
            serial = c.send(SERVICE, B, BUS_IFACE, 'Scan', 'a{sv}', [[]])
            time.sleep(0.05)
            ip('link', 'set', MASTER, 'down')
            t = time.monotonic()
            try:
                r = c.wait_reply(serial, 60)
                log('Scan across the link going down finished: %r' % (r,))
            except dbusmini.DBusError as e:
                log('Scan across the link going down: %s: %s (%.1f s)' % (e.name, e, time.monotonic() - t))
                expect(e.name in (ERR + 'BusDown', ERR + 'NoResponse'), 'error of the interrupted Scan: %s' % e.name)
            c.close()
            ip('link', 'set', MASTER, 'up')
            env.wait_until(lambda: env.get(B, BUS_IFACE, 'State') == 'idle', what='State idle after the 2nd up')
            expect_eq(scan(env), EXPECTED, 'Scan after the 2nd up')
            env.wait_until(lambda: all(env.slave_state(SIM, s.serial).get('lss_state') == 'waiting' for s in SLAVES),
                           what='slaves back in waiting')
        finally:
            link_up(MASTER)
        env.alive()


TESTS = {
    'kvaser-scan-assign': test_scan_assign,
    'kvaser-enobufs': test_enobufs,
    'kvaser-link': test_link,
}

if __name__ == '__main__':
    sys.exit(run(TESTS))
