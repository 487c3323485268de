#!/usr/bin/env python3
"""A client of spherov2.py's TCP relay protocol, written from the protocol description
(no spherov2 code): scan, find, init, handshake, subscribe and drive a Sphero API v2 droid
(R2-D2) through `droidctl serve`, reading back its notifications.

Usage: relay_client.py HOST PORT
Prints one JSON object with what it saw; exits non-zero on any protocol surprise.
Standard library only; every socket read is bounded by a timeout.
"""

import json
import socket
import struct
import sys
import threading
import time

# Requests and replies (big-endian integers).
SCAN, INIT, SET_CALLBACK, WRITE, FIND, END = 0x00, 0x01, 0x02, 0x03, 0x04, 0xFF
OK, ON_DATA, ERROR = 0x00, 0x01, 0xFF

ANTI_DOS = "00020005-574f-4f20-5370-6865726f2121"
API = "00010002-574f-4f20-5370-6865726f2121"
UNLOCK = b"usetheforce...band"

# Sphero API v2 framing.
SOP, EOP, ESC = 0x8D, 0xD8, 0xAB
ESCAPED = {ESC: 0x23, SOP: 0x05, EOP: 0x50}


def u16(n):
    return struct.pack(">H", n)


def text(s):
    b = s.encode("utf-8")
    return u16(len(b)) + b


def read_exact(sock, n):
    out = b""
    while len(out) < n:
        chunk = sock.recv(n - len(out))
        if not chunk:
            raise EOFError("the relay closed the connection")
        out += chunk
    return out


def read_u16(sock):
    return struct.unpack(">H", read_exact(sock, 2))[0]


def read_text(sock):
    return read_exact(sock, read_u16(sock)).decode("utf-8")


def connect(host, port):
    s = socket.create_connection((host, port), timeout=10)
    s.settimeout(10)
    return s


def discover(host, port, request):
    """SCAN or FIND on a connection of its own; the devices, or None for "not found"."""
    s = connect(host, port)
    try:
        s.sendall(request)
        op = read_exact(s, 1)[0]
        if op == ERROR:
            msg = read_text(s)
            if msg == "" and request[0] == FIND:
                return None
            raise RuntimeError("relay error: " + msg)
        if op != OK:
            raise RuntimeError("unexpected reply opcode %#x" % op)
        count = read_u16(s) if request[0] == SCAN else 1
        return [(read_text(s), read_text(s)) for _ in range(count)]
    finally:
        s.sendall(bytes([END]))
        s.close()


class Session:
    """One connection holding one droid: replies matched by seq, ON_DATA collected."""

    def __init__(self, host, port):
        self.sock = connect(host, port)
        self.seq = 0
        self.lock = threading.Condition()
        self.replies = {}
        self.notifications = []  # (uuid, bytes)
        self.closed = None
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self):
        try:
            while True:
                op = read_exact(self.sock, 1)[0]
                if op == OK:
                    seq = read_exact(self.sock, 1)[0]
                    with self.lock:
                        self.replies[seq] = None
                        self.lock.notify_all()
                elif op == ERROR:
                    msg = read_text(self.sock)
                    seq = read_exact(self.sock, 1)[0]
                    with self.lock:
                        self.replies[seq] = msg
                        self.lock.notify_all()
                elif op == ON_DATA:
                    uuid = read_text(self.sock)
                    data = read_exact(self.sock, read_exact(self.sock, 1)[0])
                    with self.lock:
                        self.notifications.append((uuid, data))
                        self.lock.notify_all()
                else:
                    raise RuntimeError("unexpected reply opcode %#x" % op)
        except (EOFError, OSError, RuntimeError) as e:
            with self.lock:
                self.closed = str(e)
                self.lock.notify_all()

    def call(self, op, payload):
        seq = self.seq
        self.seq = (self.seq + 1) % 256
        self.sock.sendall(bytes([op, seq]) + payload)
        deadline = time.time() + 10
        with self.lock:
            while seq not in self.replies:
                if self.closed is not None:
                    raise RuntimeError("connection closed: " + self.closed)
                left = deadline - time.time()
                if left <= 0:
                    raise RuntimeError("no reply to seq %d" % seq)
                self.lock.wait(left)
            err = self.replies.pop(seq)
        if err is not None:
            raise RuntimeError("relay error: " + err)

    def init(self, address):
        self.call(INIT, text(address))

    def set_callback(self, uuid):
        self.call(SET_CALLBACK, text(uuid))

    def write(self, uuid, data):
        self.call(WRITE, text(uuid) + u16(len(data)) + data)

    def end(self):
        self.sock.sendall(bytes([END]))
        self.sock.close()


def packet(did, cid, seq, data=b""):
    """An API v2 command asking for a response (flags 0x0A: requests response, activity)."""
    body = bytes([0x0A, did, cid, seq]) + bytes(data)
    chk = 0xFF - (sum(body) & 0xFF)
    out = bytearray([SOP])
    for b in body + bytes([chk]):
        if b in ESCAPED:
            out += bytes([ESC, ESCAPED[b]])
        else:
            out.append(b)
    out.append(EOP)
    return bytes(out)


def packets(stream):
    """Whole v2 packets (unescaped bodies without checksum) in a byte stream."""
    out, cur, esc, inside = [], bytearray(), False, False
    back = {v: k for k, v in ESCAPED.items()}
    for b in stream:
        if b == SOP:
            cur, esc, inside = bytearray(), False, True
        elif not inside:
            continue
        elif b == EOP:
            if len(cur) >= 2 and (sum(cur[:-1]) + cur[-1]) & 0xFF == 0xFF:
                out.append(bytes(cur[:-1]))
            inside = False
        elif b == ESC:
            esc = True
        else:
            cur.append(back.get(b, b) if esc else b)
            esc = False
    return out


def main():
    host, port = sys.argv[1], int(sys.argv[2])
    seen = {}
    devices = discover(host, port, bytes([SCAN]) + struct.pack(">f", 1.0))
    seen["scanned"] = [name for name, _ in devices]
    name = next(n for n, _ in devices if n.startswith("D2-"))
    found = discover(host, port, bytes([FIND]) + text(name) + struct.pack(">f", 1.0))
    address = found[0][1]
    seen["not_found"] = discover(host, port, bytes([FIND]) + text("D2-NONE") + struct.pack(">f", 0.2)) is None

    s = Session(host, port)
    s.init(address)
    # The handshake, as a toy does it: the unlock, then notifications.
    s.write(ANTI_DOS, UNLOCK)
    s.set_callback(API)

    seq = [0]

    def send(did, cid, data=b""):
        p = packet(did, cid, seq[0], data)
        seq[0] = (seq[0] + 1) % 256
        for i in range(0, len(p), 20):  # 20-byte writes, as over BLE
            s.write(API, p[i : i + 20])
        time.sleep(0.12)

    def stream():
        with s.lock:
            return b"".join(d for u, d in s.notifications if u.lower() == API)

    send(0x13, 0x0D)  # wake
    send(0x17, 0x0D, [1])  # perform leg action: tripod
    time.sleep(2.2)  # the stance change
    # Sensor streaming every 100 ms: locator x and y (mask 0x60).
    send(0x18, 0x00, u16(100) + bytes([0]) + struct.pack(">I", 0x60))
    for _ in range(6):  # drive at speed 120 toward 0° for about 1.5 s
        send(0x16, 0x07, bytes([120]) + u16(0) + bytes([0]))
        time.sleep(0.13)
    send(0x16, 0x07, bytes([0]) + u16(0) + bytes([0]))
    time.sleep(0.5)
    got = packets(stream())
    s.end()

    responses = [(p[1], p[2]) for p in got if p[0] & 0x01]
    seen["wake_response"] = (0x13, 0x0D) in responses
    seen["stance_response"] = (0x17, 0x0D) in responses
    samples = [p for p in got if p[1:3] == bytes([0x18, 0x02])]
    seen["samples"] = len(samples)
    if samples:
        # Flags, DID, CID, SEQ (no error byte in an async), then x and y in metres.
        x, y = struct.unpack(">ff", samples[-1][4:12])
        seen["x_cm"], seen["y_cm"] = x * 100, y * 100
    seen["notifications"] = len(s.notifications)
    print(json.dumps(seen))


if __name__ == "__main__":
    main()
