#!/usr/bin/env python3
"""spherov2.py's Sphero Edu API against one simulated model, through `droidctl serve --sim`
(spherov2's TCP adapter) or on the virtual BlueZ of `droidctl sim --bluez` (bleak, with
DBUS_SYSTEM_BUS_ADDRESS pointing at its bus); run by tests/it/relay_e2e.rs when a Python with
spherov2 is at hand (issue 32): spin(360, 1) while sampling the streamed yaw, raw motors on a
v1 droid, then a roll east into the wall with collision detection.

Usage: sphero_edu_models.py tcp PORT NAME | sphero_edu_models.py bleak NAME
Prints one JSON object:
  class         the class spherov2 made of the toy
  yaw           [t_s, yaw] streamed from the start of the spin to a second after it
  gyro          [t_s, z] the gyroscope's yaw rate (°/s, get_gyroscope()["z"]) at the same times
  raw_location  get_location() after raw_motor(80, 80, 1.5) (v1 droids only, else null)
  location      get_location() after the roll east into the wall
  collisions    the collision notifications spherov2 decoded: x_axis, y_axis, accel x/y
"""

import json
import sys
import threading
import time

from spherov2.sphero_edu import SpheroEduAPI
from spherov2.toy.sphero import Sphero

from sphero_edu import find_toy


def main():
    toy = find_toy(sys.argv[1:])
    out = {"class": type(toy).__name__, "yaw": [], "gyro": [], "raw_location": None,
           "collisions": []}
    v1 = isinstance(toy, Sphero)  # BB-8, SPRK+ and Ollie derive from spherov2's v1 Sphero
    with SpheroEduAPI(toy) as api:
        time.sleep(0.5)
        # The streamed yaw, every 20 ms, while spherov2 spins the droid.
        sampling = threading.Event()
        start = time.time()

        def sample():
            while not sampling.is_set():
                o = api.get_orientation()
                if o is not None:
                    out["yaw"].append([time.time() - start, o["yaw"]])
                g = api.get_gyroscope()
                if g is not None:
                    out["gyro"].append([time.time() - start, g["z"]])
                time.sleep(0.02)

        sampler = threading.Thread(target=sample)
        sampler.start()
        api.spin(360, 1)
        time.sleep(1.0)
        sampling.set()
        sampler.join()

        if v1:
            api.raw_motor(80, 80, 1.5)
            time.sleep(0.5)
            out["raw_location"] = api.get_location()

        if hasattr(toy, "add_collision_detected_notify_listener"):
            def hit(c):
                out["collisions"].append({
                    "x_axis": bool(c.x_axis), "y_axis": bool(c.y_axis),
                    "accel_x": c.acceleration_x, "accel_y": c.acceleration_y,
                })
            toy.add_collision_detected_notify_listener(hit)
        api.roll(90, 200, 3.5)
        time.sleep(0.5)
        out["location"] = api.get_location()
    print(json.dumps(out))


if __name__ == "__main__":
    main()
