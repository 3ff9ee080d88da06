# SPDX-License-Identifier: LGPL-2.1-or-later
"""Shared parts of the lssd benchmarks: identities, the CAN bus-time floor,
statistics, result files, slave state files, process helpers.

The benchmarks reuse the integration harness (tests/integration/lssdtest.py:
private dbus-daemon with the real policy, lss-sim, lssd, candump)."""

import json
import os
import random
import re
import signal
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE_ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(SOURCE_ROOT, 'tests', 'integration'))

BITRATE = 125000
VENDOR, PRODUCT = 0x9A, 0x3          # lss-sim's default profile (servo-drive) fixes these
LATENCY_MS, JITTER_MS = '1', '0.3'   # slave answer latency + uniform jitter
SIM_ARGS = ['--latency', LATENCY_MS, '--jitter', JITTER_MS]


class BenchFailure(Exception):
    """A wrong result (mis-assignment, lost call): the bench must fail."""


def log(*args):
    print(*args, file=sys.stderr, flush=True)


def seed_of(n, rep):
    """Fixed seed per (N, repetition): every implementation meets the same slaves."""
    return 7919 * n + rep


def identities(n, seed):
    """n random identities (vendor/product fixed, random revision and distinct serials)."""
    rng = random.Random(seed)
    out, serials = [], set()
    while len(out) < n:
        rev, serial = rng.getrandbits(32), rng.getrandbits(32)
        if serial in serials:
            continue
        serials.add(serial)
        out.append((VENDOR, PRODUCT, rev, serial))
    return out


# ---- CAN frame length with exact bit stuffing (as can_frame_bits() in src/lss/lss_proto.c) ----

def _crc15(bits):
    crc = 0
    for b in bits:
        nxt = b ^ ((crc >> 14) & 1)
        crc = (crc << 1) & 0x7FFF
        if nxt:
            crc ^= 0x4599
    return crc


def frame_bits(can_id, data, eff=False, rtr=False, dlc=None):
    dlc = len(data) if dlc is None else dlc
    bits = [0]
    if eff:
        bits += [(can_id >> i) & 1 for i in range(28, 17, -1)] + [1, 1]
        bits += [(can_id >> i) & 1 for i in range(17, -1, -1)] + [1 if rtr else 0, 0, 0]
    else:
        bits += [(can_id >> i) & 1 for i in range(10, -1, -1)] + [1 if rtr else 0, 0, 0]
    bits += [(dlc >> i) & 1 for i in range(3, -1, -1)]
    if not rtr:
        for byte in data[:8]:
            bits += [(byte >> i) & 1 for i in range(7, -1, -1)]
    crc = _crc15(bits)
    bits += [(crc >> i) & 1 for i in range(14, -1, -1)]
    stuff, run, last = 0, 0, -1
    for b in bits:
        if b == last:
            run += 1
        else:
            last, run = b, 1
        if run == 5:
            stuff += 1
            last, run = 1 - last, 1
    return len(bits) + stuff + 3 + 7 + 3


CANDUMP_RE = re.compile(r'\((\d+\.\d+)\) (\S+) ([0-9A-Fa-f]+)#(R?)([0-9A-Fa-f]*)')


def read_candump(path, ifname, t_from=None, t_to=None):
    """[(time, id, data, eff, rtr)] of ifname from a `candump -L` log, optionally in a time window."""
    out = []
    try:
        with open(path) as f:
            text = f.read()
    except OSError:
        return out
    for line in text.splitlines():
        m = CANDUMP_RE.match(line)
        if not m or m.group(2) != ifname:
            continue
        t = float(m.group(1))
        if (t_from is not None and t < t_from) or (t_to is not None and t > t_to):
            continue
        ident = m.group(3)
        out.append((t, int(ident, 16), bytes.fromhex(m.group(5)), len(ident) == 8, m.group(4) == 'R'))
    return out


def frame_stats(frames):
    """Counts and the bus-time floor (s) at BITRATE of a list from read_candump()."""
    lss = sum(1 for f in frames if f[1] in (0x7E4, 0x7E5))
    bits = sum(frame_bits(f[1], f[2], f[3], f[4]) for f in frames)
    return {'frames': len(frames), 'lss_frames': lss, 'bits': bits, 'floor_s': bits / BITRATE}


def step_times(frames):
    """Where an LSS pass's time goes, from a list from read_candump(): each
    request (0x7E5 frames back to back are one request) up to the next one
    is a step; answered (0x7E4 first answer: its latency) or silent."""
    steps = []  # [request time, first answer time or None, next request time]
    for t, ident, _data, _eff, _rtr in frames:
        if ident == 0x7E5:
            if steps and steps[-1][1] is None and t - steps[-1][0] < 0.0003:
                steps[-1][0] = t  # the next frame of a multi-frame request
                continue
            if steps:
                steps[-1][2] = t
            steps.append([t, None, None])
        elif ident == 0x7E4 and steps and steps[-1][1] is None:
            steps[-1][1] = t
    done = [s for s in steps if s[2] is not None]
    answered = [s for s in done if s[1] is not None]
    silent = [s for s in done if s[1] is None]
    lat = [(s[1] - s[0]) * 1000 for s in answered]
    return {'answered': len(answered), 'silent': len(silent),
            'answered_s': sum(s[2] - s[0] for s in answered), 'silent_s': sum(s[2] - s[0] for s in silent),
            'latency_ms': {p: percentile(lat, p) for p in (50, 90, 99, 100)} if lat else {},
            'silent_ms_median': percentile([(s[2] - s[0]) * 1000 for s in silent], 50) if silent else 0.0}


# ---- statistics ----

def summary(values):
    v = sorted(values)
    if not v:
        return {'n': 0}
    return {'n': len(v), 'median': statistics.median(v), 'min': v[0], 'max': v[-1]}


def percentile(values, p):
    v = sorted(values)
    if not v:
        return float('nan')
    k = (len(v) - 1) * p / 100.0
    lo = int(k)
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (v[hi] - v[lo]) * (k - lo)


# ---- results ----

def results_dir():
    d = os.environ.get('LSSD_BENCH_RESULTS') or os.path.join(SOURCE_ROOT, 'build', 'bench-results')
    os.makedirs(d, exist_ok=True)
    return d


def save(name, data):
    path = os.path.join(results_dir(), name + '.json')
    data = dict(data, saved=time.strftime('%Y-%m-%d %H:%M:%S %Z'), in_vm=bool(os.environ.get('LSSD_IN_VM')),
                source=source_version())
    tmp = path + '.tmp'
    with open(tmp, 'w') as f:
        json.dump(data, f, indent=1, sort_keys=True)
    os.replace(tmp, path)
    log('saved', path)
    return path


def source_version():
    """The commit the binaries were built from (+ 'dirty' for a changed tree):
    bench/run's, taken when it built them, else the tree's now."""
    if os.environ.get('LSSD_BENCH_SOURCE'):
        return os.environ['LSSD_BENCH_SOURCE']
    try:
        head = subprocess.run(['git', '-C', SOURCE_ROOT, 'rev-parse', '--short', 'HEAD'], capture_output=True,
                              text=True, timeout=10).stdout.strip()
        dirty = subprocess.run(['git', '-C', SOURCE_ROOT, 'status', '--porcelain', '--untracked-files=no', 'src'],
                               capture_output=True, text=True, timeout=30).stdout.strip()
        return head + ('+dirty' if dirty else '')
    except (OSError, subprocess.SubprocessError):
        return '?'


def report_failures(failures):
    """Log the wrong results of a phase; its exit status (1 when any)."""
    if not failures:
        return 0
    log('\n!!!! %d WRONG RESULTS — the bench FAILS:' % len(failures))
    for f in failures:
        log('!!!!   ' + f)
    return 1


def record_failure(text):
    """Every wrong result ever seen stays in failures.log (a rerun replaces a
    case's JSON file, not this)."""
    with open(os.path.join(results_dir(), 'failures.log'), 'a') as f:
        f.write('%s %s\n' % (time.strftime('%Y-%m-%d %H:%M:%S'), text))


def load_all():
    d = results_dir()
    out = {}
    for name in sorted(os.listdir(d)):
        if name.endswith('.json'):
            with open(os.path.join(d, name)) as f:
                out[name[:-5]] = json.load(f)
    return out


# ---- slaves and processes ----

def slave_spec(ident):
    return '0x%x:0x%x:0x%x:0x%x' % ident


def read_state(state_dir, serial):
    path = os.path.join(state_dir, '%08x.state' % serial)
    with open(path) as f:
        return dict(line.strip().split('=', 1) for line in f if '=' in line and not line.startswith('#'))


def check_states(state_dir, expected, who):
    """expected: {identity: node_id}. Every slave must be active and stored at
    its node-ID, in LSS waiting; raises BenchFailure naming every wrong one."""
    bad = []
    for ident, nid in expected.items():
        try:
            st = read_state(state_dir, ident[3])
        except OSError as e:
            bad.append('%08x: no state file (%s)' % (ident[3], e))
            continue
        got = (st.get('active_node_id'), st.get('stored_node_id'), st.get('lss_state'))
        if got != (str(nid), str(nid), 'waiting'):
            bad.append('%08x: active/stored/state %s, expected %d' % (ident[3], '/'.join(map(str, got)), nid))
    if bad:
        raise BenchFailure('%s: %d of %d slaves wrong: %s' % (who, len(bad), len(expected), '; '.join(bad[:8])))


def proc_cpu_s(pid):
    """utime + stime of a process in seconds."""
    with open('/proc/%d/stat' % pid) as f:
        fields = f.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def system_cpu():
    """(busy, total) jiffies of all CPUs since boot, from /proc/stat (idle and iowait are not busy)."""
    with open('/proc/stat') as f:
        fields = [int(x) for x in f.readline().split()[1:]]
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0)
    return sum(fields) - idle, sum(fields)


def proc_status(pid):
    out = {}
    with open('/proc/%d/status' % pid) as f:
        for line in f:
            k, _, v = line.partition(':')
            out[k] = v.strip()
    return out


def proc_wakeups(pid):
    """Context switches of every thread of pid (each sleep that ends is one wakeup)."""
    n = 0
    for tid in os.listdir('/proc/%d/task' % pid):
        st = proc_status_path('/proc/%d/task/%s/status' % (pid, tid))
        n += int(st.get('voluntary_ctxt_switches', 0)) + int(st.get('nonvoluntary_ctxt_switches', 0))
    return n


def proc_status_path(path):
    out = {}
    with open(path) as f:
        for line in f:
            k, _, v = line.partition(':')
            out[k] = v.strip()
    return out


class Procs:
    """lss-sim and candump without lssd (for the python-canopen runs)."""

    def __init__(self, ifname, slaves, workdir):
        self.ifname, self.slaves, self.dir = ifname, slaves, workdir
        self.procs = []

    def __enter__(self):
        try:
            self.candump_path = os.path.join(self.dir, 'candump.log')
            f = open(self.candump_path, 'w')
            self.procs.append(subprocess.Popen(['candump', '-L', self.ifname], stdout=f, stderr=subprocess.STDOUT))
            self.state_dir = os.path.join(self.dir, 'state')
            os.mkdir(self.state_dir)
            cmd = [os.environ.get('LSS_SIM_BINARY', 'lss-sim'), self.ifname, '--state', self.state_dir] + SIM_ARGS
            for s in self.slaves:
                cmd += ['--slave', slave_spec(s)]
            logf = open(os.path.join(self.dir, 'lss-sim.log'), 'w')
            p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=logf, text=True)
            self.procs.append(p)
            for line in p.stdout:
                if line.strip() == 'ready':
                    break
            else:
                raise RuntimeError('lss-sim did not start: ' + open(os.path.join(self.dir, 'lss-sim.log')).read())
            time.sleep(0.3)  # candump has no "ready"
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, *exc):
        for p in reversed(self.procs):
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
                try:
                    p.wait(10)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()
        self.procs = []
        return False
