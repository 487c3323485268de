"""The twin of first_sensors.js."""

import time

from spherov2.types import Color


def program(api):
    # spherov2 reads None until the first sample is in: Sphero Edu's robots read numbers.
    yaw = (api.get_orientation() or {"yaw": 0})["yaw"]
    accel = api.get_acceleration() or {"z": 1}
    where = api.get_location() or {"x": 0}
    spin = (api.get_gyroscope() or {"z": 0})["z"]
    moving = api.get_velocity() or {"y": 0}
    if accel["z"] > 0.5 and where["x"] == 0 and moving["y"] == 0 and spin == 0:
        api.set_main_led(Color(0, 255, 0))
    else:
        api.set_main_led(Color(255, 0, 0))
    heading = round(yaw)
    for side in range(4):
        api.roll(heading + side * 90, 60, 1)
    api.set_main_led(Color(255, 255, 255))
    time.sleep(1)
