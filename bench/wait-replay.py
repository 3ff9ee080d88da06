#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""What other no-answer waits would have cost, replayed on a candump.

    wait-replay.py CANDUMP...

For the fastscan bit steps of a kept candump (LSSD_BENCH_KEEP_LOGS=1 in
bench/autoaddress.py: BUILDDIR/bench-results/kept-*.candump.log) it takes
each answered step's latency (request to first answer, as candump saw them)
and each silent step, and replays the wait rule of docs/engine.md with other
estimators: a silent step decides at T + T/4 (the late guard), T = factor x
the estimator over the last 32 latencies. Printed per rule: the waits of the
silent steps, and how many answered steps answered later than that rule's
silence would have (each a bit read wrong: the field is not confirmed and is
scanned again, ~33 steps), with that retry cost estimated from the mean
fastscan step of the same file. A model, not a run: patience, the guard
floor and the shift a retry causes are left out. Not a test."""

import re
import sys

WINDOW = 32
RULES = [('max', 1.5, 1), ('max', 1.25, 1), ('2nd max', 1.5, 2), ('2nd max', 1.25, 2), ('3rd max', 1.5, 3)]
RETRY_STEPS = 33


def fastscan_steps(path):
    """[('answered', latency_ms) | ('silent', duration_ms)] of the fastscan bit steps, and every fastscan step's mean ms."""
    rows = []
    with open(path) as f:
        for line in f:
            m = re.match(r'\((\d+\.\d+)\) \S+ (\w+)#(\w*)', line)
            if m:
                rows.append((float(m.group(1)), int(m.group(2), 16), m.group(3)))
    reqs = [i for i, r in enumerate(rows) if r[1] == 0x7E5]
    steps, all_ms = [], []
    for a, b in zip(reqs, reqs[1:]):
        data = rows[a][2]
        if data[:2] != '51':
            continue
        all_ms.append((rows[b][0] - rows[a][0]) * 1000)
        if data[10:12] in ('80', '00'):  # the ping and confirmations wait by other rules
            continue
        answers = [r for r in rows[a + 1:b] if r[1] == 0x7E4]
        if answers:
            steps.append(('answered', (answers[0][0] - rows[a][0]) * 1000))
        else:
            steps.append(('silent', (rows[b][0] - rows[a][0]) * 1000))
    return steps, sum(all_ms) / max(1, len(all_ms))


def replay(steps, rank, factor):
    window, waits, late = [], 0.0, 0
    for kind, ms in steps:
        if not window:
            decide = None  # the first wait is the full timeout: not replayed
        else:
            est = sorted(window)[-min(rank, len(window))]
            decide = factor * est * 1.25
        if kind == 'answered':
            if decide is not None and ms > decide:
                late += 1
            window = (window + [ms])[-WINDOW:]
        elif decide is not None:
            waits += decide
    return waits / 1000, late


def main():
    if len(sys.argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    for path in sys.argv[1:]:
        steps, step_ms = fastscan_steps(path)
        lat = sorted(ms for kind, ms in steps if kind == 'answered')
        silent = [ms for kind, ms in steps if kind == 'silent']
        if not lat or not silent:
            print('%s: no fastscan bit steps' % path)
            continue
        q = lambda p: lat[min(len(lat) - 1, int(len(lat) * p))]  # noqa: E731
        print('## %s' % path)
        print('%d answered bit steps: latency p50 %.2f, p90 %.2f, p99 %.2f, p99.9 %.2f, max %.2f ms; '
              '%d silent: %.2f s as run; a retry ~%.2f s (%d x %.2f ms)'
              % (len(lat), q(.5), q(.9), q(.99), q(.999), lat[-1], len(silent), sum(silent) / 1000,
                 RETRY_STEPS * step_ms / 1000, RETRY_STEPS, step_ms))
        print('%-16s %14s %16s %16s %12s' % ('rule (T = f x)', 'silent waits s', 'answers too late',
                                              'their retries s', 'sum s'))
        for name, factor, rank in RULES:
            waits, late = replay(steps, rank, factor)
            retries = late * RETRY_STEPS * step_ms / 1000
            print('%-16s %14.2f %16d %16.2f %12.2f' % ('%s x %.2f' % (name, factor), waits, late, retries,
                                                       waits + retries))
        print()
    return 0


if __name__ == '__main__':
    sys.exit(main())
