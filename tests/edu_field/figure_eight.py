"""The twin of figure_eight.js."""

import time

from spherov2.types import Color


def program(api):
    api.set_main_led(Color(0, 0, 255))
    api.set_speed(50)
    api.spin(360, 2)
    api.set_main_led(Color(255, 0, 255))
    api.spin(-360, 2)
    api.stop_roll()
    time.sleep(0.5)
    api.raw_motor(80, 80, 0.8)
    time.sleep(0.5)
    api.set_main_led(Color(255, 255, 255))
    time.sleep(0.5)
