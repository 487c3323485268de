#!/usr/bin/env python3
"""spherov2.py's own TCP adapter against `droidctl serve` (run by tests/it/relay_e2e.rs when a
Python with spherov2 installed is at hand): find the toy through the relay, then drive it with
spherov2's Sphero Edu API, which connects, unlocks, subscribes, wakes and streams sensors.

Usage: relay_spherov2.py PORT NAME
Prints one JSON object: the toys listed, the class spherov2 made of the one found, and the
location and velocity its sensor streaming reported after a roll.
"""

import json
import sys
import time

from spherov2 import scanner
from spherov2.adapter.tcp_adapter import get_tcp_adapter
from spherov2.sphero_edu import SpheroEduAPI
from spherov2.types import Color


def main():
    port, name = int(sys.argv[1]), sys.argv[2]
    adapter = get_tcp_adapter("127.0.0.1", port)
    listed = [t.name for t in scanner.find_toys(adapter=adapter, timeout=1.0)]
    toy = scanner.find_toy(toy_name=name, adapter=adapter, timeout=1.0)
    with SpheroEduAPI(toy) as api:
        api.set_front_led(Color(255, 0, 0))
        api.roll(0, 100, 1.5)
        time.sleep(0.5)
        location = api.get_location()
    print(json.dumps({"listed": listed, "class": type(toy).__name__, "location": location}))


if __name__ == "__main__":
    main()
