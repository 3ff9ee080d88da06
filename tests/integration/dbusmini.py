# SPDX-License-Identifier: LGPL-2.1-or-later
"""A minimal D-Bus client in pure Python (stdlib only) for the integration
tests: what busctl cannot do from a shell — keep a connection open (to hold
a bus), watch signals while calling, many clients at once, and report the
error *name* of a failed call.

Values: basic types map to int/float/str/bool; structs to tuples; arrays to
lists, a{..} to dicts; a variant is a (signature, value) tuple both ways."""

import os
import socket
import struct
import threading
import time

ALIGN = {'y': 1, 'b': 4, 'n': 2, 'q': 2, 'i': 4, 'u': 4, 'x': 8, 't': 8,
         'd': 8, 's': 4, 'o': 4, 'g': 1, 'a': 4, '(': 8, '{': 8, 'v': 1, 'h': 4}
FIXED = {'y': 'B', 'b': 'I', 'n': 'h', 'q': 'H', 'i': 'i', 'u': 'I',
         'x': 'q', 't': 'Q', 'd': 'd', 'h': 'I'}

METHOD_CALL, METHOD_RETURN, ERROR, SIGNAL = 1, 2, 3, 4
NO_REPLY_EXPECTED = 1


class DBusError(Exception):
    def __init__(self, name, message=''):
        super().__init__('%s: %s' % (name, message))
        self.name = name
        self.message = message


def split_signature(sig):
    """'a{sv}ii' -> ['a{sv}', 'i', 'i']"""
    out, i = [], 0
    while i < len(sig):
        j = _type_end(sig, i)
        out.append(sig[i:j])
        i = j
    return out


def _type_end(sig, i):
    c = sig[i]
    if c == 'a':
        return _type_end(sig, i + 1)
    if c in '({':
        close = ')' if c == '(' else '}'
        depth, j = 0, i
        while True:
            if sig[j] in '({':
                depth += 1
            elif sig[j] in ')}':
                depth -= 1
                if depth == 0:
                    return j + 1
            j += 1
    return i + 1


class _Writer:
    def __init__(self):
        self.buf = bytearray()

    def pad(self, n):
        while len(self.buf) % n:
            self.buf.append(0)

    def put(self, sig, v):
        c = sig[0]
        self.pad(ALIGN[c])
        if c in FIXED:
            if c == 'b':
                v = 1 if v else 0
            self.buf += struct.pack('<' + FIXED[c], v)
        elif c in 'so':
            b = v.encode()
            self.buf += struct.pack('<I', len(b)) + b + b'\0'
        elif c == 'g':
            b = v.encode()
            self.buf += struct.pack('<B', len(b)) + b + b'\0'
        elif c == 'v':
            vsig, vval = v
            self.put('g', vsig)
            self.put(vsig, vval)
        elif c == 'a':
            elem = sig[1:]
            at = len(self.buf)
            self.buf += b'\0\0\0\0'
            self.pad(ALIGN[elem[0]])
            start = len(self.buf)
            if elem[0] == '{':
                kt, vt = split_signature(elem[1:-1])
                for k, val in (v.items() if isinstance(v, dict) else v):
                    self.pad(8)
                    self.put(kt, k)
                    self.put(vt, val)
            else:
                for e in v:
                    self.put(elem, e)
            struct.pack_into('<I', self.buf, at, len(self.buf) - start)
        elif c == '(':
            for t, e in zip(split_signature(sig[1:-1]), v):
                self.put(t, e)
        else:
            raise ValueError('cannot marshal ' + sig)


class _Reader:
    def __init__(self, data, pos=0):
        self.data, self.pos = data, pos

    def align(self, n):
        self.pos = (self.pos + n - 1) // n * n

    def get(self, sig):
        c = sig[0]
        self.align(ALIGN[c])
        if c in FIXED:
            fmt = '<' + FIXED[c]
            v = struct.unpack_from(fmt, self.data, self.pos)[0]
            self.pos += struct.calcsize(fmt)
            return bool(v) if c == 'b' else v
        if c in 'so':
            n = struct.unpack_from('<I', self.data, self.pos)[0]
            v = self.data[self.pos + 4:self.pos + 4 + n].decode()
            self.pos += 4 + n + 1
            return v
        if c == 'g':
            n = self.data[self.pos]
            v = self.data[self.pos + 1:self.pos + 1 + n].decode()
            self.pos += 1 + n + 1
            return v
        if c == 'v':
            vsig = self.get('g')
            return (vsig, self.get(vsig))
        if c == 'a':
            n = struct.unpack_from('<I', self.data, self.pos)[0]
            self.pos += 4
            elem = sig[1:]
            self.align(ALIGN[elem[0]])
            end = self.pos + n
            if elem[0] == '{':
                kt, vt = split_signature(elem[1:-1])
                out = {}
                while self.pos < end:
                    self.align(8)
                    k = self.get(kt)
                    out[k] = self.get(vt)
                return out
            out = []
            while self.pos < end:
                out.append(self.get(elem))
            return out
        if c == '(':
            return tuple(self.get(t) for t in split_signature(sig[1:-1]))
        raise ValueError('cannot unmarshal ' + sig)


class Message:
    def __init__(self, mtype, serial=0, flags=0, fields=None, signature='', body=()):
        self.type, self.serial, self.flags = mtype, serial, flags
        self.fields = fields or {}
        self.signature, self.body = signature, list(body)

    path = property(lambda s: s.fields.get(1))
    interface = property(lambda s: s.fields.get(2))
    member = property(lambda s: s.fields.get(3))
    error_name = property(lambda s: s.fields.get(4))
    reply_serial = property(lambda s: s.fields.get(5))
    sender = property(lambda s: s.fields.get(7))

    def encode(self):
        body = _Writer()
        for t, v in zip(split_signature(self.signature), self.body):
            body.put(t, v)
        fields = dict(self.fields)
        if self.signature:
            fields[8] = self.signature
        codes = {1: 'o', 2: 's', 3: 's', 4: 's', 5: 'u', 6: 's', 7: 's', 8: 'g'}
        hdr = _Writer()
        hdr.put('y', ord('l'))
        hdr.put('y', self.type)
        hdr.put('y', self.flags)
        hdr.put('y', 1)
        hdr.put('u', len(body.buf))
        hdr.put('u', self.serial)
        hdr.put('a(yv)', [(k, (codes[k], v)) for k, v in sorted(fields.items())])
        hdr.pad(8)
        return bytes(hdr.buf + body.buf)


def _parse(data):
    """Returns (message, bytes used) or (None, 0) when incomplete."""
    if len(data) < 16:
        return None, 0
    if data[0:1] != b'l':
        raise ValueError('big-endian messages are not supported')
    body_len, serial, fields_len = struct.unpack_from('<III', data, 4)
    hdr_end = 16 + fields_len
    hdr_end = (hdr_end + 7) // 8 * 8
    total = hdr_end + body_len
    if len(data) < total:
        return None, 0
    r = _Reader(data, 12)
    fields = {k: v[1] for k, v in r.get('a(yv)')}
    msg = Message(data[1], serial, data[2], fields, fields.get(8, ''))
    br = _Reader(data[hdr_end:total])
    msg.body = [br.get(t) for t in split_signature(msg.signature)]
    return msg, total


class Connection:
    """One connection to the bus; a reader thread sorts replies and signals."""

    def __init__(self, address=None):
        address = address or os.environ.get('DBUS_SYSTEM_BUS_ADDRESS', 'unix:path=/run/dbus/system_bus_socket')
        path = None
        for part in address.split(';')[0].split(':', 1)[1].split(','):
            k, _, v = part.partition('=')
            if k == 'path':
                path = v
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.sock.connect(path)
        self.sock.sendall(b'\0AUTH EXTERNAL ' + str(os.geteuid()).encode().hex().encode() + b'\r\n')
        line = b''
        while not line.endswith(b'\r\n'):
            chunk = self.sock.recv(1)
            if not chunk:
                raise ConnectionError('bus closed during authentication')
            line += chunk
        if not line.startswith(b'OK'):
            raise ConnectionError('authentication failed: %r' % line)
        self.sock.sendall(b'BEGIN\r\n')
        self.lock = threading.Condition()
        self.serial = 0
        self.replies = {}
        self.signals = []
        self.closed = False
        self.thread = threading.Thread(target=self._read_loop, daemon=True)
        self.thread.start()
        self.unique_name = self.call('org.freedesktop.DBus', '/org/freedesktop/DBus', 'org.freedesktop.DBus',
                                     'Hello')[0]

    def _read_loop(self):
        data = b''
        try:
            while True:
                chunk = self.sock.recv(65536)
                if not chunk:
                    break
                data += chunk
                while True:
                    msg, used = _parse(data)
                    if not msg:
                        break
                    data = data[used:]
                    msg.received = time.monotonic()
                    with self.lock:
                        if msg.type in (METHOD_RETURN, ERROR):
                            self.replies[msg.reply_serial] = msg
                        elif msg.type == SIGNAL:
                            self.signals.append(msg)
                        self.lock.notify_all()
        except OSError:
            pass
        with self.lock:
            self.closed = True
            self.lock.notify_all()

    def send(self, dest, path, iface, member, signature='', body=(), flags=0):
        with self.lock:
            self.serial += 1
            serial = self.serial
        fields = {1: path, 3: member}
        if iface:
            fields[2] = iface
        if dest:
            fields[6] = dest
        msg = Message(METHOD_CALL, serial, flags, fields, signature, body)
        self.sock.sendall(msg.encode())
        return serial

    def wait_reply(self, serial, timeout=300, timed=False):
        """The reply's body; timed: (body, when it was read off the socket, time.monotonic())."""
        deadline = time.monotonic() + timeout
        with self.lock:
            while serial not in self.replies:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise TimeoutError('no reply to call %d' % serial)
                if self.closed:
                    raise ConnectionError('connection closed')
                self.lock.wait(left)
            msg = self.replies.pop(serial)
        if msg.type == ERROR:
            raise DBusError(msg.error_name, msg.body[0] if msg.body else '')
        return (msg.body, msg.received) if timed else msg.body

    def call(self, dest, path, iface, member, signature='', body=(), timeout=300):
        return self.wait_reply(self.send(dest, path, iface, member, signature, body), timeout)

    def add_match(self, rule):
        self.call('org.freedesktop.DBus', '/org/freedesktop/DBus', 'org.freedesktop.DBus', 'AddMatch', 's', [rule])

    def wait_signal(self, pred, timeout=10):
        """The first received signal pred() accepts (removed from the list)."""
        deadline = time.monotonic() + timeout
        with self.lock:
            while True:
                for i, s in enumerate(self.signals):
                    if pred(s):
                        return self.signals.pop(i)
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                self.lock.wait(left)

    def get_property(self, dest, path, iface, name):
        return self.call(dest, path, 'org.freedesktop.DBus.Properties', 'Get', 'ss', [iface, name])[0][1]

    def close(self):
        try:
            self.sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self.sock.close()
