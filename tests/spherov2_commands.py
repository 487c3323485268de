#!/usr/bin/env python3
"""Every command spherov2.py builds for an API v2 toy, called method by method (run by
tests/it/spherov2_catalogue.rs when a Python with spherov2 installed is at hand).

For each toy class (R2D2, R2Q5, BB9E, BOLT, Mini, RVR; with `sphero_unsw` as the argument,
that fork's BOLTPLUS, the Sphero BOLT+) and each of its methods that is one of
spherov2's command builders (a `commands.*` static method, bound plainly or through a
partialmethod that names the processor), the builder is called once with fixed arguments on a
toy whose `_execute` records the packet instead of writing it. A method that leaves the
processor to the caller on a toy that requires one (RVR) is called once per processor.

Prints one JSON object a line: toy, method, did, cid, tid, sid, flags, seq, data (hex of the
payload) and wire (hex of the framed packet, as spherov2 writes it); then one summary line a
toy: {"summary": toy, "distinct": number of distinct (did, cid, tid) sent}.

Usage: spherov2_commands.py [sphero_unsw]
"""

import importlib
import inspect
import json
import sys
from enum import IntEnum
from functools import partialmethod

# spherov2 itself, or sphero-unsw (a fork of it under its own package name, with BOLT+).
LIB = sys.argv[1] if len(sys.argv) > 1 else "spherov2"
Commands = importlib.import_module(f"{LIB}.commands").Commands
_controls = importlib.import_module(f"{LIB}.controls.v2")
Packet, Processors = _controls.Packet, _controls.Processors


def _toy(module, name):
    return getattr(importlib.import_module(f"{LIB}.toy.{module}"), name)


if LIB == "sphero_unsw":
    TOYS = [_toy("boltplus", "BOLTPLUS")]
else:
    TOYS = [_toy(m, n) for m, n in [("r2d2", "R2D2"), ("r2q5", "R2Q5"), ("bb9e", "BB9E"),
                                    ("bolt", "BOLT"), ("mini", "Mini"), ("rvr", "RVR")]]

# Arguments by parameter name: fixed values, so the Rust side can rebuild the same packets.
ARGS = {
    "data": [1, 2],
    "command": b"hi",
    "s": 1,
    "s2": 2,
    "s3": 3,
    "s4": 4,
    "s5": 5,
    "b": 6,
    "z": 1,
    "i": 7,
    "i2": 8,
    "i3": 9,
    "i4": 10,
    "i5": 11,
    "j": 0x01020304,
    "j2": 0x05060708,
    "f": 3,
    "f2": 4,
    "f_arr": [1.5, -2.0],
    "s_arr": [1, 2, 3],
    "i_arr": [4, 5],
    "name": b"BOLT",
    "challenge": 0x0A0B0C0D,
    "enable": True,
    "strategy": 1,
    "reset_strategy": 1,
    "speed": 100,
    "heading": 270,
    "drive_flags": 1,
    "left_mode": 1,
    "left_speed": 200,
    "right_mode": 2,
    "right_speed": 50,
    "index": 1,
    "mode": 2,
    "stabilization_index": 1,
    "timeout": 2000,
    "interval": 150,
    "count": 0,
    "sensor_masks": 0x0007E078,
    "collision_detection_method": 1,
    "x_threshold": 90,
    "x_speed": 130,
    "y_threshold": 91,
    "y_speed": 131,
    "dead_time": 10,
    "locator_flags": True,
    "threshold": 0.5,
    "far_code": 3,
    "near_code": 4,
    "minimum_confidence_threshold": 80,
    "token": 1,
    "configuration": [0, 6, 2, 0, 7, 2],
    "period": 100,
    "infrared_code": 5,
    "front_strength": 10,
    "left_strength": 20,
    "right_strength": 30,
    "rear_strength": 40,
    "motor_index": 1,
    "method": 1,
    "level": 2,
    "reading_type": 1,
    "amplifier_id": 1,
    "efuse_id": 1,
    "metadata_version": 1,
    "config_block_version": 2,
    "application_data": [9, 9],
    "animation": 7,
    "leg_action": 2,
    "head_position": 45.0,
    "leg_position": 1.0,
    "sound": 1915,
    "playback_mode": 0,
    "volume": 128,
    "mask": 0x07,
    "values": [255, 0, 128],
    "x": 2,
    "y": 3,
    "r": 255,
    "g": 0,
    "b_": 0,
    "frame_index": 1,
    "compressed_frame": [1, 2, 3, 4],
    "animation_id": 2,
    "fps": 10,
    "fade_animation": True,
    "palette_colors": [255, 0, 0, 0, 255, 0],
    "frames_indexes": [1, 2],
    "fade_options": 1,
    "rotation": None,  # an enum with .value: set below
    "str_to_display": "HI",
    "repeat": True,
    "x1": 0,
    "y1": 1,
    "x2": 7,
    "y2": 6,
    "character": "A",
    "loop": True,
    "rgb_index_bytes": [1, 2, 3],
    "red": 10,
    "green": 20,
    "blue": 30,
    "confidence_threshold": 50,
    "palette_index": 1,
    "enabled": True,
}


class _Rotation(IntEnum):
    ROTATE_90_DEGREES = 1


ARGS["rotation"] = _Rotation.ROTATE_90_DEGREES


class Response:
    """What the fake _execute answers: zeros, enough for most parsers (those that still
    fail raise after the packet was recorded)."""

    data = bytearray(64)

    def check_error(self):
        pass


def builders(cls):
    """(method name, function, fixed keywords) for each command builder of a toy class."""
    out = []
    for name in sorted(dir(cls)):
        attr = inspect.getattr_static(cls, name, None)
        kw = {}
        if isinstance(attr, partialmethod):
            kw = dict(attr.keywords)
            attr = attr.func
        if isinstance(attr, staticmethod):
            attr = attr.__func__
        if not inspect.isfunction(attr):
            continue
        owner = attr.__qualname__.split(".")[0]
        mod = sys.modules.get(attr.__module__)
        owner_cls = getattr(mod, owner, None)
        if not (isinstance(owner_cls, type) and issubclass(owner_cls, Commands)):
            continue
        out.append((name, attr, kw))
    return out


def call(cls, fn, kw):
    """The packets `fn` builds on a fresh toy of `cls` (some builders send two)."""
    toy = cls.__new__(cls)
    toy._packet_manager = Packet.Manager()
    seen = []

    def execute(packet):
        seen.append(packet)
        return Response()

    toy._execute = execute
    params = list(inspect.signature(fn).parameters)[1:]
    args = {}
    for p in params:
        if p == "proc" or p in kw:
            continue
        key = "b_" if p == "b" and fn.__name__.startswith(("set_compressed", "draw_")) else p
        if key not in ARGS:
            raise KeyError(f"{fn.__qualname__}: no argument for {p}")
        args[p] = ARGS[key]
    try:
        fn(toy, **args, **kw)
    except Exception:  # parsing our zeros, or spherov2's own bugs: what was built stands
        pass
    return seen


def main():
    for cls in TOYS:
        distinct = set()
        for name, fn, kw in builders(cls):
            variants = [kw]
            if cls._require_target and "proc" not in kw:
                variants = [dict(kw, proc=Processors.PRIMARY), dict(kw, proc=Processors.SECONDARY)]
            for v in variants:
                for p in call(cls, fn, v):
                    distinct.add((p.did, p.cid, p.tid))
                    print(json.dumps({
                        "toy": cls.__name__,
                        "method": name,
                        "did": p.did,
                        "cid": p.cid,
                        "tid": p.tid,
                        "sid": p.sid,
                        "flags": int(p.flags),
                        "seq": p.seq,
                        "data": bytes(p.data).hex(),
                        "wire": bytes(p.build()).hex(),
                    }))
        print(json.dumps({"summary": cls.__name__, "distinct": len(distinct)}))


if __name__ == "__main__":
    main()
