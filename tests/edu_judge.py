#!/usr/bin/env python3
"""The Sphero Edu programs of tests/fixtures/edu/*.js written again in Python, run by
spherov2.py's own SpheroEduAPI against `droidctl serve --sim bolt` (tests/it/edu_spherov2.rs
compares where the droid went, its lights and its matrix with droidctl's runs of the
JavaScript).

Usage: edu_judge.py PORT NAME PROGRAM    (PROGRAM: square, pong, spin, matrix, animation)
Prints one JSON object: the location spherov2 read at the end of the program.

       edu_judge.py PORT infrared SENDER LISTENER BEACON
Infrared between three robots of one `droidctl serve --sim rvr rvr bolt` room, driven by
spherov2's own API: the sender's message reaches the listener's on_ir_message; then the
listener follows the beacon. Prints what the listener heard and where it went.
"""

import json
import sys
import threading
import time

from spherov2.sphero_edu import EventType, SpheroEduAPI
from spherov2.types import Color

from sphero_edu import find_toy


def square(api):
    colours = [Color(255, 0, 0), Color(0, 255, 0), Color(0, 0, 255), Color(255, 255, 0)]
    for side in range(4):
        api.set_main_led(colours[side])
        api.roll(side * 90, 80, 1)
        time.sleep(0.5)
    api.set_main_led(Color(255, 255, 255))


def pong(api):
    done = threading.Event()
    hits = [0]

    def on_collision(api):
        hits[0] += 1
        api.stop_roll()
        api.set_main_led(Color(255, 0, 0))
        if hits[0] >= 3:
            done.set()
            return
        time.sleep(0.5)
        api.set_main_led(Color(0, 255, 0))
        api.set_heading((api.get_heading() + 180) % 360)
        api.set_speed(100)

    api.register_event(EventType.on_collision, on_collision)
    api.set_main_led(Color(0, 255, 0))
    api.set_heading(0)
    api.set_speed(100)
    done.wait(60)


def spin(api):
    api.set_main_led(Color(0, 0, 255))
    api.roll(0, 60, 1)
    api.spin(450, 1.5)
    api.roll(api.get_heading(), 60, 1)
    api.spin(-90, 1)
    api.roll(api.get_heading(), 60, 1)


def matrix(api):
    api.set_matrix_character("A", Color(255, 0, 0))
    time.sleep(1)
    api.clear_matrix()
    api.set_main_led(Color(0, 0, 0))
    api.set_matrix_line(0, 0, 7, 0, Color(0, 0, 255))
    api.set_matrix_fill(2, 2, 5, 5, Color(0, 255, 0))
    api.set_matrix_pixel(7, 7, Color(255, 255, 255))
    api.set_front_led(Color(255, 0, 255))
    api.set_back_led(Color(0, 255, 255))
    time.sleep(1)


ARROW = [
    [1, 1, 1, 0, 0, 0, 0, 0],
    [1, 1, 0, 0, 0, 0, 0, 0],
    [1, 0, 1, 0, 0, 0, 0, 0],
    [0, 0, 0, 1, 0, 0, 0, 0],
    [0, 0, 0, 0, 1, 0, 0, 0],
    [0, 0, 0, 0, 0, 1, 0, 0],
    [0, 0, 0, 0, 0, 0, 1, 0],
    [0, 0, 0, 0, 0, 0, 0, 2],
]
STRIPES = [
    [0, 1, 2, 3, 4, 5, 6, 7],
    [8, 9, 10, 11, 12, 13, 14, 15],
    [15, 14, 13, 12, 11, 10, 9, 8],
    [7, 6, 5, 4, 3, 2, 1, 0],
    [0, 0, 0, 0, 15, 15, 15, 15],
    [9, 0, 9, 0, 9, 0, 9, 0],
    [0, 0, 0, 0, 0, 0, 0, 0],
    [3, 3, 3, 3, 3, 3, 3, 12],
]


def animation(api):
    palette = [Color(i * 16, 255 - i * 16, (i * 37) % 256) for i in range(16)]
    api.register_matrix_animation([ARROW], [Color(0, 0, 0), Color(255, 0, 0), Color(0, 0, 255)], 5, False)
    api.register_matrix_animation([ARROW, STRIPES, ARROW, STRIPES], palette, 4, False)
    api.play_matrix_animation(0, True)
    time.sleep(1)
    api.play_matrix_animation(1, False)
    time.sleep(2)
    api.set_front_led(Color(255, 0, 255))
    time.sleep(0.5)


def infrared(port, names):
    sender, listener, beacon = (find_toy(["tcp", port, n]) for n in names)
    heard = []
    got = threading.Event()
    with SpheroEduAPI(sender) as tx, SpheroEduAPI(listener) as rx, SpheroEduAPI(beacon) as bc:

        def on_ir_message(api, channel):
            heard.append([channel, api.get_last_ir_message()])
            got.set()

        rx.register_event(EventType.on_ir_message, on_ir_message)
        rx.listen_for_ir_message(3)
        time.sleep(0.5)
        tx.send_ir_message(3, 64)
        got.wait(5)
        start = rx.get_location()
        bc.start_ir_broadcast(0, 1)
        rx.start_ir_follow(0, 1)
        time.sleep(3)
        rx.stop_ir_follow()
        bc.stop_ir_broadcast()
        time.sleep(0.5)
        end = rx.get_location()
    print(json.dumps({"heard": heard, "start": start, "end": end}))


def main():
    if sys.argv[2] == "infrared":
        infrared(sys.argv[1], sys.argv[3:6])
        return
    port, name, program = sys.argv[1:4]
    toy = find_toy(["tcp", port, name])
    with SpheroEduAPI(toy) as api:
        time.sleep(0.5)
        globals()[program](api)
        time.sleep(1.0)
        location = api.get_location()
    print(json.dumps({"location": location}))


if __name__ == "__main__":
    main()
