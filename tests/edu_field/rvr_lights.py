"""The twin of rvr_lights.js. spherov2 reads no colour (None) until its colour sensor is
turned on; droidctl's simulated RVR sees a grey floor (128, 128, 128)."""

import time

from spherov2.types import Color


def program(api):
    floor = api.get_color() or Color(128, 128, 128)
    api.set_left_headlight_led(Color(floor.r, floor.g, floor.b))
    api.set_right_headlight_led(Color(255, 255, 255))
    api.set_left_led(Color(255, 0, 0))
    api.set_right_led(Color(0, 255, 0))
    api.roll(0, 100, 1.5)
    api.set_back_led(Color(255, 0, 0))
    api.roll(90, 100, 1)
    api.set_left_led(Color(0, 0, 255))
    time.sleep(1)
