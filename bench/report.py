#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Prints the benchmark tables from the results bench/run saved
(BUILDDIR/bench-results/*.json), the targets met or missed, and as the last
line the speedup of lssd over python-canopen at N = 8."""

import os
import platform
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchlib as bl  # noqa: E402

ORDER = ['mapped', 'vendor', 'serial', 'blind', 'vendor-canopennode', 'blind-canopennode', 'canopen']  # modes
LABEL = {'mapped': 'lssd, map (full identities)', 'vendor': 'lssd, vendor/product known',
         'serial': 'lssd, map keyed by serial', 'blind': 'lssd, blind (pool)',
         'vendor-canopennode': 'lssd, vendor known, CANopenNode', 'blind-canopennode': 'lssd, blind, CANopenNode',
         'canopen': 'python-canopen fast_scan loop'}
SPEEDUP_NAME = {'mapped': 'mapped', 'vendor': 'known-vendor', 'blind': 'blind'}
# lssd's modes and engine-bench's cases: the same procedure (AutoAssign with the mode's map)
ENGINE_CASE = {'mapped': 'e', 'vendor': 'g', 'blind': 'h'}
ENGINE_NAME = {'e': '(e) AutoAssign, full map', 'g': '(g) AutoAssign pool, v+p', 'h': '(h) AutoAssign pool, blind'}
ENGINE_ROW = re.compile(r'^\(([a-h])\)\D*?\s+(\d+)\s+(\d+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)x\s*$')
PARALLEL_MAX = 1.2  # "about as long as the slowest bus alone"


def engine_table():
    """engine-bench's output: run now (LSSD_ENGINE_BENCH or BUILDDIR/bench/engine-bench, ~1 s;
    saved as engine.txt), else the engine phase's engine.txt. Returns (text, where)."""
    path = os.environ.get('LSSD_ENGINE_BENCH') or os.path.join(os.path.dirname(bl.results_dir()), 'bench',
                                                                'engine-bench')
    if os.access(path, os.X_OK):
        try:
            p = subprocess.run([path], capture_output=True, text=True, timeout=300)
            if p.returncode == 0 and p.stdout.strip():
                with open(os.path.join(bl.results_dir(), 'engine.txt'), 'w') as f:
                    f.write(p.stdout)
                return p.stdout.rstrip(), 'run now'
        except (OSError, subprocess.SubprocessError):
            pass
    try:
        with open(os.path.join(bl.results_dir(), 'engine.txt')) as f:
            return f.read().rstrip(), 'engine.txt'
    except OSError:
        return '', ''


def engine_per_node(text):
    """{(case letter, N): s/node in virtual time} from engine-bench's first table."""
    out = {}
    for line in text.splitlines():
        m = ENGINE_ROW.match(line)
        if m:
            out[(m.group(1), int(m.group(2)))] = float(m.group(7)) / 1000
    return out


def machine():
    cpu = '?'
    try:
        with open('/proc/cpuinfo') as f:
            for line in f:
                if line.startswith('model name'):
                    cpu = line.split(':', 1)[1].strip()
                    break
    except OSError:
        pass
    return '%s, %d cores, Linux %s' % (cpu, os.cpu_count() or 0, platform.release())


def ok_runs(case):
    return [r for r in case['runs'] if 'failed' not in r]


def tally(c, what, failures):
    """The runs of a case whose every slave was right, 'k of n right' for
    the table, and a line in `failures` for each wrong run."""
    runs = ok_runs(c)
    bad = len(c['runs']) - len(runs)
    for r in c['runs']:
        if 'failed' in r:
            failures.append('%s rep %d: %s' % (what, r['rep'], r['failed']))
    return runs, '%d of %d right' % (len(runs), len(c['runs'])) + (' !!!! %d WRONG' % bad if bad else '')


def med(runs, key):
    s = bl.summary([r[key] for r in runs if key in r])
    return s


def fmt_spread(s, scale=1.0, digits=3):
    if not s.get('n'):
        return '-'
    return '%.*f (%.*f-%.*f)' % (digits, s['median'] * scale, digits, s['min'] * scale, digits, s['max'] * scale)


def canopen_waits(n, seed):
    """python-canopen's own fixed waits for these slaves: its 0.5 s response
    timeout for every bit nobody answers (the 1-bits of the lowest identity
    left), its 10 ms pause after each of the 133 fastscan messages of a
    found node, and the final ping nobody answers."""
    total = 0.5
    for ident in sorted(bl.identities(n, seed)):
        total += 0.5 * sum(bin(x).count('1') for x in ident) + 133 * 0.01
    return total


def where_time_goes(allcases):
    """Steps from the candump of each VM case's median run (benchlib.step_times)."""
    rows = []
    for mode in ORDER:
        for (impl, m, n), c in sorted(allcases.items()):
            if impl != 'lssd' or m != mode:
                continue
            runs = [r for r in tally(c, '%s %s N=%d' % (impl, mode, n), [])[0] if r.get('steps')]
            if runs:
                runs.sort(key=lambda r: r['elapsed_s'])
                rows.append((mode, n, runs[len(runs) // 2]))
    if not rows:
        return
    print()
    print('## Where the time goes (vcan0 in the VM; candump of the median run: a step is a request up to the next)')
    print('%-31s %3s %8s %8s %9s %-27s %7s %8s %9s' % (
        'case', 'N', 'time s', 'answered', 'answered s', 'latency ms p50/p90/p99/max', 'silent', 'silent s',
        'silent ms'))
    for mode, n, r in rows:
        st = r['steps']
        lat = st['latency_ms']
        print('%-31s %3d %8.2f %8d %9.2f  %-26s %7d %8.2f %9.2f' % (
            LABEL[mode], n, r['elapsed_s'], st['answered'], st['answered_s'],
            '/'.join('%.1f' % lat[k] for k in ('50', '90', '99', '100')) if lat else '-',
            st['silent'], st['silent_s'], st['silent_ms_median']))
    print('# answered s: from each answered request to the next request (latency + the answer guard that lets '
          'further answers in); silent s: from each unanswered request to the next (the no-answer wait + the late '
          'guard); silent ms: their median. The waits follow the slowest answers of the last 32 (docs/engine.md)')


def main():
    res = bl.load_all()
    print('# lssd benchmarks, %s' % machine())
    dates = sorted({v.get('saved', '?')[:10] for v in res.values()})
    print('# results of %s; binaries built from %s' % (', '.join(dates), ', '.join(
        sorted({v.get('source', '?') for v in res.values()}))))
    # what users run: no bench configuration sets a timing of its own
    print('# lssd at its default timing (lss_timeout_ms 20, adaptive waits), as installed')
    allcases = {(v['impl'], v['mode'], v['n']): v for k, v in res.items() if k.startswith('autoaddress-')}
    failures = []
    medians = {}
    for impl, title in (('vm', 'vcan0 in the qemu/TCG VM (lss-sim, candump)'),
                        ('lssd-sim', 'lssd --simulate on the host (in-memory bus, slaves inside lssd: '
                                     'no frames counted)')):
        cases = {(m, n): v for (i, m, n), v in allcases.items()
                 if (i in ('lssd', 'canopen') if impl == 'vm' else i == impl)}
        if not cases:
            continue
        print()
        print('## Auto-addressing, %s; 125 kbit/s, N non-configured slaves (latency %s)' % (
            title, '1 ms + 0..0.3 ms jitter' if impl == 'vm' else '0.5 ms'))
        print('%-31s %3s %4s %-26s %8s %7s %7s %9s %7s %-22s' % (
            'case', 'N', 'reps', 'time s: median (min-max)', 's/node', 'frames', 'LSS', 'floor ms', 'x floor',
            'lssd CPU s: median (min-max)'))
        for mode in ORDER:
            for n in sorted({k[1] for k in cases}):
                c = cases.get((mode, n))
                if not c:
                    continue
                runs, _ = tally(c, '%s %s N=%d' % (c['impl'], mode, n), failures)
                t = med(runs, 'elapsed_s')
                bad = len(c['runs']) - len(runs)
                if not t.get('n'):
                    print('%-31s %3d %4d FAILED (%d of %d runs wrong)' % (LABEL[mode], n, len(c['runs']), bad,
                                                                         len(c['runs'])))
                    continue
                medians[(impl, mode, n)] = t['median']
                fr, lss, fl = med(runs, 'frames'), med(runs, 'lss_frames'), med(runs, 'floor_s')
                cpu = med(runs, 'cpu_s')
                if fr.get('n'):
                    frames = '%7d %7d %9.1f %6.1fx' % (fr['median'], lss['median'], fl['median'] * 1000,
                                                      t['median'] / fl['median'])
                else:
                    frames = '%7s %7s %9s %7s' % ('-', '-', '-', '-')
                print('%-31s %3d %4d %-26s %8.3f %s %-22s%s' % (
                    LABEL[mode], n, len(runs), fmt_spread(t), t['median'] / n, frames,
                    fmt_spread(cpu, digits=2) if cpu.get('n') else '-',
                    '  + %d WRONG run(s)' % bad if bad else ''))
    where_time_goes(allcases)
    canopen = [(n, c) for (i, m, n), c in sorted(allcases.items()) if i == 'canopen']
    for n, c in canopen:
        runs = ok_runs(c)
        if runs:
            w = [canopen_waits(n, r['seed']) for r in runs]
            t = [r['elapsed_s'] for r in runs]
            print('# python-canopen N=%d: its own fixed waits (0.5 s timeouts, 10 ms pauses) %.1f s median = %.0f%% '
                  'of its time' % (n, bl.summary(w)['median'], 100 * sum(w) / sum(t)))
    if medians:
        print('# time: wall time of the whole procedure (one AutoAssign call; python-canopen: its loop until '
              'fast_scan finds nothing);')
        print('# frames: every frame on vcan0 meanwhile (candump); floor: their bus time at 125 kbit/s with exact '
              'bit stuffing; x floor = time / floor')

    # ---- the same cases with a CPU hog on every vCPU, beside the idle figures ----
    hog = {(m, n): c for (i, m, n), c in allcases.items() if i == 'lssd-hog'}
    hog_medians = {}
    if hog:
        print()
        print('## Auto-addressing with a CPU hog: a spinning shell on every vCPU of the VM (%s), beside the idle '
              'figures above (vcan0, same slaves)' % ', '.join(sorted({str(c.get('hog_processes', '?'))
                                                                     for c in hog.values()})))
        print('%-31s %3s %4s %9s %-26s %8s %8s %8s %-22s %s' % (
            'case', 'N', 'reps', 'idle s', 'CPU hog s: median (min-max)', 'idle s/n', 'hog s/n', 'hog/idle',
            'lssd CPU s (hog)', 'results'))
        for mode in ORDER:
            for n in sorted({k[1] for k in hog}):
                c = hog.get((mode, n))
                if not c:
                    continue
                runs, right = tally(c, '%s %s N=%d' % (c['impl'], mode, n), failures)
                t = med(runs, 'elapsed_s')
                idle = medians.get(('vm', mode, n))
                if not t.get('n'):
                    print('%-31s %3d %4d %9s %-26s %8s %8s %8s %-22s %s' % (
                        LABEL[mode], n, len(c['runs']), '%.3f' % idle if idle else '-', 'FAILED', '-', '-', '-', '-',
                        right))
                    continue
                hog_medians[(mode, n)] = t['median']
                print('%-31s %3d %4d %9s %-26s %8s %8.3f %8s %-22s %s' % (
                    LABEL[mode], n, len(runs), '%.3f' % idle if idle else '-', fmt_spread(t),
                    '%.3f' % (idle / n) if idle else '-', t['median'] / n,
                    '%.2fx' % (t['median'] / idle) if idle else '-', fmt_spread(med(runs, 'cpu_s'), digits=2), right))
        print('# results: runs whose every slave got the expected node-ID (reply and state files, as above); '
              'slower is fine')

    # ---- buses in parallel ----
    par = {(v['mode'], v['n']): v for k, v in res.items() if k.startswith('parallel-')}
    par_ratio = {}
    if par:
        nb = max(len(v.get('buses', [])) for v in par.values())
        print()
        print('## Buses in parallel: AutoAssign on %d vcan buses at once vs each bus alone (VM; one lssd with the %d '
              'buses, one lss-sim per bus, N slaves per bus)' % (nb, nb))
        print('%-31s %5s %4s %-26s %-26s %7s %-27s %-27s %-22s %s' % (
            'case', 'N/bus', 'reps', 'slowest alone s: median', 'all at once s: median', 'ratio',
            'alone per bus s (rep 0)', 'at once per bus s (rep 0)', 'at once: CPUs lssd sims', 'results'))
        for mode in ORDER:
            for n in sorted({k[1] for k in par}):
                c = par.get((mode, n))
                if not c:
                    continue
                runs, right = tally(c, 'parallel %s N=%d' % (mode, n), failures)
                if not runs:
                    print('%-31s %5d %4d FAILED %s' % (LABEL[mode], n, len(c['runs']), right))
                    continue
                ratio = bl.summary([r['ratio'] for r in runs])
                par_ratio[(mode, n)] = ratio['median']
                r0 = runs[0]
                p0 = r0['parallel']
                load = ('%3.0f%% %5.2f %5.2f' % (100 * p0['cpus_busy'], p0['cpu_s'], p0['sims_cpu_s'])
                        if 'cpus_busy' in p0 else '-')
                print('%-31s %5d %4d %-26s %-26s %6.2fx %-27s %-27s %-22s %s' % (
                    LABEL[mode], n, len(runs), fmt_spread(med(runs, 'slowest_alone_s')),
                    fmt_spread(med(runs, 'parallel_s')), ratio['median'],
                    '/'.join('%.2f' % t for t in r0['alone']['bus_s']),
                    '/'.join('%.2f' % t for t in p0['bus_s']), load, right))
        print('# alone: AutoAssign on one bus after the other (fresh slaves), each call timed from its send to its reply '
              'read; at once: one call per bus, sent one after the other, timed from the first send to the last reply;')
        print('# ratio = at once / slowest alone (target: about 1x); results: every slave of every bus at its node-ID '
              '(reply and state files)')
        print('# at once (rep 0): how busy the VM\'s CPUs were (all of them, /proc/stat), and the CPU seconds of lssd '
              'and of the lss-sims (the slaves) meanwhile; the rest: candump, the harness, the kernel')

    # ---- targets ----
    print()
    print('## Targets')
    targets = []
    c8 = medians.get(('vm', 'canopen', 8))
    for mode, want in (('mapped', 100), ('blind', 10)):
        if c8 and ('vm', mode, 8) in medians:
            x = c8 / medians[('vm', mode, 8)]
            targets.append(('%s >= %dx faster than python-canopen at N = 8 (VM)' % (mode, want), x >= want,
                            '%.0fx' % x))
    for impl in ('vm', 'lssd-sim'):
        for mode in ('mapped', 'vendor', 'serial', 'blind'):
            if (impl, mode, 8) in medians and (impl, mode, 32) in medians:
                r = (medians[(impl, mode, 32)] / 32) / (medians[(impl, mode, 8)] / 8)
                targets.append(('lssd %s linear (%s): s/node N=32 within 1.2x of N=8' % (mode, impl), r <= 1.2,
                                '%.2fx' % r))
    # issue 22: seconds per node in the VM, and a blind Scan of 127
    for mode, want in (('mapped', 0.030), ('vendor', 0.40), ('blind', 0.55)):
        for n in (8, 32):
            if ('vm', mode, n) in medians:
                per = medians[('vm', mode, n)] / n
                targets.append(('lssd %s (vm), N=%d: <= %.3f s/node' % (mode, n, want), per <= want,
                                '%.3f s/node' % per))
    for k in ('footprint-vcan',):
        fp = res.get(k)
        if fp and 'scan' in fp and 'failed' not in fp['scan']:
            targets.append(('blind Scan of %d slaves (vm) <= 70 s' % fp['slaves'], fp['scan']['elapsed_s'] <= 70,
                            '%.1f s' % fp['scan']['elapsed_s']))
    for (mode, n), x in sorted(par_ratio.items(), key=lambda kv: (ORDER.index(kv[0][0]), kv[0][1])):
        targets.append(('lssd %s, %d buses at once, N=%d/bus: <= %.1fx slowest alone' % (
            mode, max(len(v.get('buses', [])) for v in par.values()), n, PARALLEL_MAX), x <= PARALLEL_MAX,
            '%.2fx' % x))
    if hog:
        hog_runs = sum(len(c['runs']) for c in hog.values())
        hog_bad = sum(1 for c in hog.values() for r in c['runs'] if 'failed' in r)
        targets.append(('every result right with a CPU hog on every vCPU (%d runs)' % hog_runs, hog_bad == 0,
                        '%d wrong' % hog_bad))
    n_runs = sum(len(c['runs']) for c in allcases.values()) + 2 * sum(len(c['runs']) for c in par.values())
    try:
        with open(os.path.join(bl.results_dir(), 'failures.log')) as f:
            history = [line.rstrip() for line in f if line.strip()]
    except OSError:
        history = []
    # failures.log has the current runs' failures too
    earlier = max(0, len(history) - len(failures))
    targets.append(('zero wrong results over all %d runs (+ failures.log)' % n_runs, not failures and not earlier,
                    '%d wrong in these runs, %d in earlier runs (failures.log)' % (len(failures), earlier)))
    for key, what in (('encoder-mixed', 'VM'), ('encoder-mixed-hog', 'VM, a spinning process on every CPU')):
        em = res.get(key)
        if em:
            targets.append(('encoder scenario on a mixed bus: every boot pass right (%s)' % what,
                            em['right'] == len(em['runs']), '%d of %d right' % (em['right'], len(em['runs']))))
    fps = [res[k] for k in ('footprint-vcan', 'footprint-sim') if k in res]
    for fp in fps:
        if 'rss_after_scan_kib' in fp:
            rss = fp['rss_after_scan_kib']
            targets.append(('RSS <= 4 MiB with %d devices (%s)' % (fp['slaves'], fp['backend']), rss['VmRSS'] <= 4096,
                            '%d KiB (anon %d KiB)' % (rss['VmRSS'], rss.get('RssAnon', 0))))
        w = fp['idle_no_watchdog']['per_s']
        targets.append(('0 idle wakeups/s without watchdog (%s)' % fp['backend'], w == 0, '%.3f/s' % w))
    dl = res.get('dbus-load')
    if dl:
        lost = dl['gets']['lost'] + sum(j['lost'] for j in dl['jobs'])
        targets.append(('no lost D-Bus call', lost == 0, '%d lost' % lost))
    for what, ok, got in targets:
        print('%-62s %-6s %s' % (what, 'MET' if ok else 'MISSED', got))

    for fp in fps:
        print()
        print('## Footprint of lssd (%s%s)' % (fp['backend'], ', qemu/TCG VM' if fp.get('in_vm') else ''))

        def rss_line(label, r):
            extra = ', Pss %d, private dirty %d' % (r['Pss'], r['Private_Dirty']) if 'Pss' in r else ''
            print('%-34s %5d KiB (anon %d, file %d%s; peak %d)' % (label, r['VmRSS'], r.get('RssAnon', 0),
                                                                  r.get('RssFile', 0), extra, r.get('VmHWM', 0)))
        rss_line('RSS after start, %d slaves' % fp['slaves'], fp['rss_start_kib'])
        if 'rss_after_scan_kib' in fp:
            rss_line('RSS after Scan of %d slaves' % fp['slaves'], fp['rss_after_scan_kib'])
            print('%-34s %.1f s, lssd CPU %.2f s (%s)%s' % (
                'Scan of %d slaves' % fp['slaves'], fp['scan']['elapsed_s'], fp['scan']['cpu_s'],
                fp['scan']['options'], ' !!!! ' + fp['scan']['failed'] if 'failed' in fp['scan'] else ''))
        cs = fp.get('configured_scan')
        if cs:
            print('%-34s %.1f s: %d found; its %d SDO requests on the bus: floor %.2f s (x %.1f)%s' % (
                'Scan of %d configured slaves' % fp['slaves'], cs['elapsed_s'], cs['found'], cs['sdo_requests'],
                cs['sdo_floor_s'], cs['elapsed_s'] / cs['sdo_floor_s'] if cs['sdo_floor_s'] else 0,
                ' !!!! ' + cs['failed'] if 'failed' in cs else ''))
        for k, label in (('idle_no_watchdog', 'no watchdog'), ('idle_watchdog_30s', 'WATCHDOG_USEC=30 s')):
            i = fp[k]
            print('%-34s %d in %.0f s = %.3f/s (CPU %.2f s)%s' % (
                'idle wakeups, ' + label, i['wakeups'], i['seconds'], i['per_s'], i['cpu_s'],
                ', %d watchdog pings' % i['watchdog_pings_seen'] if 'watchdog_pings_seen' in i else ''))
    for impl in ('lssd', 'lssd-sim'):
        for mode in ('mapped', 'vendor', 'blind'):
            c = allcases.get((impl, mode, 32))
            if c and ok_runs(c):
                print('CPU time of a 32-device AutoAssign (%s, %s): %s s' % (
                    mode, 'vcan in the VM' if impl == 'lssd' else 'lssd --simulate, host',
                    fmt_spread(med(ok_runs(c), 'cpu_s'), digits=2)))

    engine, engine_from = engine_table()
    if engine:
        print()
        print('## The engine alone (build/bench/engine-bench, %s: in-memory bus, virtual time, floor 1 ms)'
              % engine_from)
        print(engine)

    if dl:
        print()
        print('## D-Bus load (%s)' % dl['backend'])
        print('%-58s %6s %8s %6s %9s %9s %9s  %s' % ('calls (one client connection each)', 'calls', 'answered',
                                                   'lost', 'p50 ms', 'p99 ms', 'max ms', 'errors'))
        g = dl['gets']
        print('%-58s %6d %8d %6d %9.1f %9.1f %9.1f  %s' % ('Properties.Get, all at once', g['calls'], g['answered'],
                                                          g['lost'], g['p50_ms'], g['p99_ms'], g['max_ms'],
                                                          g['errors'] or '-'))
        for j in dl['jobs']:
            print('%-58s %6d %8d %6d %9.1f %9.1f %9.1f  %s' % (
                'Execute(SwitchModeSelective, InquireNodeId), queue %s' % j['queue_size'], j['calls'], j['answered'],
                j['lost'], j['p50_ms'], j['p99_ms'], j['max_ms'], j['errors'] or '-'))

    eng = engine_per_node(engine)
    rows = [(mode, n) for mode in ('mapped', 'vendor', 'blind') for n in sorted({k[2] for k in medians})
            if ('vm', mode, n) in medians and (ENGINE_CASE[mode], n) in eng]
    if rows:
        print()
        print('## lssd in the VM against the engine alone (engine-bench, virtual time): s/node and their ratio')
        print('%-31s %3s %-27s %13s %12s %13s %12s' % ('case', 'N', 'engine case', 'lssd s/node', 'engine s/n',
                                                       'lssd/engine', 'hog/engine'))
        for mode, n in rows:
            lssd_pn = medians[('vm', mode, n)] / n
            eng_pn = eng[(ENGINE_CASE[mode], n)]
            hog_pn = hog_medians.get((mode, n))
            print('%-31s %3d %-27s %13.3f %12.3f %12.2fx %12s' % (
                LABEL[mode], n, ENGINE_NAME[ENGINE_CASE[mode]], lssd_pn, eng_pn, lssd_pn / eng_pn,
                '%.2fx' % (hog_pn / n / eng_pn) if hog_pn else '-'))
        print('# lssd s/node: median wall time / N (VM, vcan0, idle); engine s/n: engine-bench ms/node (same latency '
              'and bus, virtual time); hog: the CPU hog runs')
        print("# the engine case runs lssd's procedure, AutoAssign with the bench's map (and pool); its bus has 125 "
              'kbit/s frame times, vcan none. The targets of issue 22 came from (c), (b) and (a), one assignment (and '
              "fastscan) per device: no probe, no enumeration (confirmation and selection of each find), no absent "
              'device looked for twice')

    if history:
        print()
        print('# wrong results recorded in earlier runs (failures.log; their case files were replaced since):')
        for line in history:
            print('#   ' + line[:300])
    if failures:
        print()
        print('!!!! WRONG RESULTS (the bench fails):')
        for f in failures:
            print('!!!!  ' + f)
    print()
    if c8:
        host = ['%s %.0fx' % (SPEEDUP_NAME[m], c8 / medians[('lssd-sim', m, 8)])
                for m in ('mapped', 'vendor', 'blind') if ('lssd-sim', m, 8) in medians]
        if host:
            print('# context, not side by side: python-canopen (VM, %.0f%% its own fixed waits) vs lssd --simulate '
                  '(host), N = 8: %s' % (100 * sum(canopen_waits(8, r['seed']) for r in ok_runs(allcases[
                      ('canopen', 'canopen', 8)])) / sum(r['elapsed_s'] for r in ok_runs(allcases[
                          ('canopen', 'canopen', 8)])), ', '.join(host)))
        parts = []
        for mode in ('mapped', 'vendor', 'blind'):
            m = medians.get(('vm', mode, 8))
            parts.append('%s %s' % (SPEEDUP_NAME[mode], ('%.0fx' % (c8 / m)) if m else '?'))
        print('speedup vs python-canopen: ' + ', '.join(parts))
    else:
        print('speedup vs python-canopen: ? (no python-canopen result at N = 8: bench/run --only canopen)')
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main())
