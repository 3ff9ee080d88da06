# SPDX-License-Identifier: LGPL-2.1-or-later
"""Harness of the lssd integration tests: a private system bus (the real
policy file included), lss-sim on vcan interfaces, the real lssd, candump,
and busctl exactly as users run it. Python 3 stdlib only.

Environment (set by tests/integration/meson.build):
  LSSD_BINARY, LSS_SIM_BINARY, LSSD_SOURCE_ROOT
  LSSD_RUNTIME_DIR   tmpfs for unix sockets (the VM runner sets it)
  LSSD_TEST_WRAPPER  command lssd runs under, e.g. "valgrind --error-exitcode=99
                     --leak-check=full"
  LSSD_TEST_BACKEND  "vcan" (default): needs vcan0 (else the test SKIPs);
                     "simulate": lssd --simulate, no SocketCAN (parts that
                     need lss-sim, candump or ip link are skipped)
"""

import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import dbusmini  # noqa: E402

SKIP = 77
SOURCE_ROOT = os.environ.get('LSSD_SOURCE_ROOT',
                             os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
NAMES_HEADER = os.path.join(SOURCE_ROOT, 'src', 'names', 'lssd_names.h')


def read_names(path=NAMES_HEADER):
    """lssd's D-Bus names from their one home, src/names/lssd_names.h: (the
    #define'd strings {LSSD_X: value}, the error rows {SYMBOL: (name, lssctl
    exit status)})."""
    with open(path) as f:
        text = f.read()
    token = r'(?:"[^"]*"|LSSD_\w+)'
    names = {}
    for m in re.finditer(r'^#define (LSSD_\w+)[ \t]+(%s(?:[ \t]+%s)*)[ \t]*$' % (token, token), text, re.M):
        names[m.group(1)] = ''.join(lit or names[ref] for lit, ref in re.findall(r'"([^"]*)"|(LSSD_\w+)', m.group(2)))
    errors = {m.group(1): (names['LSSD_ERROR_' + m.group(1)], int(m.group(2)))
              for m in re.finditer(r'^\s*X\((\w+), \w+, (\d+),', text, re.M)}
    assert names and errors, 'no names in ' + path
    return names, errors


NAMES, ERRORS = read_names()
SERVICE = NAMES['LSSD_BUS_NAME']
ROOT = NAMES['LSSD_ROOT_PATH']
MANAGER = NAMES['LSSD_MANAGER_PATH']
MANAGER_IFACE = NAMES['LSSD_MANAGER_IFACE']
BUS_IFACE = NAMES['LSSD_BUS_IFACE']
DEVICE_IFACE = NAMES['LSSD_DEVICE_IFACE']
ERR = NAMES['LSSD_ERROR_PREFIX']
INVALID_ARGS = 'org.freedesktop.DBus.Error.InvalidArgs'
ACCESS_DENIED = 'org.freedesktop.DBus.Error.AccessDenied'


class Skip(Exception):
    pass


def unit_exec_start(config_path):
    """lssd's command line as systemd/lssd.service.in starts it, for config_path."""
    with open(os.path.join(SOURCE_ROOT, 'systemd', 'lssd.service.in')) as f:
        line = next(x for x in f.read().splitlines() if x.startswith('ExecStart='))
    argv = line[len('ExecStart='):].split()
    argv = [a.replace('@sysconfdir@/lssd/lssd.conf', config_path) for a in argv]
    assert argv[0] == '@sbindir@/lssd' and config_path in argv, 'unexpected ExecStart line: ' + line
    return [os.environ.get('LSSD_BINARY', 'lssd')] + argv[1:]


def bus_path(ifname):
    return NAMES['LSSD_BUSES_PATH'] + '/' + ''.join(c if c.isascii() and c.isalnum() else '_%02x' % ord(c) for c in ifname)


def device_path(ifname, v, p, r, s):
    return '%s/devices/%08x_%08x_%08x_%08x' % (bus_path(ifname), v, p, r, s)


def log(*args):
    print(*args, flush=True)


def auto_assign(env, ifname='vcan0', options=(0,)):
    """AutoAssign: (changes, outcomes, result). changes: [v, p, r, s, old,
    new] of the devices that got a node-ID; outcomes: {serial: (outcome,
    old, new, detail)} of every device the pass dealt with."""
    outcomes, result = env.call(bus_path(ifname), BUS_IFACE, 'AutoAssign', 'a{sv}', *options)
    changes = [list(o[:6]) for o in outcomes if o[6] in ('assigned', 'pool')]
    return changes, {o[3]: (o[6], o[4], o[5], o[7]) for o in outcomes}, result


class Slave:
    def __init__(self, vendor, product, revision, serial, node_id=0xFF, faults=(), profile=None, sim_profile=None):
        self.vendor, self.product, self.revision, self.serial = vendor, product, revision, serial
        self.node_id = node_id
        self.faults = list(faults)
        # an lss-sim profile: 'canopennode', 'canopennode-bitrate' or 'lely'
        # (lssd --simulate knows them too), or None for the lss-sim process's own
        self.profile = profile
        # lssd --simulate's profile where lss-sim has faults instead (e.g.
        # 'no-selective-switch' for ignore-cs=0x40): lss-sim ignores it
        self.sim_profile = sim_profile or profile

    @property
    def identity(self):
        return (self.vendor, self.product, self.revision, self.serial)

    def spec(self):
        s = '0x%x:0x%x:0x%x:0x%x' % self.identity
        return s + (':%d' % self.node_id if self.node_id != 0xFF else '')

    def sim_spec(self):
        """lssd --sim-slave's form (after IFACE:), which names the profile."""
        p = self.sim_profile
        return self.spec() + ((':' if self.node_id != 0xFF else ':0xff:') + p if p else '')


class BusctlResult:
    def __init__(self, proc):
        self.rc = proc.returncode
        self.stdout = proc.stdout
        self.stderr = proc.stderr
        self.error_name = self.error_message = None
        for line in proc.stderr.splitlines():
            m = re.search(r'type=error .*error-name=(\S+) error-message=(.*)$', line)
            if m:
                self.error_name, self.error_message = m.group(1), m.group(2)
        self.data = None
        if self.rc == 0 and self.stdout.strip().startswith('{'):
            self.data = json.loads(self.stdout)

    def __repr__(self):
        return 'busctl rc=%d error=%s (%s) out=%r' % (self.rc, self.error_name, self.error_message, self.stdout)


def configure_node_ids(frames):
    """The node-IDs of the Configure Node-ID requests among (time, id, data)
    frames, as devices were given them: the same request asked again right
    after itself (its answer silent or stalled) is one."""
    ids, last = [], None
    for f in frames:
        if f[1] != 0x7E5:
            continue
        if f[2][0] == 0x11 and f[2] != last:
            ids.append(f[2][1])
        last = f[2] if f[2][0] == 0x11 else None
    return ids


class Env:
    """One private bus, lss-sim per interface, one lssd."""

    def __init__(self, slaves=None, config=None, lssd_args=(), lssd_policy_override=False, candump=False,
                 notify=False, sim_args=(), absent=(), start_lssd=True, more_sims=(), lssd_prefix=()):
        self.slaves = slaves if slaves is not None else {'vcan0': []}
        # (ifname, slaves, lss-sim arguments): another lss-sim process on a bus
        # already served, e.g. devices of another kind beside the first ones
        self.more_sims = list(more_sims)
        # interfaces the test creates later: no check, no lss-sim at start
        self.absent = set(absent)
        self.want_lssd = start_lssd
        # a command lssd runs under, e.g. setpriv dropping a capability
        self.lssd_prefix = list(lssd_prefix)
        self.config = config
        self.lssd_args = list(lssd_args)
        self.override = lssd_policy_override
        self.want_candump = candump
        self.want_notify = notify
        self.sim_args = list(sim_args)
        self.backend = os.environ.get('LSSD_TEST_BACKEND', 'vcan')
        self.real = self.backend != 'simulate'
        self.t0 = time.monotonic()
        self.procs = []
        self.sims = {}
        self.lssd = None
        self.lssd_rc = None
        self.dir = None
        self.conns = []

    # ---- set-up ----

    def __enter__(self):
        try:
            self.start()
        except BaseException:
            self.stop()
            raise
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is not None and exc_type is not Skip and self.lssd:
            # what lssd saw, for the test log
            log('---- lssd log (last 60 lines) ----')
            log('\n'.join(self.lssd_output().splitlines()[-60:]))
        self.stop()
        return False

    def start(self):
        self.step('start (%s, lssd at its default timing)' % self.backend)
        if self.real:
            for ifname in self.slaves:
                if ifname in self.absent:
                    continue
                if not os.path.exists('/sys/class/net/' + ifname):
                    raise Skip('%s is not there (run through tests/vm/run)' % ifname)
            if os.geteuid() != 0:
                raise Skip('needs root')
        base = os.environ.get('LSSD_RUNTIME_DIR') or ('/dev/shm' if os.path.isdir('/dev/shm') else None)
        self.dir = tempfile.mkdtemp(prefix='lssd-test.', dir=base)
        os.chmod(self.dir, 0o755)
        self.state_dirs = {}
        self._start_dbus()
        if self.want_candump and self.real:
            self._start_candump()
        if self.real:
            for ifname, slaves in self.slaves.items():
                if ifname not in self.absent:
                    self._start_sim(ifname, [s for s in slaves if not s.profile])
                    # slaves of another profile: an lss-sim process of that profile each
                    for profile in sorted({s.profile for s in slaves if s.profile}):
                        self._start_sim(ifname, [s for s in slaves if s.profile == profile],
                                        key='%s+%s' % (ifname, profile),
                                        args=self.sim_args + ['--profile', profile])
            for i, (ifname, slaves, args) in enumerate(self.more_sims):
                self._start_sim(ifname, slaves, key='%s+%d' % (ifname, i + 1), args=args)
        if self.want_lssd:
            self._start_lssd()
            self.step('lssd ready')

    def bus_config_extra(self):
        """XML added to the private bus's configuration (subclasses add limits)."""
        if self.override:
            # open the bus wide: only lssd's own credential check stands
            return ('<policy context="mandatory"><allow send_destination="org.lssd.LSS1"/>'
                    '<allow own="org.lssd.LSS1"/></policy>')
        return ''

    def _start_dbus(self):
        sock = os.path.join(self.dir, 'system_bus_socket')
        self.address = 'unix:path=' + sock
        with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), 'system-bus.conf.in')) as f:
            conf = f.read()
        conf = conf.replace('@LISTEN@', self.address).replace('@EXTRA@', self.bus_config_extra())
        conf = conf.replace('@POLICY@', os.path.join(SOURCE_ROOT, 'dbus', 'org.lssd.LSS1.conf'))
        path = os.path.join(self.dir, 'bus.conf')
        with open(path, 'w') as f:
            f.write(conf)
        self.dbus_log = open(os.path.join(self.dir, 'dbus.log'), 'w')
        p = subprocess.Popen(['dbus-daemon', '--nofork', '--nopidfile', '--config-file=' + path],
                             stdout=self.dbus_log, stderr=subprocess.STDOUT)
        self.procs.append(p)
        self.dbus = p
        # the socket file appears at bind(), before listen(): a connect in
        # between is refused (an ASan run of the CI met it), so wait until
        # one is taken
        for _ in range(500):
            if os.path.exists(sock) and self._accepts(sock):
                break
            if p.poll() is not None:
                raise RuntimeError('dbus-daemon exited: ' + self.read(os.path.join(self.dir, 'dbus.log')))
            time.sleep(0.02)
        os.chmod(sock, 0o777)
        os.environ['DBUS_SYSTEM_BUS_ADDRESS'] = self.address

    @staticmethod
    def _accepts(path):
        t = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            t.connect(path)
            return True
        except OSError:
            return False
        finally:
            t.close()

    def _start_candump(self):
        # bound to every CAN interface: a socket bound to one dies with its link (ENETDOWN)
        self.candump_path = os.path.join(self.dir, 'candump.log')
        f = open(self.candump_path, 'w')
        # line-buffered: tests watch the log while things happen
        p = subprocess.Popen(['stdbuf', '-oL', 'candump', '-L', 'any'], stdout=f, stderr=subprocess.STDOUT)
        self.procs.append(p)
        time.sleep(0.3)  # candump has no "ready"

    def _start_sim(self, ifname, slaves, key=None, args=None):
        key = key or ifname
        state = os.path.join(self.dir, 'state-' + key)
        os.mkdir(state)
        self.state_dirs[key] = state
        cmd = [os.environ.get('LSS_SIM_BINARY', 'lss-sim'), ifname, '--state', state] + \
            (self.sim_args if args is None else list(args))
        for s in slaves:
            cmd += ['--slave', s.spec()]
            for fault in s.faults:
                cmd += ['--fault', '%s@0x%x' % (fault, s.serial)]
        logf = open(os.path.join(self.dir, 'lss-sim-%s.log' % key), 'w')
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=logf, text=True)
        self.procs.append(p)
        self.sims[key] = p
        for line in p.stdout:
            if line.strip() == 'ready':
                break
        else:
            raise RuntimeError('lss-sim on %s did not start' % ifname)

    def restart_sim(self, ifname, slaves):
        """A power cycle of the bus with other slaves (their stored state is kept)."""
        p = self.sims.pop(ifname)
        p.send_signal(signal.SIGTERM)
        p.wait(10)
        self.procs.remove(p)
        shutil.rmtree(self.state_dirs[ifname], ignore_errors=True)
        self._start_sim(ifname, slaves)

    def _start_lssd(self):
        cmd = self.lssd_prefix + os.environ.get('LSSD_TEST_WRAPPER', '').split()
        if self.config is not None:
            self.config_path = os.path.join(self.dir, 'lssd.conf')
            with open(self.config_path, 'w') as f:
                f.write(self.config)
            # with a configuration: exactly the unit's command line
            cmd += unit_exec_start(self.config_path)
        else:
            cmd += [os.environ.get('LSSD_BINARY', 'lssd')]
            for ifname in self.slaves:
                cmd += ['--bus', ifname]
        if not self.real:
            cmd += ['--simulate']
            for ifname, slaves in self.slaves.items():
                for s in slaves:
                    cmd += ['--sim-slave', ifname + ':' + s.sim_spec()]
        cmd += self.lssd_args
        env = dict(os.environ, DBUS_SYSTEM_BUS_ADDRESS=self.address)
        env.setdefault('LSSD_LOG_LEVEL', 'debug')
        if self.want_notify:
            if not hasattr(self, 'notify'):
                self.notify_path = os.path.join(self.dir, 'notify')
                self.notify = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
                self.notify.bind(self.notify_path)
                self.notify_msgs = []
            env['NOTIFY_SOCKET'] = self.notify_path
        self.lssd_log_path = os.path.join(self.dir, 'lssd.log')
        self.lssd_log = open(self.lssd_log_path, 'a')
        # how it was started, for tests that start another one the same way
        self.lssd_cmd, self.lssd_env = cmd, env
        self.lssd = subprocess.Popen(cmd, env=env, stdout=self.lssd_log, stderr=subprocess.STDOUT)
        self.procs.append(self.lssd)
        self.wait_for_name()

    def step(self, what):
        log('[%7.2f s] %s' % (time.monotonic() - self.t0, what))

    def wait_for_name(self, timeout=60):
        c = self.connect()
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if c.call('org.freedesktop.DBus', '/org/freedesktop/DBus', 'org.freedesktop.DBus', 'NameHasOwner',
                      's', [SERVICE])[0]:
                c.close()
                self.conns.remove(c)
                return
            if self.lssd.poll() is not None:
                raise RuntimeError('lssd exited with %d:\n%s' % (self.lssd.returncode, self.lssd_output()))
            time.sleep(0.05)
        raise RuntimeError('lssd did not take its name:\n' + self.lssd_output())

    def restart_lssd(self, sig=signal.SIGTERM, between=None):
        """Stops lssd with sig (SIGKILL: a crash) and starts it again the same
        way; between() runs while it is not running."""
        if sig == signal.SIGKILL:
            self.lssd.kill()
            self.lssd.wait()
        else:
            rc = self.stop_lssd(sig)
            assert rc == 0, 'lssd exited with %s on %s' % (rc, sig)
        self.procs.remove(self.lssd)
        self.step('lssd stopped (%s), starting it again' % signal.Signals(sig).name)
        if between:
            between()
        self._start_lssd()

    def notify_wait(self, pred, timeout=60, what='sd_notify message'):
        """Reads sd_notify datagrams until pred(message dict) holds; returns that message."""
        deadline = time.monotonic() + timeout
        while True:
            for m in self.notify_msgs:
                if pred(m):
                    return m
            left = deadline - time.monotonic()
            if left <= 0:
                raise AssertionError('timed out waiting for %s; got %r' % (what, self.notify_msgs))
            self.notify.settimeout(min(left, 0.5))
            try:
                data = self.notify.recv(4096)
            except socket.timeout:
                continue
            m = dict(line.split('=', 1) for line in data.decode().splitlines() if '=' in line)
            m['_t'], m['_rt'] = time.monotonic(), time.time()
            self.notify_msgs.append(m)
            self.step('sd_notify: %r' % data.decode())

    # ---- tear-down ----

    def stop_lssd(self, sig=signal.SIGTERM, timeout=20):
        if not self.lssd or self.lssd.poll() is not None:
            return self.lssd.returncode if self.lssd else None
        self.lssd.send_signal(sig)
        try:
            self.lssd_rc = self.lssd.wait(timeout)
        except subprocess.TimeoutExpired:
            self.lssd.kill()
            self.lssd.wait()
            raise AssertionError('lssd did not exit within %ds after %s' % (timeout, sig))
        return self.lssd_rc

    def stop(self):
        self.step('stop')
        for c in self.conns:
            c.close()
        self.conns = []
        rc = None
        try:
            if self.lssd:
                rc = self.stop_lssd()
        finally:
            for p in reversed(self.procs):
                if p.poll() is None:
                    p.send_signal(signal.SIGTERM)
                    try:
                        p.wait(10)
                    except subprocess.TimeoutExpired:
                        p.kill()
                        p.wait()
            if os.environ.get('LSSD_TEST_KEEP'):
                log('kept', self.dir)
            elif self.dir:
                if self.lssd and (rc not in (0, None)):
                    log(self.lssd_output())
                shutil.rmtree(self.dir, ignore_errors=True)
        if self.lssd and rc not in (0, None):
            raise AssertionError('lssd exited with status %s' % rc)

    # ---- helpers ----

    @staticmethod
    def read(path):
        try:
            with open(path) as f:
                return f.read()
        except OSError:
            return ''

    def lssd_output(self):
        return self.read(self.lssd_log_path)

    def connect(self):
        c = dbusmini.Connection(self.address)
        self.conns.append(c)
        return c

    def busctl(self, *args, user=None, timeout=300, json_out=True):
        cmd = ['busctl', '--system', '--timeout=%d' % timeout]
        if json_out:
            cmd.append('--json=short')
        cmd += list(args)
        if user:
            if os.geteuid() != 0:
                raise Skip('acting as another user needs root')
            cmd = ['setpriv', '--reuid=' + user, '--regid=nogroup', '--clear-groups'] + cmd
        env = dict(os.environ, DBUS_SYSTEM_BUS_ADDRESS=self.address, SYSTEMD_LOG_LEVEL='debug',
                   SYSTEMD_COLORS='0', SYSTEMD_PAGER='cat')
        t = time.monotonic()
        p = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout + 30)
        if time.monotonic() - t > 1:
            self.step('busctl %s took %.1f s' % (' '.join(args[:4]), time.monotonic() - t))
        return BusctlResult(p)

    def call(self, path, iface, method, *args, **kw):
        """busctl call; returns the data, raises AssertionError on failure."""
        r = self.busctl('call', SERVICE, path, iface, method, *[str(a) for a in args], **kw)
        assert r.rc == 0, 'busctl call %s.%s %s failed: %r' % (iface, method, args, r)
        return r.data['data'] if r.data else None

    def call_error(self, path, iface, method, *args, **kw):
        """busctl call that must fail; returns (error name, message)."""
        r = self.busctl('call', SERVICE, path, iface, method, *[str(a) for a in args], **kw)
        assert r.rc != 0, 'busctl call %s.%s %s succeeded: %r' % (iface, method, args, r)
        assert r.error_name, 'no error name in busctl output: %r' % r
        return r.error_name, r.error_message

    def get(self, path, iface, prop, **kw):
        r = self.busctl('get-property', SERVICE, path, iface, prop, **kw)
        assert r.rc == 0, 'get-property %s.%s failed: %r' % (iface, prop, r)
        return r.data['data']

    def alive(self):
        """lssd still runs and answers."""
        assert self.lssd.poll() is None, 'lssd died:\n' + self.lssd_output()
        r = self.busctl('call', SERVICE, ROOT, 'org.freedesktop.DBus.Peer', 'Ping')
        assert r.rc == 0, 'lssd does not answer Ping: %r' % r

    def frames(self, ifname):
        """(time, id, data bytes) of the frames on ifname, from candump -L."""
        out = []
        for line in self.read(self.candump_path).splitlines():
            m = re.match(r'\((\d+\.\d+)\) (\S+) ([0-9A-F]+)#([0-9A-F]*)', line)
            if m and m.group(2) == ifname:
                out.append((float(m.group(1)), int(m.group(3), 16), bytes.fromhex(m.group(4))))
        return out

    def lss_frames(self, ifname):
        return [f for f in self.frames(ifname) if f[1] in (0x7E4, 0x7E5)]

    def configure_node_ids(self, ifname, start=0):
        """configure_node_ids() of ifname's LSS frames from `start` on."""
        return configure_node_ids(self.lss_frames(ifname)[start:])

    def slave_state(self, ifname, serial):
        name = '%08x.state' % serial
        dirs = [d for k, d in self.state_dirs.items() if k == ifname or k.startswith(ifname + '+')]
        path = next((os.path.join(d, name) for d in dirs if os.path.exists(os.path.join(d, name))),
                    os.path.join(self.state_dirs[ifname], name))
        text = self.read(path)
        return dict(line.split('=', 1) for line in text.splitlines() if '=' in line and not line.startswith('#'))

    def wait_until(self, pred, timeout=10, what='condition'):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            v = pred()
            if v:
                return v
            time.sleep(0.05)
        raise AssertionError('timed out waiting for ' + what)


def run(tests):
    """main() of a test program: run.py NAME runs tests[NAME]."""
    name = sys.argv[1] if len(sys.argv) > 1 else None
    if name not in tests:
        print('usage: %s {%s}' % (sys.argv[0], ','.join(sorted(tests))))
        return 2
    try:
        tests[name]()
    except Skip as e:
        log('SKIP:', e)
        return SKIP
    log('PASS:', name)
    return 0
