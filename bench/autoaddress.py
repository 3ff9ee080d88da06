#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Auto-addressing on vcan: lssd AutoAssign vs python-canopen's fastscan loop.

    autoaddress.py --impl lssd|canopen [--n 1,8,32] [--reps 5] [--modes mapped,vendor,serial,blind,...]
    autoaddress.py --impl lssd --hog [--n 8,32] [--reps 3] [--modes mapped,vendor,blind]

N non-configured lss-sim slaves (vendor 0x9A, product 3, random revision and
serial from a fixed seed per N and repetition; latency 1 ms + 0..0.3 ms
jitter) on vcan0, 125 kbit/s. Per run: wall time of the whole procedure,
frames on the bus (candump), the bus-time floor of those frames, lssd's CPU
time; afterwards every slave's state file must hold the expected node-ID
(active and stored, LSS waiting), or the bench fails. --hog: the same lssd
runs with a spinning `sh -c 'while :; do :; done'` on every CPU (every vCPU
of the VM) for the whole phase; saved as impl lssd-hog.

Needs root and vcan0: run it through bench/run (which uses tests/vm/run)."""

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
import traceback

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchlib as bl  # noqa: E402

IFNAME = 'vcan0'
POOL = (1, 64)

MODES = {
    'mapped': 'map with full identities',
    'vendor': 'vendor/product known (map: one absent device of that type; unknown = "pool")',
    'serial': 'map keyed by serial (vendor/product + serial, no revision)',
    'blind': 'blind (empty map, unknown = "pool")',
    'vendor-canopennode': 'vendor/product known, CANopenNode v4 slaves (lss-sim profile canopennode)',
    'blind-canopennode': 'blind, CANopenNode v4 slaves (lss-sim profile canopennode)',
}
PROFILE_SUFFIX = '-canopennode'  # the same pass on slaves that answer Fastscan in configuration state


def bus_block(mode, slaves, ifname=IFNAME):
    """One bus's libconfig group for one mode; returns (text, {identity: node} or None for the pool)."""
    head = '{ interface = "%s"; bitrate = %d; store = true;\n' % (ifname, bl.BITRATE)
    if mode == 'mapped':
        devs = ',\n'.join('{ vendor = 0x%x; product = 0x%x; revision = 0x%x; serial = 0x%x; node_id = %d; }'
                          % (s + (i + 1,)) for i, s in enumerate(slaves))
        return head + 'devices = (\n%s\n); }' % devs, {s: i + 1 for i, s in enumerate(slaves)}
    if mode == 'serial':
        devs = ',\n'.join('{ serial = 0x%x; node_id = %d; }' % (s[3], i + 1) for i, s in enumerate(slaves))
        return (head + 'vendor = 0x%x; product = 0x%x;\ndevices = (\n%s\n); }' % (bl.VENDOR, bl.PRODUCT, devs),
                {s: i + 1 for i, s in enumerate(slaves)})
    pool = 'unknown = "pool"; pool = [ %d, %d ];\n' % POOL
    if mode == 'vendor':
        # the only thing the map tells about the new devices is their vendor and product
        taken = {s[3] for s in slaves}
        absent = next(x for x in range(0xA0000000, 0xA0001000) if x not in taken)
        return (head + pool + 'devices = ( { vendor = 0x%x; product = 0x%x; revision = 0; serial = 0x%x; '
                'node_id = 127; } ); }' % (bl.VENDOR, bl.PRODUCT, absent), None)
    return head + pool + '}', None


def lssconf(mode, slaves):
    """libconfig text for one mode on vcan0; returns (text, {identity: node} or None for the pool)."""
    block, expected = bus_block(mode, slaves)
    return 'buses = ( %s );\n' % block, expected


def check_reply(reply, slaves, expected, who):
    """The AutoAssign reply must give every slave its node-ID (from the map,
    or distinct ones from the pool); returns {identity: node-ID}."""
    # the reply lists every device the pass dealt with (the vendor mode's absent one too)
    got = {tuple(r[:4]): r[5] for r in reply if r[6] in ('assigned', 'pool')}
    if expected is None:
        ids = sorted(got.values())
        if len(set(ids)) != len(ids) or any(not POOL[0] <= x <= POOL[1] for x in ids):
            raise bl.BenchFailure('%s: bad pool node-IDs %r' % (who, ids))
        expected = {s: got.get(s, 0) for s in slaves}
    if set(got) != set(slaves) or any(got[s] != expected[s] for s in slaves):
        raise bl.BenchFailure('%s: reply %r does not give every slave its node-ID' % (who, sorted(reply)))
    return expected


def check_reply_and_states(reply, slaves, expected, state_dir, who):
    """check_reply, then the state files; a wrong reply names what the
    state files hold too (a wrong account of a right assignment, or not)."""
    try:
        expected = check_reply(reply, slaves, expected, who)
    except bl.BenchFailure as e:
        if expected is not None:
            try:
                bl.check_states(state_dir, expected, who)
                held = 'every slave has its node-ID (active, stored, waiting)'
            except bl.BenchFailure as e2:
                held = str(e2)
        else:
            held = ', '.join('%08x: %s' % (x[3], '/'.join(bl.read_state(state_dir, x[3]).get(k, '?') for k in (
                'active_node_id', 'stored_node_id', 'lss_state'))) for x in slaves)
        raise bl.BenchFailure('%s; state files: %s' % (e, held))
    bl.check_states(state_dir, expected, who)
    return expected


def cpu_hogs():
    """A spinning shell on every CPU (every vCPU in the VM): a loaded host."""
    return [subprocess.Popen(['sh', '-c', 'while :; do :; done']) for _ in range(os.cpu_count() or 1)]


def stop_hogs(hogs):
    for p in hogs:
        p.kill()
        p.wait()


def run_lssd(mode, n, rep, simulate=False, hog=False):
    from lssdtest import Env, Slave

    slaves = bl.identities(n, bl.seed_of(n, rep))
    sim_args = list(bl.SIM_ARGS)
    base = mode
    if mode.endswith(PROFILE_SUFFIX):
        if simulate:
            raise bl.BenchFailure('%s: lssd --simulate has no lss-sim profiles' % mode)
        base = mode[:-len(PROFILE_SUFFIX)]
        sim_args += ['--profile', PROFILE_SUFFIX[1:]]
    conf, expected = lssconf(base, slaves)
    os.environ.setdefault('LSSD_LOG_LEVEL', 'debug')  # one line per job: the engine's counters
    os.environ['LSSD_TEST_BACKEND'] = 'simulate' if simulate else 'vcan'
    who = 'lssd%s%s %s N=%d rep %d' % (' --simulate' if simulate else '', ' (CPU hog)' if hog else '', mode, n, rep)
    with Env({IFNAME: [Slave(*s) for s in slaves]}, config=conf, candump=not simulate, sim_args=sim_args) as env:
        try:
            r = run_lssd_in(env, mode, n, rep, simulate, slaves, expected, who)
            if os.environ.get('LSSD_BENCH_KEEP_LOGS') == '1' and not simulate:
                base = os.path.join(bl.results_dir(), 'kept-vcan%s-%s-n%d-rep%d' % ('-hog' if hog else '', mode, n, rep))
                shutil.copy(env.lssd_log_path, base + '.lssd.log')
                shutil.copy(env.candump_path, base + '.candump.log')
            return r
        except bl.BenchFailure:
            # keep what lssd and the candump saw, for the findings
            base = os.path.join(bl.results_dir(), 'failed-%s-%s-n%d-rep%d'
                                % ('sim' if simulate else 'vcan-hog' if hog else 'vcan', mode, n, rep))
            shutil.copy(env.lssd_log_path, base + '.lssd.log')
            if not simulate:
                shutil.copy(env.candump_path, base + '.candump.log')
            raise


def run_lssd_in(env, mode, n, rep, simulate, slaves, expected, who):
    from lssdtest import BUS_IFACE, SERVICE, bus_path

    c = env.connect()
    time.sleep(0.2)  # lssd's start-up switch to waiting is not part of the run
    cpu0 = bl.proc_cpu_s(env.lssd.pid)
    w0, t0 = time.time(), time.monotonic()
    reply = c.call(SERVICE, bus_path(IFNAME), BUS_IFACE, 'AutoAssign', 'a{sv}', [{}], timeout=1800)[0]
    elapsed = time.monotonic() - t0
    w1 = time.time()
    cpu = bl.proc_cpu_s(env.lssd.pid) - cpu0
    if simulate:
        expected = check_reply(reply, slaves, expected, who)
        # the slaves live inside lssd: ask each one its node-ID (selective switch + inquire)
        now = {}
        for ident in slaves:
            r = c.call(SERVICE, bus_path(IFNAME), BUS_IFACE, 'Execute', 'a(sv)', [[
                ('SwitchModeSelective', ('(uuuu)', ident)), ('InquireNodeId', ('b', True))]], timeout=60)[0]
            now[ident] = r[1][1] if r[0] == ('b', True) else None
        if now != expected:
            raise bl.BenchFailure('%s: after the pass the slaves answer %r, expected %r' % (who, now, expected))
        stats = {}
    else:
        time.sleep(0.3)  # let candump write the last frames
        frames = bl.read_candump(env.candump_path, IFNAME, w0 - 0.05, w1 + 0.05)
        stats = dict(bl.frame_stats(frames), steps=bl.step_times(frames))
        check_reply_and_states(reply, slaves, expected, env.state_dirs[IFNAME], who)
    c.close()
    env.conns.remove(c)
    # the engine's own account of the pass (steps, retries, timeouts, waits): the profile
    engine = [line.split('engine: ', 1)[1] for line in env.lssd_output().splitlines()
              if 'AutoAssign finished' in line and 'engine: ' in line]
    return dict(stats, elapsed_s=elapsed, cpu_s=cpu, engine=engine[-1] if engine else '')


def run_canopen(n, rep):
    import canopen

    slaves = bl.identities(n, bl.seed_of(n, rep))
    work = tempfile.mkdtemp(prefix='lssd-bench.', dir=os.environ.get('LSSD_RUNTIME_DIR'))
    try:
        with bl.Procs(IFNAME, slaves, work) as procs:
            net = canopen.Network()
            net.connect(interface='socketcan', channel=IFNAME)
            try:
                found = {}
                w0, t0 = time.time(), time.monotonic()
                # what python-canopen's users do (its docs' LSS example, in a loop)
                next_id = 1
                while True:
                    ok, lss_id = net.lss.fast_scan()
                    if not ok:
                        break
                    net.lss.configure_node_id(next_id)
                    net.lss.store_configuration()
                    net.lss.send_switch_state_global(net.lss.WAITING_STATE)
                    found.setdefault(tuple(lss_id), []).append(next_id)
                    next_id += 1
                    if next_id > n + 3:
                        raise bl.BenchFailure('canopen N=%d rep %d: fast_scan keeps finding slaves: %r'
                                              % (n, rep, found))
                elapsed = time.monotonic() - t0
                w1 = time.time()
            finally:
                net.disconnect()
            time.sleep(0.3)
            frames = bl.read_candump(procs.candump_path, IFNAME, w0 - 0.05, w1 + 0.05)
            who = 'canopen N=%d rep %d' % (n, rep)
            wrong = [k for k in found if k not in slaves or len(found[k]) != 1]
            if wrong or len(found) != n:
                raise bl.BenchFailure('%s: fast_scan reported %r, slaves are %r' % (who, found, slaves))
            bl.check_states(procs.state_dir, {s: found[s][0] for s in slaves}, who)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return dict(bl.frame_stats(frames), elapsed_s=elapsed)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--impl', choices=('lssd', 'lssd-sim', 'canopen'), required=True,
                    help='lssd-sim: lssd --simulate on the host (in-memory bus, no vcan, no VM)')
    ap.add_argument('--n', default=None, help='comma-separated slave counts (lssd: 1,8,32; canopen: 1,8)')
    ap.add_argument('--reps', type=int, default=None, help='repetitions per case (lssd: 5, canopen: 3)')
    ap.add_argument('--hog', action='store_true',
                    help='(--impl lssd) a spinning shell on every CPU, started before the first run and killed '
                    'after the last; saved as impl lssd-hog (default N 8,32, modes mapped,vendor,blind)')
    ap.add_argument('--modes', default=None,
                    help='lssd modes (default mapped,vendor,blind and, on vcan, the two -canopennode ones): '
                    + ','.join(MODES))
    a = ap.parse_args()
    if a.hog and a.impl != 'lssd':
        ap.error('--hog is for --impl lssd')
    lssd = a.impl != 'canopen'
    impl = 'lssd-hog' if a.hog else a.impl
    ns = [int(x) for x in (a.n or ('8,32' if a.hog else '1,8,32' if lssd else '1,8')).split(',')]
    reps = a.reps or (3 if a.hog else 5 if lssd else 3)
    if a.modes is None:
        a.modes = 'mapped,vendor,blind' + (',vendor-canopennode,blind-canopennode'
                                           if a.impl == 'lssd' and not a.hog else '')
    modes = a.modes.split(',') if lssd else ['canopen']
    for m in modes:
        if lssd and m not in MODES:
            ap.error('unknown mode ' + m)
    if a.impl != 'lssd-sim' and not os.path.exists('/sys/class/net/' + IFNAME):
        bl.log('%s is not there: run through bench/run (tests/vm/run)' % IFNAME)
        return 2

    failures = []
    hogs = cpu_hogs() if a.hog else []
    try:
        run_cases(a, impl, lssd, ns, modes, reps, failures)
    finally:
        stop_hogs(hogs)
    return bl.report_failures(failures)


def run_cases(a, impl, lssd, ns, modes, reps, failures):
    """The repetitions go round the cases (every case's first, then every
    case's second, ...): a minute of a loaded host costs one repetition of
    several cases, not every repetition of one. Saved after every round."""
    runs = {(n, mode): [] for n in ns for mode in modes}
    for rep in range(reps):
        for n in ns:
            for mode in modes:
                try:
                    r = run_lssd(mode, n, rep, a.impl == 'lssd-sim', a.hog) if lssd else run_canopen(n, rep)
                except bl.BenchFailure as e:
                    failures.append(str(e))
                    bl.record_failure(str(e))
                    bl.log('!!!! MIS-ASSIGNMENT / WRONG RESULT: %s' % e)
                    r = {'failed': str(e)}
                except Exception as e:  # noqa: BLE001
                    failures.append('%s %s N=%d rep %d: %r' % (impl, mode, n, rep, e))
                    bl.log(traceback.format_exc())
                    r = {'failed': repr(e)}
                r.update(rep=rep, seed=bl.seed_of(n, rep))
                runs[(n, mode)].append(r)
                bl.log('%-7s %-7s N=%-3d rep %d: %s' % (impl, mode, n, rep, ' '.join(
                    '%s=%s' % (k, ('%.4g' % v) if isinstance(v, float) else v) for k, v in sorted(r.items()))))
        for (n, mode), case_runs in runs.items():
            bl.save('autoaddress-%s-%s-n%d' % (impl, mode, n),
                    {'impl': impl, 'mode': mode, 'n': n, 'reps': len(case_runs), 'runs': case_runs,
                     'hog_processes': os.cpu_count() if a.hog else 0,
                     'description': MODES.get(mode, 'python-canopen fast_scan loop, its defaults'),
                     'latency_ms': bl.LATENCY_MS, 'jitter_ms': bl.JITTER_MS})


if __name__ == '__main__':
    sys.exit(main())
