"""The twin of light_loop.js."""

import time

from spherov2.types import Color

colours = [Color(255, 0, 0), Color(0, 255, 0), Color(0, 0, 255)]


def program(api):
    for side in range(6):
        api.set_main_led(colours[side % 3])
        api.roll(side * 60, 50, 0.6)
    time.sleep(0.5)
    for i in range(10):
        api.set_main_led(colours[i % 3])
        time.sleep(0.1)
    api.set_main_led(colours[1])
    time.sleep(0.5)
