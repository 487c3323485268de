"""A mixed Sphero API v2 stream as spherov2.py's own `Packet.build` makes it, and spherov2's
`Packet.Collector` timed on it as a BLE link feeds it (20-byte chunks).

The case a user meets (issue 42 point 6): half sensor-streaming notifications of 17 f32 values
(no masks given to the decoder), drive commands, responses, and LED commands whose values are
the framing bytes (so they need escapes). `benches/spherov2_compare.sh` writes the stream with
`write`, times `droidctl packet decode --file - --json` on it (stdin to a file), and runs
`time` for spherov2's side.

Usage: python spherov2_mixed.py write PATH PACKETS
       python spherov2_mixed.py time PATH        (prints: packets seconds packets/s)
"""

import random
import struct
import sys
import time

from spherov2.controls.v2 import Packet

F = Packet.Flags


def packets(count):
    """`count` packets, in the proportions of benches/codec.rs's mixed stream."""
    rng = random.Random(0xC0FFEE)
    manager = Packet.Manager()
    for i in range(count):
        kind = i % 10
        if kind < 5:
            # A sensor-streaming notification (Sensor 0x18, 0x02): 17 floats, SEQ 0xFF.
            values = [rng.uniform(-300.0, 300.0) for _ in range(17)]
            data = bytearray(struct.pack(">17f", *values))
            yield Packet(F(0), 0x18, 0x02, 0xFF, None, None, data)
        elif kind < 7:
            # Drive With Heading (Drive 0x07): speed, heading, flags.
            heading = rng.randrange(360)
            data = [rng.randrange(256), heading >> 8, heading & 0xFF, rng.choice([0, 1])]
            yield manager.new_packet(0x16, 0x07, data=data)
        elif kind < 9:
            # A response: to a drive (empty) or to Get Battery Voltage (u16).
            request = manager.new_packet(*rng.choice([(0x16, 0x07), (0x13, 0x03)]))
            data = bytearray(struct.pack(">H", 380 + rng.randrange(40))) if request.did == 0x13 else bytearray()
            flags = F.is_response | (request.flags & F.is_activity)
            yield Packet(flags, request.did, request.cid, request.seq, None, None, data, Packet.Error.success)
        else:
            # Set All LEDs With 16-bit Mask (IO 0x0E), values that are SOP, ESC and EOP.
            data = [0x00, 0xFF, 0x8D, 0xAB, 0xD8, 0x00, 0xFF, 0x8D, 0xD8, 0xAB]
            yield manager.new_packet(0x1A, 0x0E, data=data)


def write(path, count):
    with open(path, "wb") as f:
        for p in packets(count):
            f.write(p.build())


def time_collector(path):
    data = open(path, "rb").read()
    count = [0]

    def counted(_packet):
        count[0] += 1

    collector = Packet.Collector(counted)
    start = time.perf_counter()
    for i in range(0, len(data), 20):
        collector.add(data[i : i + 20])
    took = time.perf_counter() - start
    print(f"{count[0]} {took:.4f} {count[0] / took:.0f}")


if __name__ == "__main__":
    if sys.argv[1] == "write":
        write(sys.argv[2], int(sys.argv[3]))
    else:
        time_collector(sys.argv[2])
