"""The twin of droid_r2.js."""

import time

from spherov2.types import Color


def program(api):
    api.set_holo_projector_led(255)
    api.set_logic_display_leds(128)
    api.set_dome_position(90)
    api.set_front_led(Color(0, 0, 255))
    api.roll(0, 80, 1.5)
    time.sleep(0.5)
    api.set_dome_position(-90)
    api.set_back_led(Color(255, 0, 0))
    api.roll(180, 80, 1)
    api.set_holo_projector_led(0)
    api.set_dome_position(0)
    time.sleep(1)
