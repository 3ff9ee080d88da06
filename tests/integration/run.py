#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""lssd integration tests: `run.py NAME` runs one (meson test per name).

Each test starts its own private system bus, lss-sim and lssd (lssdtest.Env)
and drives lssd with busctl as users do; dbusmini covers what busctl cannot
(holding a connection, signals while calling, many clients at once)."""

import os
import random
import signal
import subprocess
import sys
import threading
import time
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import dbusmini  # noqa: E402
from lssdtest import (ACCESS_DENIED, BUS_IFACE, DEVICE_IFACE, ERR, INVALID_ARGS, MANAGER, MANAGER_IFACE, ROOT,  # noqa: E402
                      SERVICE, SOURCE_ROOT, Env, Skip, Slave, auto_assign, bus_path, device_path, log, run)

B0 = bus_path('vcan0')
B1 = bus_path('vcan1')

# two vendors, configured and not, a serial with the top bit set and the largest one
SLAVES = [
    Slave(0xEC, 0x1234, 0x00010002, 0x00001276),
    Slave(0xEC, 0x1234, 0x00010002, 0x80002468, 6),
    Slave(0x9A, 3, 1, 17, 7),
    Slave(0x9A, 3, 1, 0xFFFFFFFF),
]

CONFIG = """
buses = (
  {
    interface = "vcan0";
    bitrate = 125000;
    vendor = 0xEC;
    product = 0x1234;
    devices = (
      { serial = 0x1276; node_id = 5; },
      { serial = 0x80002468; node_id = 6; },
      { vendor = 0x9A; product = 3; serial = 17; node_id = 7; }
    );
  }%s
);
"""

VCAN1 = """,
  { interface = "vcan1"; bitrate = 125000; }"""


def dev(ifname, s):
    return device_path(ifname, *s.identity)


def lssd_signals(c):
    c.add_match(f"type='signal',sender='{SERVICE}'")


def expect(cond, what):
    if not cond:
        raise AssertionError(what)


def expect_eq(got, want, what):
    if got != want:
        raise AssertionError('%s: got %r, want %r' % (what, got, want))


def all_waiting(env, ifname, slaves):
    for s in slaves:
        st = env.slave_state(ifname, s.serial)
        if st.get('lss_state') != 'waiting':
            return False
    return True


# ---- the API as published ----

def interface_of(xml_text, name):
    node = ET.fromstring(xml_text)
    for i in node.iter('interface'):
        if i.get('name') == name:
            return i
    raise AssertionError('interface %s not found' % name)


def describe(iface):
    """Everything the contract fixes about an interface, order-independent."""
    out = {}
    for m in iface.findall('method'):
        out['method ' + m.get('name')] = [(a.get('type'), a.get('name'), a.get('direction', 'in'))
                                          for a in m.findall('arg')]
    for s in iface.findall('signal'):
        out['signal ' + s.get('name')] = [(a.get('type'), a.get('name')) for a in s.findall('arg')]
    for p in iface.findall('property'):
        emits = 'true'
        for a in p.findall('annotation'):
            if a.get('name') == 'org.freedesktop.DBus.Property.EmitsChangedSignal':
                emits = a.get('value')
        out['property ' + p.get('name')] = (p.get('type'), p.get('access'), emits)
    return out


def test_introspection():
    with Env({'vcan0': SLAVES[:1]}) as env:
        env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)
        objects = [(MANAGER, MANAGER_IFACE), (B0, BUS_IFACE), (dev('vcan0', SLAVES[0]), DEVICE_IFACE)]
        for path, name in objects:
            r = env.busctl('introspect', '--xml-interface', SERVICE, path, json_out=False)
            expect(r.rc == 0, 'introspect %s: %r' % (path, r))
            live = describe(interface_of(r.stdout, name))
            with open(os.path.join(SOURCE_ROOT, 'dbus', name + '.xml')) as f:
                documented = describe(interface_of(f.read(), name))
            for key in sorted(set(live) | set(documented)):
                expect_eq(live.get(key), documented.get(key), '%s %s (live vs dbus/%s.xml)' % (name, key, name))
        # the object manager lists the bus and the device with their interfaces
        objs = env.call(ROOT, 'org.freedesktop.DBus.ObjectManager', 'GetManagedObjects')[0]
        expect(BUS_IFACE in objs.get(B0, {}), 'GetManagedObjects lacks the bus: %r' % objs.keys())
        expect(DEVICE_IFACE in objs.get(dev('vcan0', SLAVES[0]), {}), 'GetManagedObjects lacks the device')


def test_properties():
    with Env({'vcan0': SLAVES[1:3]}) as env:
        version = subprocess.run([os.environ.get('LSSD_BINARY', 'lssd'), '--version'], capture_output=True,
                                 text=True).stdout.split()[-1]
        expect_eq(env.get(MANAGER, MANAGER_IFACE, 'Version'), version, 'Version')
        expect_eq(env.get(MANAGER, MANAGER_IFACE, 'Buses'), [B0], 'Buses')
        expect_eq(env.call(MANAGER, MANAGER_IFACE, 'GetBus', 's', 'vcan0'), [B0], 'GetBus')
        name, _ = env.call_error(MANAGER, MANAGER_IFACE, 'GetBus', 's', 'vcan7')
        expect_eq(name, ERR + 'NotFound', 'GetBus of a bus not served')
        expect_eq(env.get(B0, BUS_IFACE, 'Interface'), 'vcan0', 'Interface')
        expect_eq(env.get(B0, BUS_IFACE, 'State'), 'idle', 'State')
        expect_eq(env.get(B0, BUS_IFACE, 'Bitrate'), 125000, 'Bitrate')
        expect_eq(env.get(B0, BUS_IFACE, 'Job'), '', 'Job')
        expect_eq(env.get(B0, BUS_IFACE, 'Progress'), 0.0, 'Progress')
        expect_eq(env.get(B0, BUS_IFACE, 'QueueLength'), 0, 'QueueLength')

        # Job, Progress and State change while a scan runs, with PropertiesChanged
        c = env.connect()
        c.add_match(f"type='signal',sender='{SERVICE}',interface='org.freedesktop.DBus.Properties'")
        c.add_match(f"type='signal',sender='{SERVICE}',interface='{BUS_IFACE}'")
        serial = c.send(SERVICE, B0, BUS_IFACE, 'Scan', 'a{sv}', [{'vendor': ('u', 0xEC), 'product': ('u', 0x1234)}])
        seen_job = c.wait_signal(lambda m: m.member == 'PropertiesChanged' and m.path == B0 and
                                 m.body[1].get('Job') == ('s', 'Scan'))
        expect(seen_job, 'no PropertiesChanged with Job "Scan"')
        c.wait_reply(serial)
        done = c.wait_signal(lambda m: m.member == 'JobFinished')
        expect(done and done.body == ['Scan', 'done'], 'JobFinished: %r' % (done and done.body))
        idle = c.wait_signal(lambda m: m.member == 'PropertiesChanged' and m.body[1].get('Job') == ('s', ''))
        expect(idle, 'no PropertiesChanged back to Job ""')
        progress = [m.body[1]['Progress'][1] for m in list(c.signals)
                    if m.member == 'PropertiesChanged' and 'Progress' in m.body[1]]
        expect(all(0 <= p <= 1 for p in progress), 'Progress out of 0..1: %r' % progress)
        expect_eq(env.get(B0, BUS_IFACE, 'State'), 'idle', 'State after the scan')


# ---- scanning ----

def test_scan():
    with Env({'vcan0': SLAVES}, config=CONFIG % '') as env:
        c = env.connect()
        lssd_signals(c)
        c.add_match(f"type='signal',sender='{SERVICE}',interface='org.freedesktop.DBus.ObjectManager'")
        found = env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)[0]
        want = sorted([list(s.identity) + [s.node_id] for s in SLAVES])
        expect_eq(sorted(found), want, 'Scan result')
        expect_eq(found, sorted(found), 'Scan result order')

        for s in SLAVES:
            path = dev('vcan0', s)
            expect(c.wait_signal(lambda m, p=path: m.member == 'InterfacesAdded' and m.body[0] == p),
                   'no InterfacesAdded for ' + path)
            expect(c.wait_signal(lambda m, p=path: m.member == 'DeviceFound' and m.body == [p]),
                   'no DeviceFound for ' + path)
            expect_eq(env.get(path, DEVICE_IFACE, 'VendorId'), s.vendor, 'VendorId')
            expect_eq(env.get(path, DEVICE_IFACE, 'ProductCode'), s.product, 'ProductCode')
            expect_eq(env.get(path, DEVICE_IFACE, 'RevisionNumber'), s.revision, 'RevisionNumber')
            expect_eq(env.get(path, DEVICE_IFACE, 'SerialNumber'), s.serial, 'SerialNumber')
            expect_eq(env.get(path, DEVICE_IFACE, 'NodeId'), s.node_id, 'NodeId of %x' % s.serial)
            expect(env.get(path, DEVICE_IFACE, 'LastSeen') > time.time() * 1e6 - 600e6, 'LastSeen')
        mapped = {0x1276: 5, 0x80002468: 6, 17: 7, 0xFFFFFFFF: 0}
        states = {0x1276: 'non-configured', 0x80002468: 'assigned', 17: 'assigned', 0xFFFFFFFF: 'non-configured'}
        for s in SLAVES:
            expect_eq(env.get(dev('vcan0', s), DEVICE_IFACE, 'MappedNodeId'), mapped[s.serial], 'MappedNodeId')
            expect_eq(env.get(dev('vcan0', s), DEVICE_IFACE, 'State'), states[s.serial], 'State %x' % s.serial)
        unknown = c.wait_signal(lambda m: m.member == 'UnknownDevice')
        expect(unknown and tuple(unknown.body) == SLAVES[3].identity, 'UnknownDevice: %r' % (unknown and unknown.body))
        expect(not c.wait_signal(lambda m: m.member == 'UnknownDevice', timeout=0.5), 'a second UnknownDevice')

        if env.real:
            # nothing changed on the slaves, and all are back in waiting
            for s in SLAVES:
                st = env.slave_state('vcan0', s.serial)
                expect_eq(st.get('lss_state'), 'waiting', 'lss_state of %x' % s.serial)
                expect_eq(int(st['active_node_id']), s.node_id, 'active node-ID of %x' % s.serial)

        # again: same answer, no new objects
        expect_eq(sorted(env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)[0]), want, 'second Scan')
        expect(not c.wait_signal(lambda m: m.member == 'InterfacesAdded', timeout=0.5), 'objects added twice')
        tree = env.busctl('tree', '--list', SERVICE, json_out=False).stdout.split()
        expect_eq(len([p for p in tree if '/devices/' in p]), len(SLAVES), 'device objects')


def test_scan_options():
    # no map, LSS only (sdo false): only non-configured slaves, unless the
    # call names a vendor/product pair; with SDO (the default) every slave
    with Env({'vcan0': SLAVES[:3]}) as env:
        slaves = SLAVES[:3]
        found = env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 1, 'sdo', 'b', 'false')[0]
        expect_eq(sorted(found), sorted([list(s.identity) + [255] for s in slaves if s.node_id == 0xFF]),
                  'Scan without map, sdo false')
        found = env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 3, 'vendor', 'u', 0x9A, 'product', 'u', 3,
                         'sdo', 'b', 'false')[0]
        want = [list(s.identity) + [s.node_id] for s in slaves if s.vendor == 0x9A or s.node_id == 0xFF]
        expect_eq(sorted(found), sorted(want), 'Scan with vendor/product 0x9A/3, sdo false')
        found = env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)[0]
        expect_eq(sorted(found), sorted(list(s.identity) + [s.node_id] for s in slaves), 'Scan without map')
        for s in slaves:
            if s.vendor == 0x9A:
                expect_eq(env.get(dev('vcan0', s), DEVICE_IFACE, 'State'), 'configured' if s.node_id != 0xFF
                          else 'non-configured', 'State of %x' % s.serial)
        if env.real:
            # the 0x9A slave is gone: a scan covering 0x9A/3 misses it
            env.restart_sim('vcan0', [x for x in slaves if x.vendor != 0x9A])
            found = env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 3, 'vendor', 'u', 0x9A, 'product', 'u', 3,
                             'sdo', 'b', 'false')[0]
            expect_eq(len(found), len([x for x in slaves if x.vendor != 0x9A and x.node_id == 0xFF]),
                      'devices after the power cycle')
            expect_eq(env.get(dev('vcan0', SLAVES[2]), DEVICE_IFACE, 'State'), 'missing', 'State of a gone slave')


def test_scan_sdo():
    """Scan with no options finds every device (issue 18): configured devices
    of three vendors the map does not name (found by SDO upload of 1018h,
    confirmed through LSS), non-configured ones (fastscan), and a CANopenNode
    v4 device configured and one not, each with its identity, node-ID and
    FoundBy; option sdo=false: only what LSS alone finds. On lss-sim also a
    device that answers SDO but not the selective switch (FoundBy sdo only)
    and one in NMT Stopped sending heartbeats (not a device: a journal line
    says how to find it)."""
    configured = [Slave(0x1001, 1, 1, 0x11, 20), Slave(0x2002, 7, 3, 0x22, 21), Slave(0x3003, 9, 2, 0x33, 127)]
    non_configured = [Slave(0xEC, 0x1234, 0x00010002, 0x1276), Slave(0x4004, 2, 1, 0x44)]
    canopennode = [Slave(0x5005, 0x11, 1, 0x55, 42, profile='canopennode'),
                   Slave(0x5005, 0x11, 1, 0x56, profile='canopennode')]
    slaves = configured + non_configured + canopennode
    real = os.environ.get('LSSD_TEST_BACKEND', 'vcan') != 'simulate'
    # lss-sim only: ignores Switch State Selective (vendor), answers SDO
    sdo_only = [Slave(0x6006, 1, 1, 0x66, 60, faults=['ignore-cs=0x40'])] if real else []
    stopped = Slave(0x7007, 1, 1, 0x77, 70)
    more = [('vcan0', [stopped], ['--nmt-state', 'stopped', '--heartbeat', '100'])] if real else []
    by = {s.serial: ['lss', 'sdo'] for s in configured + canopennode[:1]}
    by.update({s.serial: ['lss'] for s in non_configured + canopennode[1:]})
    by.update({s.serial: ['sdo'] for s in sdo_only})
    with Env({'vcan0': slaves + sdo_only}, config=CONFIG % '', more_sims=more) as env:
        c = env.connect()
        lssd_signals(c)
        # LSS alone: the non-configured ones; the configured vendors are not in the map
        found, notes = env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 1, 'sdo', 'b', 'false')
        want = sorted(list(s.identity) + [s.node_id] for s in non_configured + canopennode[1:])
        expect_eq(sorted(found), want, 'Scan with sdo=false')
        # the reply says what it did not look for
        expect(any('pairs not scanned were not looked for (option sdo = false, lssctl scan --no-sdo); scanned: 000000ec:00001234 '
                   '0000009a:00000003' in n for n in notes), 'notes of the Scan with sdo=false: %r' % notes)
        for s in non_configured + canopennode[1:]:
            expect_eq(env.get(dev('vcan0', s), DEVICE_IFACE, 'FoundBy'), ['lss'], 'FoundBy of %x' % s.serial)

        expect(c.wait_signal(lambda m: m.member == 'JobFinished'), 'no JobFinished of the first Scan')
        with c.lock:
            c.signals.clear()
        found, notes = env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)
        want = sorted(list(s.identity) + [s.node_id] for s in slaves + sdo_only)
        expect_eq(sorted(found), want, 'Scan with no options')
        expect(any('configured devices in NMT Stopped that send no heartbeat were not looked for' in n
                   for n in notes), 'notes of the Scan: %r' % notes)
        expect_eq(found, sorted(found), 'Scan result order')
        for s in slaves + sdo_only:
            path = dev('vcan0', s)
            expect_eq(env.get(path, DEVICE_IFACE, 'NodeId'), s.node_id, 'NodeId of %x' % s.serial)
            expect_eq(env.get(path, DEVICE_IFACE, 'FoundBy'), by[s.serial], 'FoundBy of %x' % s.serial)
        done = c.wait_signal(lambda m: m.member == 'JobFinished' and m.body == ['Scan', 'done'])
        expect(done, 'no JobFinished of the Scan')
        with c.lock:
            signals = list(c.signals)
        unknown = sorted(tuple(m.body) for m in signals if m.member == 'UnknownDevice')
        expect_eq(unknown, sorted(s.identity for s in slaves + sdo_only if s.serial != 0x1276),
                  'one UnknownDevice per device not in the map')
        if real:
            expect('node 70 sends heartbeats in NMT Stopped' in env.lssd_output(),
                   'no journal line about the stopped node 70')
            expect(any(n.startswith('node 70 sends heartbeats in NMT Stopped') for n in notes),
                   'no note about the stopped node 70: %r' % notes)
            expect(any(n.startswith('node 60: 00006006:00000001:00000001:00000066 answered SDO (1018h) but not '
                                    'the LSS selective switch') for n in notes),
                   'no note about the SDO-only node 60: %r' % notes)
            # nothing changed on the slaves, all in waiting
            for s in slaves + sdo_only:
                st = env.slave_state('vcan0', s.serial)
                expect_eq((st.get('lss_state'), int(st['active_node_id'])), ('waiting', s.node_id),
                          'state of %x' % s.serial)


# ---- assigning ----

def test_assign():
    slaves = SLAVES + ([Slave(0xEC, 0x1234, 0x00010002, 0x4242, faults=['configure-error-specific'])]
                       if os.environ.get('LSSD_TEST_BACKEND', 'vcan') != 'simulate' else [])
    with Env({'vcan0': slaves}, config=CONFIG % '', candump=True) as env:
        c = env.connect()
        lssd_signals(c)
        env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)
        s = SLAVES[0]
        path = dev('vcan0', s)

        env.call(B0, BUS_IFACE, 'AssignNodeId', 'uuuuya{sv}', *s.identity, 5, 0)
        sig = c.wait_signal(lambda m: m.member == 'NodeIdAssigned')
        expect(sig and sig.body == [path, 255, 5], 'NodeIdAssigned: %r' % (sig and sig.body))
        expect_eq(env.get(path, DEVICE_IFACE, 'NodeId'), 5, 'NodeId after assignment')
        expect_eq(env.get(path, DEVICE_IFACE, 'State'), 'assigned', 'State after assignment')
        if env.real:
            st = env.slave_state('vcan0', s.serial)
            expect_eq((st['active_node_id'], st['stored_node_id'], st['lss_state']), ('5', '5', 'waiting'),
                      'slave after assignment')

        # idempotent: nothing is configured the second time
        if env.real:
            before = len(env.lss_frames('vcan0'))
        env.call(B0, BUS_IFACE, 'AssignNodeId', 'uuuuya{sv}', *s.identity, 5, 0)
        expect(not c.wait_signal(lambda m: m.member == 'NodeIdAssigned', timeout=0.5), 'NodeIdAssigned again')
        if env.real:
            time.sleep(0.2)
            sent = [f[2][0] for f in env.lss_frames('vcan0')[before:] if f[1] == 0x7E5]
            expect(0x11 not in sent and 0x17 not in sent, 'configured again: %r' % sent)

        # the Device variant, without store: the stored node-ID stays
        s2 = SLAVES[1]
        env.call(dev('vcan0', s2), DEVICE_IFACE, 'AssignNodeId', 'ya{sv}', 9, 1, 'store', 'b', 'false')
        expect_eq(env.get(dev('vcan0', s2), DEVICE_IFACE, 'NodeId'), 9, 'NodeId (Device.AssignNodeId)')
        expect_eq(env.get(dev('vcan0', s2), DEVICE_IFACE, 'State'), 'mismatch', 'State: map says 6')
        if env.real:
            st = env.slave_state('vcan0', s2.serial)
            expect_eq((st['active_node_id'], st['stored_node_id']), ('9', '6'), 'store=false')

        # a node-ID another device has
        name, msg = env.call_error(B0, BUS_IFACE, 'AssignNodeId', 'uuuuya{sv}', *SLAVES[3].identity, 7, 0)
        expect_eq(name, ERR + 'Conflict', 'assigning node 7 twice')
        # nobody with that identity
        name, msg = env.call_error(B0, BUS_IFACE, 'AssignNodeId', 'uuuuya{sv}', 1, 2, 3, 4, 40, 0)
        expect_eq(name, ERR + 'NotFound', 'assigning to an absent identity')
        # the slave refuses: its codes are in the message
        if env.real:
            bad = slaves[-1]
            name, msg = env.call_error(B0, BUS_IFACE, 'AssignNodeId', 'uuuuya{sv}', *bad.identity, 41, 0)
            expect_eq(name, ERR + 'Rejected', 'refused Configure Node-ID')
            expect('error 255 (manufacturer-specific), spec 66' in msg, 'Rejected message: ' + msg)
            expect(all_waiting(env, 'vcan0', slaves), 'slaves left in configuration')
        env.alive()


def test_unassign():
    """UnassignNodeId: 255 configured and stored; CiA 305 keeps the old
    node-ID until a reset, and the reply says which it is."""
    with Env({'vcan0': SLAVES}, config=CONFIG % '', candump=True) as env:
        c = env.connect()
        lssd_signals(c)
        s = SLAVES[1]  # node 6, the map says 6 (no scan needed: the device answers, lssd knows it then)
        path = dev('vcan0', s)

        # without the reset: pending, and the warning says so
        old, stored, in_effect, msg, warning = env.call(B0, BUS_IFACE, 'UnassignNodeId', 'uuuua{sv}',
                                                        *s.identity, 0)
        expect_eq((old, stored, in_effect), (6, True, False), 'UnassignNodeId without reset')
        expect('pending' in msg, 'message: ' + msg)
        expect('keeps node-ID 6 until it is reset or power-cycled' in warning, 'warning: ' + warning)
        expect('the map gives this device node-ID 6' in warning, 'warning (map): ' + warning)
        expect_eq(env.get(path, DEVICE_IFACE, 'NodeId'), 6, 'NodeId until the reset')
        expect(not c.wait_signal(lambda m: m.member == 'NodeIdAssigned', timeout=0.3), 'NodeIdAssigned too early')
        if env.real:
            st = env.slave_state('vcan0', s.serial)
            expect_eq((st['active_node_id'], st['pending_node_id'], st['stored_node_id'], st['lss_state']),
                      ('6', '255', '255', 'waiting'), 'slave without reset')

        # with the reset: in effect, verified
        old, stored, in_effect, msg, warning = env.call(B0, BUS_IFACE, 'UnassignNodeId', 'uuuua{sv}',
                                                        *s.identity, 1, 'reset', 'b', True)
        expect_eq((old, stored, in_effect), (6, True, True), 'UnassignNodeId with reset')
        expect('runs non-configured now' in msg, 'message: ' + msg)
        expect('until it is reset' not in warning, 'warning after the reset: ' + warning)
        sig = c.wait_signal(lambda m: m.member == 'NodeIdAssigned')
        expect(sig and sig.body == [path, 6, 255], 'NodeIdAssigned: %r' % (sig and sig.body))
        expect_eq(env.get(path, DEVICE_IFACE, 'NodeId'), 255, 'NodeId after the reset')
        expect_eq(env.get(path, DEVICE_IFACE, 'State'), 'non-configured', 'State after the reset')
        if env.real:
            st = env.slave_state('vcan0', s.serial)
            expect_eq((st['active_node_id'], st['stored_node_id'], st['lss_state']), ('255', '255', 'waiting'),
                      'slave after the reset')
            nmt = [f for f in env.frames('vcan0') if f[1] == 0]
            expect([0x82, 6] in [list(f[2]) for f in nmt], 'NMT Reset Communication of node 6: %r' % nmt)

        # again: non-configured already, in effect, no reset needed
        old, stored, in_effect, msg, warning = env.call(B0, BUS_IFACE, 'UnassignNodeId', 'uuuua{sv}',
                                                        *s.identity, 1, 'reset', 'b', True)
        expect_eq((old, stored, in_effect), (255, True, True), 'UnassignNodeId of a non-configured device')
        expect('already' in msg, 'message: ' + msg)

        # not stored: in effect now, the old node-ID back at the next power cycle
        s2 = SLAVES[2]  # node 7
        old, stored, in_effect, msg, warning = env.call(B0, BUS_IFACE, 'UnassignNodeId', 'uuuua{sv}',
                                                        *s2.identity, 2, 'reset', 'b', True, 'store', 'b', False)
        expect_eq((old, stored, in_effect), (7, False, True), 'UnassignNodeId store=false')
        expect('node-ID 7 comes back at the next power cycle' in warning, 'warning: ' + warning)
        if env.real:
            st = env.slave_state('vcan0', s2.serial)
            expect_eq((st['active_node_id'], st['stored_node_id']), ('255', '7'), 'slave store=false')

        # nobody with that identity: a named error, nothing changed
        name, msg = env.call_error(B0, BUS_IFACE, 'UnassignNodeId', 'uuuua{sv}', 1, 2, 3, 4, 0)
        expect_eq(name, ERR + 'NotFound', 'unassigning an absent identity')
        expect('00000001:00000002:00000003:00000004' in msg, 'NotFound message: ' + msg)
        name, msg = env.call_error(B0, BUS_IFACE, 'UnassignNodeId', 'uuuua{sv}', *s.identity, 1,
                                   'reset', 's', 'yes')
        expect_eq(name, INVALID_ARGS, 'reset as a string')
        expect("'reset'" in msg, 'InvalidArgs message: ' + msg)
        if env.real:
            expect(all_waiting(env, 'vcan0', SLAVES), 'slaves left in configuration')
        env.alive()


def test_autoassign():
    with Env({'vcan0': SLAVES}, config=CONFIG % '') as env:
        c = env.connect()
        lssd_signals(c)
        s = SLAVES[0]
        path = dev('vcan0', s)
        got, outcomes, result = auto_assign(env)
        expect_eq(got, [list(s.identity) + [255, 5]], 'AutoAssign reply')
        # every device the pass dealt with, and whether the bus matches the map
        expect_eq(outcomes, {0x1276: ('assigned', 255, 5, ''), 0x80002468: ('unchanged', 6, 6, ''),
                             17: ('unchanged', 7, 7, ''), 0xFFFFFFFF: ('unknown', 255, 255, '')}, 'AutoAssign outcomes')
        expect_eq(result, 'done', 'AutoAssign result')
        sig = c.wait_signal(lambda m: m.member == 'NodeIdAssigned')
        expect(sig and sig.body == [path, 255, 5], 'NodeIdAssigned: %r' % (sig and sig.body))
        unknown = c.wait_signal(lambda m: m.member == 'UnknownDevice')
        expect(unknown and tuple(unknown.body) == SLAVES[3].identity, 'UnknownDevice: %r' % (unknown and unknown.body))
        fin = c.wait_signal(lambda m: m.member == 'JobFinished')
        expect(fin and fin.body == ['AutoAssign', 'done'], 'JobFinished: %r' % (fin and fin.body))
        nodes = {0x1276: 5, 0x80002468: 6, 17: 7, 0xFFFFFFFF: 255}
        states = {0x1276: 'assigned', 0x80002468: 'assigned', 17: 'assigned', 0xFFFFFFFF: 'non-configured'}
        mapped = {0x1276: 5, 0x80002468: 6, 17: 7, 0xFFFFFFFF: 0}
        for x in SLAVES:
            p = dev('vcan0', x)
            expect_eq(env.get(p, DEVICE_IFACE, 'NodeId'), nodes[x.serial], 'NodeId of %x' % x.serial)
            expect_eq(env.get(p, DEVICE_IFACE, 'MappedNodeId'), mapped[x.serial], 'MappedNodeId of %x' % x.serial)
            expect_eq(env.get(p, DEVICE_IFACE, 'State'), states[x.serial], 'State of %x' % x.serial)
        if env.real:
            st = env.slave_state('vcan0', s.serial)
            expect_eq((st['active_node_id'], st['stored_node_id']), ('5', '5'), 'slave after AutoAssign')
            expect(all_waiting(env, 'vcan0', SLAVES), 'slaves left in configuration')

        # idempotent: the second pass changes nothing, with or without the overrides
        expect_eq(auto_assign(env)[0], [], 'second AutoAssign')
        expect_eq(auto_assign(env, options=(2, 'store', 'b', 'false', 'nmt_stop', 'b', 'true'))[0],
                  [], 'AutoAssign with options')
        expect(not c.wait_signal(lambda m: m.member == 'NodeIdAssigned', timeout=0.5), 'NodeIdAssigned again')
        expect_eq(env.get(path, DEVICE_IFACE, 'NodeId'), 5, 'NodeId after the second pass')
        env.alive()


def test_autoassign_pool():
    # unknown devices get node-IDs from the pool; a mapped one that is absent is missing
    slaves = [SLAVES[0], SLAVES[3]]
    pool = CONFIG.replace('product = 0x1234;', 'product = 0x1234;\n    unknown = "pool";\n    pool = [100, 101];')
    with Env({'vcan0': slaves}, config=pool % '') as env:
        got, outcomes, result = auto_assign(env)
        expect_eq(sorted(got), sorted([list(SLAVES[0].identity) + [255, 5], list(SLAVES[3].identity) + [255, 100]]),
                  'AutoAssign reply with a pool')
        # the mapped 0x9A/3/17 is not there: the reply says so, not only the journal
        expect_eq(outcomes.get(17), ('missing', 0, 0, outcomes.get(17, ('',) * 4)[3]), 'outcome of the absent slave')
        expect_eq(result, 'partial', 'AutoAssign result with a mapped device missing')
        expect_eq(env.get(dev('vcan0', SLAVES[3]), DEVICE_IFACE, 'NodeId'), 100, 'NodeId from the pool')
        # the journal's and AutoAssign's word for it, and lssctl list's too
        expect_eq(env.get(dev('vcan0', SLAVES[3]), DEVICE_IFACE, 'State'), 'pool', 'State of a pool device')
        # never seen, and the map has no revision: the object has the map's identity
        absent = device_path('vcan0', 0x9A, 3, 0, 17)
        expect_eq(env.get(absent, DEVICE_IFACE, 'State'), 'missing', 'State of an absent slave')
        expect_eq(env.get(absent, DEVICE_IFACE, 'MappedNodeId'), 7, 'MappedNodeId of an absent slave')
        # ... whose revision 0 means nothing: RevisionKnown says so (issue 21)
        expect_eq(env.get(absent, DEVICE_IFACE, 'RevisionKnown'), False, 'RevisionKnown of an absent slave')
        expect_eq(env.get(dev('vcan0', SLAVES[0]), DEVICE_IFACE, 'RevisionKnown'), True, 'RevisionKnown of a found one')
        expect_eq(env.get(dev('vcan0', SLAVES[0]), DEVICE_IFACE, 'State'), 'assigned', 'State after the pass')
        env.alive()


def test_autoassign_boot():
    # auto_assign = true: the pass runs at start, before any call
    boot = CONFIG.replace('product = 0x1234;', 'product = 0x1234;\n    auto_assign = true;')
    with Env({'vcan0': SLAVES}, config=boot % '') as env:
        path = dev('vcan0', SLAVES[0])
        env.wait_until(lambda: env.busctl('get-property', SERVICE, path, DEVICE_IFACE, 'NodeId').rc == 0 and
                       env.get(path, DEVICE_IFACE, 'NodeId') == 5, timeout=600,
                       what='NodeId 5 from the boot pass')
        expect_eq(env.get(path, DEVICE_IFACE, 'State'), 'assigned', 'State after the boot pass')
        expect_eq(auto_assign(env)[0], [], 'AutoAssign after the boot pass')
        env.alive()


# ---- raw services while holding the bus ----

def test_raw():
    with Env({'vcan0': SLAVES}) as env:
        holder = env.connect()
        lssd_signals(holder)

        def h(method, sig='', *args):
            return holder.call(SERVICE, B0, BUS_IFACE, method, sig, list(args), timeout=60)

        def h_err(method, sig='', *args):
            try:
                h(method, sig, *args)
            except dbusmini.DBusError as e:
                return e.name, e.message
            raise AssertionError(method + ' succeeded')

        # not without Acquire
        expect_eq(h_err('SwitchModeGlobal', 'y', 1)[0], ERR + 'NotHeld', 'raw service without Acquire')
        h('Acquire')
        h('Acquire')  # again: nothing happens
        expect_eq(env.get(B0, BUS_IFACE, 'State'), 'busy', 'State while held')

        # everybody else: Busy
        for args in (('Acquire',), ('Release',), ('Scan', 'a{sv}', 0), ('SwitchModeGlobal', 'y', 0),
                     ('Execute', 'a(sv)', 1, 'InquireNodeId', 'b', 1),
                     ('AssignNodeId', 'uuuuya{sv}', 1, 2, 3, 4, 5, 0)):
            name, _ = env.call_error(B0, BUS_IFACE, *args)
            expect_eq(name, ERR + 'Busy', '%s while held by another' % args[0])

        s = SLAVES[0]
        expect_eq(h('SwitchModeSelective', 'uuuu', *s.identity), [True], 'SwitchModeSelective')
        expect_eq(h('InquireNodeId'), [255], 'InquireNodeId')
        expect_eq(h('InquireIdentity'), [s.identity], 'InquireIdentity')
        expect_eq(h_err('ConfigureNodeId', 'y', 0)[0], INVALID_ARGS, 'ConfigureNodeId 0')
        h('ConfigureNodeId', 'y', 20)
        h('StoreConfiguration')
        h('ConfigureBitTiming', 'yy', 0, 4)
        expect_eq(h_err('ConfigureBitTiming', 'yy', 0, 10)[0], INVALID_ARGS, 'ConfigureBitTiming 0/10')
        h('ActivateBitTiming', 'q', 20)  # same rate again: harmless
        # the slaves are off the bus for 2 x the delay: a switch sent in that
        # window is lost (and the selected slave stays in configuration)
        time.sleep(0.1)
        h('SwitchModeGlobal', 'y', 0)
        expect_eq(h('SwitchModeSelective', 'uuuu', 1, 2, 3, 4), [False], 'SwitchModeSelective of nobody')
        expect_eq(h('IdentifyNonConfigured'), [True], 'IdentifyNonConfigured')
        expect_eq(h('IdentifyRemoteSlaves', 'uuuuuu', 0x9A, 3, 0, 0xFFFFFFFF, 0, 0xFFFFFFFF), [True],
                  'IdentifyRemoteSlaves 0x9A/3')
        expect_eq(h('IdentifyRemoteSlaves', 'uuuuuu', 0x77, 3, 0, 0xFFFFFFFF, 0, 0xFFFFFFFF), [False],
                  'IdentifyRemoteSlaves of nobody')
        expect_eq(h('Fastscan', 'a{sv}', {'vendor': ('u', 0x9A)}), [SLAVES[3].identity], 'Fastscan')
        expect_eq(h('InquireNodeId'), [255], 'InquireNodeId after Fastscan')
        h('SwitchModeGlobal', 'y', 0)
        # the one that got node 20 answers as node 20 now
        expect_eq(h('SwitchModeSelective', 'uuuu', *s.identity), [True], 'SwitchModeSelective again')
        expect_eq(h('InquireNodeId'), [20], 'InquireNodeId after configuring')
        h('Release')
        expect_eq(env.get(B0, BUS_IFACE, 'State'), 'idle', 'State after Release')
        if env.real:
            env.wait_until(lambda: all_waiting(env, 'vcan0', SLAVES), what='all slaves waiting after Release')
            expect_eq(env.slave_state('vcan0', s.serial)['stored_node_id'], '20', 'stored node-ID')
        expect_eq(h_err('InquireNodeId')[0], ERR + 'NotHeld', 'raw service after Release')
        h('Release')  # not held: nothing happens


def test_holder_killed():
    with Env({'vcan0': SLAVES}) as env:
        script = ("import sys,time; sys.path.insert(0, %r); import dbusmini as d; c=d.Connection(); "
                  "c.call(%r,%r,%r,'Acquire'); c.call(%r,%r,%r,'SwitchModeGlobal','y',[1]); "
                  "print('held', flush=True); time.sleep(600)"
                  % (os.path.dirname(os.path.abspath(__file__)), SERVICE, B0, BUS_IFACE, SERVICE, B0, BUS_IFACE))
        p = subprocess.Popen([sys.executable, '-c', script], stdout=subprocess.PIPE, text=True,
                             env=dict(os.environ, DBUS_SYSTEM_BUS_ADDRESS=env.address))
        try:
            expect_eq(p.stdout.readline().strip(), 'held', 'holder started')
            expect_eq(env.get(B0, BUS_IFACE, 'State'), 'busy', 'State while held')
            if env.real:
                expect(all(env.slave_state('vcan0', s.serial)['lss_state'] == 'configuration' for s in SLAVES),
                       'slaves in configuration')
            name, _ = env.call_error(B0, BUS_IFACE, 'Acquire')
            expect_eq(name, ERR + 'Busy', 'second Acquire while held')
        finally:
            p.kill()
            p.wait()
        env.wait_until(lambda: env.get(B0, BUS_IFACE, 'State') == 'idle', what='bus released')
        if env.real:
            env.wait_until(lambda: all_waiting(env, 'vcan0', SLAVES), what='slaves back in waiting')
        # busctl's connection ends right after the call: the bus is released again at once
        env.call(B0, BUS_IFACE, 'Acquire')
        env.wait_until(lambda: env.get(B0, BUS_IFACE, 'State') == 'idle', what='busctl holder released')
        env.alive()


# ---- Execute ----

def test_execute():
    slaves = SLAVES + ([Slave(0xEC, 0x1234, 0x00010002, 0x4242, faults=['configure-error-specific'])]
                       if os.environ.get('LSSD_TEST_BACKEND', 'vcan') != 'simulate' else [])
    with Env({'vcan0': slaves}, candump=True) as env:
        s = SLAVES[1]
        r = env.call(B0, BUS_IFACE, 'Execute', 'a(sv)', 4, 'SwitchModeSelective', '(uuuu)', *s.identity,
                     'ConfigureNodeId', 'y', 30, 'StoreConfiguration', 'b', 'true', 'InquireNodeId', 'b', 'true')
        expect_eq(r, [[{'type': 'b', 'data': True}, {'type': 'b', 'data': True}, {'type': 'b', 'data': True},
                       {'type': 'y', 'data': 6}]], 'Execute results')
        if env.real:
            time.sleep(0.1)
            st = env.slave_state('vcan0', s.serial)
            expect_eq((st['stored_node_id'], st['lss_state']), ('30', 'waiting'), 'after Execute')
            last = [f for f in env.lss_frames('vcan0') if f[1] == 0x7E5][-1]
            expect_eq(last[2][:2], b'\x04\x00', 'Execute ends with switch-global waiting')

        # stops at the first failure, names the step, still ends in waiting
        name, msg = env.call_error(B0, BUS_IFACE, 'Execute', 'a(sv)', 3, 'SwitchModeGlobal', 'y', 0,
                                   'InquireNodeId', 'b', 'true', 'StoreConfiguration', 'b', 'true')
        expect_eq(name, ERR + 'NoResponse', 'Execute with nobody in configuration')
        expect(msg.startswith('steps[1] (InquireNodeId): '), 'message names the step: ' + msg)
        if env.real:
            bad = slaves[-1]
            name, msg = env.call_error(B0, BUS_IFACE, 'Execute', 'a(sv)', 2, 'SwitchModeSelective', '(uuuu)',
                                       *bad.identity, 'ConfigureNodeId', 'y', 44)
            expect_eq(name, ERR + 'Rejected', 'refused Configure Node-ID')
            expect_eq(msg, 'steps[1] (ConfigureNodeId): Configure Node-ID rejected by the slave: '
                           'error 255 (manufacturer-specific), spec 66', 'Rejected message')
            time.sleep(0.1)
            expect(all_waiting(env, 'vcan0', slaves), 'slaves waiting after a failed Execute')
        expect_eq(env.call(B0, BUS_IFACE, 'Execute', 'a(sv)', 0), [[]], 'empty Execute')


# ---- bad input ----

def test_bad_arguments():
    with Env({'vcan0': SLAVES[:2]}) as env:
        env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 2, 'vendor', 'u', 0xEC, 'product', 'u', 0x1234)
        d = dev('vcan0', SLAVES[0])
        cases = [
            (B0, BUS_IFACE, 'Scan', ('a{sv}', 1, 'foo', 'u', 1), INVALID_ARGS, "Unknown option 'foo'"),
            (B0, BUS_IFACE, 'Scan', ('a{sv}', 2, 'vendor', 's', 'x', 'product', 'u', 1), INVALID_ARGS, "'vendor'"),
            (B0, BUS_IFACE, 'Scan', ('a{sv}', 1, 'vendor', 'u', 1), INVALID_ARGS, "'vendor' and 'product'"),
            (B0, BUS_IFACE, 'AssignNodeId', ('uuuuya{sv}', 1, 2, 3, 4, 0, 0), INVALID_ARGS, 'node_id 0'),
            (B0, BUS_IFACE, 'AssignNodeId', ('uuuuya{sv}', 1, 2, 3, 4, 128, 0), INVALID_ARGS, 'node_id 128'),
            (B0, BUS_IFACE, 'AssignNodeId', ('uuuuya{sv}', 1, 2, 3, 4, 255, 0), INVALID_ARGS, 'node_id 255'),
            (B0, BUS_IFACE, 'AssignNodeId', ('uuuuya{sv}', 1, 2, 3, 4, 5, 1, 'store', 's', 'yes'), INVALID_ARGS,
             "'store'"),
            (B0, BUS_IFACE, 'UnassignNodeId', ('uuuua{sv}', 1, 2, 3, 4, 1, 'verify', 'b', 'true'), INVALID_ARGS,
             "Unknown option 'verify'"),
            (d, DEVICE_IFACE, 'AssignNodeId', ('ya{sv}', 0, 0), INVALID_ARGS, 'node_id 0'),
            (d, DEVICE_IFACE, 'AssignNodeId', ('ya{sv}', 5, 1, 'force', 's', 'yes'), INVALID_ARGS, "'force'"),
            (d, DEVICE_IFACE, 'AssignNodeId', ('ya{sv}', 5, 1, 'forced', 'b', 'true'), INVALID_ARGS, "'forced'"),
            (B0, BUS_IFACE, 'Execute', ('a(sv)', 1, 'ConfigureNodeId', '(yy)', 5, 1), INVALID_ARGS, "or '(yb)'"),
            (B0, BUS_IFACE, 'Execute', ('a(sv)', 1, 'ConfigureNodeId', '(yb)', 0, 1), INVALID_ARGS,
             'steps[0] (ConfigureNodeId): Invalid node_id 0'),
            (B0, BUS_IFACE, 'SetBitrate', ('uqa{sv}', 12345, 10, 0), INVALID_ARGS, 'bitrate 12345'),
            (B0, BUS_IFACE, 'SetBitrate', ('uqa{sv}', 250000, 10, 0), ERR + 'NotSupported', ''),
            (B0, BUS_IFACE, 'AutoAssign', ('a{sv}', 1, 'x', 'b', 'true'), INVALID_ARGS, "'x'"),
            (B0, BUS_IFACE, 'AutoAssign', ('a{sv}', 1, 'store', 's', 'yes'), INVALID_ARGS, "'store'"),
            (B0, BUS_IFACE, 'Execute', ('a(sv)', 1, 'Reboot', 'b', 'true'), INVALID_ARGS, "'Reboot'"),
            (B0, BUS_IFACE, 'Execute', ('a(sv)', 1, 'ConfigureNodeId', 'y', 0), INVALID_ARGS, 'node_id 0'),
            (B0, BUS_IFACE, 'Execute', ('a(sv)', 1, 'ConfigureNodeId', 'u', 5), INVALID_ARGS, "'y' or '(yb)' (node-ID, force), not 'u'"),
            (B0, BUS_IFACE, 'Execute', ('a(sv)', 1, 'ConfigureBitTiming', '(yy)', 0, 10), INVALID_ARGS, 'index 10'),
            (B0, BUS_IFACE, 'Execute', ('a(sv)', 1, 'ConfigureBitTiming', '(yy)', 1, 0), INVALID_ARGS, 'table 1'),
            (B0, BUS_IFACE, 'Execute', ('a(sv)', 1, 'SwitchModeGlobal', 'y', 2), INVALID_ARGS, 'mode 2'),
            (B0, BUS_IFACE, 'Execute', ('a(sv)', 1, 'IdentifyRemoteSlaves', '(uuuuuu)', 1, 2, 5, 4, 0, 0),
             INVALID_ARGS, 'rev_lo'),
            (B0, BUS_IFACE, 'Execute', ('a(sv)', 65) + ('InquireNodeId', 'b', 'true') * 65,
             ERR + 'LimitsExceeded', 'at most 64'),
            (B0, BUS_IFACE, 'SwitchModeGlobal', ('y', 1), ERR + 'NotHeld', 'Acquire'),
            (B0, BUS_IFACE, 'ConfigureNodeId', ('s', 'x'), INVALID_ARGS, ''),
            (B0, BUS_IFACE, 'NoSuchMethod', (), 'org.freedesktop.DBus.Error.UnknownMethod', ''),
            (MANAGER, MANAGER_IFACE, 'GetBus', ('s', ''), INVALID_ARGS, 'interface'),
            (MANAGER, MANAGER_IFACE, 'GetBus', ('s', 'a/b'), INVALID_ARGS, 'a/b'),
            (MANAGER, MANAGER_IFACE, 'GetBus', ('s', 'x' * 300), INVALID_ARGS, '...'),
        ]
        for path, iface, method, args, want, text in cases:
            name, msg = env.call_error(path, iface, method, *args)
            expect_eq(name, want, '%s%s' % (method, args[:4]))
            expect(text in msg, '%s%s: %r lacks %r' % (method, args[:4], msg, text))
            env.alive()

        # garbage of every shape through the wire: the daemon stays up
        c = env.connect()
        rnd = random.Random(4)
        methods = ['Scan', 'AssignNodeId', 'Execute', 'Fastscan', 'SetBitrate', 'ConfigureNodeId', 'Acquire',
                   'GetBus', 'Release', 'Cancel', 'X']
        sigs = [('', []), ('y', [255]), ('s', ['\x01' * 40]), ('a{sv}', [{'vendor': ('as', ['x'] * 50)}]),
                ('a(sv)', [[('InquireNodeId', ('b', True))] * 64]),
                ('a(sv)', [[('SwitchModeSelective', ('(uuu)', (1, 2, 3)))]]),
                ('a(sv)', [[('StoreConfiguration', ('a{sv}', {'x': ('v', ('s', 'deep'))}))]]),
                ('uuuuya{sv}', [1, 2, 3, 4, 5, {'store': ('b', True), 'verify': ('y', 1)}]),
                ('a{sv}', [{'': ('u', 0)}]), ('ay', [list(range(256))])]
        for i in range(300):
            path = rnd.choice([B0, MANAGER, d, ROOT + '/buses/nope'])
            iface = rnd.choice([BUS_IFACE, MANAGER_IFACE, DEVICE_IFACE])
            sig, body = rnd.choice(sigs)
            try:
                c.call(SERVICE, path, iface, rnd.choice(methods), sig, body, timeout=60)
            except dbusmini.DBusError:
                pass
            # leave the bus free for the next ones
            try:
                c.call(SERVICE, B0, BUS_IFACE, 'Release', '', [], timeout=60)
            except dbusmini.DBusError:
                pass
        env.alive()
        expect_eq(env.get(B0, BUS_IFACE, 'QueueLength'), 0, 'QueueLength after the garbage')


# ---- privilege ----

MUTATING = [
    (B0, BUS_IFACE, 'Scan', ('a{sv}', 0)),
    (B0, BUS_IFACE, 'AutoAssign', ('a{sv}', 0)),
    (B0, BUS_IFACE, 'AssignNodeId', ('uuuuya{sv}', 0xEC, 0x1234, 0x10002, 0x1276, 5, 0)),
    (B0, BUS_IFACE, 'UnassignNodeId', ('uuuua{sv}', 0xEC, 0x1234, 0x10002, 0x1276, 0)),
    (B0, BUS_IFACE, 'SetBitrate', ('uqa{sv}', 250000, 10, 0)),
    (B0, BUS_IFACE, 'Acquire', ()),
    (B0, BUS_IFACE, 'SwitchModeGlobal', ('y', 1)),
    (B0, BUS_IFACE, 'SwitchModeSelective', ('uuuu', 1, 2, 3, 4)),
    (B0, BUS_IFACE, 'ConfigureNodeId', ('y', 5)),
    (B0, BUS_IFACE, 'StoreConfiguration', ()),
    (B0, BUS_IFACE, 'Fastscan', ('a{sv}', 0)),
    (B0, BUS_IFACE, 'Execute', ('a(sv)', 1, 'SwitchModeGlobal', 'y', 0)),
    (MANAGER, MANAGER_IFACE, 'ReloadConfig', ()),
]


def test_unprivileged():
    with Env({'vcan0': SLAVES[:1]}) as env:
        env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)
        d = dev('vcan0', SLAVES[0])
        nobody = {'user': 'nobody'}
        # reading is for everyone
        expect_eq(env.get(B0, BUS_IFACE, 'State', **nobody), 'idle', 'State as nobody')
        expect_eq(env.get(d, DEVICE_IFACE, 'NodeId', **nobody), 255, 'NodeId as nobody')
        expect_eq(env.get(MANAGER, MANAGER_IFACE, 'Buses', **nobody), [B0], 'Buses as nobody')
        expect_eq(env.call(MANAGER, MANAGER_IFACE, 'GetBus', 's', 'vcan0', **nobody), [B0], 'GetBus as nobody')
        r = env.busctl('introspect', '--xml-interface', SERVICE, B0, json_out=False, **nobody)
        expect(r.rc == 0 and BUS_IFACE in r.stdout, 'introspect as nobody: %r' % r)
        objs = env.call(ROOT, 'org.freedesktop.DBus.ObjectManager', 'GetManagedObjects', **nobody)[0]
        expect(d in objs, 'GetManagedObjects as nobody')
        # changing is not: the policy lets the calls through and lssd refuses them (no polkit on this bus:
        # root and group lssd only)
        for path, iface, method, args in MUTATING + [(d, DEVICE_IFACE, 'AssignNodeId', ('ya{sv}', 5, 0))]:
            name, _ = env.call_error(path, iface, method, *args, **nobody)
            expect_eq(name, ACCESS_DENIED, '%s as nobody' % method)
        # what does nothing is answered before anyone is asked: no job to cancel, no holder to release
        env.call(B0, BUS_IFACE, 'Cancel', **nobody)
        env.call(B0, BUS_IFACE, 'Release', **nobody)
        env.alive()
        expect_eq(env.get(B0, BUS_IFACE, 'State'), 'idle', 'nothing happened')


def test_daemon_checks_credentials():
    # the bus policy opened wide: lssd refuses on its own
    with Env({'vcan0': SLAVES[:1]}, lssd_policy_override=True) as env:
        nobody = {'user': 'nobody'}
        for path, iface, method, args in MUTATING:
            name, msg = env.call_error(path, iface, method, *args, **nobody)
            expect_eq(name, ACCESS_DENIED, '%s as nobody, policy open' % method)
            expect("group 'lssd'" in msg, 'lssd refused it itself: ' + msg)
        expect_eq(env.call(MANAGER, MANAGER_IFACE, 'GetBus', 's', 'vcan0', **nobody), [B0], 'GetBus as nobody')
        expect_eq(env.get(B0, BUS_IFACE, 'State'), 'idle', 'nothing happened')
        env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)  # root still may


# ---- load ----

def test_concurrent_clients():
    clients, calls = 100, 10
    slaves = [Slave(0x9A, 3, 1, 100 + i, 10 + i) for i in range(4)]
    with Env({'vcan0': slaves}, candump=True) as env:
        failures, timing = [], []
        answered = [0]
        lock = threading.Lock()

        def client(k):
            try:
                c = dbusmini.Connection(env.address)
            except Exception as e:  # noqa: BLE001
                with lock:
                    failures.append('connect: %s' % e)
                return
            try:
                for i in range(calls):
                    s = slaves[(k + i) % len(slaves)]
                    try:
                        r = c.call(SERVICE, B0, BUS_IFACE, 'Execute', 'a(sv)',
                                   [[('SwitchModeSelective', ('(uuuu)', s.identity)), ('InquireNodeId', ('b', True))]])
                    except dbusmini.DBusError as e:
                        r = e
                    with lock:
                        answered[0] += 1
                        if r == [[('b', True), ('y', s.node_id)]]:
                            continue
                        # an answer the engine judged too late or stale: a timing matter of the
                        # host, not of serialisation (see the candump check below)
                        if (r == [[('b', False), ('y', s.node_id)]] or
                                (isinstance(r, dbusmini.DBusError) and r.name == ERR + 'NoResponse')):
                            timing.append('client %d call %d: %r' % (k, i, r))
                        else:
                            failures.append('client %d call %d (slave node %d): %r' % (k, i, s.node_id, r))
            except Exception as e:  # noqa: BLE001
                with lock:
                    failures.append('client %d: %r' % (k, e))
            finally:
                c.close()

        start = time.monotonic()
        threads = [threading.Thread(target=client, args=(k,)) for k in range(clients)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        log('%d calls answered in %.1f s, %d timing misses' % (answered[0], time.monotonic() - start, len(timing)))
        for t in timing[:5]:
            log('  timing miss: ' + t)
        expect(not failures, '%d failures, first: %s' % (len(failures), failures[:3]))
        expect_eq(answered[0], clients * calls, 'calls answered')
        expect(len(timing) <= clients * calls // 100, 'too many timing misses: %d' % len(timing))
        env.alive()

        if env.real:
            time.sleep(0.2)
            check_no_interleaving(env.lss_frames('vcan0'), clients * calls, {s.serial: s.node_id for s in slaves})


def check_no_interleaving(frames, jobs, node_of_serial):
    """Cut the LSS traffic at every switch-global-waiting (04 00): each piece is
    one Execute, and must address one slave and see only that slave's answers
    (retries allowed). Interleaved transactions would mix two in a piece."""
    pieces, cur = [], []
    for _, cob, data in frames:
        if cob == 0x7E5 and data[:2] == b'\x04\x00':
            if cur:
                pieces.append(cur)
            cur = []
        else:
            cur.append((cob, data))
    expect(not cur, 'traffic after the last switch to waiting: %r' % cur[:4])
    expect_eq(len(pieces), jobs, 'transactions (pieces between switches to waiting)')
    for i, piece in enumerate(pieces):
        serials = {int.from_bytes(d[1:5], 'little') for cob, d in piece if cob == 0x7E5 and d[0] == 0x43}
        expect_eq(len(serials), 1, 'slaves addressed in transaction %d' % i)
        node = node_of_serial[serials.pop()]
        answers = [d[1] for cob, d in piece if cob == 0x7E4 and d[0] == 0x5E]
        expect(answers and all(a == node for a in answers), 'transaction %d: node %d, answers %r' % (i, node, answers))
        expect(all(d[0] in (0x40, 0x41, 0x42, 0x43, 0x44, 0x5E) for _, d in piece),
               'transaction %d: other services %r' % (i, [d[0] for _, d in piece]))


def test_two_buses():
    a = [Slave(0x9A, 3, 1, 0x10 + i) for i in range(3)]
    b = [Slave(0x9A, 3, 2, 0x20 + i) for i in range(3)]
    with Env({'vcan0': a, 'vcan1': b}, candump=True) as env:
        expect_eq(sorted(env.get(MANAGER, MANAGER_IFACE, 'Buses')), sorted([B0, B1]), 'Buses')
        results = {}

        def scan(path):
            c = dbusmini.Connection(env.address)
            results[path] = c.call(SERVICE, path, BUS_IFACE, 'Scan', 'a{sv}', [{}], timeout=300)[0]
            c.close()

        threads = [threading.Thread(target=scan, args=(p,)) for p in (B0, B1)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        expect_eq(sorted(results.get(B0, [])), sorted([s.identity + (255,) for s in a]), 'vcan0 devices')
        expect_eq(sorted(results.get(B1, [])), sorted([s.identity + (255,) for s in b]), 'vcan1 devices')
        for s in a:
            env.get(dev('vcan0', s), DEVICE_IFACE, 'NodeId')
        for s in b:
            env.get(dev('vcan1', s), DEVICE_IFACE, 'NodeId')
        if env.real:
            f0 = [f[0] for f in env.lss_frames('vcan0')[1:]]
            f1 = [f[0] for f in env.lss_frames('vcan1')[1:]]
            expect(f0 and f1, 'frames on both buses')
            # the scans overlapped in time
            expect(f1[0] < f0[-1] and f0[0] < f1[-1], 'scans ran one after the other: vcan0 %.3f..%.3f, '
                   'vcan1 %.3f..%.3f' % (f0[0], f0[-1], f1[0], f1[-1]))


def test_txqueue_full():
    """vcan0's tx queue held full (a token-bucket qdisc that drains one frame a second, kept full
    by cangen) while a burst of Scans waits for it on vcan0: the Scan on vcan1 finishes normally
    and property reads answer promptly. An lssd that waited for tx room inside the event loop
    (up to 100 ms per frame) answered a read sent behind the burst only after every vcan0 Scan
    had had its 100 ms: seconds."""
    a = [Slave(0x9A, 3, 1, 0x10 + i) for i in range(2)]
    b = [Slave(0x9A, 3, 2, 0x20 + i) for i in range(3)]
    burst = 20
    with Env({'vcan0': a, 'vcan1': b}) as env:
        if not env.real:
            raise Skip('needs a real interface with a tx queue')
        subprocess.run(['modprobe', 'sch_tbf'], check=False)
        # vcan has no queue of its own (txqueuelen 0, noqueue): give it one
        subprocess.run(['ip', 'link', 'set', 'vcan0', 'txqueuelen', '1000'], check=True)
        subprocess.run(['tc', 'qdisc', 'replace', 'dev', 'vcan0', 'root', 'tbf', 'rate', '100bit', 'burst', '64',
                        'limit', '64'], check=True)
        flood = subprocess.Popen(['cangen', 'vcan0', '-g', '5', '-i', '-I', '123', '-L', '8'],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            time.sleep(0.5)
            p = subprocess.run(['cangen', 'vcan0', '-g', '0', '-I', '123', '-L', '8', '-n', '50'],
                               capture_output=True, text=True, timeout=60)
            expect(p.returncode != 0 and 'No buffer space' in p.stderr + p.stdout,
                   'the queue of vcan0 is full (cangen meets ENOBUFS): rc %d %r' % (p.returncode, p.stderr[-200:]))

            done = threading.Event()
            latencies = []
            found = {}

            def reader():
                c = dbusmini.Connection(env.address)
                while not done.is_set():
                    t = time.monotonic()
                    c.call(SERVICE, B1, 'org.freedesktop.DBus.Properties', 'Get', 'ss', [BUS_IFACE, 'State'],
                           timeout=60)
                    latencies.append(time.monotonic() - t)
                    time.sleep(0.01)
                c.close()

            def scan1():
                c = dbusmini.Connection(env.address)
                found['vcan1'] = c.call(SERVICE, B1, BUS_IFACE, 'Scan', 'a{sv}', [{}], timeout=300)[0]
                c.close()

            threads = [threading.Thread(target=reader), threading.Thread(target=scan1)]
            for t in threads:
                t.start()
            time.sleep(0.2)
            c0 = env.connect()
            t0 = time.monotonic()
            serials = [c0.send(SERVICE, B0, BUS_IFACE, 'Scan', 'a{sv}', [{}]) for _ in range(burst)]
            # busctl too, right behind the burst
            t = time.monotonic()
            state1 = env.get(B1, BUS_IFACE, 'State')
            log('busctl get-property behind the burst: %.3f s (%s)' % (time.monotonic() - t, state1))
            errors = []
            for s in serials:
                try:
                    c0.wait_reply(s, 120)
                except dbusmini.DBusError as e:
                    errors.append(str(e))
            log('%d Scans on vcan0: %d failed in %.1f s, e.g. %s' % (burst, len(errors), time.monotonic() - t0,
                                                                      errors[:1]))
            threads[1].join(300)
            done.set()
            threads[0].join(60)
            worst = max(latencies) if latencies else None
            log('%d property reads meanwhile, worst %.3f s' % (len(latencies), worst or -1))
            expect(any('transmit queue stayed full' in e for e in errors),
                   'a Scan on vcan0 failed on the full queue (else the queue was not held full)')
            expect_eq(sorted(found.get('vcan1', [])), sorted([s.identity + (255,) for s in b]), 'Scan on vcan1')
            expect(len(latencies) >= 5, 'property reads went on: %d' % len(latencies))
            expect(worst is not None and worst < 1.0, 'worst property read %.3f s' % (worst or -1))
        finally:
            flood.terminate()
            flood.wait(10)
            subprocess.run(['tc', 'qdisc', 'del', 'dev', 'vcan0', 'root'], check=False)
            subprocess.run(['ip', 'link', 'set', 'vcan0', 'txqueuelen', '0'], check=False)
        env.alive()
        env.wait_until(lambda: env.get(B0, BUS_IFACE, 'State') == 'idle', timeout=60, what='vcan0 idle')
        expect_eq(sorted(env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)[0]), sorted([list(s.identity) + [255] for s in a]),
                  'Scan on vcan0 once the queue drains')


# ---- life cycle ----

def test_lifecycle():
    # 24: the Scan must still run when Cancel comes (busctl takes 2 s in a
    # slow VM; a Scan of 6 ended first on 2026-12-02)
    slaves = [Slave(0x9A, 3, 1, 0x1000 + i) for i in range(24)]
    with Env({'vcan0': slaves}, candump=True, notify=True) as env:
        env.notify.settimeout(10)
        msgs = ''
        while 'READY=1' not in msgs:
            msgs += env.notify.recv(4096).decode() + '\n'
        expect('STATUS=' in msgs, 'no STATUS= in %r' % msgs)
        if env.real:
            # lssd sent it before READY; candump, another process, may write it a little later
            env.wait_until(lambda: env.lss_frames('vcan0'), what='the first LSS frame in the candump')
            first = env.lss_frames('vcan0')[0]
            expect_eq((first[1], first[2][:2]), (0x7E5, b'\x04\x00'), 'first frame')

        # Cancel a running scan
        c = env.connect()
        lssd_signals(c)
        serial = c.send(SERVICE, B0, BUS_IFACE, 'Scan', 'a{sv}', [{}])
        env.wait_until(lambda: env.get(B0, BUS_IFACE, 'Job') == 'Scan', what='the scan to run')
        env.call(B0, BUS_IFACE, 'Cancel')
        try:
            c.wait_reply(serial, 60)
            raise AssertionError('cancelled Scan succeeded')
        except dbusmini.DBusError as e:
            expect_eq(e.name, ERR + 'Cancelled', 'cancelled Scan')
        sig = c.wait_signal(lambda m: m.member == 'JobFinished')
        expect(sig and sig.body == ['Scan', 'cancelled'], 'JobFinished: %r' % (sig and sig.body))
        if env.real:
            env.wait_until(lambda: all_waiting(env, 'vcan0', slaves), what='slaves waiting after Cancel')
        env.call(B0, BUS_IFACE, 'Cancel')  # nothing running: nothing happens

        # SIGTERM during a scan: the caller gets Cancelled, slaves end in waiting, exit 0
        serial = c.send(SERVICE, B0, BUS_IFACE, 'Scan', 'a{sv}', [{}])
        env.wait_until(lambda: env.get(B0, BUS_IFACE, 'Job') == 'Scan', what='the scan to run')
        rc = env.stop_lssd(signal.SIGTERM)
        expect_eq(rc, 0, 'exit status after SIGTERM')
        try:
            c.wait_reply(serial, 10)
            raise AssertionError('Scan succeeded although lssd stopped')
        except dbusmini.DBusError as e:
            expect_eq(e.name, ERR + 'Cancelled', 'Scan during stop')
        owner = c.call('org.freedesktop.DBus', '/org/freedesktop/DBus', 'org.freedesktop.DBus', 'NameHasOwner', 's',
                       [SERVICE])
        expect_eq(owner, [False], 'name released')
        if env.real:
            time.sleep(0.2)
            last = [f for f in env.lss_frames('vcan0') if f[1] == 0x7E5][-1]
            expect_eq(last[2][:2], b'\x04\x00', 'last frame')
            expect(all_waiting(env, 'vcan0', slaves), 'slaves waiting after stop')
        expect('Stopped' in env.lssd_output(), 'log of the stop')


def test_slow_devices():
    """Devices slower than lss_timeout_ms (40 ms against 20): a Scan finds them
    (it said "0 devices" before), AutoAssign then gives each its node-ID
    (with the waits the Scan made patient: none of its answers comes late),
    and the journal says so once, for the Scan, not again for the switch to
    waiting at the stop, which no device answers."""
    if os.environ.get('LSSD_TEST_BACKEND') == 'simulate':
        raise Skip('lssd --simulate has no slow slaves (lss-sim --latency)')
    slaves = [Slave(0x9A, 3, 1, 0x1100 + i) for i in range(3)]
    devices = ', '.join('{ vendor = 0x9A; product = 3; revision = 1; serial = 0x%x; node_id = %d; }'
                        % (s.serial, 10 + i) for i, s in enumerate(slaves))
    config = ('lss_timeout_ms = 20;\nbuses = ( { interface = "vcan0"; bitrate = 125000; devices = ( %s ); } );\n'
              % devices)
    with Env({'vcan0': slaves}, config=config, sim_args=['--latency', '40']) as env:
        found = env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 1, 'sdo', 'b', 'false')[0]
        expect_eq(sorted(tuple(d[:4]) for d in found), sorted(s.identity for s in slaves), 'Scan')
        got, _, result = auto_assign(env)
        expect_eq(sorted(x[3:] for x in got), [[s.serial, 255, 10 + i] for i, s in enumerate(slaves)], 'AutoAssign')
        expect_eq(result, 'done', 'AutoAssign result')
        expect_eq(env.stop_lssd(signal.SIGTERM), 0, 'exit status after SIGTERM')
        out = env.lssd_output()
        notices = [line for line in out.splitlines() if 'answered later than lss_timeout_ms = 20 allows' in line]
        expect_eq(len(notices), 1, 'notices of late answers in %r' % out[-3000:])
        expect(out.index(notices[0]) < out.index('AutoAssign:'), 'the notice came with the Scan, not later')


def test_second_instance():
    """A second lssd for a bus already served (issue 17): it must not send a
    frame (its switch to waiting would cut into the first one's work), must
    say that lssd is already running and exit 1; the first one serves on."""
    slaves = [Slave(0x9A, 3, 1, 0x1000 + i) for i in range(3)]
    with Env({'vcan0': slaves}, candump=True) as env:
        env.wait_until(lambda: env.get(B0, BUS_IFACE, 'State') == 'idle', what='the first lssd idle')
        time.sleep(0.5)
        before = len(env.frames('vcan0')) if env.real else 0
        p = subprocess.run(env.lssd_cmd, env=env.lssd_env, capture_output=True, text=True, timeout=120)
        env.step('second lssd exited with %d: %r' % (p.returncode, p.stdout + p.stderr))
        out = p.stdout + p.stderr
        if env.real:  # the witness first
            time.sleep(0.5)  # candump writes what it saw
            expect_eq(env.frames('vcan0')[before:], [], 'frames on vcan0 while the second lssd ran')
        expect_eq(p.returncode, 1, 'exit status of the second lssd')
        expect('lssd is already running' in out, 'message of the second lssd: %r' % out)
        # (it may open its sockets: sending is what would disturb)
        expect('switched to waiting' not in out, 'the second lssd sent its first frame: %r' % out)
        # the first one serves on
        env.alive()
        got = env.call(B0, BUS_IFACE, 'Execute', 'a(sv)', 2, 'SwitchModeSelective', '(uuuu)', *slaves[0].identity,
                       'InquireNodeId', 'b', 'true')
        expect_eq([v['data'] for v in got[0]], [True, 0xFF], 'the first lssd still reaches a slave')


def test_reload():
    with Env({'vcan0': SLAVES, 'vcan1': []}, config=CONFIG % '') as env:
        c = env.connect()
        c.add_match(f"type='signal',sender='{SERVICE}',interface='org.freedesktop.DBus.ObjectManager'")
        c.add_match(f"type='signal',sender='{SERVICE}',interface='org.freedesktop.DBus.Properties'")
        expect_eq(env.get(MANAGER, MANAGER_IFACE, 'Buses'), [B0], 'Buses at start')
        env.call(B0, BUS_IFACE, 'Scan', 'a{sv}', 0)
        d = dev('vcan0', SLAVES[0])
        expect_eq(env.get(d, DEVICE_IFACE, 'MappedNodeId'), 5, 'MappedNodeId at start')

        # a second bus and a changed map
        with open(env.config_path, 'w') as f:
            f.write((CONFIG % VCAN1).replace('node_id = 5;', 'node_id = 15;'))
        env.call(MANAGER, MANAGER_IFACE, 'ReloadConfig')
        expect_eq(env.get(MANAGER, MANAGER_IFACE, 'Buses'), [B0, B1], 'Buses after adding vcan1')
        expect(c.wait_signal(lambda m: m.member == 'InterfacesAdded' and m.body[0] == B1), 'InterfacesAdded')
        expect_eq(env.get(d, DEVICE_IFACE, 'MappedNodeId'), 15, 'MappedNodeId after reload')
        expect(c.wait_signal(lambda m: m.member == 'PropertiesChanged' and m.path == d and
                             'MappedNodeId' in m.body[1]), 'PropertiesChanged MappedNodeId')

        # a bad file changes nothing
        with open(env.config_path, 'w') as f:
            f.write('buses = ( { interface = "vcan0"; devices = ( { serial = 1; node_id = 200; } ); } );\n')
        name, msg = env.call_error(MANAGER, MANAGER_IFACE, 'ReloadConfig')
        expect_eq(name, 'org.freedesktop.DBus.Error.InvalidFileContent', 'bad configuration')
        expect(env.config_path in msg, 'the message names the file: ' + msg)
        expect_eq(env.get(MANAGER, MANAGER_IFACE, 'Buses'), [B0, B1], 'Buses after a bad file')

        # SIGHUP too; vcan1 goes away again
        with open(env.config_path, 'w') as f:
            f.write(CONFIG % '')
        env.lssd.send_signal(signal.SIGHUP)
        env.wait_until(lambda: env.get(MANAGER, MANAGER_IFACE, 'Buses') == [B0], what='vcan1 removed')
        expect(c.wait_signal(lambda m: m.member == 'InterfacesRemoved' and m.body[0] == B1), 'InterfacesRemoved')
        name, _ = env.call_error(MANAGER, MANAGER_IFACE, 'GetBus', 's', 'vcan1')
        expect_eq(name, ERR + 'NotFound', 'GetBus of the removed bus')
        env.alive()


def test_bus_down():
    with Env({'vcan1': SLAVES[:1]}, candump=True) as env:
        if not env.real:
            raise Skip('needs a real interface to take down')
        c = env.connect()
        c.add_match(f"type='signal',sender='{SERVICE}',interface='org.freedesktop.DBus.Properties'")
        try:
            subprocess.run(['ip', 'link', 'set', 'vcan1', 'down'], check=True)
            env.wait_until(lambda: env.get(B1, BUS_IFACE, 'State') == 'down', what='State down')
            expect(c.wait_signal(lambda m: m.path == B1 and m.body[1].get('State') == ('s', 'down')),
                   'PropertiesChanged State down')
            name, _ = env.call_error(B1, BUS_IFACE, 'Scan', 'a{sv}', 0)
            expect_eq(name, ERR + 'BusDown', 'Scan on a down bus')
            n = len(env.lss_frames('vcan1'))
        finally:
            subprocess.run(['ip', 'link', 'set', 'vcan1', 'up'], check=True)
        env.wait_until(lambda: env.get(B1, BUS_IFACE, 'State') == 'idle', what='State idle again')
        # lss-sim lost its socket's link too; what matters is lssd's first frame after up
        env.wait_until(lambda: len(env.lss_frames('vcan1')) > n, what='a frame after the link came back')
        f = env.lss_frames('vcan1')[n]
        expect_eq((f[1], f[2][:2]), (0x7E5, b'\x04\x00'), 'first frame after link up')
        env.alive()



def test_no_interface():
    """An interface that is not there says why in the journal, not only
    'link gone': no such interface, or no CAN in this kernel at all (issue 21).
    The real SocketCAN lssd on either backend: it needs no CAN to say so."""
    import socket
    ifname = 'lssdnone0'
    try:
        socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW).close()
        has_can = True
    except (OSError, AttributeError):
        has_can = False
    if os.path.exists('/sys/class/net/' + ifname):
        raise Skip('%s exists here' % ifname)
    with Env({ifname: []}, absent={ifname}, start_lssd=False) as env:
        env.real = True  # no --simulate: the SocketCAN path is the point
        env._start_lssd()
        path = bus_path(ifname)
        expect_eq(env.get(path, BUS_IFACE, 'State'), 'down', 'State of a bus without its interface')
        out = env.lssd_output()
        if has_can:
            want = '%s: serving (SocketCAN, link gone): no interface %s (yet)' % (ifname, ifname)
        else:
            want = '%s: serving (SocketCAN, link gone): this kernel has no CAN support' % ifname
        expect(want in out, 'why the link is gone (%s): %r' % ('CAN kernel' if has_can else 'no CAN', out))
        env.alive()


def test_check_config():
    """lssd --check-config as lssd(8) says: FILE as a word or with '=', the
    map it read shown line by line, an extra word named, no file at all an
    error (issue 21)."""
    import tempfile
    lssd = os.environ.get('LSSD_BINARY', 'lssd')
    conf = os.path.join(SOURCE_ROOT, 'conf', 'lssd.conf')

    def check(*args):
        return subprocess.run([lssd] + list(args), capture_output=True, text=True, timeout=60)
    with open(conf) as f:  # the example's first map entry (its line moves as the example grows)
        line = 1 + next(i for i, x in enumerate(f) if '{ serial = 0x00001276; node_id = 5; }' in x)
    for args in (('--check-config', conf), ('--check-config=' + conf)):
        r = check(*args) if isinstance(args, tuple) else check(args)
        expect(r.returncode == 0, '%r: %r' % (args, r))
        expect('line %d: vendor 0x000000ec product 0x00001234 revision any serial 0x00001276 -> node-ID 5' % line
               in r.stdout, 'the map shown: %r' % r.stdout)
    r = check('--check-config', conf, 'extra')
    expect(r.returncode == 1 and "Unexpected argument 'extra'" in r.stderr, 'the extra word named: %r' % r)
    with tempfile.TemporaryDirectory() as d:
        # no file: the default does not exist here (a private --config that is missing is an error too)
        r = check('--check-config', '--config', os.path.join(d, 'none.conf'))
        expect(r.returncode == 1 and 'none.conf' in r.stderr, 'a missing file: %r' % r)
        path = os.path.join(d, 'zeros.conf')
        with open(path, 'w') as f:
            f.write('buses = ( { interface = "can0"; vendor = 1; product = 2;\n'
                    '  devices = ( { serial = 3; node_id = 010; } ); } );\n')
        r = check('--check-config', path)
        expect(r.returncode == 0 and 'line 2: ' in r.stdout and '-> node-ID 10' in r.stdout,
               'what node_id = 010 was read as: %r' % r)
    if not os.path.exists('/etc/lssd/lssd.conf'):
        r = check('--check-config')
        expect(r.returncode == 1 and 'Nothing to check' in r.stderr, 'no file, no --bus: %r' % r)


def test_progress():
    """Progress follows the work (issues 21 and 39): sampled during a Scan of
    16 non-configured devices, the first one (nothing known of the bus) and
    the second (16 expected, the parts' times of the first known): never
    backwards, never 1 before the reply, at every sample within 0.35 of the
    share of the Scan's time gone, and never standing still for more than
    20 % of that time."""
    slaves = [Slave(0xEC, 0x1234, 1, 0x100 + i) for i in range(16)]
    with Env({'vcan0': slaves}) as env:
        c = env.connect()
        for rep in ('first', 'second'):
            caller = env.connect()
            ended = []
            t0 = time.monotonic()
            serial = caller.send(SERVICE, B0, BUS_IFACE, 'Scan', 'a{sv}', [{}])
            t = threading.Thread(target=lambda: ended.append(caller.wait_reply(serial, timed=True)))
            t.start()
            samples = []
            while t.is_alive():
                p = c.get_property(SERVICE, B0, BUS_IFACE, 'Progress')
                at = time.monotonic() - t0
                # read while the job ran, not after its end (Progress is then
                # 0 again) and before its reply came
                if c.get_property(SERVICE, B0, BUS_IFACE, 'Job') == 'Scan' and t.is_alive():
                    samples.append((at, p))
                time.sleep(0.05)
            t.join()
            expect(len(ended) == 1, 'no reply to the Scan')
            total = ended[0][1] - t0
            expect_eq(len(ended[0][0][0]), 16, 'devices found')
            shares = [(at / total, p) for at, p in samples]
            log('%s scan, %.2f s: %s' % (rep, total, ' '.join('%.2f/%.2f' % x for x in shares)))
            expect(len(samples) >= 20, 'too few samples: %r' % samples)
            expect(all(b2 >= a2 for (_, a2), (_, b2) in zip(samples, samples[1:])), 'backwards: %r' % shares)
            expect(all(p < 1 for _, p in samples), '1 before the end: %r' % shares)
            off = max(abs(p - s) for s, p in shares)
            # the longest run of samples reading one value: at least that still
            still, first = 0, 0
            for i in range(1, len(shares)):
                if shares[i][1] != shares[first][1]:
                    first = i
                still = max(still, shares[i][0] - shares[first][0])
            log('%s scan: at most %.2f off the share of the time gone, still for %.2f of it' % (rep, off, still))
            expect(off <= 0.35, '%.2f off the share of the time gone: %r' % (off, shares))
            expect(still <= 0.2, 'still for %.2f of the Scan: %r' % (still, shares))


def test_scan_found_early():
    """DeviceFound comes when a device is found, not at the end (issue 21):
    during a Scan of 12 devices (10 non-configured, found by the fastscan
    enumeration; 2 configured, found by the slowscan of their vendor/product,
    which finds the non-configured ones again) the signals arrive spread over
    the Scan, the first before half of its time, each before JobFinished, one
    per device (none again at the end), matching the reply."""
    slaves = [Slave(0xEC, 0x1234, 1, 0x100 + i) for i in range(10)]
    slaves += [Slave(0xEC, 0x1234, 2, 0x200 + i, 20 + i) for i in range(2)]
    with Env({'vcan0': slaves}) as env:
        c = env.connect()
        lssd_signals(c)
        t0 = time.monotonic()
        serial = c.send(SERVICE, B0, BUS_IFACE, 'Scan', 'a{sv}', [{'vendor': ('u', 0xEC), 'product': ('u', 0x1234)}])
        found = c.wait_reply(serial)[0]
        done = c.wait_signal(lambda m: m.member == 'JobFinished')
        expect(done and done.body == ['Scan', 'done'], 'JobFinished: %r' % (done and done.body))
        # anything sent after the reply (a second DeviceFound) has come by now
        time.sleep(0.5)
        expect_eq(sorted(tuple(f) for f in found), sorted(s.identity + (s.node_id,) for s in slaves), 'Scan result')
        total = done.received - t0
        with c.lock:
            signals = list(c.signals)
        dfound = [m for m in signals if m.member == 'DeviceFound']
        shares = [(m.received - t0) / total for m in dfound]
        log('Scan %.1f s, DeviceFound at %s' % (total, ' '.join('%.2f' % x for x in shares)))
        paths = [m.body[0] for m in dfound]
        expect_eq(sorted(paths), sorted(device_path('vcan0', *f[:4]) for f in found), 'DeviceFound paths')
        expect_eq(len(set(paths)), len(paths), 'one DeviceFound per device')
        # one reader thread: received in the order sent
        expect(all(m.received < done.received for m in dfound), 'DeviceFound after JobFinished')
        expect(shares and shares[0] < 0.5, 'the first DeviceFound at %.2f of the Scan' % (shares[0] if shares else 1))
        # spread over the Scan, not in a burst at its end
        expect(shares and shares[len(shares) // 2] < 0.8, 'half the DeviceFound only at the end: %r' % shares)
        unknown = [tuple(m.body) for m in signals if m.member == 'UnknownDevice']
        expect_eq(sorted(unknown), sorted(s.identity for s in slaves), 'one UnknownDevice per device')


def test_startup_order():
    """Objects, then the name, then frames: a client that sees the name sees
    every bus already (no InterfacesAdded for a bus after the name appears;
    the VM's scan test caught one), and the first frame comes after it."""
    with Env({'vcan0': SLAVES[:1]}, config=CONFIG % '', start_lssd=False) as env:
        c = env.connect()
        c.add_match(f"type='signal',sender='{SERVICE}',interface='org.freedesktop.DBus.ObjectManager'")
        env._start_lssd()
        env.wait_for_name()
        expect(B0 in env.call(ROOT, 'org.freedesktop.DBus.ObjectManager', 'GetManagedObjects')[0],
               'the bus object once the name is there')
        added = c.wait_signal(lambda m: m.member == 'InterfacesAdded', timeout=2)
        expect(added is None, 'InterfacesAdded after the name appeared: %r' % (added and added.body))

TESTS = {
    'introspection': test_introspection,
    'properties': test_properties,
    'scan': test_scan,
    'scan-options': test_scan_options,
    'scan-sdo': test_scan_sdo,
    'assign': test_assign,
    'unassign': test_unassign,
    'autoassign': test_autoassign,
    'autoassign-pool': test_autoassign_pool,
    'autoassign-boot': test_autoassign_boot,
    'raw': test_raw,
    'holder-killed': test_holder_killed,
    'execute': test_execute,
    'bad-arguments': test_bad_arguments,
    'unprivileged': test_unprivileged,
    'daemon-checks-credentials': test_daemon_checks_credentials,
    'concurrent-clients': test_concurrent_clients,
    'two-buses': test_two_buses,
    'txqueue-full': test_txqueue_full,
    'lifecycle': test_lifecycle,
    'second-instance': test_second_instance,
    'slow-devices': test_slow_devices,
    'check-config': test_check_config,
    'progress': test_progress,
    'scan-found-early': test_scan_found_early,
    'startup-order': test_startup_order,
    'reload': test_reload,
    'bus-down': test_bus_down,
    'no-interface': test_no_interface,
}

if __name__ == '__main__':
    sys.exit(run(TESTS))
