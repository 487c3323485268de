"""The twin of unawaited.js: the un-awaited helper is a thread."""

import threading
import time

from spherov2.types import Color


def flash(api):
    for _ in range(4):
        api.set_main_led(Color(255, 128, 0))
        time.sleep(0.25)
        api.set_main_led(Color(0, 0, 0))
        time.sleep(0.25)
    api.set_back_led(Color(0, 0, 255))


def program(api):
    helper = threading.Thread(target=flash, args=(api,))
    helper.start()
    api.roll(0, 70, 1.5)
    api.roll(180, 70, 1)
    time.sleep(1)
    helper.join()
