#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""dfuzzer against org.lssd.LSS1: `dfuzzer.py NAME` runs one (meson test per name).

dfuzzer (https://github.com/dbus-fuzzer/dfuzzer; tests/install-deps builds
it from tests/vendor/dfuzzer) calls every method of every object with
generated arguments and reads every property. As root it gets past the
policy and drives the jobs; as nobody it meets the policy. lssd must survive,
and every call must get a reply or an error: dfuzzer fails on a crash or a
call left unanswered. Without dfuzzer the tests FAIL, never skip: a skip
would hide from CI that they did not run."""

import os
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from lssdtest import BUS_IFACE, SERVICE, Env, Skip, Slave, bus_path, log, run  # noqa: E402

B0 = bus_path('vcan0')
SLAVES = [Slave(0xEC, 0x1234, 1, 0x1276), Slave(0x9A, 3, 1, 17, 7)]


def dfuzzer_binary():
    # where tests/install-deps puts it, also when a caller's PATH lacks /usr/local/bin
    search = os.environ.get('PATH', os.defpath) + os.pathsep + '/usr/local/bin'
    path = os.environ.get('LSSD_DFUZZER') or shutil.which('dfuzzer', path=search)
    assert path and os.access(path, os.X_OK), \
        'dfuzzer not found (LSSD_DFUZZER or PATH): run tests/install-deps as root, it builds tests/vendor/dfuzzer'
    p = subprocess.run([path, '--version'], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0 and p.stdout.startswith('dfuzzer '), \
        '%s --version: exit %d, %r' % (path, p.returncode, (p.stdout + p.stderr).strip())
    log(p.stdout.strip(), 'at', path)
    return path


def fuzz(user=None):
    binary = dfuzzer_binary()
    if user and os.geteuid() != 0:
        raise Skip('acting as another user needs root')
    with Env({'vcan0': SLAVES}) as env:
        env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)  # device objects for dfuzzer to find
        # skip nothing, bounded: the Execute/Scan jobs of a VM take their time
        iterations = os.environ.get('LSSD_DFUZZER_ITERATIONS', '20')
        cmd = [binary, '-v', '-s', '-n', SERVICE, '-b', '4096', '-x', iterations]
        if user:
            cmd = ['setpriv', '--reuid=' + user, '--regid=nogroup', '--clear-groups'] + cmd
        # dfuzzer looks on the session bus first: give it none
        envv = {k: v for k, v in os.environ.items() if k != 'DBUS_SESSION_BUS_ADDRESS'}
        envv['DBUS_SYSTEM_BUS_ADDRESS'] = env.address
        envv['DBUS_SESSION_BUS_ADDRESS'] = 'unix:path=/nonexistent'
        env.step('dfuzzer as %s' % (user or 'root'))
        p = subprocess.run(cmd, env=envv, capture_output=True, text=True, timeout=1200)
        out = p.stdout + p.stderr
        lines = [line for line in out.splitlines() if line.strip().startswith(('[M]', '[P]', 'Exit'))]
        log('\n'.join(lines))
        env.step('dfuzzer exited with %d' % p.returncode)
        # dfuzzer: 0 = clean, 1 = its own error, 2 = a crash or exception found
        assert p.returncode == 0, 'dfuzzer exited with %d' % p.returncode
        for member in ('Scan', 'Execute', 'AssignNodeId', 'UnassignNodeId', 'SwitchModeSelective', 'GetBus'):
            assert any(('[M] %s' % member) in line and ('PASS' in line or 'SKIP' in line) for line in lines), \
                'dfuzzer did not test %s' % member
        env.alive()
        # and lssd still does its job
        r = env.busctl('call', SERVICE, B0, BUS_IFACE, 'Release')
        assert r.rc == 0 or user, r
        if not user:
            env.wait_until(lambda: env.get(B0, BUS_IFACE, 'State') == 'idle', timeout=60, what='bus idle')
            env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)


TESTS = {
    'dfuzzer-root': lambda: fuzz(),
    'dfuzzer-unprivileged': lambda: fuzz('nobody'),
}

if __name__ == '__main__':
    sys.exit(run(TESTS))
