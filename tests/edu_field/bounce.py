"""The twin of bounce.js: it runs 8 s, as `droidctl run --timeout 8` ends the JavaScript."""

from spherov2.sphero_edu import EventType
from spherov2.types import Color

HOLD = 8


def on_collision(api):
    api.stop_roll()
    api.set_main_led(Color(255, 0, 0))
    api.set_heading(270)


def program(api):
    api.register_event(EventType.on_collision, on_collision)
    api.set_main_led(Color(0, 255, 0))
    api.set_heading(90)
    api.set_speed(150)
