#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Builds of lssd against each other in one VM boot, taking turns.

    tests/vm/run --rwdir BUILD... -- python3 bench/ab.py --build old=BUILD --build new=BUILD
        [--turns 4] [--cases mapped,vendor,blind,scan] [--n 32] [--slaves 127] [--keep DIR]

This machine's speed moves by 20-100 % within the hour (bench/README,
"Results"): one run's figure says more about the host than about lssd. So
builds are compared in one boot, taking turns (old, new, new, old, ...):
AutoAssign of N non-configured slaves (autoaddress.py's cases, same slaves
and seeds) and the blind Scan of --slaves slaves (footprint.py's). Printed:
each run, then per case each build's median (min-max) and its ratio to the
first build, the LSS frames (the work, which the host does not change), and
for the Scan the fastscan bit steps: silent and answered, their median
step time (the adaptive waits follow the host's answer latency). Every
build uses the first build's lss-sim. --keep: the Scans' candumps are
copied there. Not a test: a run that finds a slave missing fails."""

import argparse
import os
import shutil
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchlib as bl  # noqa: E402

IFNAME = 'vcan0'
CONFIG = 'buses = ( { interface = "%s"; bitrate = %d; } );\n' % (IFNAME, bl.BITRATE)


def bit_steps(frames):
    """Fastscan bit steps (bitcheck < 32, LSSNext the field itself): (silent, answered) step times in ms."""
    silent, answered = [], []
    reqs = [i for i, f in enumerate(frames) if f[1] == 0x7E5]
    for a, b in zip(reqs, reqs[1:]):
        d = frames[a][2]
        if len(d) < 8 or d[0] != 0x51 or d[5] >= 0x80 or d[6] != d[7]:
            continue
        ms = (frames[b][0] - frames[a][0]) * 1000
        (answered if any(f[1] == 0x7E4 for f in frames[a + 1:b]) else silent).append(ms)
    return silent, answered


def scan(name, n, keep, turn):
    from lssdtest import BUS_IFACE, SERVICE, Env, Slave, bus_path
    slaves = bl.identities(n, 4242)  # footprint.py's
    with Env({IFNAME: [Slave(*s) for s in slaves]}, config=CONFIG, sim_args=bl.SIM_ARGS, candump=True) as env:
        time.sleep(1.0)
        c = env.connect()
        pid = env.lssd.pid
        cpu0, w0, t0 = bl.proc_cpu_s(pid), time.time(), time.monotonic()
        found = c.call(SERVICE, bus_path(IFNAME), BUS_IFACE, 'Scan', 'a{sv}', [{}], timeout=3600)[0]
        elapsed, w1, cpu = time.monotonic() - t0, time.time(), bl.proc_cpu_s(pid) - cpu0
        time.sleep(0.3)  # candump writes the last frames
        frames = bl.read_candump(env.candump_path, IFNAME, w0 - 0.05, w1 + 0.05)
        if keep:
            shutil.copy(env.candump_path, os.path.join(keep, '%s-scan-turn%d.candump.log' % (name, turn)))
        c.close()
        env.conns.remove(c)
    if sorted(tuple(f[:4]) for f in found) != sorted(slaves):
        raise bl.BenchFailure('%s: Scan found %d of %d slaves' % (name, len(found), n))
    silent, answered = bit_steps(frames)
    return {'elapsed_s': elapsed, 'cpu_s': cpu, 'lss_frames': bl.frame_stats(frames)['lss_frames'],
            'silent': len(silent), 'silent_ms': bl.percentile(silent, 50),
            'answered': len(answered), 'answered_ms': bl.percentile(answered, 50)}


def autoassign(mode, n, turn):
    import autoaddress
    return autoaddress.run_lssd(mode, n, turn)


def fmt(values, fmt_='%.3f'):
    s = bl.summary(values)
    return (fmt_ + ' (' + fmt_ + '-' + fmt_ + ')') % (s['median'], s['min'], s['max'])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--build', action='append', required=True, help='NAME=BUILDDIR (two or more)')
    ap.add_argument('--turns', type=int, default=4)
    ap.add_argument('--cases', default='mapped,vendor,blind,scan')
    ap.add_argument('--n', type=int, default=32, help='slaves of the AutoAssign cases')
    ap.add_argument('--slaves', type=int, default=127, help='slaves of the Scan')
    ap.add_argument('--keep', help='directory for the Scans\' candumps')
    a = ap.parse_args()
    builds = [b.split('=', 1) for b in a.build]
    if len(builds) < 2 or any(len(b) != 2 for b in builds):
        ap.error('--build NAME=BUILDDIR, two or more')
    if not os.path.exists('/sys/class/net/' + IFNAME):
        bl.log('%s is not there: run it through tests/vm/run' % IFNAME)
        return 2
    os.environ['LSSD_TEST_BACKEND'] = 'vcan'
    os.environ.setdefault('LSSD_SOURCE_ROOT', bl.SOURCE_ROOT)
    os.environ['LSS_SIM_BINARY'] = os.path.join(builds[0][1], 'src/lss-sim/lss-sim')
    if a.keep:
        os.makedirs(a.keep, exist_ok=True)
    cases = a.cases.split(',')
    runs = {}  # (case, build) -> [result]
    for turn in range(a.turns):
        # the order turns too: a host getting slower within a turn favours no build
        for name, build in (builds if turn % 2 == 0 else builds[::-1]):
            os.environ['LSSD_BINARY'] = os.path.join(build, 'src/daemon/lssd')
            for case in cases:
                r = scan(name, a.slaves, a.keep, turn) if case == 'scan' else autoassign(case, a.n, turn)
                runs.setdefault((case, name), []).append(r)
                print('turn %d %-8s %-7s %.3f s, lssd CPU %.2f s, %d LSS frames'
                      % (turn, name, case, r['elapsed_s'], r['cpu_s'], r['lss_frames']), flush=True)
    print('\n# %d turns in one boot; medians (min-max); ratio: of the medians, to %s' % (a.turns, builds[0][0]))
    print('%-8s %-8s %-28s %6s %-24s %s' % ('case', 'build', 'time s', 'ratio', 'LSS frames', 'lssd CPU s'))
    for case in cases:
        first = bl.summary([r['elapsed_s'] for r in runs[(case, builds[0][0])]])['median']
        for name, _ in builds:
            rs = runs[(case, name)]
            t = [r['elapsed_s'] for r in rs]
            print('%-8s %-8s %-28s %5.2fx %-24s %s' % (case, name, fmt(t), bl.summary(t)['median'] / first,
                                                        fmt([r['lss_frames'] for r in rs], '%d'),
                                                        fmt([r['cpu_s'] for r in rs], '%.2f')))
    if 'scan' in cases:
        print('\n# the Scans\' fastscan bit steps: count and median step time (request to next request)')
        for name, _ in builds:
            rs = runs[('scan', name)]
            print('%-8s silent %s, %s ms; answered %s, %s ms' % (
                name, fmt([r['silent'] for r in rs], '%d'), fmt([r['silent_ms'] for r in rs], '%.2f'),
                fmt([r['answered'] for r in rs], '%d'), fmt([r['answered_ms'] for r in rs], '%.2f')))
    return 0


if __name__ == '__main__':
    try:
        sys.exit(main())
    except bl.BenchFailure as e:
        bl.log('!!!! %s' % e)
        sys.exit(1)
