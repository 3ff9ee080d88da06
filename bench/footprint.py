#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Footprint of lssd on vcan0: RSS after start and after a Scan of 127 slaves,
wakeups per second while idle (no watchdog, then WATCHDOG_USEC = 30 s as
systemd's WatchdogSec=30 sets it), each over --idle seconds. And a Scan of
127 configured slaves (node-IDs 1..127, no map: found by SDO 1018h, then
confirmed through LSS) against the bus floor of the SDO requests it sent.

    footprint.py [--idle 30] [--slaves 127] [--no-scan] [--simulate]

--simulate: on the host against `lssd --simulate` (the slaves are simulated
inside lssd, so its RSS includes them: an upper bound); otherwise vcan0.
The Scan is blind (fastscan; every slave is non-configured).

Wakeups are the context switches of every lssd thread (/proc/PID/task/*/status:
voluntary + nonvoluntary): each time the process sleeps and is woken counts
one. Needs root and vcan0: run it through bench/run."""

import argparse
import os
import socket
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchlib as bl  # noqa: E402

IFNAME = 'vcan0'
CONFIG = 'buses = ( { interface = "%s"; bitrate = %d; } );\n' % (IFNAME, bl.BITRATE)


def rss_kib(pid):
    st = bl.proc_status(pid)
    out = {k: int(st[k].split()[0]) for k in ('VmRSS', 'VmHWM', 'RssAnon', 'RssFile', 'RssShmem') if k in st}
    # what is lssd's own: proportional and private pages (shared libraries are mostly shared)
    try:
        with open('/proc/%d/smaps_rollup' % pid) as f:
            for line in f:
                k, _, v = line.partition(':')
                if k in ('Pss', 'Shared_Clean', 'Private_Clean', 'Private_Dirty'):
                    out[k] = int(v.split()[0])
    except OSError:
        pass
    return out


def idle(env, seconds):
    pid = env.lssd.pid
    time.sleep(1.0)  # the start-up settles
    w0, cpu0 = bl.proc_wakeups(pid), bl.proc_cpu_s(pid)
    time.sleep(seconds)
    w1, cpu1 = bl.proc_wakeups(pid), bl.proc_cpu_s(pid)
    return {'seconds': seconds, 'wakeups': w1 - w0, 'per_s': (w1 - w0) / seconds, 'cpu_s': cpu1 - cpu0}


def configured_scan(n):
    """A Scan with no options of n configured slaves (node-IDs 1..n, not in
    the map): the time, and the bus floor of the SDO requests (0x600 + node)
    candump saw meanwhile."""
    from lssdtest import BUS_IFACE, SERVICE, Env, Slave, bus_path
    slaves = bl.identities(n, 4343)
    with Env({IFNAME: [Slave(*s, node_id=i + 1) for i, s in enumerate(slaves)]}, config=CONFIG,
             sim_args=bl.SIM_ARGS, candump=True) as env:
        c = env.connect()
        t_from, t0 = time.time(), time.monotonic()
        found = c.call(SERVICE, bus_path(IFNAME), BUS_IFACE, 'Scan', 'a{sv}', [{}], timeout=3600)[0]
        elapsed, t_to = time.monotonic() - t0, time.time()
        time.sleep(0.3)  # candump writes the last frames
        frames = bl.read_candump(env.candump_path, IFNAME, t_from, t_to)
        sdo = [f for f in frames if 0x601 <= f[1] <= 0x67F]
        r = {'elapsed_s': elapsed, 'found': len(found), 'sdo_requests': len(sdo),
             'sdo_floor_s': bl.frame_stats(sdo)['floor_s'], 'all': bl.frame_stats(frames)}
        want = sorted(s + (i + 1,) for i, s in enumerate(slaves))
        if sorted(tuple(f[:5]) for f in found) != want:
            r['failed'] = 'footprint: Scan of %d configured slaves found %d, or wrong node-IDs' % (n, len(found))
            bl.log('!!!! ' + r['failed'])
            bl.record_failure(r['failed'])
        bl.log('configured Scan: %r' % r)
        c.close()
        env.conns.remove(c)
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--idle', type=float, default=30.0)
    ap.add_argument('--slaves', type=int, default=127)
    ap.add_argument('--no-scan', action='store_true')
    ap.add_argument('--no-configured-scan', action='store_true')
    ap.add_argument('--simulate', action='store_true')
    a = ap.parse_args()
    os.environ['LSSD_TEST_BACKEND'] = 'simulate' if a.simulate else 'vcan'
    if not a.simulate and not os.path.exists('/sys/class/net/' + IFNAME):
        bl.log('%s is not there: run through bench/run (tests/vm/run)' % IFNAME)
        return 2
    from lssdtest import BUS_IFACE, SERVICE, Env, Slave, bus_path

    os.environ.setdefault('LSSD_LOG_LEVEL', 'info')
    os.environ.pop('WATCHDOG_USEC', None)
    slaves = bl.identities(a.slaves, 4242)
    out = {'slaves': a.slaves, 'backend': 'lssd --simulate on the host' if a.simulate else 'vcan0'}
    with Env({IFNAME: [Slave(*s) for s in slaves]}, config=CONFIG, sim_args=bl.SIM_ARGS) as env:
        pid = env.lssd.pid
        time.sleep(1.0)
        out['rss_start_kib'] = rss_kib(pid)
        bl.log('RSS after start: %r' % out['rss_start_kib'])
        out['idle_no_watchdog'] = idle(env, a.idle)
        bl.log('idle, no watchdog: %r' % out['idle_no_watchdog'])
        if not a.no_scan:
            c = env.connect()
            cpu0, t0 = bl.proc_cpu_s(pid), time.monotonic()
            found = c.call(SERVICE, bus_path(IFNAME), BUS_IFACE, 'Scan', 'a{sv}', [{}], timeout=3600)[0]
            out['scan'] = {'elapsed_s': time.monotonic() - t0, 'cpu_s': bl.proc_cpu_s(pid) - cpu0,
                           'found': len(found), 'options': 'blind'}
            if sorted(tuple(f[:4]) for f in found) != sorted(slaves):
                # still measure the RSS; the miss is recorded and fails the run
                failed = 'footprint: Scan found %d of %d slaves' % (len(found), len(slaves))
                bl.log('!!!! ' + failed)
                bl.record_failure(failed)
                out['scan']['failed'] = failed
            time.sleep(0.5)
            out['rss_after_scan_kib'] = rss_kib(pid)
            bl.log('scan: %r; RSS after: %r' % (out['scan'], out['rss_after_scan_kib']))
            c.close()
            env.conns.remove(c)

    if not a.no_scan and not a.no_configured_scan and not a.simulate:
        out['configured_scan'] = configured_scan(a.slaves)

    # systemd's WatchdogSec=30 passes WATCHDOG_USEC (and WATCHDOG_PID, which
    # would name the service's main PID; unset, sd_watchdog_enabled() accepts)
    os.environ['WATCHDOG_USEC'] = '30000000'
    try:
        with Env({IFNAME: []}, config=CONFIG, notify=True) as env:
            env.notify.settimeout(0.1)
            r = idle(env, a.idle)
            pings = 0
            while True:
                try:
                    msg = env.notify.recv(4096)
                except socket.timeout:
                    break
                pings += msg.count(b'WATCHDOG=1')
            r['watchdog_pings_seen'] = pings
            out['idle_watchdog_30s'] = r
            bl.log('idle, WATCHDOG_USEC=30000000: %r' % r)
    finally:
        del os.environ['WATCHDOG_USEC']
    bl.save('footprint-' + ('sim' if a.simulate else 'vcan'), out)
    return 1 if 'failed' in out.get('scan', {}) or 'failed' in out.get('configured_scan', {}) else 0


if __name__ == '__main__':
    sys.exit(main())
