#!/usr/bin/env python3
"""sphero-unsw's own Sphero Edu API (a spherov2 fork with the Sphero BOLT+, PyPI `sphero-unsw`)
driving a simulated BOLT+ through `droidctl serve --sim boltplus` (its TCP adapter, as
spherov2's): run by tests/it/sphero_unsw.rs when a Python with sphero-unsw is at hand.

The checks spherov2's Edu API runs on the other models (tests/sphero_edu_models.py): spin while
sampling the streamed yaw, heading, the lights, every sensor getter, the compass, infrared
broadcasting, the screen calls sphero-unsw has (BOLT's matrix calls: character, text, pixel,
line, fill, rotation, an animation), then a roll east into the wall with collisions counted both
as sphero-unsw's Edu API reports them (its own software detection from the streamed sensors, and
the robot's notification) and as the toy's raw collision notifications.

Usage: sphero_unsw_edu.py tcp PORT NAME | sphero_unsw_edu.py bleak NAME
(bleak: on the virtual BlueZ of `droidctl sim --bluez boltplus`, DBUS_SYSTEM_BUS_ADDRESS
pointing at its bus)
Prints one JSON object:
  class        the class sphero-unsw made of the toy (BOLTPLUS)
  yaw          [t_s, yaw] streamed from the start of the spin to a second after it
  heading      get_heading() after set_heading(45)
  sensors      every getter's answer after the spin (acceleration, orientation, gyroscope,
               velocity, location, distance, speed, luminosity, compass)
  lights       get_main_led(), get_front_led(), get_back_led() after setting them
  location     get_location() after the roll east into the wall
  collisions   on_collision events sphero-unsw's Edu API fired during the roll
  notified     raw collision notifications (x_axis, y_axis, accel x/y)
  secondary_version  get_secondary_main_app_version() (its notification followed)
"""

import json
import sys
import threading
import time

from sphero_unsw import scanner
from sphero_unsw.adapter.tcp_adapter import get_tcp_adapter
from sphero_unsw.commands.io import FrameRotationOptions
from sphero_unsw.sphero_edu import EventType, SpheroEduAPI
from sphero_unsw.types import Color


def main():
    if sys.argv[1] == "tcp":
        adapter, name = get_tcp_adapter("127.0.0.1", int(sys.argv[2])), sys.argv[3]
    else:
        from sphero_unsw.adapter.bleak_adapter import BleakAdapter

        adapter, name = BleakAdapter, sys.argv[2]
    toy = scanner.find_toy(toy_name=name, adapter=adapter, timeout=5.0)
    out = {"class": type(toy).__name__, "yaw": [], "collisions": 0, "notified": []}
    with SpheroEduAPI(toy) as api:
        time.sleep(0.5)
        sampling = threading.Event()
        start = time.time()

        def sample():
            while not sampling.is_set():
                o = api.get_orientation()
                if o is not None:
                    out["yaw"].append([time.time() - start, o["yaw"]])
                time.sleep(0.02)

        sampler = threading.Thread(target=sample)
        sampler.start()
        api.spin(360, 1)
        time.sleep(1.0)
        sampling.set()
        sampler.join()

        api.set_heading(45)
        time.sleep(0.3)
        out["heading"] = api.get_heading()
        api.stop_roll()

        # Lights: the main light fills the screen on BOLT+ (sphero-unsw), front and back LEDs.
        api.set_main_led(Color(0, 0, 255))
        api.set_front_led(Color(255, 0, 0))
        api.set_back_led(Color(0, 255, 0))
        out["lights"] = {
            "main": api.get_main_led(),
            "front": api.get_front_led(),
            "back": api.get_back_led(),
        }

        # The screen, through BOLT's matrix calls (all sphero-unsw has for it).
        api.set_matrix_character("A", Color(255, 0, 0))
        api.scroll_matrix_text("HI", Color(0, 255, 0), 30, False)
        api.set_matrix_pixel(1, 2, Color(255, 255, 0))
        api.set_matrix_line(0, 0, 7, 7, Color(0, 255, 255))
        api.set_matrix_fill(2, 2, 5, 5, Color(255, 0, 255))
        api.set_matrix_rotation(FrameRotationOptions.ROTATE_90_DEGREES)
        red, blue = Color(255, 0, 0), Color(0, 0, 255)
        frames = [[[1] * 8 for _ in range(8)], [[2] * 8 for _ in range(8)]]
        api.register_matrix_animation(frames, [Color(0, 0, 0), red, blue], 10, False)
        api.play_matrix_animation(0, True)
        time.sleep(0.3)
        api.pause_matrix_animation()
        api.resume_matrix_animation()
        api.clear_matrix()

        # Sensors and the compass.
        api.calibrate_compass()
        time.sleep(0.3)
        out["sensors"] = {
            "acceleration": api.get_acceleration(),
            "orientation": api.get_orientation(),
            "gyroscope": api.get_gyroscope(),
            "velocity": api.get_velocity(),
            "location": api.get_location(),
            "distance": api.get_distance(),
            "speed": api.get_speed(),
            "luminosity": api.get_luminosity(),
            "compass": api.get_compass_direction(),
        }

        # The secondary processor's version: a response, then the version as a notification.
        out["secondary_version"] = list(toy.get_secondary_main_app_version())

        # Infrared: broadcasting on channels 0 and 1, then stopped.
        api.start_ir_broadcast(0, 1)
        api.stop_ir_broadcast()

        # Collisions: the roll east ends against the wall.
        def on_collision(_api):
            out["collisions"] += 1

        api.register_event(EventType.on_collision, on_collision)

        def hit(c):
            out["notified"].append({
                "x_axis": bool(c.x_axis), "y_axis": bool(c.y_axis),
                "accel_x": c.acceleration_x, "accel_y": c.acceleration_y,
            })

        toy.add_collision_detected_notify_listener(hit)
        api.reset_aim()
        api.roll(90, 200, 3.5)
        time.sleep(0.5)
        out["location"] = api.get_location()
    print(json.dumps(out))


if __name__ == "__main__":
    main()
