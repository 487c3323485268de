"""The twin of maze_animation.js."""

import time

from spherov2.types import Color

arrow = [
    [0, 0, 0, 1, 1, 0, 0, 0],
    [0, 0, 1, 1, 1, 1, 0, 0],
    [0, 1, 0, 1, 1, 0, 1, 0],
    [1, 0, 0, 1, 1, 0, 0, 1],
    [0, 0, 0, 1, 1, 0, 0, 0],
    [0, 0, 0, 1, 1, 0, 0, 0],
    [0, 0, 0, 1, 1, 0, 0, 0],
    [0, 0, 0, 2, 2, 0, 0, 0],
]
blank = [
    [0, 0, 0, 0, 0, 0, 0, 0],
    [0, 0, 0, 0, 0, 0, 0, 0],
    [0, 0, 0, 0, 0, 0, 0, 0],
    [0, 0, 0, 2, 2, 0, 0, 0],
    [0, 0, 0, 2, 2, 0, 0, 0],
    [0, 0, 0, 0, 0, 0, 0, 0],
    [0, 0, 0, 0, 0, 0, 0, 0],
    [0, 0, 0, 0, 0, 0, 0, 0],
]


def program(api):
    api.register_matrix_animation(
        [arrow, blank, arrow], [Color(0, 0, 0), Color(255, 255, 0), Color(0, 128, 255)], 4, False
    )
    api.play_matrix_animation(0, False)
    api.roll(0, 70, 1)
    time.sleep(0.5)
    api.set_matrix_line(0, 0, 7, 0, Color(255, 0, 0))
    api.set_matrix_pixel(3, 4, Color(0, 255, 0))
    api.roll(90, 70, 1)
    api.set_matrix_fill(5, 5, 7, 7, Color(0, 0, 255))
    api.set_front_led(Color(255, 255, 0))
    api.set_back_led(Color(255, 0, 0))
    time.sleep(0.5)
