#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""SetBitrate on a bus the map does not describe (issue 18): it finds its
devices as Scan does (fastscan, slowscan, SDO discovery of 1018h, LSS
confirmation). `bitrate_mixed.py NAME`, on lss-sim (vcan0) or lssd
--simulate (LSSD_TEST_BACKEND=simulate):

  mixed     configured devices of three vendors not in the map, non-configured
            ones, a CANopenNode v4 device (with a bit-rate callback)
            configured and one not: 125k -> 250k switches every one, the
            reply lists each with its outcome
  sdo-only  a device that answers SDO but not the selective switch: refused
            with NotSupported naming it, nothing changed
  global    the same bus with option global (lssctl set-bitrate --global
            where lssctl is built): all of them switched at once
  mixed-kvaser  mixed on the emulated Kvaser PCI controllers: lssd on can0,
            lss-sim on can1 of the same bus; the host interface can0 follows
            to 250k (SKIPs without can0/can1: tests/vm/run --kvaser)"""

import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bitrate import CONFIG as BUS_CONFIG, expect, expect_eq, ip_link_rate, set_link_rate  # noqa: E402
from lssdtest import BUS_IFACE, ERR, NAMES, Env, Skip, Slave, bus_path, log, run  # noqa: E402

B0 = bus_path('vcan0')
# bitrate.py's bus with a bus-level vendor/product and one device mapped
# (non-configured, found by fastscan), as on the plant of issue 18
CONFIG = BUS_CONFIG.replace('store = false;', 'store = false;\n    vendor = 0xEC;\n    product = 0x1234;') % {
    'ifname': 'vcan0', 'devices': '{ serial = 0x1276; node_id = 5; }'}
CONFIGURED = [Slave(0x1001, 1, 1, 0x11, 10), Slave(0x2002, 7, 3, 0x22, 11), Slave(0x3003, 9, 2, 0x33, 12)]
NON_CONFIGURED = [Slave(0xEC, 0x1234, 0x00010002, 0x1276), Slave(0x4004, 2, 1, 0x44)]
CANOPENNODE = [Slave(0x5005, 0x11, 1, 0x55, 42, profile='canopennode-bitrate'),
               Slave(0x5005, 0x11, 1, 0x56, profile='canopennode-bitrate')]
MIXED = CONFIGURED + NON_CONFIGURED + CANOPENNODE
# answers SDO, ignores Switch State Selective (vendor): found by SDO only
SDO_ONLY = Slave(0x6006, 1, 1, 0x66, 60, faults=['ignore-cs=0x40'], sim_profile='no-selective-switch')
INDEX = {250000: 3, 125000: 4}
GLOBAL = NAMES['LSSD_BITRATE_OPTION_GLOBAL']


def env_of(slaves):
    return Env({'vcan0': slaves}, config=CONFIG, sim_args=['--bitrate', '125000'], candump=True)


def set_bitrate(env, rate, *options):
    return env.call(B0, BUS_IFACE, 'SetBitrate', 'uqa{sv}', rate, 16, len(options) // 3, *options)[0]


def expect_switched(env, reply, slaves, rate):
    """The reply lists every slave once, switched; the bus and (lss-sim) each slave run at rate."""
    got = sorted((tuple(d[:4]), d[4]) for d in reply)
    expect_eq(got, sorted((s.identity, 'switched') for s in slaves), 'SetBitrate reply')
    expect_eq(env.get(B0, BUS_IFACE, 'Bitrate'), rate, 'Bitrate property')
    if env.real:
        for s in slaves:
            expect_eq(int(env.slave_state('vcan0', s.serial)['bit_timing_index']), INDEX[rate],
                      'bit timing index of %x' % s.serial)
    for s in slaves:
        expect('device %08x:%08x:%08x:%08x switched' % s.identity in env.lssd_output(),
               'journal line of %x' % s.serial)


def test_mixed():
    with env_of(MIXED) as env:
        expect_switched(env, set_bitrate(env, 250000), MIXED, 250000)
        env.alive()


def test_sdo_only():
    slaves = CONFIGURED[:1] + NON_CONFIGURED[:1] + [SDO_ONLY]
    with env_of(slaves) as env:
        name, msg = env.call_error(B0, BUS_IFACE, 'SetBitrate', 'uqa{sv}', 250000, 16, 0)
        expect_eq(name, ERR + 'NotSupported', 'an SDO-only device: ' + msg)
        expect('00006006:00000001:00000001:00000066 at node 60' in msg, 'the device is named: ' + msg)
        expect('selective switch' in msg and 'nothing changed' in msg and GLOBAL + '=true' in msg and
               'lssctl set-bitrate --global' in msg, msg)
        expect('not the LSS selective switch' in env.lssd_output(), 'journal line')
        expect_eq(env.get(B0, BUS_IFACE, 'Bitrate'), 125000, 'Bitrate property')
        if env.real:
            expect_eq([f for f in env.lss_frames('vcan0') if f[1] == 0x7E5 and f[2][0] in (0x13, 0x15)], [],
                      'no Configure or Activate Bit Timing on the wire')
            for s in slaves:
                expect_eq(int(env.slave_state('vcan0', s.serial)['bit_timing_index']), INDEX[125000],
                          'bit timing index of %x' % s.serial)
        env.alive()


def test_global():
    slaves = MIXED + [SDO_ONLY]
    with env_of(slaves) as env:
        expect_switched(env, set_bitrate(env, 250000, GLOBAL, 'b', 'true'), slaves, 250000)
        expect('global: ' in env.lssd_output() and 'to Configure Bit Timing' in env.lssd_output(),
               'the answers counted in the journal')
        # and back, through lssctl where it is built
        lssctl = os.environ.get('LSSCTL_BINARY')
        if lssctl:
            p = subprocess.run([lssctl, 'set-bitrate', '125k', '--bus', 'vcan0', '--delay', '16', '--global'],
                               capture_output=True, text=True,
                               env=dict(os.environ, DBUS_SYSTEM_BUS_ADDRESS=env.address))
            expect_eq(p.returncode, 0, 'lssctl set-bitrate --global: %s %s' % (p.stdout, p.stderr))
            expect_eq(env.get(B0, BUS_IFACE, 'Bitrate'), 125000, 'Bitrate property after lssctl')
        env.alive()


class KvaserEnv(Env):
    """lssd on can0; the slaves (lss-sim) on can1, the other card of the same emulated bus."""

    def _start_sim(self, ifname, slaves, key=None, args=None):
        super()._start_sim('can1', slaves, key=key or ifname, args=args)


def test_mixed_kvaser():
    for i in ('can0', 'can1'):
        if not os.path.exists('/sys/class/net/' + i):
            raise Skip('%s is not there (run through tests/vm/run --kvaser)' % i)
    if os.environ.get('LSSD_TEST_BACKEND') == 'simulate':
        raise Skip('needs the real driver')
    for i in ('can0', 'can1'):
        set_link_rate(i, 125000)
    b = bus_path('can0')
    try:
        # the emulated bus has no wire time: slaves as slow as real ones
        # (bitrate.py's kvaser backend, docs/engine.md "drain by time")
        with KvaserEnv({'can0': MIXED}, config=CONFIG.replace('"vcan0"', '"can0"'),
                       sim_args=['--bitrate', '125000', '--latency', '8'], candump=True) as env:
            reply = env.call(b, BUS_IFACE, 'SetBitrate', 'uqa{sv}', 250000, 16, 0)[0]
            got = sorted((tuple(d[:4]), d[4]) for d in reply)
            expect_eq(got, sorted((s.identity, 'switched') for s in MIXED), 'SetBitrate reply')
            expect_eq(env.get(b, BUS_IFACE, 'Bitrate'), 250000, 'Bitrate property')
            expect_eq(ip_link_rate('can0'), 250000, 'bit rate of can0 (ip -details link)')
            expect('retuned to 250000 bit/s' in env.lssd_output(), 'host retune reported done')
            for s in MIXED:
                expect_eq(int(env.slave_state('can0', s.serial)['bit_timing_index']), INDEX[250000],
                          'bit timing index of %x' % s.serial)
            env.alive()
    finally:
        for i in ('can0', 'can1'):
            set_link_rate(i, 125000)


if __name__ == '__main__':
    log('bitrate_mixed.py', ' '.join(sys.argv[1:]))
    sys.exit(run({'mixed': test_mixed, 'sdo-only': test_sdo_only, 'global': test_global,
                  'mixed-kvaser': test_mixed_kvaser}))
