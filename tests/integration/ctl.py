#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""lssctl integration tests: `ctl.py NAME` runs one (meson test per name).

Every command runs against the real lssd (lssdtest.Env: private system bus
with the real policy, lss-sim on vcan or lssd --simulate), asserting on
--json output and exit codes as documented in lssctl(1). Also: the bash
completion loads and completes, and every manual page renders without
warnings."""

import glob
import json
import os
import pty
import re
import select
import signal
import subprocess
import shutil
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from lssdtest import (BUS_IFACE, DEVICE_IFACE, ERR, ERRORS, SERVICE, SOURCE_ROOT, Env, Skip, Slave, bus_path,  # noqa: E402
                      device_path, run)

B0 = bus_path('vcan0')
B1 = bus_path('vcan1')
LSSCTL = os.environ.get('LSSCTL_BINARY', 'lssctl')

# lssctl(1), EXIT STATUS
EXIT = {
    'ok': 0, 'failure': 1, 'usage': 2, 'not-running': 3, 'access-denied': 4, 'no-response': 5, 'rejected': 6,
    'busy': 7, 'bus-down': 8, 'bus-off': 9, 'not-found': 10, 'conflict': 11, 'cancelled': 12,
    'not-supported': 13, 'limits-exceeded': 14, 'bad-config': 15, 'permission-denied': 16, 'partial': 17, 'not-held': 18,
    'foreign-master': 19, 'interrupted': 130,
}

# the bus and map of the D-Bus tests (run.py), so both check the same devices
from run import CONFIG, SLAVES, VCAN1  # noqa: E402

JSON_DEVICE_KEYS = ['bus', 'vendor', 'product', 'revision', 'serial', 'revision_known', 'node_id', 'mapped_node_id',
                    'state', 'last_seen', 'path']
JSON_BUS_KEYS = ['interface', 'state', 'bitrate', 'job', 'progress', 'queue_length', 'devices', 'device_states',
                 'last_pass', 'foreign_master']


def expect(cond, what):
    if not cond:
        raise AssertionError(what)


def expect_eq(got, want, what):
    if got != want:
        raise AssertionError('%s: got %r, want %r' % (what, got, want))


def ident(s):
    return '0x%x:0x%x:0x%x:0x%x' % s.identity


def ident8(s):
    return '0x%08x:0x%08x:0x%08x:0x%08x' % s.identity


class Result:
    def __init__(self, args, rc, out, err):
        self.args, self.rc, self.out, self.err = args, rc, out, err

    @property
    def json(self):
        try:
            return json.loads(self.out)
        except ValueError as e:
            raise AssertionError('lssctl %s: no JSON (%s): %r' % (' '.join(self.args), e, self.out))

    def __repr__(self):
        return 'lssctl %s: rc=%d out=%r err=%r' % (' '.join(self.args), self.rc, self.out, self.err)


class Ctl:
    """lssctl as users run it, on the Env's private system bus."""

    def __init__(self, env):
        self.env = env

    def environ(self, **extra):
        e = dict(os.environ, DBUS_SYSTEM_BUS_ADDRESS=self.env.address, LANG='C.UTF-8')
        for k in ('SYSTEMD_COLORS', 'NO_COLOR', 'SYSTEMD_PAGER', 'PAGER'):
            e.pop(k, None)
        e.update(extra)
        return e

    def command(self, args, user=None):
        cmd = os.environ.get('LSSCTL_TEST_WRAPPER', '').split() + [LSSCTL] + list(args)
        if user:
            if os.geteuid() != 0:
                raise Skip('acting as another user needs root')
            cmd = ['setpriv', '--reuid=' + user, '--regid=nogroup', '--clear-groups'] + cmd
        return cmd

    def __call__(self, *args, user=None, timeout=300):
        p = subprocess.run(self.command(args, user), env=self.environ(), capture_output=True, text=True,
                           timeout=timeout)
        return Result(args, p.returncode, p.stdout, p.stderr)

    def ok(self, *args, **kw):
        r = self(*args, **kw)
        expect(r.rc == 0, 'failed: %r' % r)
        expect(r.err == '', 'stderr on success: %r' % r)
        return r

    def fails(self, code, text, *args, **kw):
        r = self(*args, **kw)
        expect_eq(r.rc, EXIT[code], 'exit status of lssctl %s (%r)' % (' '.join(args), r.err))
        expect(text in r.err, 'lssctl %s: %r lacks %r' % (' '.join(args), r.err, text))
        expect(r.out == '', 'stdout on failure: %r' % r)
        expect(len(r.err.strip().splitlines()) <= 6, 'a long error: %r' % r.err)
        return r

    def spawn(self, *args, **kw):
        return subprocess.Popen(self.command(args), env=self.environ(), text=True, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, **kw)

    def on_tty(self, *args, timeout=120, on_output=None):
        """Runs lssctl with stdout and stderr on a pseudo-terminal; returns (rc, output)."""
        master, slave = pty.openpty()
        p = subprocess.Popen(self.command(args), env=self.environ(TERM='xterm', PAGER='cat'), stdin=slave,
                             stdout=slave, stderr=slave, start_new_session=True)
        os.close(slave)
        out = b''
        deadline = time.monotonic() + timeout
        try:
            while time.monotonic() < deadline:
                ready, _, _ = select.select([master], [], [], 0.1)
                if ready:
                    try:
                        chunk = os.read(master, 4096)
                    except OSError:
                        break
                    if not chunk:
                        break
                    out += chunk
                    if on_output:
                        on_output(p, out)
                elif p.poll() is not None:
                    break
            rc = p.wait(timeout=max(1, deadline - time.monotonic()))
        finally:
            if p.poll() is None:
                p.kill()
                p.wait()
            os.close(master)
        return rc, out.decode(errors='replace')


def scan_all(env):
    env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)


def table_columns(header):
    """Start offsets of the columns of a table header (names separated by spaces, 'LAST SEEN' is one)."""
    return [m.start() for m in re.finditer(r'\S+(?: SEEN)?', header)]


# ---- listing ----

def test_status():
    with Env({'vcan0': SLAVES}, config=CONFIG % '') as env:
        ctl = Ctl(env)
        st = ctl.ok('status', '--json').json
        version = subprocess.run([os.environ.get('LSSD_BINARY', 'lssd'), '--version'], capture_output=True,
                                 text=True).stdout.split()[-1]
        expect_eq(st['version'], version, 'version')
        expect_eq(len(st['buses']), 1, 'buses')
        b = st['buses'][0]
        expect_eq(sorted(b), sorted(JSON_BUS_KEYS), 'bus keys')
        expect_eq((b['interface'], b['state'], b['bitrate'], b['job'], b['queue_length']),
                  ('vcan0', 'idle', 125000, '', 0), 'bus')
        expect_eq(b['foreign_master'], None, 'no other LSS master heard')
        scan_all(env)
        b = ctl.ok('--json', 'status').json['buses'][0]  # options before the command work too
        expect_eq(b['devices'], 4, 'device count')
        expect_eq(b['device_states'], {'assigned': 2, 'pool': 0, 'pending-reset': 0, 'configured': 0,
                                       'non-configured': 2, 'mismatch': 0, 'conflict': 0, 'missing': 0},
                  'device states')
        # the default command is status; text for people, no colours off a terminal
        text = ctl.ok().out
        expect_eq(text, ctl.ok('status').out, 'lssctl == lssctl status')
        for want in ('Version: ' + version, 'Bus: vcan0', 'State: idle', 'Bitrate: 125 kbit/s', 'Job: none',
                     'Devices: 4 (2 assigned, 2 non-configured)'):
            expect(want in text, 'status lacks %r:\n%s' % (want, text))
        expect('\x1b' not in text, 'colours off a terminal')
        ctl.fails('not-found', "does not serve interface 'vcan9'", 'status', '--bus', 'vcan9')
        expect_eq(ctl.ok('status', '--bus', 'vcan0', '--json').json['buses'][0]['interface'], 'vcan0', '--bus')


def test_list():
    with Env({'vcan0': SLAVES}, config=CONFIG % '') as env:
        ctl = Ctl(env)
        expect_eq(ctl.ok('list', '--json').json, [], 'list before a scan')
        expect('0 devices listed' in ctl.ok('list').out, 'empty list text')
        t0 = time.time()
        scan_all(env)
        devices = ctl.ok('list', '--json').json
        expect_eq(len(devices), 4, 'devices')
        mapped = {0x1276: 5, 0x80002468: 6, 17: 7, 0xFFFFFFFF: 0}
        states = {0x1276: 'non-configured', 0x80002468: 'assigned', 17: 'assigned', 0xFFFFFFFF: 'non-configured'}
        for d, s in zip(devices, sorted(SLAVES, key=lambda x: x.identity)):
            expect_eq(list(d), JSON_DEVICE_KEYS, 'device keys (and their order)')
            expect_eq((d['vendor'], d['product'], d['revision'], d['serial']), s.identity, 'identity')
            expect_eq(d['node_id'], s.node_id, 'node_id of %x' % s.serial)
            expect_eq(d['mapped_node_id'], mapped[s.serial], 'mapped_node_id of %x' % s.serial)
            expect_eq(d['state'], states[s.serial], 'state of %x' % s.serial)
            expect_eq(d['bus'], 'vcan0', 'bus')
            expect_eq(d['path'], device_path('vcan0', *s.identity), 'path')
            expect(t0 - 60 < d['last_seen'] / 1e6 < time.time() + 60, 'last_seen %r' % d['last_seen'])

        # the table, once for shape: a header, one aligned row per device, identities in hex
        out = ctl.ok('list').out
        lines = out.splitlines()
        expect_eq(lines[0].split(), ['BUS', 'VENDOR', 'PRODUCT', 'REVISION', 'SERIAL', 'NODE', 'MAPPED', 'STATE',
                                     'LAST', 'SEEN'], 'header')
        expect_eq(lines[5:], ['', '4 devices listed.'], 'footer')
        cols = table_columns(lines[0])
        rows = lines[1:5]
        for row, s in zip(rows, sorted(SLAVES, key=lambda x: x.identity)):
            f = row.split()
            expect_eq(f[:5], ['vcan0'] + ['0x%08x' % v for v in s.identity], 'row ' + row)
            expect_eq(f[5], '-' if s.node_id == 0xFF else str(s.node_id), 'NODE in ' + row)
            expect_eq(f[7], states[s.serial], 'STATE in ' + row)
            expect(re.match(r'\d{4}-\d\d-\d\d \d\d:\d\d:\d\d$', row[cols[8]:]), 'LAST SEEN in ' + row)
            for c in (cols[1], cols[2], cols[3], cols[4], cols[7]):  # left-aligned columns start together
                expect(row[c - 1] == ' ' and row[c] != ' ', 'column at %d in %r' % (c, row))
            expect(row[cols[7] - 2] != ' ', 'MAPPED right-aligned in %r' % row)
        expect('\x1b' not in out, 'colours off a terminal')
        legendless = ctl.ok('list', '--no-legend').out.splitlines()
        expect_eq([x.split() for x in legendless], [x.split() for x in rows], '--no-legend')

        expect_eq(len(ctl.ok('list', '--bus', 'vcan0', '--json').json), 4, 'list --bus vcan0')
        ctl.fails('not-found', "does not serve interface 'vcan1'", 'list', '--bus', 'vcan1')

        # colours on a terminal, none with SYSTEMD_COLORS=0
        rc, tty = ctl.on_tty('list', '--no-pager')
        expect_eq(rc, 0, 'list on a terminal: ' + tty)
        expect('\x1b[0;32massigned' in tty, 'colours on a terminal: %r' % tty[:300])


def test_scan():
    with Env({'vcan0': SLAVES}, config=CONFIG % '') as env:
        ctl = Ctl(env)
        found = ctl.ok('scan', '--json').json
        expect_eq([(d['bus'], d['vendor'], d['product'], d['revision'], d['serial'], d['node_id']) for d in found],
                  sorted([('vcan0',) + s.identity + (s.node_id,) for s in SLAVES]), 'scan --json')
        expect_eq(list(found[0]), ['bus', 'vendor', 'product', 'revision', 'serial', 'node_id', 'found_by'],
                  'scan keys')
        # configured: found by SDO and by LSS (the map's pairs); non-configured: by LSS
        expect_eq([(d['serial'], d['found_by']) for d in found],
                  [(s.serial, ['lss', 'sdo'] if s.node_id != 0xFF else ['lss']) for s in sorted(SLAVES, key=lambda s: s.identity)],
                  'scan --json found_by')
        text = ctl.ok('scan').out
        expect('4 devices found.' in text and '0x80002468' in text, 'scan text: ' + text)
        expect('FOUND-BY' in text and 'lss,sdo' in text, 'scan text, FOUND-BY column: ' + text)
        expect('Note: vcan0: configured devices in NMT Stopped that send no heartbeat were not looked for' in text,
               'scan legend: ' + text)
        expect_eq(len(ctl.ok('list', '--json').json), 4, 'devices after scan')
    # no map: every slave (SDO finds the configured ones); with --no-sdo
    # configured ones only with --vendor/--product
    with Env({'vcan0': SLAVES[:3]}) as env:
        ctl = Ctl(env)
        expect_eq(len(ctl.ok('scan', '--json', '--no-sdo').json), 1, 'scan --no-sdo without a map')
        text = ctl.ok('scan', '--no-sdo').out
        expect('Note: vcan0: configured devices of vendor/product pairs not scanned were not looked for (option '
               'sdo = false, lssctl scan --no-sdo); scanned: none.' in text, 'scan --no-sdo legend: ' + text)
        found = ctl.ok('scan', '--json', '--no-sdo', '--vendor', '0x9A', '--product', '3').json
        expect_eq([d['serial'] for d in found], [17, 0x1276], 'scan --no-sdo --vendor 0x9A --product 3')
        found = ctl.ok('scan', '--json').json
        expect_eq(sorted(d['serial'] for d in found), sorted(s.serial for s in SLAVES[:3]), 'scan without a map')
        ctl.fails('usage', '--vendor and --product go together', 'scan', '--vendor', '0x9A')


def check_printed_map(env, out):
    """lssd --check-config takes what scan --as-config printed, without a warning."""
    path = os.path.join(env.dir, 'frozen.conf')
    with open(path, 'w') as f:
        f.write(out)
    check = subprocess.run([os.environ.get('LSSD_BINARY', 'lssd'), '--check-config', path], capture_output=True,
                           text=True)
    expect_eq(check.returncode, 0, 'lssd --check-config on the printed map: %s%s' % (check.stdout, check.stderr))
    expect('warning' not in (check.stdout + check.stderr).lower(), 'check-config warns: %r' % check.stderr)


# ---- DCFs (issue 41) ----

# the DCFs of public CANopen projects the DCF reader's unit tests read
DCF_DATA = os.path.join(SOURCE_ROOT, 'tests', 'unit', 'dcf')
LELY_MASTER = os.path.join(DCF_DATA, 'lely-co-nmt-master.dcf')
LELY_SLAVE = os.path.join(DCF_DATA, 'lely-co-nmt-slave.dcf')
# the device both describe, at node-ID 2
LELY_DEVICE = Slave(0x360, 2, 3, 4)
MAP_ENTRY = '{ vendor = 0x%08x; product = 0x%08x; revision = 0x%08x; serial = 0x%08x; node_id = %s; }'


def lssctl_alone(*args):
    """lssctl with no lssd anywhere (a system bus that is not there)."""
    p = subprocess.run([LSSCTL] + list(args), capture_output=True, text=True, timeout=60,
                       env=dict(os.environ, DBUS_SYSTEM_BUS_ADDRESS='unix:path=/nonexistent/bus', LANG='C.UTF-8'))
    return Result(args, p.returncode, p.stdout, p.stderr)


def test_import_dcf():
    """import-dcf (issue 41): the integrator's DCFs as the buses of
    lssd.conf(5), with no lssd running. The DCFs of public CANopen projects
    (tests/unit/dcf): lely-core's NMT master and slave name one device, one
    entry; every other file is a comment saying why it is none. The printed
    map passes lssd --check-config, and lssd's AutoAssign with it gives the
    device its node-ID. Errors name FILE:LINE and print nothing."""
    files = sorted(glob.glob(os.path.join(DCF_DATA, '*.dcf')) + glob.glob(os.path.join(DCF_DATA, '*.eds')))
    r = lssctl_alone('import-dcf', '--bus', 'vcan0', *files)
    expect_eq(r.rc, 0, 'import-dcf of the public DCFs: %r' % r)
    lines = r.out.splitlines()
    expect(lines[0].startswith("# lssd.conf(5) buses from CiA 306 DCFs by 'lssctl import-dcf', lssctl "),
           'header: %r' % r.out)
    expect('# 1 device from %d files, 7 left out (see there).' % len(files) in r.out, 'counts: %r' % r.out)
    entries = [x.strip() for x in lines if x.strip().startswith('{ vendor')]
    expect_eq(entries, [MAP_ENTRY % (LELY_DEVICE.identity + (2,)) + '  # %s:230, also %s:17' % (LELY_MASTER, LELY_SLAVE)],
              'the one entry, from the master and the slave')
    left = [x.strip() for x in lines if x.strip().startswith('# left out: ')]
    expect_eq(len(left), 7, 'left out: %r' % left)
    expect('# left out: %s:33 (NodeName "Some name"): no serial number (LSS_SerialNumber 0 or not given, no '
           'ParameterValue of [1018sub4])' % os.path.join(DCF_DATA, 'canopen-python-sample.eds') in left,
           'canopen-python sample.eds left out: %r' % left)
    expect('# left out: %s:52: NodeID 0 is out of 1..127' % os.path.join(DCF_DATA, 'ros_canopen-ISD860.dcf') in left,
           'ISD860 left out: %r' % left)
    expect('interface = "vcan0";' in r.out and 'auto_assign = true;' in r.out, 'the bus: %r' % r.out)
    expect('# bitrate = ...;  the DCFs do not say the bit rate (Baudrate): give it' in r.out, 'no bit rate: %r' % r.out)
    e35 = os.path.join(DCF_DATA, 'canopen-python-e35.eds')
    warnings = r.err.splitlines()
    expect_eq(len(warnings), 3, 'warnings: %r' % r.err)
    expect(all(w.startswith('lssctl: warning: %s:' % e35) for w in warnings), 'e35.eds warnings: %r' % r.err)

    d = tempfile.mkdtemp(prefix='lssd-test-dcf.')
    try:
        # errors: FILE:LINE, nothing printed, status 15 (bad-config); every file read
        bad = os.path.join(d, 'bad.dcf')
        with open(bad, 'w') as f:
            f.write('[DeviceComissioning]\r\nNodeID=0x\r\n')
        other = os.path.join(d, 'other.dcf')
        with open(LELY_SLAVE) as f:
            text = f.read()
        with open(other, 'w') as f:
            f.write(text.replace('NodeID=0x02', 'NodeID=0x03'))
        for args, want in ((('import-dcf', bad, LELY_SLAVE),
                            ['%s:2: [DeviceComissioning] NodeID: "0x" is not a number' % bad,
                             '1 error in the DCFs (above): no map printed.']),
                           (('import-dcf', LELY_SLAVE, other, bad, os.path.join(d, 'none.dcf')),
                            ['%s:17: one device gets two node-IDs: vendor 0x00000360, product 0x00000002, serial '
                             '0x00000004 gets node-ID 3 here and node-ID 2 at %s:17' % (other, LELY_SLAVE),
                             '%s:2:' % bad, '%s: cannot open: No such file or directory' % os.path.join(d, 'none.dcf'),
                             '3 errors in the DCFs (above): no map printed.'])):
            r = lssctl_alone(*args)
            expect_eq((r.rc, r.out), (EXIT['bad-config'], ''), 'import-dcf with errors: %r' % r)
            for w in want:
                expect(w in r.err, 'import-dcf %r: %r lacks %r' % (args, r.err, w))
        for args, text in ((('import-dcf',), "Too few arguments for 'import-dcf'"),
                           (('import-dcf', '--json', LELY_SLAVE), "Option --json does not go with 'import-dcf'"),
                           (('import-dcf', '--bus', 'can 0', LELY_SLAVE), "Invalid --bus 'can 0'")):
            r = lssctl_alone(*args)
            expect_eq((r.rc, r.out), (EXIT['usage'], ''), 'lssctl %r: %r' % (args, r))
            expect(text in r.err, 'lssctl %r: %r lacks %r' % (args, r.err, text))
    finally:
        shutil.rmtree(d)

    # the printed map: lssd takes it, and its boot pass (auto_assign = true)
    # makes it true; an AutoAssign after it changes nothing
    r = lssctl_alone('import-dcf', '--bus', 'vcan0', LELY_MASTER, LELY_SLAVE)
    expect_eq((r.rc, r.err), (0, ''), 'import-dcf of lely\'s pair: %r' % r)
    with Env({'vcan0': [LELY_DEVICE]}) as env:
        ctl = Ctl(env)
        # a file name with a line break stays in its comment
        odd = os.path.join(env.dir, 'odd\nname.dcf')
        shutil.copy(LELY_SLAVE, odd)
        odd_out = lssctl_alone('import-dcf', odd).out
        expect('# %s:17' % odd.replace('\n', '?') in odd_out, 'the odd name: %r' % odd_out)
        check_printed_map(env, odd_out)
        check_printed_map(env, r.out)
        env.config = r.out
        env.restart_lssd()
        got = ctl.ok('auto-assign', '--json').json  # queued behind the boot pass
        expect_eq([(x['serial'], x['outcome'], x['new_node_id']) for x in got], [(4, 'unchanged', 2)],
                  'auto-assign after the boot pass with the map of the DCFs')
        dev = ctl.ok('list', '--json').json
        expect_eq([(x['serial'], x['node_id'], x['mapped_node_id'], x['state']) for x in dev], [(4, 2, 2, 'assigned')],
                  'the device after the boot pass')
        expect('Ready' in env.lssd_output() and '1 assigned' in env.lssd_output(), 'the boot pass assigned it: %s'
               % env.lssd_output()[-2000:])
        env.alive()


def test_scan_dcf():
    """scan --as-dcf DIR (issue 41): one DCF fragment per configured device
    found ([DeviceInfo], [DeviceComissioning] NodeID, Baudrate and
    LSS_SerialNumber, 1018h; CRLF), for the integrator's tool; read back by
    import-dcf they are the map scan --as-config prints."""
    configured = [Slave(0xEC, 0x1234, 0x00010002, 0x1001, 5), Slave(0xEC, 0x1234, 0x00010002, 0x1002, 6),
                  Slave(0xEC, 0x1234, 0x00010003, 0x80001003, 7)]
    fresh = Slave(0xEC, 0x1234, 0x00010002, 0x1004)
    with Env({'vcan0': configured + [fresh]}) as env:
        ctl = Ctl(env)
        folder = os.path.join(env.dir, 'dcf-out')
        ctl.fails('usage', "Option '--as-dcf' needs a value", 'scan', '--as-dcf')
        ctl.fails('usage', '--as-dcf does not go with --json', 'scan', '--as-dcf', folder, '--json')
        ctl.fails('usage', '--as-config does not go with --as-dcf', 'scan', '--as-config', '--as-dcf', folder)
        ctl.fails('usage', "Option --as-dcf does not go with 'list'", 'list', '--as-dcf', folder)
        for _ in range(2):  # the second time over the files of the first
            r = ctl.ok('scan', '--as-dcf', folder, '--vendor', '0xEC', '--product', '0x1234')
            env.step('lssctl scan --as-dcf:\n' + r.out)
            names = ['vcan0-node%03d.dcf' % s.node_id for s in configured]
            expect_eq(sorted(os.listdir(folder)), names, 'the files written')
            for s in configured:
                expect(('vcan0: device %s at node-ID %d: %s/vcan0-node%03d.dcf' % (ident8(s), s.node_id, folder,
                                                                                    s.node_id)) in r.out,
                       'said: %r' % r.out)
            expect('vcan0: device %s not written: non-configured (node-ID 255)' % ident8(fresh) in r.out,
                   'the non-configured device: %r' % r.out)
            expect(r.out.endswith('3 DCFs written to %s.\n' % folder), 'summary: %r' % r.out)
        with open(os.path.join(folder, 'vcan0-node005.dcf'), 'rb') as f:
            data = f.read()
        expect(data.count(b'\r\n') == data.count(b'\n') > 40, 'CRLF line ends: %r' % data[:200])
        text = data.decode().replace('\r\n', '\n')
        for want in ('[DeviceInfo]\nVendorNumber=0x000000EC\nProductNumber=0x00001234\nRevisionNumber=0x00010002\n',
                     '[DeviceComissioning]\nNodeID=5\nBaudrate=125\nLSS_SerialNumber=0x00001001\n',
                     '[1018sub4]\nParameterName=Serial number\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\n'
                     'ParameterValue=0x00001001\n', 'FileName=vcan0-node005.dcf\n', 'CreatedBy=lssctl '):
            expect(want in text, 'vcan0-node005.dcf lacks %r:\n%s' % (want, text))

        # read back: the map scan --as-config prints
        r = ctl.ok('import-dcf', '--bus', 'vcan0', *sorted(glob.glob(os.path.join(folder, '*.dcf'))))
        back = [x.strip().split('  #')[0].rstrip(',') for x in r.out.splitlines() if x.strip().startswith('{ vendor')]
        printed = ctl.ok('scan', '--as-config', '--vendor', '0xEC', '--product', '0x1234').out
        active = [x.strip().split('  #')[0].rstrip(',') for x in printed.splitlines() if x.strip().startswith('{ vendor')]
        expect_eq(back, active, 'import-dcf of the written DCFs against scan --as-config')
        expect_eq(back, [MAP_ENTRY % (s.identity + (s.node_id,)) for s in configured], 'the entries')
        expect('bitrate = 125000;' in r.out, 'the bit rate back from Baudrate: %r' % r.out)

        # a folder that cannot be made
        blocker = os.path.join(env.dir, 'a-file')
        open(blocker, 'w').close()
        r = ctl('scan', '--as-dcf', os.path.join(blocker, 'sub'))
        expect(r.rc == EXIT['failure'] and 'Failed to make the folder %s/sub' % blocker in r.err, 'unwritable: %r' % r)


def test_scan_config():
    """scan --as-config (issue 18, commissioning): the bus as it is, printed as
    the buses of lssd.conf(5), passes lssd --check-config, and lssd started
    with it finds every device where the map wants it: AutoAssign reports all
    unchanged and sends no Configure Node-ID or Store frame."""
    configured = [Slave(0xEC, 0x1234, 0x00010002, 0x1001, 5), Slave(0xEC, 0x1234, 0x00010002, 0x1002, 6),
                  Slave(0xEC, 0x1234, 0x00010003, 0x80001003, 7)]
    fresh = Slave(0xEC, 0x1234, 0x00010002, 0x1004)
    # lss-sim only: answers SDO, ignores Switch State Selective (vendor): found by SDO alone
    real = os.environ.get('LSSD_TEST_BACKEND', 'vcan') != 'simulate'
    sdo_only = [Slave(0x6006, 1, 1, 0x66, 9, faults=['ignore-cs=0x40'])] if real else []
    with Env({'vcan0': configured + [fresh] + sdo_only}, candump=True) as env:
        ctl = Ctl(env)
        ctl.fails('usage', '--as-config does not go with --json', 'scan', '--as-config', '--json')
        ctl.fails('usage', "--as-config does not go with 'list'", 'list', '--as-config')
        out = ctl.ok('scan', '--as-config', '--vendor', '0xEC', '--product', '0x1234').out
        env.step('lssctl scan --as-config:\n' + out)
        lines = out.splitlines()
        expect(lines[0].startswith("# lssd.conf(5) buses as found by 'lssctl scan --as-config'"), 'header: %r' % out)
        expect('3 devices mapped at their current node-IDs, %d commented out (see there), on vcan0.'
               % (1 + len(sdo_only)) in out, 'header counts: %r' % out)
        entry = '{ vendor = 0x%08x; product = 0x%08x; revision = 0x%08x; serial = 0x%08x; node_id = %s; }'
        active = [x.strip().rstrip(',') for x in lines if x.strip().startswith('{ vendor')]
        expect_eq(active, [entry % (s.identity + (s.node_id,)) for s in configured], 'one map line per device')
        commented = [x.strip() for x in lines if x.strip().startswith('# { vendor')]
        # by node-ID: the one found by SDO only (9) before the non-configured one
        expect_eq(commented, ['# ' + entry % (s.identity + (s.node_id,)) + '  # found by SDO only: it does not '
                              'answer LSS, so lssd cannot give it a node-ID' for s in sdo_only] +
                  ['# ' + entry % (fresh.identity + ('N',)) +
                   '  # non-configured (node-ID 255): give it a node-ID, then scan again'],
                  'the non-configured device and the one found by SDO only, commented out')
        expect('interface = "vcan0";' in out and 'bitrate = 125000;' in out, 'the bus: %r' % out)

        check_printed_map(env, out)

        # lssd with the printed map (the test's LSS timeout in front, as an
        # installed file has its global settings): the bus already matches it
        env.config = out
        env.restart_lssd()
        since = len(env.frames('vcan0')) if env.real else 0
        got = ctl.ok('auto-assign', '--json').json
        expect_eq(sorted((x['serial'], x['outcome'], x['new_node_id']) for x in got),
                  sorted([(s.serial, 'unchanged', s.node_id) for s in configured] + [(fresh.serial, 'unknown', 255)]),
                  'auto-assign with the printed map')
        if env.real:
            # Nothing stored, and no mapped node-ID configured. The pass still
            # looks for non-configured devices: the one here is set aside with
            # a volatile node-ID from 127 down and given 255 back
            # (docs/engine.md), which stores nothing and changes nothing.
            frames = env.frames('vcan0')[since:]
            stores = [f for f in frames if f[1] == 0x7E5 and f[2][0] == 0x17]
            expect_eq(stores, [], 'Store frames of the auto-assign')
            mapped = {s.node_id for s in configured}
            configures = [f[2][1] for f in frames if f[1] == 0x7E5 and f[2][0] == 0x11]
            expect(not mapped & set(configures) and all(n == 0xFF or n >= 100 for n in configures),
                   'Configure Node-ID of the auto-assign only to set the non-configured device aside and back: %r'
                   % configures)
            expect_eq(int(env.slave_state('vcan0', fresh.serial)['active_node_id'], 0), 255,
                      'the non-configured device is non-configured again')
            expect(any(f[1] == 0x7E5 for f in frames), 'the auto-assign was on the wire')

        # A map entry whose device is gone while another device answers to
        # its node-ID: kept, the printed map would give the node-ID twice, so
        # it is commented out and says why.
        env.config = ('buses = ( { interface = "vcan0"; bitrate = 125000; devices = ( '
                      '{ vendor = 0xEC; product = 0x1234; serial = 0x9999; node_id = %d; } ); } );\n'
                      % configured[0].node_id)
        env.restart_lssd()
        # no AutoAssign ran (auto_assign is false by default): the Scan of
        # --as-config itself tells lssd the entry is missing
        out = ctl.ok('scan', '--as-config', '--vendor', '0xEC', '--product', '0x1234').out
        env.step('lssctl scan --as-config, a map entry gone and its node-ID taken:\n' + out)
        expect(('# { vendor = 0x000000ec; product = 0x00001234; serial = 0x00009999; node_id = %d; }  # in the map, '
                "not found by this scan; node-ID %d is another device's now") % ((configured[0].node_id,) * 2) in out,
               'the gone entry commented out: %r' % out)
        expect((entry % (configured[0].identity + (configured[0].node_id,))) in out,
               'the device at that node-ID mapped: %r' % out)
        check_printed_map(env, out)
        # the entry deleted and reloaded: lssd forgets the device it knew
        # only from the map, and keeps those it saw
        listed = [x['serial'] for x in ctl.ok('list', '--json').json]
        expect(0x9999 in listed, 'the gone entry listed before the reload: %r' % listed)
        with open(env.config_path, 'w') as f:
            f.write('buses = ( { interface = "vcan0"; bitrate = 125000; } );\n')
        ctl.ok('reload')
        listed = [x['serial'] for x in ctl.ok('list', '--json').json]
        expect(0x9999 not in listed and configured[0].serial in listed,
               'after the entry was deleted and lssd reloaded: %r' % listed)

        # The map's devices as the bus has them now: one non-configured
        # keeps its entry at the map's node-ID (as the bus is, it would lose
        # it); one at another node-ID than the map's is mapped where it is,
        # and the line says what the map had.
        env.config = ('buses = ( { interface = "vcan0"; bitrate = 125000; devices = ( '
                      '{ vendor = 0xEC; product = 0x1234; revision = 0x%x; serial = 0x%x; node_id = 20; }, '
                      '{ vendor = 0xEC; product = 0x1234; revision = 0x%x; serial = 0x%x; node_id = 16; } ); } );\n'
                      % (fresh.identity[2], fresh.serial, configured[1].identity[2], configured[1].serial))
        env.restart_lssd()
        out = ctl.ok('scan', '--as-config', '--vendor', '0xEC', '--product', '0x1234').out
        env.step('lssctl scan --as-config, a mapped device non-configured, one at another node-ID:\n' + out)
        lines = [x.strip() for x in out.splitlines()]
        expect(any(x.startswith(entry % (fresh.identity + (20,))) and
                   x.endswith("# non-configured now: at the map's node-ID, which AutoAssign gives it") for x in lines),
               'the non-configured device at its map node-ID: %r' % out)
        expect(any(x.startswith(entry % (configured[1].identity + (configured[1].node_id,))) and
                   x.endswith('# the map has node-ID 16: this is the node-ID it has now') for x in lines),
               'the device at another node-ID than the map\'s: %r' % out)
        expect(("# 3 devices mapped at their current node-IDs (1 of them not at the map's node-ID: see there), "
                "1 non-configured at the map's node-ID") in out, 'header counts: %r' % out)
        check_printed_map(env, out)


def test_scan_two_buses():
    a, b = [Slave(0x9A, 3, 1, 0x10)], [Slave(0x9A, 3, 2, 0x20)]
    with Env({'vcan0': a, 'vcan1': b}) as env:
        ctl = Ctl(env)
        found = ctl.ok('scan', '--json').json
        expect_eq([(d['bus'], d['serial']) for d in found], [('vcan0', 0x10), ('vcan1', 0x20)], 'both buses')
        expect_eq([d['serial'] for d in ctl.ok('scan', '--bus', 'vcan1', '--json').json], [0x20], 'scan --bus')
        st = ctl.ok('status', '--json').json
        expect_eq([x['interface'] for x in st['buses']], ['vcan0', 'vcan1'], 'status of two buses')
        ctl.fails('usage', 'say which one with --bus', 'raw', 'inquire-node-id')
        # a bare serial resolves to its bus
        ctl.ok('assign', '0x20', '12')
        expect_eq(env.get(device_path('vcan1', *b[0].identity), DEVICE_IFACE, 'NodeId'), 12, 'assigned on vcan1')


# ---- assigning ----

def test_assign():
    # the same serial on two buses (lss-sim keeps one state file per serial, so not on one)
    twin0, twin1 = Slave(0xEC, 0x1234, 0x00010002, 0x55), Slave(0xEC, 0x1234, 0x00010003, 0x55)
    refuser = ([Slave(0xEC, 0x1234, 0x00010002, 0x4242, faults=['configure-error-specific'])]
               if os.environ.get('LSSD_TEST_BACKEND', 'vcan') != 'simulate' else [])
    with Env({'vcan0': SLAVES + [twin0] + refuser, 'vcan1': [twin1]}, config=CONFIG % VCAN1) as env:
        ctl = Ctl(env)
        ctl.fails('not-found', 'No known device has serial number 0x00001276', 'assign', '0x1276', '5')
        scan_all(env)
        env.call(B1, BUS_IFACE, 'Scan', 'a{sv}', 0)
        # a bare serial, resolved through the known devices
        ctl.ok('assign', '0x1276', '5')
        expect_eq(env.get(device_path('vcan0', *SLAVES[0].identity), DEVICE_IFACE, 'NodeId'), 5, 'NodeId')
        if env.real:
            st = env.slave_state('vcan0', SLAVES[0].serial)
            expect_eq((st['active_node_id'], st['stored_node_id']), ('5', '5'), 'stored')
        # the whole identity, decimal works too; --no-store
        r = ctl('assign', '236:4660:65538:2147492968', '9', '--no-store')
        expect_eq((r.rc, r.out), (0, 'vcan0: device 0x000000ec:0x00001234:0x00010002:0x80002468: node-ID 6 -> 9, '
                                  'not stored.\n'), 'assign --no-store (%r)' % r.err)
        expect_eq(r.err, 'lssctl: warning: the map gives this device node-ID 6: the next auto-assign pass (also the '
                  'one at boot) puts 6 back\n', 'the map warning')
        d = [x for x in ctl.ok('list', '--json').json if x['serial'] == 0x80002468][0]
        expect_eq((d['node_id'], d['state']), (9, 'mismatch'), 'after assign --no-store')
        if env.real:
            st = env.slave_state('vcan0', SLAVES[1].serial)
            expect_eq((st['active_node_id'], st['stored_node_id']), ('9', '6'), '--no-store')
        # ambiguous: two known devices with serial 0x55; --bus settles it
        r = ctl.fails('usage', 'is ambiguous', 'assign', '0x55', '20')
        expect('0x000000ec:0x00001234:0x00010002:0x00000055 on vcan0' in r.err and
               '0x000000ec:0x00001234:0x00010003:0x00000055 on vcan1' in r.err, 'both candidates named: ' + r.err)
        ctl.ok('assign', '0x55', '20', '--bus', 'vcan1')
        expect_eq(env.get(device_path('vcan1', *twin1.identity), DEVICE_IFACE, 'NodeId'), 20, 'twin on vcan1')
        ctl.ok('assign', ident(twin0), '21')
        expect_eq(env.get(device_path('vcan0', *twin0.identity), DEVICE_IFACE, 'NodeId'), 21, 'twin on vcan0')
        # lssd's errors, each with its exit status
        ctl.fails('conflict', 'conflict', 'assign', ident(SLAVES[3]), '7')
        ctl.fails('not-found', 'no such device', 'assign', '1:2:3:4', '40', '--bus', 'vcan0')
        ctl.fails('usage', 'none knows this identity', 'assign', '1:2:3:4', '40')
        ctl.fails('not-found', "does not serve interface 'vcan3'", 'assign', '1:2:3:4', '40', '--bus', 'vcan3')
        for x in refuser:  # lss-sim only: the slave refuses, its codes are in the message
            e = ctl.fails('rejected', 'the device refused the request', 'assign', ident(x), '41')
            expect('error 255 (manufacturer-specific), spec 66' in e.err, 'Rejected message: ' + e.err)
        # refused before asking lssd
        for args, text in ((('0x1276', '0'), "Invalid node-ID '0'"), (('0x1276', '128'), "Invalid node-ID '128'"),
                           (('1:2:3', '5'), "Invalid identity '1:2:3'"), (('0xZZ', '5'), "Invalid serial"),
                           (('000000ec:1:2:3', '5'), 'Invalid identity'), (('0x1276',), 'Too few arguments')):
            ctl.fails('usage', text, 'assign', *args)
        ctl.fails('usage', 'does not go with', 'assign', '0x1276', '5', '--delay', '5')
        env.alive()


def test_unassign():
    """lssctl unassign: what happened, and what remains (CiA 305: the old
    node-ID stays until a reset); --reset finishes the job."""
    with Env({'vcan0': SLAVES}, config=CONFIG % '') as env:
        ctl = Ctl(env)
        ctl.fails('not-found', 'No known device has serial number 0x80002468', 'unassign', '0x80002468')
        scan_all(env)
        s = SLAVES[1]  # node 6, the map says 6
        path = device_path('vcan0', *s.identity)
        # the whole identity (a configured device a fastscan does not find); without
        # --reset the device keeps node 6, and lssctl says so
        r = ctl('unassign', ident(s))
        expect_eq((r.rc, r.out), (0, 'vcan0: device 0x000000ec:0x00001234:0x00010002:0x80002468: node-ID 6 -> 255 '
                                  '(non-configured) pending, stored.\n'), 'unassign (%r)' % r.err)
        expect('lssctl: warning: the device keeps node-ID 6 until it is reset or power-cycled; use the option reset '
               '(lssctl unassign --reset)' in r.err, 'pending warning: %r' % r.err)
        expect('the map gives this device node-ID 6' in r.err, 'map warning: %r' % r.err)
        expect_eq(env.get(path, DEVICE_IFACE, 'NodeId'), 6, 'NodeId until the reset')
        # now lssd knows it: a bare serial; --reset: in effect, checked; --json says the same
        got = ctl.ok('unassign', '0x80002468', '--reset', '--json').json
        expect_eq({k: got[k] for k in ('bus', 'serial', 'old', 'stored', 'in_effect')},
                  {'bus': 'vcan0', 'serial': 0x80002468, 'old': 6, 'stored': True, 'in_effect': True},
                  'unassign --reset --json')
        expect('runs non-configured now' in got['message'], 'message: %r' % got['message'])
        expect('until it is reset' not in (got['warning'] or ''), 'warning: %r' % got['warning'])
        expect_eq(env.get(path, DEVICE_IFACE, 'NodeId'), 255, 'NodeId after --reset')
        d = [x for x in ctl.ok('list', '--json').json if x['serial'] == 0x80002468][0]
        expect_eq((d['node_id'], d['state']), (255, 'non-configured'), 'list after unassign --reset')
        if env.real:
            st = env.slave_state('vcan0', s.serial)
            expect_eq((st['active_node_id'], st['stored_node_id']), ('255', '255'), 'slave after --reset')
        # --no-store --quiet: nothing on stdout, the warning still on stderr
        r = ctl('unassign', ident(SLAVES[2]), '--reset', '--no-store', '--quiet')
        expect_eq((r.rc, r.out), (0, ''), 'unassign --quiet (%r)' % r.err)
        expect('not stored: node-ID 7 comes back at the next power cycle' in r.err, 'no-store warning: %r' % r.err)
        # lssd's errors, each with its exit status; usage errors before asking lssd
        ctl.fails('not-found', 'no such device', 'unassign', '1:2:3:4')
        ctl.fails('not-found', "does not serve interface 'vcan3'", 'unassign', '1:2:3:4', '--bus', 'vcan3')
        for args, text in ((('1:2:3',), "Invalid identity '1:2:3'"), (('0xZZ',), 'Invalid serial'),
                           ((), 'Too few arguments'), (('0x1276', '5'), 'Too many arguments'),
                           (('0x1276', '--force'), 'does not go with'), (('0x1276', '--no-verify'), 'does not go with')):
            ctl.fails('usage', text, 'unassign', *args)
        ctl.fails('usage', 'does not go with', 'assign', '0x1276', '5', '--reset')
        env.alive()


def test_raw_unassign_note():
    """raw configure-node-id 255: done, and a note that it is pending until a reset."""
    with Env({'vcan0': SLAVES}) as env:
        ctl = Ctl(env)
        r = ctl('raw', 'switch-selective', ident(SLAVES[1]), 'configure-node-id', '255', 'store')
        expect_eq(r.rc, 0, 'raw configure-node-id 255 (%r)' % r.err)
        expect('configure-node-id: done' in r.out, 'raw output: %r' % r.out)
        expect('node-ID 255 is pending' in r.err and 'lssctl unassign --reset' in r.err, 'raw note: %r' % r.err)
        r = ctl('raw', 'switch-selective', ident(SLAVES[1]), 'configure-node-id', '6')
        expect('pending' not in r.err, 'no note for 1..127: %r' % r.err)


def test_auto_assign():
    with Env({'vcan0': SLAVES}, config=CONFIG % '') as env:
        ctl = Ctl(env)
        expect_eq(ctl.ok('status', '--json').json['buses'][0]['last_pass'], None, 'no pass yet')
        expect('Last pass: none since lssd started' in ctl.ok('status').out, 'status before a pass')
        t0 = time.time()
        got = ctl.ok('auto-assign', '--json').json
        expect_eq([x for x in got if x['outcome'] == 'assigned'],
                  [{'bus': 'vcan0', 'vendor': 0xEC, 'product': 0x1234, 'revision': 0x00010002,
                    'serial': 0x1276, 'revision_known': True, 'old_node_id': 255, 'new_node_id': 5, 'outcome': 'assigned', 'detail': ''}],
                  'auto-assign --json')
        expect_eq(sorted((x['serial'], x['outcome']) for x in got),
                  [(17, 'unchanged'), (0x1276, 'assigned'), (0x80002468, 'unchanged'), (0xFFFFFFFF, 'unknown')],
                  'auto-assign --json: every device')
        # the pass can be asked about afterwards (issue 21)
        last = ctl.ok('status', '--json').json['buses'][0]['last_pass']
        expect_eq((last['kind'], last['result']), ('call', 'done'), 'last_pass')
        expect(t0 - 1 <= last['started'] / 1e6 <= time.time() and 0 < last['duration'] < 600e6, 'when: %r' % last)
        expect(re.search(r'Last pass: call, [0-9-]+ [0-9:]+, [0-9.]+ s: done, 2 unchanged, 1 assigned, 1 unknown',
                         ctl.ok('status').out), 'status text: %r' % ctl.ok('status').out)
        expect_eq([x for x in ctl.ok('auto-assign', '--json').json if x['outcome'] != 'unchanged' and
                   x['outcome'] != 'unknown'], [], 'second auto-assign')
        out = ctl.ok('auto-assign', '--no-store').out
        expect_eq(out.strip().splitlines()[-1], '0 node-IDs assigned, 3 unchanged, 1 unknown.', 'auto-assign text')
        d = [x for x in ctl.ok('list', '--json').json if x['serial'] == 0x1276][0]
        expect_eq((d['node_id'], d['state']), (5, 'assigned'), 'after auto-assign')


def test_auto_assign_dry_run():
    """auto-assign --dry-run (issue 21): what a pass would change, with no
    Configure, Store or NMT frame on the wire; the pass after it does it."""
    with Env({'vcan0': SLAVES}, config=CONFIG % '', candump=True) as env:
        ctl = Ctl(env)
        r = ctl.ok('auto-assign', '--dry-run')
        expect_eq(r.out.strip().splitlines()[-1],
                  'Dry run, nothing was configured: 1 node-ID would be assigned, 2 unchanged, 1 unknown.',
                  'the dry run\'s count: %r' % r.out)
        expect('would-assign' in r.out, 'the table names what would change: %r' % r.out)
        got = ctl.ok('auto-assign', '--dry-run', '--json').json
        expect_eq(sorted((x['serial'], x['outcome']) for x in got),
                  [(17, 'unchanged'), (0x1276, 'would-assign'), (0x80002468, 'unchanged'), (0xFFFFFFFF, 'unknown')],
                  'dry run --json')
        d = [x for x in ctl.ok('list', '--json').json if x['serial'] == 0x1276][0]
        expect_eq(d['node_id'], 255, 'the device after the dry run')
        expect_eq(ctl.ok('status', '--json').json['buses'][0]['last_pass'], None, 'a dry run is no pass')
        if env.real:
            expect_eq(env.slave_state('vcan0', 0x1276)['active_node_id'], '255', 'the slave after the dry run')
            changing = [f for f in env.frames('vcan0') if f[1] == 0 or
                        (f[1] == 0x7E5 and f[2][0] in (0x11, 0x13, 0x15, 0x17))]
            expect_eq(changing, [], 'Configure, Store or NMT frames of the dry runs')
        got = ctl.ok('auto-assign', '--json').json
        expect_eq([x['outcome'] for x in got if x['serial'] == 0x1276], ['assigned'], 'the pass after the dry run')


def test_assign_taken():
    """No path gives a node-ID another device answers to (issue 17): not the
    known devices', not one lssd does not know (SDO probe), not one it heard
    (a heartbeat from a device in NMT Stopped, which answers no SDO); only
    --force does, and lssctl says what it did."""
    # configured long ago, another vendor, not in the map: lssd does not know it
    foreign = Slave(0x1ABC, 0x99, 1, 0x77, 12)
    with Env({'vcan0': SLAVES + [foreign]}, config=CONFIG % '', candump=True) as env:
        ctl = Ctl(env)
        # LSS only: the SDO pass of a plain Scan would make the foreign device known
        env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 1, 'sdo', 'b', 'false')
        dev0 = device_path('vcan0', *SLAVES[0].identity)

        def untouched(what):
            expect_eq(env.get(dev0, DEVICE_IFACE, 'NodeId'), 0xFF, what + ': NodeId')
            if env.real:
                expect_eq(env.slave_state('vcan0', SLAVES[0].serial)['active_node_id'], '255', what + ': the slave')

        ctl.fails('conflict', 'Node-ID 12 is taken on vcan0: a device lssd does not know answered an SDO '
                  'request just now as node 12. Nothing was changed', 'assign', '0x1276', '12')
        untouched('assign onto a device lssd does not know')
        # a plain Scan finds it by SDO: then lssd names it
        scan_all(env)
        ctl.fails('conflict', 'Node-ID 12 is taken on vcan0: device 00001abc:00000099:00000001:00000077 has it',
                  'assign', '0x1276', '12')
        untouched('assign onto a device found by SDO')
        ctl.fails('conflict', 'Node-ID 6 is taken on vcan0: device 000000ec:00001234:00010002:80002468 has '
                  'it', 'assign', '0x1276', '6')
        untouched('assign onto a known device')
        if env.real:
            # a device in NMT Stopped: no SDO answer, but its heartbeat was heard
            subprocess.run(['cansend', 'vcan0', '714#04'], check=True)
            time.sleep(0.3)
            ctl.fails('conflict', 'a device lssd does not know sent a heartbeat (stopped)', 'assign', '0x1276', '20')
            untouched('assign onto a heartbeat')
        # the raw service checks too (and says how to force it)
        r = ctl('raw', 'switch-selective', ident(SLAVES[0]), 'configure-node-id', '12')
        expect_eq(r.rc, EXIT['conflict'], 'raw configure-node-id onto a taken node-ID (%r)' % r.err)
        expect('Node-ID 12 is taken on vcan0' in r.err, 'raw: ' + r.err)
        untouched('raw configure-node-id')
        name, msg = env.call_error(B0, BUS_IFACE, 'Execute', 'a(sv)', 2, 'SwitchModeSelective', '(uuuu)',
                                   *SLAVES[0].identity, 'ConfigureNodeId', '(yb)', 12, 'false')
        expect_eq(name, ERR + 'Conflict', 'Execute ConfigureNodeId (12, false): ' + msg)
        expect(msg.startswith('steps[1] (ConfigureNodeId): Node-ID 12 is taken on vcan0'), 'Execute: ' + msg)
        untouched('Execute ConfigureNodeId')
        if env.real:
            # (the Scan's set-aside node-IDs from 127 down and their 255 are its own)
            configures = [f for f in env.lss_frames('vcan0') if f[1] == 0x7E5 and f[2][0] == 0x11 and f[2][1] < 100]
            expect_eq(configures, [], 'Configure Node-ID requests for a taken node-ID on the wire')

        # forced: done, said, and the map's node-ID is announced to come back
        r = ctl('assign', '0x1276', '12', '--force')
        expect_eq(r.rc, 0, 'assign --force (%r)' % r.err)
        expect_eq(r.out, 'vcan0: device 0x000000ec:0x00001234:0x00010002:0x00001276: node-ID 255 -> 12, stored.\n',
                  'what assign did')
        expect('lssctl: warning: the map gives this device node-ID 5: the next auto-assign pass' in r.err,
               'the map warning: %r' % r.err)
        if env.real:
            expect_eq(env.slave_state('vcan0', SLAVES[0].serial)['active_node_id'], '12', 'forced')
        r = ctl('assign', '0x1276', '5', '--json')
        expect_eq(r.rc, 0, 'assign --json (%r)' % r.err)
        expect_eq(json.loads(r.out), {'bus': 'vcan0', 'vendor': 0xEC, 'product': 0x1234, 'revision': 0x00010002,
                                      'serial': 0x1276, 'old': 12, 'new': 5, 'stored': True, 'warning': None},
                  'assign --json')
        expect_eq(ctl.ok('assign', '0x1276', '5', '--quiet').out, '', 'assign --quiet')
        r = ctl('assign', '0x1276', '30', '--no-store', '--json')
        expect_eq(json.loads(r.out)['warning'], 'the map gives this device node-ID 5: the next auto-assign pass '
                  '(also the one at boot) puts 5 back', 'the warning in --json')


def test_auto_assign_partial():
    # the map's 0x9A/3/17 is not on the bus: the bus does not match the map
    with Env({'vcan0': SLAVES[:2]}, config=CONFIG % '') as env:
        ctl = Ctl(env)
        r = ctl('auto-assign')
        expect_eq(r.rc, EXIT['partial'], 'exit status of a partial pass (%r)' % r.err)
        # the map has no revision: unknown, not 0x00000000 (issue 21)
        expect(re.search(r'device 0x0000009a:0x00000003:-:0x00000011 missing', r.err),
               'the missing device on stderr: %r' % r.err)
        expect(re.search(r'^vcan0 +0x0000009a +0x00000003 +- +0x00000011 +- +- +missing', r.out, re.M),
               'the missing device in the table: %r' % r.out)
        expect('does not match the map: 1 mapped device missing' in r.err, 'the verdict on stderr: %r' % r.err)
        expect_eq(r.out.strip().splitlines()[-1], '1 node-ID assigned, 1 unchanged, 1 missing.', 'the count')
        expect('device 0000009a:00000003:-:00000011 missing, map node-ID 7' in env.lssd_output(), 'the journal line of the '
               'missing device: %r' % [x for x in env.lssd_output().splitlines() if 'missing' in x])
        r = ctl('auto-assign', '--json')
        expect_eq(r.rc, EXIT['partial'], 'exit status of a partial pass with --json')
        expect_eq([(x['serial'], x['outcome'], x['revision_known']) for x in json.loads(r.out)
                   if x['outcome'] == 'missing'], [(17, 'missing', False)], '--json names the missing device')
        r = ctl('auto-assign', '--quiet')
        expect_eq((r.rc, r.out), (EXIT['partial'], ''), 'auto-assign --quiet: nothing on stdout (%r)' % r.err)
        expect('device 0x0000009a:0x00000003:-:0x00000011 missing' in r.err, 'problems still said: %r' % r.err)
        # never seen, and the map has no revision: list shows it unknown, not 0x00000000 (issue 21)
        out = ctl.ok('list').out
        expect(re.search(r'^vcan0 +0x0000009a +0x00000003 +- +0x00000011 +- +7 +missing', out, re.M),
               'the missing device in list: %r' % out)
        got = [(x['serial'], x['revision_known']) for x in ctl.ok('list', '--json').json]
        expect((17, False) in got and all(k for s, k in got if s != 17), 'revision_known in list --json: %r' % got)
        # scan says the map has a device it did not find
        out = ctl.ok('scan').out
        expect("1 device of the map not found (missing): 'lssctl list' shows it." in out,
               'scan names the missing count: %r' % out)
        # A map printed from a scan keeps the map's device it did not find
        # (written over lssd.conf, it would drop it without a word): at the
        # map's node-ID, without the revision the map does not have.
        out = ctl.ok('scan', '--as-config').out
        env.step('lssctl scan --as-config with a device of the map missing:\n' + out)
        expect('2 devices mapped at their current node-IDs, 1 kept from the map (not found), on vcan0.' in out,
               'header counts: %r' % out)
        expect('{ vendor = 0x0000009a; product = 0x00000003; serial = 0x00000011; node_id = 7; }  # in the map, '
               'not found by this scan: kept (delete the line if the device is gone)' in out,
               'the missing device kept: %r' % out)
        check_printed_map(env, out)


def test_set_bitrate():
    # vcan0 may change its bit rate, vcan1 may not; the map's 0x9A/3/17 is not on vcan0
    conf = (CONFIG % VCAN1).replace('bitrate = 125000;', 'bitrate = 125000;\n    bitrate_change = true;', 1)
    with Env({'vcan0': SLAVES[:2], 'vcan1': []}, config=conf) as env:
        ctl = Ctl(env)
        for bad in ('12345', '250', 'fast', '250kk', '0x3d090'):
            ctl.fails('usage', "Invalid bit rate '%s'" % bad, 'set-bitrate', bad)
        ctl.fails('usage', "Unknown option '-1'", 'set-bitrate', '-1')
        ctl.fails('usage', "Invalid --delay", 'set-bitrate', '250k', '--delay', '70000')
        ctl.fails('usage', 'does not go with', 'set-bitrate', '250k', '--no-verify')
        ctl.fails('usage', 'say which one with --bus', 'set-bitrate', '250k')
        ctl.fails('not-supported', 'not supported by lssd, its configuration', 'set-bitrate', '250k', '--bus', 'vcan1')
        ctl.fails('not-found', 'no such device or bus', 'set-bitrate', '250k', '--bus', 'vcan0', '--delay', '20')
        expect_eq(env.get(B0, BUS_IFACE, 'Bitrate'), 125000, 'Bitrate after a refused change')
        r = ctl.ok('set-bitrate', '250k', '--bus', 'vcan0', '--delay', '20', '--skip-missing', '--no-store')
        lines = r.out.splitlines()
        expect_eq(lines[-1], 'vcan0: the interface and %d devices switched from 125000 to 250000 bit/s.'
                  % (len(lines) - 1), 'what set-bitrate did: %r' % r.out)
        expect_eq(sorted(lines[:-1]), sorted('vcan0: device %s: 125000 -> 250000 bit/s, not stored.'
                                             % ident8(s) for s in SLAVES[:2]), 'a line per device: %r' % r.out)
        expect_eq(ctl.ok('status', '--bus', 'vcan0', '--json').json['buses'][0]['bitrate'], 250000, 'bitrate')
        expect_eq(ctl.ok('set-bitrate', '250k', '--bus', 'vcan0').out,
                  'vcan0: the network runs at 250000 bit/s already, nothing changed.\n', 'set-bitrate again')
        expect_eq(ctl.ok('set-bitrate', '250k', '--bus', 'vcan0', '-q').out, '', 'set-bitrate --quiet')
        env.alive()


def test_reload():
    with Env({'vcan0': SLAVES, 'vcan1': []}, config=CONFIG % '') as env:
        ctl = Ctl(env)
        with open(env.config_path, 'w') as f:
            f.write(CONFIG % VCAN1)
        expect_eq(ctl.ok('reload').out, 'lssd read its configuration again.\n', 'what reload did')
        expect_eq(ctl.ok('reload', '--quiet').out, '', 'reload --quiet')
        expect_eq([b['interface'] for b in ctl.ok('status', '--json').json['buses']], ['vcan0', 'vcan1'], 'reloaded')
        with open(env.config_path, 'w') as f:
            f.write('buses = ( { interface = "vcan0"; devices = ( { serial = 1; node_id = 200; } ); } );\n')
        r = ctl.fails('bad-config', 'the configuration file is invalid', 'reload')
        expect(env.config_path in r.err, 'file named: ' + r.err)
        ctl.fails('usage', 'Too many arguments', 'reload', 'now')


# ---- live ----

def test_monitor():
    with Env({'vcan0': SLAVES[:2]}, config=CONFIG % '') as env:
        ctl = Ctl(env)
        p = ctl.spawn('monitor', '--json')
        text = ctl.spawn('monitor')
        try:
            for x in (p, text):
                expect_eq(x.stderr.readline(), 'Monitoring lssd; press ^C to stop.\n', 'monitor ready')
            scan_all(env)
            env.call(B0, BUS_IFACE, 'AssignNodeId', 'uuuuya{sv}', *SLAVES[0].identity, 5, 0)
            env.wait_until(lambda: env.get(B0, BUS_IFACE, 'Job') == '', what='idle')
            time.sleep(0.5)
        finally:
            for x in (p, text):
                x.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=20)
        expect_eq(p.returncode, 0, 'monitor exit status after ^C (%r)' % err)
        events = [json.loads(line) for line in out.splitlines()]
        expect(all(set(e) >= {'time', 'signal', 'path', 'bus', 'args'} for e in events), 'keys: %r' % events[:2])
        sigs = [e['signal'] for e in events]
        for want in ('PropertiesChanged', 'DeviceFound', 'JobFinished', 'NodeIdAssigned', 'InterfacesAdded'):
            expect(want in sigs, 'monitor saw no %s: %r' % (want, sigs))
        d0 = device_path('vcan0', *SLAVES[0].identity)
        nia = [e for e in events if e['signal'] == 'NodeIdAssigned'][0]
        expect_eq((nia['bus'], nia['path'], nia['args']), ('vcan0', B0, [d0, 255, 5]), 'NodeIdAssigned')
        jf = [e for e in events if e['signal'] == 'JobFinished'][0]
        expect_eq(jf['args'], ['Scan', 'done'], 'JobFinished')
        pc = [e for e in events if e['signal'] == 'PropertiesChanged' and e['path'] == B0]
        expect(any(e['args'][1].get('Job') == 'Scan' for e in pc), 'Job=Scan change: %r' % pc[:3])

        tout, _ = text.communicate(timeout=20)
        expect_eq(text.returncode, 0, 'text monitor exit status')
        lines = tout.splitlines()
        expect(any(re.match(r'\d\d:\d\d:\d\d\.\d{3} vcan0 NodeIdAssigned 0x000000ec:0x00001234:0x00010002:'
                            r'0x00001276 255 5$', x) for x in lines), 'NodeIdAssigned line: %r' % lines)
        expect(any(re.match(r'\S+ vcan0 .*\bJob=Scan\b', x) for x in lines), 'Job=Scan line: %r' % lines)

        # lssd stopping is said
        mon = ctl.spawn('monitor', '--bus', 'vcan0')
        expect_eq(mon.stderr.readline(), 'Monitoring lssd on vcan0; press ^C to stop.\n', 'monitor --bus ready')
        env.stop_lssd()
        time.sleep(0.5)
        mon.send_signal(signal.SIGINT)
        out, _ = mon.communicate(timeout=20)
        expect(re.search(r'^\S+ lssd stopped$', out, re.M), 'monitor of a stopping lssd: %r' % out)
        expect_eq(mon.returncode, 0, 'monitor exit status')


def test_raw():
    with Env({'vcan0': SLAVES}) as env:
        ctl = Ctl(env)
        s = SLAVES[0]
        got = ctl.ok('raw', 'switch-selective', ident(s), 'inquire-node-id', 'inquire-identity',
                     'configure-node-id', '20', 'store', 'switch-global', 'waiting', 'identify-non-configured',
                     'fastscan', 'vendor=0x9A', '--json').json
        expect_eq(got, [
            {'service': 'SwitchModeSelective', 'result': True},
            {'service': 'InquireNodeId', 'result': 255},
            {'service': 'InquireIdentity', 'result': dict(zip(('vendor', 'product', 'revision', 'serial'),
                                                               s.identity))},
            {'service': 'ConfigureNodeId', 'result': None},
            {'service': 'StoreConfiguration', 'result': None},
            {'service': 'SwitchModeGlobal', 'result': None},
            {'service': 'IdentifyNonConfigured', 'result': True},
            {'service': 'Fastscan', 'result': dict(zip(('vendor', 'product', 'revision', 'serial'),
                                                        SLAVES[3].identity))},
        ], 'raw --json')
        expect_eq(env.get(B0, BUS_IFACE, 'State'), 'idle', 'released after raw')
        out = ctl.ok('raw', 'SwitchModeSelective', ident(s), 'inquire-node-id', 'identify-remote', '0x77', '3', '0',
                     '0xffffffff', '0', '0xffffffff').out
        expect_eq(out.splitlines(), ['switch-selective: answered', 'inquire-node-id: 20',
                                     'identify-remote: no answer'], 'raw text')
        if env.real:
            env.wait_until(lambda: env.slave_state('vcan0', s.serial)['lss_state'] == 'waiting', what='waiting')
            expect_eq(env.slave_state('vcan0', s.serial)['stored_node_id'], '20', 'stored by raw')
        # nobody in configuration state answers an inquiry
        ctl.fails('no-response', 'no device answered', 'raw', 'inquire-node-id')
        expect_eq(env.get(B0, BUS_IFACE, 'State'), 'idle', 'released after NoResponse')
        # lssd refuses an argument: exit 2, and the bus is released all the same
        ctl.fails('usage', 'invalid argument', 'raw', 'configure-bit-timing', '0', '10')
        expect_eq(env.get(B0, BUS_IFACE, 'State'), 'idle', 'released after a failure')
        for args, text in ((('reboot',), "Unknown raw service 'reboot'"),
                           (('configure-node-id',), 'needs 1 argument'),
                           (('switch-global', 'sideways'), "Invalid mode 'sideways'"),
                           (('fastscan', 'colour=1'), "Invalid fastscan field 'colour=1'"),
                           (('identify-remote', '1', '2'), 'needs 6 arguments')):
            ctl.fails('usage', text, 'raw', *args)
        # somebody else holds the bus: Busy
        holder = env.connect()
        holder.call(SERVICE, B0, BUS_IFACE, 'Acquire', '', [])
        ctl.fails('busy', 'the bus is held by another program', 'raw', 'inquire-node-id')
        ctl.fails('busy', 'the bus is held by another program', 'scan')
        holder.call(SERVICE, B0, BUS_IFACE, 'Release', '', [])
        env.alive()


def test_cancel():
    slaves = [Slave(0x9A, 3, 1, 0x1000 + i) for i in range(6)]
    with Env({'vcan0': slaves}) as env:
        ctl = Ctl(env)
        c = env.connect()
        c.add_match(f"type='signal',sender='{SERVICE}',interface='{BUS_IFACE}'")
        p = ctl.spawn('scan', '--json')
        env.wait_until(lambda: env.get(B0, BUS_IFACE, 'Job') == 'Scan', what='the scan to run')
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=60)
        expect_eq(p.returncode, EXIT['interrupted'], 'exit status after ^C (%r)' % err)
        expect('Scan on vcan0 interrupted' in err, 'message: %r' % err)
        expect_eq(out, '', 'no output after ^C')
        sig = c.wait_signal(lambda m: m.member == 'JobFinished')
        expect(sig and sig.body == ['Scan', 'cancelled'], 'JobFinished: %r' % (sig and sig.body))
        env.wait_until(lambda: env.get(B0, BUS_IFACE, 'Job') == '', what='idle after ^C')

        # on a terminal: a progress bar while the job runs, then ^C
        state = {'sent': False}

        def interrupt_at_progress(proc, out):
            if not state['sent'] and re.search(rb'vcan0 Scan \[[#.]{30}\] +\d+%', out):
                state['sent'] = True
                os.killpg(proc.pid, signal.SIGINT)  # as the terminal does

        rc, tty = ctl.on_tty('scan', on_output=interrupt_at_progress)
        expect(state['sent'], 'no progress bar on a terminal: %r' % tty[-300:])
        expect_eq(rc, EXIT['interrupted'], 'exit status after ^C on a terminal: %r' % tty[-300:])
        env.alive()


# ---- failures ----

def test_errors():
    # the exit status each lssd error has in its one home is lssctl(1)'s
    for sym, (name, code) in ERRORS.items():
        expect_eq(code, EXIT.get(sym.lower().replace('_', '-')), 'exit status of %s in src/names/lssd_names.h' % name)
    # enough slaves that a Scan outlasts lssctl's start at the default timing
    # (6 were done in 1-2 s: the queue was no longer full when lssctl asked)
    slaves = [Slave(0x9A, 3, 1, 0x1000 + i) for i in range(24)]
    with Env({'vcan0': slaves}, lssd_args=['--queue-size', '1']) as env:
        ctl = Ctl(env)
        # somebody else cancels lssctl's job
        p = ctl.spawn('scan')
        env.wait_until(lambda: env.get(B0, BUS_IFACE, 'Job') == 'Scan', what='the scan to run')
        env.call(B0, BUS_IFACE, 'Cancel')
        out, err = p.communicate(timeout=60)
        expect_eq(p.returncode, EXIT['cancelled'], 'exit status of a job cancelled by another (%r)' % err)
        expect('Scan on vcan0 failed: the job was cancelled' in err, 'message: %r' % err)
        # the queue is full
        c = env.connect()
        running = c.send(SERVICE, B0, BUS_IFACE, 'Scan', 'a{sv}', [{}])
        env.wait_until(lambda: env.get(B0, BUS_IFACE, 'Job') == 'Scan', what='the scan to run')
        queued = c.send(SERVICE, B0, BUS_IFACE, 'Scan', 'a{sv}', [{}])
        env.wait_until(lambda: env.get(B0, BUS_IFACE, 'QueueLength') == 1, what='a queued scan')
        ctl.fails('limits-exceeded', 'the job queue is full', 'scan')
        env.call(B0, BUS_IFACE, 'Cancel')
        for serial in (running, queued):
            try:
                c.wait_reply(serial, 120)
            except Exception:  # noqa: BLE001  cancelled, or done: either is fine here
                pass
        env.alive()


def test_bus_down():
    with Env({'vcan1': SLAVES[:1]}) as env:
        if not env.real:
            raise Skip('needs a real interface to take down')
        ctl = Ctl(env)
        try:
            subprocess.run(['ip', 'link', 'set', 'vcan1', 'down'], check=True)
            env.wait_until(lambda: env.get(B1, BUS_IFACE, 'State') == 'down', what='State down')
            expect_eq(ctl.ok('status', '--json').json['buses'][0]['state'], 'down', 'status of a down bus')
            ctl.fails('bus-down', 'the CAN interface is down or not there', 'scan')
        finally:
            subprocess.run(['ip', 'link', 'set', 'vcan1', 'up'], check=True)
        env.wait_until(lambda: env.get(B1, BUS_IFACE, 'State') == 'idle', what='State idle again')
        env.alive()


def test_not_running():
    with Env({'vcan0': SLAVES[:1]}) as env:
        ctl = Ctl(env)
        env.stop_lssd()
        for args in (('status',), ('list',), ('list', '--json'), ('scan',), ('assign', '0x1276', '5'),
                     ('assign', '1:2:3:4', '5'), ('auto-assign',), ('set-bitrate', '250k'), ('reload',),
                     ('monitor',), ('raw', 'inquire-node-id'), ()):
            r = ctl.fails('not-running', 'lssd is not running.', *args)
            expect_eq(r.err, 'lssctl: lssd is not running.\n', 'the whole message')
        # no system bus at all
        r = subprocess.run([LSSCTL, 'status'], capture_output=True, text=True,
                           env=dict(ctl.environ(), DBUS_SYSTEM_BUS_ADDRESS='unix:path=/nonexistent/socket'))
        expect_eq(r.returncode, EXIT['not-running'], 'no system bus')
        expect('lssd is not running' in r.stderr, 'no system bus: %r' % r.stderr)


def test_unprivileged():
    with Env({'vcan0': SLAVES[:1]}) as env:
        ctl = Ctl(env)
        scan_all(env)
        nobody = {'user': 'nobody'}
        expect_eq(ctl.ok('status', '--json', **nobody).json['buses'][0]['devices'], 1, 'status as nobody')
        expect_eq(len(ctl.ok('list', '--json', **nobody).json), 1, 'list as nobody')
        for args in (('scan',), ('assign', '0x1276', '5'), ('auto-assign',), ('set-bitrate', '250k'), ('reload',),
                     ('raw', 'inquire-node-id')):
            # lssd's own refusal (no polkit on this bus: root and group lssd), naming the action
            r = ctl.fails('access-denied', "permission denied (org.lssd.LSS1.",
                          *args, **nobody)
            expect("needs root or group 'lssd'" in r.err, 'the rule without polkit: %r' % r.err)
            # the point, not dbus-daemon's ~300 characters of matched rule
            expect(len(r.err) < 160 and 'Rejected send message' not in r.err, 'a long refusal: %r' % r.err)
        expect_eq(env.get(B0, BUS_IFACE, 'State'), 'idle', 'nothing happened')
        env.alive()


def test_bad_arguments():
    with Env({'vcan0': SLAVES[:1]}) as env:
        ctl = Ctl(env)
        for args, text in ((('frobnicate',), "Unknown command 'frobnicate'"),
                           (('--frobnicate',), "Unknown option '--frobnicate'"),
                           (('list', 'extra'), "Too many arguments for 'list'"),
                           (('status', '--no-store'), 'Option --no-store does not go with'),
                           (('list', '--delay', '5'), 'Option --delay does not go with'),
                           (('reload', '--bus', 'vcan0'), 'Option --bus does not go with'),
                           (('set-bitrate',), "Too few arguments for 'set-bitrate'"),
                           (('raw',), "Too few arguments for 'raw'"),
                           (('list', '--json=pretty'), '--json takes no value'),
                           (('list', '--bus'), "Option '--bus' needs a value")):
            r = ctl.fails('usage', text, *args)
            expect("Try 'lssctl --help'" in r.err, 'hint: %r' % r.err)
        h = ctl.ok('--help').out
        for verb in ('status', 'list', 'scan', 'assign', 'unassign', 'auto-assign', 'set-bitrate', 'reload', 'monitor',
                     'raw', 'import-dcf'):
            expect(re.search(r'^  %s\b' % verb, h, re.M), '--help lacks ' + verb)
        expect(ctl.ok('--version').out.startswith('lssctl '), '--version')


# ---- completion and manual pages ----

def complete(words, env=None):
    """Completions bash offers for `words` (the last one is being completed)."""
    script = os.path.join(SOURCE_ROOT, 'shell-completion', 'bash', 'lssctl')
    line = ' '.join(words)
    prog = ('source %s || exit 90\n'
            'COMP_WORDS=(%s); COMP_CWORD=%d; COMP_LINE=%s; COMP_POINT=${#COMP_LINE}\n'
            '_lssctl lssctl "${COMP_WORDS[COMP_CWORD]}" "${COMP_WORDS[COMP_CWORD-1]}" || exit 91\n'
            'printf "%%s\\n" "${COMPREPLY[@]}"\n'
            % (script, ' '.join("'%s'" % w for w in words), len(words) - 1, "'%s'" % line))
    p = subprocess.run(['bash', '--norc', '--noprofile', '-c', prog], capture_output=True, text=True, env=env)
    expect(p.returncode == 0 and p.stderr == '', 'completion of %r: rc=%d %r' % (words, p.returncode, p.stderr))
    return sorted(x for x in p.stdout.splitlines() if x)


def test_completion():
    script = os.path.join(SOURCE_ROOT, 'shell-completion', 'bash', 'lssctl')
    p = subprocess.run(['bash', '--norc', '--noprofile', '-c', 'set -u; source %s && complete -p lssctl' % script],
                       capture_output=True, text=True)
    expect_eq((p.returncode, p.stderr), (0, ''), 'loading the completion script')
    expect('_lssctl' in p.stdout, 'complete -p: %r' % p.stdout)
    expect_eq(complete(['lssctl', '']), sorted(['status', 'list', 'scan', 'assign', 'unassign', 'auto-assign',
                                                 'set-bitrate', 'reload', 'monitor', 'raw', 'import-dcf']), 'commands')
    expect_eq(complete(['lssctl', 'import-dcf', '--']), ['--bus'], 'import-dcf options')
    expect('--as-dcf' in complete(['lssctl', 'scan', '--']), 'scan options')
    expect_eq(complete(['lssctl', 'scan', '--as-dcf', os.path.join(SOURCE_ROOT, 'tests', 'unit', 'dc')]), [DCF_DATA],
              'scan --as-dcf: folders')
    expect_eq(complete(['lssctl', 'import-dcf', os.path.join(DCF_DATA, 'lely-co-nmt-s')]), [LELY_SLAVE],
              'import-dcf: file names')
    expect_eq(complete(['lssctl', 'au']), ['auto-assign'], 'command prefix')
    expect('--no-store' in complete(['lssctl', 'assign', '--']), 'assign options')
    expect_eq(complete(['lssctl', 'unassign', '--']),
              sorted(['--bus', '--json', '--no-store', '--reset', '--quiet', '--no-ask-password']), 'unassign options')
    expect('--no-store' not in complete(['lssctl', 'list', '--']), 'list options')
    expect('--json' in complete(['lssctl', 'list', '--']), 'list options')
    expect('inquire-node-id' in complete(['lssctl', 'raw', '']), 'raw services')
    expect('500000' in complete(['lssctl', 'set-bitrate', '']), 'bit rates')
    with Env({'vcan0': SLAVES}, config=CONFIG % '') as env:
        ctl = Ctl(env)
        scan_all(env)
        e = ctl.environ(PATH=os.path.dirname(os.path.abspath(LSSCTL)) + ':' + os.environ.get('PATH', ''))
        expect_eq(complete(['lssctl', 'assign', ''], env=e), sorted('0x%08x' % s.serial for s in SLAVES),
                  'known serials')
        expect_eq(complete(['lssctl', 'assign', '0x8'], env=e), ['0x80002468'], 'serial prefix')
        expect_eq(complete(['lssctl', 'unassign', '0x8'], env=e), ['0x80002468'], 'unassign: serial prefix')


MAN_PAGES = ['lssd.8', 'lssctl.1', 'lss-sim.1', 'lssd.conf.5', 'org.lssd.LSS1.5']


def test_man():
    if not shutil_which('man'):
        raise Skip('man is not installed')
    if 'vgpreload' in os.environ.get('LD_PRELOAD', ''):
        raise Skip('under valgrind: man and groff are not ours to check')
    for page in MAN_PAGES:
        path = os.path.join(SOURCE_ROOT, 'man', page)
        p = subprocess.run(['man', '--warnings', '-E', 'UTF-8', '-l', path], capture_output=True, text=True,
                           env=dict(os.environ, MANROFFSEQ='', MANWIDTH='80', MAN_KEEP_FORMATTING='0'))
        expect_eq((p.returncode, p.stderr), (0, ''), 'man -l %s' % page)
        expect(len(p.stdout.splitlines()) > 20, '%s renders to almost nothing' % page)
    # every exit status the code has is documented, with its number
    with open(os.path.join(SOURCE_ROOT, 'man', 'lssctl.1')) as f:
        text = f.read()
    for code in EXIT.values():
        expect(re.search(r'^\.IP "?%d"?$' % code, text, re.M) or
               re.search(r'^\.TP\n\.B %d$' % code, text, re.M), 'exit status %d not in lssctl(1)' % code)


def shutil_which(name):
    import shutil
    return shutil.which(name)


TESTS = {
    'status': test_status,
    'list': test_list,
    'scan': test_scan,
    'scan-config': test_scan_config,
    'import-dcf': test_import_dcf,
    'scan-dcf': test_scan_dcf,
    'scan-two-buses': test_scan_two_buses,
    'assign': test_assign,
    'assign-taken': test_assign_taken,
    'unassign': test_unassign,
    'raw-unassign-note': test_raw_unassign_note,
    'auto-assign-dry-run': test_auto_assign_dry_run,
    'auto-assign': test_auto_assign,
    'auto-assign-partial': test_auto_assign_partial,
    'set-bitrate': test_set_bitrate,
    'reload': test_reload,
    'monitor': test_monitor,
    'raw': test_raw,
    'cancel': test_cancel,
    'errors': test_errors,
    'bus-down': test_bus_down,
    'not-running': test_not_running,
    'unprivileged': test_unprivileged,
    'bad-arguments': test_bad_arguments,
    'completion': test_completion,
    'man': test_man,
}

if __name__ == '__main__':
    sys.exit(run(TESTS))
