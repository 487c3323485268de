"""The twin of sounds.js. Sphero Edu plays these sounds on the phone or tablet: a waited one
is its length (1 s, droidctl's guess, src/edu/sounds.rs), one not waited is nothing."""

import time

from spherov2.types import Color


def program(api):
    time.sleep(1)  # await Sound.Animal.Cat.play(true)
    api.roll(90, 80, 1)
    # Sound.Effects.play(false)
    api.roll(270, 80, 0.5)
    time.sleep(1)  # await Sound.play(true)
    api.set_main_led(Color(255, 0, 255))
    # await speak("all done", false)
    time.sleep(0.5)
