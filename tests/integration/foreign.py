#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Another LSS master on the bus (issue 39): `foreign.py NAME`. lssd at its
default timing (no lss_timeout_ms in the configuration); on vcan candump is
the witness and the other master is `cansend` (or python-canopen), on lssd
--simulate it is --sim-foreign-master and LSSD_SIM_TRACE's lines of the
simulated wire are the witness.

  docs        the rule and foreign_master_quiet_s in lssd(8), lssd.conf(5),
              org.lssd.LSS1(5), conf/lssd.conf and docs/fault-matrix.md as the
              code has them; every test the fault matrix names exists
  autoassign  a blind AutoAssign of 8 (pool 71..90); 0.3 s in, another
              master's request (cansend vcan0 7E5#5A00000000000000): the call
              ends within 2 s with ForeignMaster naming it, no Configure
              Node-ID or Store from lssd after it; the next call is refused
              (lssctl: exit 19), lssctl status and the ForeignMaster property
              say so; after 3 s of quiet AutoAssign gives all 8 a node-ID
  boot        the boot pass (pool, 4 devices) while another master sends a
              request every 100 ms for 2 s: it waits (STATUS= says why),
              then ends with every device assigned; READY=1 after the quiet
  bitrate     (--simulate) SetBitrate, the other master at its Activate Bit
              Timing: it keeps to its window, the bus and devices switch,
              nothing after but the switch to waiting; at its first Configure
              Bit Timing: nothing activated, that device named
  canopen     python-canopen's LssMaster.fast_scan() on vcan0 while lssd's
              boot pass runs (VM): nothing wrongly assigned, lssd waits and
              finishes after the other master stopped (python-canopen from
              the venv tests/install-deps makes: LSSD_CANOPEN_PYTHON)"""

import os
import random
import re
import socket
import struct
import subprocess
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from autoassign import all_waiting, expect, expect_eq, slave_ids  # noqa: E402
from ctl import Ctl  # noqa: E402
from lssdtest import (BUS_IFACE, DEVICE_IFACE, ERR, SOURCE_ROOT, Env, Skip, Slave, bus_path, device_path,  # noqa: E402
                      run)

B0 = bus_path('vcan0')
V, P, R = 0x2B4, 0x7A1, 0x10001
FOREIGN_ERROR = ERR + 'ForeignMaster'
POOL = (71, 90)
CS_CONFIGURE_NODE_ID, CS_STORE = 0x11, 0x17
# the frame on vcan; lssd --simulate's other master (SIMBUS_FOREIGN_FRAME)
CANSEND_FRAME = '7E5#5A00000000000000'
SIM_FRAME = '7E5#5AF0F0F0F0F0F0F0'
CANOPEN_PYTHON = os.environ.get('LSSD_CANOPEN_PYTHON', '/usr/local/lib/lssd-canopen-2.4.1/bin/python')


def slaves_of(n, seed):
    rnd = random.Random(seed)
    return [Slave(V, P, R, rnd.getrandbits(32)) for _ in range(n)]


def config(auto_assign=False):
    """A blind pool bus at lssd's default timing: no lss_timeout_ms, no foreign_master_quiet_s (3 s)."""
    return ('buses = ( { interface = "vcan0"; unknown = "pool"; pool = [ %d, %d ]; auto_assign = %s; } );\n'
            % (POOL + ('true' if auto_assign else 'false',)))


def sim_trace(env):
    """(CLOCK_MONOTONIC s, frame) of the simulated wire, from lssd's log (LSSD_SIM_TRACE=1)."""
    return [(int(m.group(1)) + int(m.group(2)) / 1e6, m.group(3))
            for m in re.finditer(r'^\((\d+)\.(\d+)\) sim (\S+)$', env.lssd_output(), re.M)]


def foreign_frame(env):
    return CANSEND_FRAME if env.real else SIM_FRAME


def send_requests(data, n, period, stop=None):
    """Another master on vcan0: n LSS requests `data`, `period` s apart (until
    `stop` is set), from a socket of its own; returns the time.time() of each."""
    sent = []
    with socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW) as s:
        s.bind(('vcan0',))
        for _ in range(n):
            if stop and stop.is_set():
                break
            sent.append(time.time())
            s.send(struct.pack('=IB3x8s', 0x7E5, 8, data))
            time.sleep(period)
    return sent


def log_candump(env, around, before=4, after=8):
    """candump's LSS lines around the time `around`, for the test log."""
    frames = env.lss_frames('vcan0')
    k = next((i for i, f in enumerate(frames) if f[0] >= around), len(frames))
    for t, ident, data in frames[max(0, k - before):k + after]:
        env.step('candump (%+.3f s) %03X#%s' % (t - around, ident, data.hex().upper()))


def lssd_requests_between(env, t0, t1, cs):
    """lssd's requests with cs in (t0, t1] (candump's wall-clock times), the other master's aside."""
    return [f for f in env.lss_frames('vcan0') if t0 < f[0] <= t1 and f[1] == 0x7E5 and f[2][0] in cs]


def pool_ids(env, slaves):
    """serial -> node-ID each slave has now: lss-sim's state on vcan (active
    and stored, which must agree), a Scan on the simulated bus."""
    if env.real:
        ids = slave_ids(env, 'vcan0', slaves)
        for serial, (active, stored) in ids.items():
            expect_eq(stored, active, 'slave %08x: stored node-ID' % serial)
        return {k: v[0] for k, v in ids.items()}
    devices, _ = env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)
    return {d[3]: d[4] for d in devices}


def expect_all_pooled(env, slaves):
    ids = pool_ids(env, slaves)
    expect_eq(sorted(ids), sorted(s.serial for s in slaves), 'the slaves')
    expect(all(POOL[0] <= n <= POOL[1] for n in ids.values()), 'a node-ID of the pool each: %r' % ids)
    expect_eq(len(set(ids.values())), len(slaves), 'a node-ID of its own each: %r' % ids)


def test_autoassign():
    slaves = slaves_of(8, 39)
    os.environ['LSSD_SIM_TRACE'] = '1'  # the simulated wire in lssd's log
    # on the simulated bus the other master starts once lssd wrote 200 LSS
    # requests, and goes on for 10 s (the checks below, while it is active)
    env = Env({'vcan0': slaves}, config=config(), candump=True,
              lssd_args=['--sim-foreign-master', 'vcan0:200:40:250'])
    if env.real:
        env.lssd_args = []
    with env:
        ctl = Ctl(env)
        reply = {}

        def call():
            reply['r'] = env.busctl('call', 'org.lssd.LSS1', B0, BUS_IFACE, 'AutoAssign', 'a{sv}', '0')
            reply['t'], reply['w'] = time.monotonic(), time.time()
        t = threading.Thread(target=call)
        w_start = time.time()
        t.start()
        if env.real:
            # 0.3 s into the pass: from lssd's first Fastscan of it on the wire
            # (busctl alone may take a second to start under TCG; lssd's switch
            # to waiting at its start may reach candump after w_start: CI
            # 2026-12-02 sent the other master's request before the pass began)
            first = env.wait_until(lambda: lssd_requests_between(env, w_start, time.time() + 1, (0x51,)),
                                   timeout=60, what='the pass on the wire')
            time.sleep(max(0.0, first[0][0] + 0.3 - time.time()))
            w_foreign = time.time()
            subprocess.run(['cansend', 'vcan0', CANSEND_FRAME], check=True)
            cansend_s = time.time() - w_foreign
        t.join(120)
        r = reply['r']
        env.step('AutoAssign: %r' % r)
        expect_eq(r.error_name, FOREIGN_ERROR, 'the call ends with ForeignMaster')
        expect('another LSS master is active on vcan0: %s at ' % foreign_frame(env) in r.error_message,
               'the error names the frame and when: %r' % r.error_message)
        if env.real:
            time.sleep(0.3)  # candump's log
            ours = [f for f in env.lss_frames('vcan0') if w_foreign - 0.05 <= f[0] and f[1] == 0x7E5 and
                    f[2] == bytes.fromhex(CANSEND_FRAME[4:])]
            expect(ours, 'candump shows the other master\'s request')
            log_candump(env, ours[0][0])
            env.step('the request %.2f s into the pass, the call ended %.2f s after it (cansend took %.2f s)'
                     % (ours[0][0] - first[0][0], reply['w'] - ours[0][0], cansend_s))
            expect(reply['w'] - ours[0][0] < 2.0, 'the call ended %.2f s after the request' % (reply['w'] - ours[0][0]))
            after = lssd_requests_between(env, ours[0][0], reply['w'], (CS_CONFIGURE_NODE_ID, CS_STORE))
            expect_eq(after, [], 'Configure Node-ID or Store from lssd after the other master\'s request')
            expect(lssd_requests_between(env, w_start, ours[0][0], range(256)), 'lssd had started its pass')
        else:
            trace = sim_trace(env)
            at = [t for t, f in trace if f == SIM_FRAME]
            expect(at, 'the simulated wire has the other master\'s request')
            expect(reply['t'] - at[0] < 2.0, 'the call ended %.2f s after the request' % (reply['t'] - at[0]))
            after = [f for t, f in trace if at[0] < t <= reply['t'] and f.startswith(('7E5#11', '7E5#17'))]
            expect_eq(after, [], 'Configure Node-ID or Store from lssd after the other master\'s request')
        expect(all_waiting(env, 'vcan0', slaves) if env.real else True, 'a slave left in configuration')

        # the other master goes on for a while (on a loaded host a busctl
        # call alone can take longer than the 3 s of quiet)
        stop = threading.Event()
        if env.real:
            talker = threading.Thread(target=send_requests, args=(bytes.fromhex(CANSEND_FRAME[4:]), 1000, 0.25, stop))
            talker.start()

        # what the pass did before stands
        last = env.get(B0, BUS_IFACE, 'LastPass')
        expect_eq((last[2], last[3]), ('call', 'foreign-master'), 'LastPass: %r' % (last,))
        pooled = last[4].get('pool', 0)
        env.step('%d devices took a pool node-ID before the request' % pooled)

        # refused until it is quiet: the call, lssctl, the property, the journal
        name, msg = env.call_error(B0, BUS_IFACE, 'AutoAssign', 'a{sv}', 0)
        expect_eq(name, FOREIGN_ERROR, 'AutoAssign during the quiet')
        expect('takes LSS jobs again once it heard no LSS request of another master for 3 s' in msg, msg)
        ctl.fails('foreign-master', 'another LSS master is active on vcan0', 'auto-assign')
        status = ctl.ok('status').out
        expect('another LSS master active, last heard ' in status and foreign_frame(env) in status,
               'lssctl status: %s' % status)
        fm = env.get(B0, BUS_IFACE, 'ForeignMaster')
        expect_eq((fm[0], fm[3]), (True, foreign_frame(env)), 'ForeignMaster: %r' % (fm,))
        expect(0 < fm[1] <= fm[2], 'ForeignMaster times: %r' % (fm,))
        expect('another LSS master is active on vcan0: %s' % foreign_frame(env) in env.lssd_output(),
               'the journal has the frame')
        if env.real:
            stop.set()
            talker.join()
        else:
            expect(env.get(B0, BUS_IFACE, 'ForeignMaster')[0], 'the checks were done while it was active')

        # 3 s of quiet: served again, the rest assigned
        env.wait_until(lambda: not env.get(B0, BUS_IFACE, 'ForeignMaster')[0], timeout=60,
                       what='the end of the quiet')
        expect('none active; another LSS master was last heard' in ctl.ok('status').out, 'lssctl status after')
        if env.real:
            # nothing configured or stored from the other master's first request to here
            expect_eq(lssd_requests_between(env, ours[0][0], time.time(), (CS_CONFIGURE_NODE_ID, CS_STORE)), [],
                      'Configure Node-ID or Store from lssd while the other master was active or since')
        outcomes, result = env.call(B0, BUS_IFACE, 'AutoAssign', 'a{sv}', 0)
        expect_eq(result, 'done', 'AutoAssign after the quiet: %r' % (outcomes,))
        expect_eq(sum(o[6] == 'pool' for o in outcomes), len(slaves) - pooled, 'pool outcomes %r' % (outcomes,))
        expect_all_pooled(env, slaves)
        env.alive()


def test_boot():
    slaves = slaves_of(4, 40)
    # the other master from the start: a request every 100 ms for 2 s (on
    # vcan until lssd's pass says it waits, 2 s at least: in a CI run beside
    # another VM lssd was up only after 5.4 s, when 2 s of requests were over)
    env = Env({'vcan0': slaves}, config=config(auto_assign=True), candump=True, notify=True, start_lssd=False,
              lssd_args=['--sim-foreign-master', 'vcan0:0:20:100'])
    if env.real:
        env.lssd_args = []
    with env:
        sent = {}
        stop = threading.Event()
        if env.real:
            t0 = time.time()
            t = threading.Thread(target=lambda: sent.setdefault('w', send_requests(b'\x5a' + bytes(7), 6000, 0.1, stop)))
            t.start()
            time.sleep(0.2)
        env._start_lssd()
        if env.real:
            env.notify_wait(lambda m: 'auto-assign waits until another LSS master' in m.get('STATUS', ''),
                            timeout=300, what='STATUS: the boot pass waits for the other master')
            time.sleep(max(0.0, t0 + 2.0 - time.time()))
            stop.set()
        ready = env.notify_wait(lambda m: m.get('READY') == '1', timeout=600, what='READY=1')
        if env.real:
            t.join()
            last = sent['w'][-1]
            expect(ready['_rt'] - last > 2.5, 'READY %.2f s after the other master\'s last request' %
                   (ready['_rt'] - last))
        waits = [m for m in env.notify_msgs if 'auto-assign waits until another LSS master' in m.get('STATUS', '')]
        expect(waits and waits[0]['_t'] < ready['_t'], 'STATUS said why the pass waits: %r' % env.notify_msgs)
        expect('from the pool' in ready.get('STATUS', ''), 'STATUS at READY: %r' % ready)
        last_pass = env.get(B0, BUS_IFACE, 'LastPass')
        expect_eq((last_pass[2], last_pass[3]), ('boot', 'done'), 'LastPass %r' % (last_pass,))
        expect('the boot pass runs again once no LSS request of another master was heard for 3 s'
               in env.lssd_output(), 'the journal says the pass waits')
        expect_all_pooled(env, slaves)
        env.alive()


CANOPEN_SCRIPT = r'''
import sys, time, canopen
net = canopen.Network()
net.connect(interface='socketcan', channel='vcan0')
print('ready', flush=True)
sys.stdin.readline()
print('start %.6f' % time.time(), flush=True)
try:
    ok, lss_id = net.lss.fast_scan()
    print('fast_scan %r %r' % (ok, lss_id), flush=True)
except Exception as e:  # how python-canopen fares is not what is tested
    print('fast_scan raised %r' % e, flush=True)
finally:
    net.disconnect()
print('end %.6f' % time.time(), flush=True)
'''


def test_canopen():
    slaves = slaves_of(4, 41)
    env = Env({'vcan0': slaves}, config=config(auto_assign=True), candump=True, notify=True, start_lssd=False)
    if not env.real:
        raise Skip('python-canopen needs SocketCAN')
    check = subprocess.run([CANOPEN_PYTHON, '-c', 'import canopen, can'], capture_output=True, text=True)
    expect(check.returncode == 0, 'no python-canopen at %s (tests/install-deps makes its venv): %s'
           % (CANOPEN_PYTHON, check.stderr[-300:]))
    with env:
        # python-canopen ready (its start alone may take seconds), then lssd
        # and its boot pass; once that is on the wire, the fastscan
        p = subprocess.Popen([CANOPEN_PYTHON, '-c', CANOPEN_SCRIPT], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
        expect_eq(p.stdout.readline().strip(), 'ready', 'python-canopen connected')
        env._start_lssd()
        env.wait_until(lambda: any(f[1] == 0x7E5 and f[2][0] == 0x51 for f in env.lss_frames('vcan0')),
                       timeout=60, what='the boot pass on the wire')
        out, err = p.communicate('go\n', timeout=600)
        env.step('python-canopen: %s %s' % (out.strip(), err[-500:]))
        expect_eq(p.returncode, 0, 'python-canopen ran')
        w = dict(line.split(' ', 1) for line in out.splitlines() if line.startswith(('start', 'end')))
        w0, w1 = float(w['start']), float(w['end'])
        ready = env.notify_wait(lambda m: m.get('READY') == '1', timeout=600, what='READY=1')
        time.sleep(0.3)  # candump's log
        # lssd noticed, waited, and finished after the other master stopped
        expect('another LSS master is active on vcan0: 7E5#51' in env.lssd_output(), 'the journal has its frame')
        expect(any('auto-assign waits until another LSS master' in m.get('STATUS', '') for m in env.notify_msgs),
               'STATUS said why the pass waits')
        expect(ready['_rt'] > w1, 'READY %.2f s after python-canopen ended' % (ready['_rt'] - w1))
        # while the other master was at it, lssd configured and stored nothing
        theirs = [f for f in env.lss_frames('vcan0') if w0 <= f[0] <= w1 and f[1] == 0x7E5 and f[2][0] == 0x51]
        expect(theirs, 'python-canopen\'s fastscan on the wire')
        log_candump(env, theirs[0][0])
        log_candump(env, theirs[-1][0], before=2, after=6)
        during = lssd_requests_between(env, theirs[0][0], theirs[-1][0], (CS_CONFIGURE_NODE_ID, CS_STORE))
        expect_eq(during, [], 'Configure Node-ID or Store from lssd while the other master was active')
        # nothing wrongly assigned: a pool node-ID of its own each, stored, as the pass says
        last_pass = env.get(B0, BUS_IFACE, 'LastPass')
        expect_eq((last_pass[2], last_pass[3]), ('boot', 'done'), 'LastPass %r' % (last_pass,))
        expect_all_pooled(env, slaves)
        for s in slaves:
            expect_eq(env.get(device_path('vcan0', *s.identity), DEVICE_IFACE, 'State'), 'pool',
                      'State of %08x' % s.serial)
        expect(all_waiting(env, 'vcan0', slaves), 'a slave left in configuration')
        env.alive()


BITRATE_CONFIG = ('buses = ( { interface = "vcan0"; bitrate = 125000; bitrate_change = true; store = false;\n'
                  '  devices = ( %s ); } );\n')


def test_bitrate():
    """SetBitrate on the simulated bus, the other master at its Activate Bit
    Timing: the devices and the host switch (the window is kept), nothing is
    verified or stored after; at its first Configure Bit Timing: nothing is
    activated, the device asked is named as holding the rate pending."""
    if os.environ.get('LSSD_TEST_BACKEND') != 'simulate':
        raise Skip('the simulated bus: the other master at an exact request (--sim-foreign-master @CS)')
    slaves = [Slave(0x9A, 3, 1, 0x31 + i, 20 + i) for i in range(2)]
    cfg = BITRATE_CONFIG % ', '.join('{ vendor = 0x9A; product = 3; revision = 1; serial = 0x%x; node_id = %d; }'
                                     % (s.serial, s.node_id) for s in slaves)
    os.environ['LSSD_SIM_TRACE'] = '1'
    for at, rate_after in (('@0x15', 250000), ('@0x13', 125000)):
        with Env({'vcan0': slaves}, config=cfg, lssd_args=['--sim-foreign-master', 'vcan0:' + at]) as env:
            t0 = time.monotonic()
            name, msg = env.call_error(B0, BUS_IFACE, 'SetBitrate', 'uqa{sv}', 250000, 20, 0)
            t1 = time.monotonic()
            env.step('%s: %s' % (at, msg))
            expect_eq(name, FOREIGN_ERROR, 'SetBitrate with the other master at %s' % at)
            expect('another LSS master is active on vcan0: %s' % SIM_FRAME in msg, msg)
            expect_eq(env.get(B0, BUS_IFACE, 'Bitrate'), rate_after, 'the bus rate after it (%s)' % at)
            trace = sim_trace(env)
            ft = [t for t, f in trace if f == SIM_FRAME][0]
            ours = [f for t, f in trace if ft < t <= t1 and f.startswith('7E5#') and f != SIM_FRAME]
            if at == '@0x15':
                expect('Activate Bit Timing to 250000 bit/s had gone out: the devices switched, 0 of 2 verified'
                       in msg, msg)
                # the window kept, then one switch to waiting at the new rate: no verification, no Store
                expect_eq(ours, ['7E5#0400000000000000'], 'lssd after the other master\'s request')
            else:
                expect('nothing was activated, the bus stays at 125000 bit/s; these took (or may have taken) '
                       'Configure Bit Timing' in msg and '0000009a:00000003:00000001:00000031' in msg, msg)
                expect(all(not f.startswith(('7E5#13', '7E5#15')) for f in ours),
                       'Configure or Activate Bit Timing after it: %r' % ours)
            expect(t1 - t0 < 60, 'SetBitrate took %.1f s' % (t1 - t0))
            # once it is quiet, both devices answer at the rate the bus has
            env.wait_until(lambda: not env.get(B0, BUS_IFACE, 'ForeignMaster')[0], timeout=30,
                           what='the end of the quiet')
            devices, _ = env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)
            expect_eq(sorted(d[3] for d in devices), [s.serial for s in slaves], 'a Scan at %u bit/s' % rate_after)
            env.alive()


def read_source(*path):
    with open(os.path.join(SOURCE_ROOT, *path)) as f:
        return f.read()


def header_number(path, name):
    m = re.search(r'^#define %s (\d+)u?$' % name, read_source(*path), re.M)
    expect(m, '%s in %s' % (name, '/'.join(path)))
    return int(m.group(1))


def test_docs():
    """The rule and its setting are where users read them, as the code has
    them, and every test the fault matrix names for it exists."""
    default = header_number(('src', 'config', 'lssconf.h'), 'LSSCONF_FOREIGN_MASTER_QUIET_S_DEFAULT')
    most = header_number(('src', 'config', 'lssconf.h'), 'LSSCONF_FOREIGN_MASTER_QUIET_S_MAX')
    lssd8 = read_source('man', 'lssd.8')
    expect('.SH ANOTHER LSS MASTER' in lssd8, 'lssd(8) has ANOTHER LSS MASTER')
    section = lssd8.split('.SH ANOTHER LSS MASTER', 1)[1].split('\n.SH ', 1)[0]
    for want in ('foreign_master_quiet_s', 'org.lssd.LSS1.Error.ForeignMaster', 'default %d' % default,
                 'No\nConfigure Node\\-ID, Configure Bit Timing, Activate Bit Timing or Store', 'boot pass',
                 'switch\\-state\\-global waiting', 'window'):
        expect(want in section, 'lssd(8), ANOTHER LSS MASTER, lacks %r' % want)
    expect('.BI \\-\\-sim\\-foreign\\-master=' in lssd8, 'lssd(8) has --sim-foreign-master')
    conf5 = read_source('man', 'lssd.conf.5')
    expect(conf5.count('foreign_master_quiet_s = " S ;') == 2, 'lssd.conf(5): the global key and the bus override')
    expect('1..%d' % most in conf5 and 'Default %d.' % default in conf5, 'lssd.conf(5): range and default')
    example = read_source('conf', 'lssd.conf')
    expect('foreign_master_quiet_s = %d;' % default in example, 'conf/lssd.conf shows the default')
    api5 = read_source('man', 'org.lssd.LSS1.5')
    expect('.B org.lssd.LSS1.Error.ForeignMaster' in api5, 'org.lssd.LSS1(5) lists the error')
    expect('readonly (btts) ForeignMaster' in api5 and '.B ForeignMaster' in api5,
           'org.lssd.LSS1(5) has the property')
    expect('<property name="ForeignMaster" type="(btts)"' in read_source('dbus', 'org.lssd.LSS1.Bus.xml'),
           'the interface XML has the property')
    # the fault matrix's row, and the tests it names
    row = [line for line in read_source('docs', 'fault-matrix.md').splitlines() if 'foreign_master_quiet_s' in line]
    expect_eq(len(row), 1, 'one row of docs/fault-matrix.md names foreign_master_quiet_s')
    tests_cell = row[0].rstrip(' |').rsplit(' | ', 1)[1]
    meson = read_source('tests', 'integration', 'meson.build')
    for prog, names in re.findall(r'unit/([a-z-]+):((?:`\w+`(?: \([^)]*\))?(?:, )?)+)', tests_cell):
        source = read_source('tests', 'unit', 'test-%s.c' % prog)
        for name in re.findall(r'`(\w+)`', names):
            expect('START_TEST(%s)' % name in source, 'unit/%s:%s, which the fault matrix names' % (prog, name))
    for name in re.findall(r'`((?:sim-)?foreign-[a-z]+)`', tests_cell):
        expect("'%s'" % name.replace('sim-', '').replace('foreign-', '') in meson and 'foreign' in meson,
               'integration test %s, which the fault matrix names' % name)
    expect(re.search(r'unit/daemon-bus-foreign:', tests_cell) and re.search(r'`foreign-canopen`', tests_cell),
           'the fault matrix names the bus\'s and the VM\'s tests')


TESTS = {
    'docs': test_docs,
    'bitrate': test_bitrate,
    'autoassign': test_autoassign,
    'boot': test_boot,
    'canopen': test_canopen,
}

if __name__ == '__main__':
    sys.exit(run(TESTS))
