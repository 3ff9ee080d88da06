#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Buses in parallel: AutoAssign on 4 vcan buses at once against each bus alone.

    parallel.py [--n 8,32] [--reps 3] [--modes mapped,vendor,blind] [--buses 4]

One lssd with the buses vcan0..vcan3 configured (the same per-bus set-up as
the lssd phase of autoaddress.py: store = true, the mode's map), one lss-sim
per bus with N non-configured slaves each (latency 1 ms + 0..0.3 ms jitter;
bus 0 has the lssd phase's slaves, the others slaves from other seeds).
Per mode, N and repetition, two fresh set-ups:

  alone     AutoAssign on vcan0, then on vcan1, ... one at a time: each bus's
            time alone; "slowest alone" is the largest of them;
  parallel  AutoAssign on every bus at once (one D-Bus connection and call per
            bus, sent one after the other from one thread): the time from the
            first call sent to the last reply read.

A call's time runs from its send to its reply read off the socket. The
repetitions go round the cases (every case's first, then every case's
second, ...): a minute of a loaded host costs one repetition of several
cases, not every repetition of one.

ratio = parallel / slowest alone (the target: about 1x). After every call
each slave's state file must hold the expected node-ID (active and stored,
LSS waiting), or the bench fails. Creates vcan2.. when missing (and removes
the ones it created).

Needs root and vcan: run it through bench/run (which uses tests/vm/run)."""

import argparse
import os
import shutil
import subprocess
import sys
import time
import traceback

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchlib as bl  # noqa: E402
import autoaddress as aa  # noqa: E402

MODES = ('mapped', 'vendor', 'serial', 'blind')


def bus_slaves(n, rep, b):
    """Bus 0: the lssd phase's slaves; bus b: another fixed seed."""
    return bl.identities(n, bl.seed_of(n, rep) + 1000003 * b)


def ensure_ifaces(names):
    created = []
    for ifname in names:
        if os.path.exists('/sys/class/net/' + ifname):
            continue
        subprocess.run(['modprobe', 'vcan'], check=False)
        subprocess.run(['ip', 'link', 'add', 'dev', ifname, 'type', 'vcan'], check=True)
        created.append(ifname)
        subprocess.run(['ip', 'link', 'set', 'dev', ifname, 'up'], check=True)
    return created


def one_setup(mode, n, rep, buses, parallel):
    """One fresh lssd + lss-sims; returns {'bus_s': [...], 'cpu_s': ..., 'frames': [...]}."""
    from lssdtest import BUS_IFACE, SERVICE, Env, Slave, bus_path

    slaves = {b: bus_slaves(n, rep, b) for b in buses}
    blocks, expected = [], {}
    for b, ifname in buses.items():
        text, expected[b] = aa.bus_block(mode, slaves[b], ifname)
        blocks.append(text)
    conf = 'buses = (\n%s\n);\n' % ',\n'.join(blocks)
    os.environ.setdefault('LSSD_LOG_LEVEL', 'debug')
    os.environ['LSSD_TEST_BACKEND'] = 'vcan'
    kind = 'parallel' if parallel else 'alone'
    who = 'lssd %d buses %s %s N=%d rep %d' % (len(buses), kind, mode, n, rep)
    with Env({ifname: [Slave(*s) for s in slaves[b]] for b, ifname in buses.items()}, config=conf,
             candump=True, sim_args=list(bl.SIM_ARGS)) as env:
        try:
            conns = {b: env.connect() for b in buses}
            time.sleep(0.2)  # lssd's start-up switch to waiting is not part of the run
            replies, times, errors = {}, {}, {}
            cpu0 = bl.proc_cpu_s(env.lssd.pid)
            sims0 = sum(bl.proc_cpu_s(p.pid) for p in env.sims.values())
            sys0 = bl.system_cpu()
            w0 = time.time()

            def send(b):
                return conns[b].send(SERVICE, bus_path(buses[b]), BUS_IFACE, 'AutoAssign', 'a{sv}', [{}])

            def wait(b, serial, t0):
                # timed from the send to the moment the reply was read (each
                # connection's reader thread): no client thread start-up or
                # reply handling in it, a 0.2 s pass is timed as lssd took it
                try:
                    body, got = conns[b].wait_reply(serial, 1800, timed=True)
                    replies[b] = body[0]
                    times[b] = got - t0
                except Exception as e:  # noqa: BLE001
                    errors[b] = repr(e)
                    times[b] = time.monotonic() - t0

            if parallel:
                # one thread sends every call, one after the other (a few ms
                # under TCG): the time runs from the first send to the last reply
                t0 = time.monotonic()
                serials = {b: send(b) for b in buses}
                for b in buses:
                    wait(b, serials[b], t0)
                total = max(times.values())
            else:
                for b in buses:
                    t0 = time.monotonic()
                    wait(b, send(b), t0)
                total = sum(times.values())
            w1 = time.time()
            cpu = bl.proc_cpu_s(env.lssd.pid) - cpu0
            # where the VM's CPUs went meanwhile: lssd, the lss-sims (the
            # slaves), the rest (candump, this harness, the kernel)
            sims = sum(bl.proc_cpu_s(p.pid) for p in env.sims.values()) - sims0
            sys1 = bl.system_cpu()
            busy = (sys1[0] - sys0[0]) / max(1, sys1[1] - sys0[1])
            if errors:
                raise bl.BenchFailure('%s: AutoAssign failed: %r' % (who, errors))
            time.sleep(0.3)  # let candump write the last frames
            frames = []
            for b, ifname in buses.items():
                bwho = '%s %s' % (who, ifname)
                aa.check_reply_and_states(replies[b], slaves[b], expected[b], env.state_dirs[ifname], bwho)
                frames.append(bl.frame_stats(bl.read_candump(env.candump_path, ifname, w0 - 0.05, w1 + 0.05)))
            # lssd's log of the set-up (the engine's account of each pass): where the time went
            shutil.copy(env.lssd_log_path, os.path.join(bl.results_dir(), 'parallel-%s-%s-n%d-rep%d.lssd.log'
                                                        % (kind, mode, n, rep)))
            engine = [line.split('engine: ', 1)[1] for line in env.lssd_output().splitlines()
                      if 'AutoAssign finished' in line and 'engine: ' in line]
            return {'bus_s': [times[b] for b in buses], 'total_s': total, 'cpu_s': cpu, 'sims_cpu_s': sims,
                    'cpus_busy': busy,
                    'frames': [f['frames'] for f in frames], 'floor_s': [f['floor_s'] for f in frames],
                    'engine': engine}
        except bl.BenchFailure:
            base = os.path.join(bl.results_dir(), 'failed-parallel-%s-%s-n%d-rep%d' % (kind, mode, n, rep))
            shutil.copy(env.lssd_log_path, base + '.lssd.log')
            shutil.copy(env.candump_path, base + '.candump.log')
            raise


def one_rep(mode, n, rep, buses, failures):
    """One repetition of a case: its alone and its parallel set-up."""
    r = {'rep': rep, 'seed': bl.seed_of(n, rep)}
    for kind in ('alone', 'parallel'):
        try:
            r[kind] = one_setup(mode, n, rep, buses, kind == 'parallel')
        except bl.BenchFailure as e:
            failures.append(str(e))
            bl.record_failure(str(e))
            bl.log('!!!! MIS-ASSIGNMENT / WRONG RESULT: %s' % e)
            r['failed'] = str(e)
        except Exception as e:  # noqa: BLE001
            failures.append('parallel %s %s N=%d rep %d: %r' % (kind, mode, n, rep, e))
            bl.log(traceback.format_exc())
            r['failed'] = repr(e)
    if 'failed' not in r:
        r['slowest_alone_s'] = max(r['alone']['bus_s'])
        r['parallel_s'] = r['parallel']['total_s']
        r['ratio'] = r['parallel_s'] / r['slowest_alone_s']
        bl.log('parallel %-7s N=%-3d rep %d: alone %s s, all %d at once %s s (%.2fx)' % (
            mode, n, rep, '/'.join('%.2f' % t for t in r['alone']['bus_s']), len(buses),
            '/'.join('%.2f' % t for t in r['parallel']['bus_s']), r['ratio']))
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--n', default='8,32', help='comma-separated slave counts per bus (default 8,32)')
    # a pass of 0.2 s follows one latency spike of the host: the ratio is of medians
    ap.add_argument('--reps', type=int, default=3, help='repetitions per case (default 3)')
    ap.add_argument('--modes', default='mapped,vendor,blind', help='modes: ' + ','.join(MODES))
    ap.add_argument('--buses', type=int, default=4, help='vcan0..vcanK-1 (default 4)')
    a = ap.parse_args()
    ns = [int(x) for x in a.n.split(',')]
    modes = a.modes.split(',')
    for m in modes:
        if m not in MODES:
            ap.error('unknown mode %s (parallel knows %s)' % (m, ','.join(MODES)))
    if not os.path.exists('/sys/class/net/vcan0'):
        bl.log('vcan0 is not there: run through bench/run (tests/vm/run)')
        return 2
    buses = {b: 'vcan%d' % b for b in range(a.buses)}
    created = ensure_ifaces(buses.values())
    failures = []
    try:
        runs = {(n, mode): [] for n in ns for mode in modes}
        for rep in range(a.reps):
            for n in ns:
                for mode in modes:
                    runs[(n, mode)].append(one_rep(mode, n, rep, buses, failures))
            # saved after every round: an aborted bench keeps what it measured
            for (n, mode), case_runs in runs.items():
                bl.save('parallel-%s-n%d' % (mode, n),
                        {'impl': 'lssd-parallel', 'mode': mode, 'n': n, 'reps': len(case_runs),
                         'buses': list(buses.values()), 'runs': case_runs, 'description': aa.MODES[mode],
                         'latency_ms': bl.LATENCY_MS, 'jitter_ms': bl.JITTER_MS})
    finally:
        for ifname in created:
            subprocess.run(['ip', 'link', 'del', 'dev', ifname], check=False)
    return bl.report_failures(failures)


if __name__ == '__main__':
    sys.exit(main())
