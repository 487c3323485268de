#!/usr/bin/env python3
"""spherov2.py's Sphero Edu API driving a simulated BOLT or Mini (run by tests/sphero_edu_e2e.rs
when a Python with spherov2 and bleak is at hand): find the toy through `droidctl serve`
(spherov2's TCP adapter) or on the virtual BlueZ of `droidctl sim --bluez` (bleak, with
DBUS_SYSTEM_BUS_ADDRESS pointing at its bus), roll east, and on BOLT draw a matrix character.

Usage: sphero_edu.py tcp PORT NAME | sphero_edu.py bleak NAME
Prints one JSON object: the class spherov2 made of the toy, and the location its sensor
streaming reported after the roll.
"""

import json
import sys
import time

from spherov2 import scanner
from spherov2.sphero_edu import SpheroEduAPI
from spherov2.toy.bolt import BOLT
from spherov2.types import Color


def find_toy(args):
    """The toy `args` name: `tcp PORT NAME` (through `droidctl serve` on loopback) or `bleak
    NAME` (on the bus DBUS_SYSTEM_BUS_ADDRESS names). Also used by sphero_edu_models.py."""
    if args[0] == "tcp":
        from spherov2.adapter.tcp_adapter import get_tcp_adapter

        adapter, name = get_tcp_adapter("127.0.0.1", int(args[1])), args[2]
    else:
        from spherov2.adapter.bleak_adapter import BleakAdapter

        adapter, name = BleakAdapter, args[1]
    return scanner.find_toy(toy_name=name, adapter=adapter, timeout=5.0)


def main():
    toy = find_toy(sys.argv[1:])
    with SpheroEduAPI(toy) as api:
        if isinstance(toy, BOLT):
            api.set_matrix_character("A", Color(255, 0, 0))
        api.roll(90, 100, 1.5)
        time.sleep(0.5)
        location = api.get_location()
    print(json.dumps({"class": type(toy).__name__, "location": location}))


if __name__ == "__main__":
    main()
