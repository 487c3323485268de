"""Sphero's own RVR SDK (`sphero-sdk` on PyPI, 0.3.4) drives `droidctl sim --serial rvr` on
its pseudo-terminal, through the SDK's serial client (`SpheroRvrAsync` with `SerialAsyncDal`,
over pyserial): what a Raspberry Pi on RVR's UART runs. Run by tests/it/serial_sdk.rs.

Usage: python sphero_sdk_rvr.py PTY

The SDK needs no Raspberry Pi library (only pyserial, pyserial-asyncio and aiohttp, all from
PyPI): nothing is stood in for.

Prints one JSON line per step: {"step": NAME, "ok": bool, "value": ...}; then
{"done": true, "failed": [...]}. Exit status 0 when every step got what it waited for.
"""

import asyncio
import datetime
import json
import os
import sys

import sphero_sdk
from sphero_sdk import (
    Colors,
    InfraredCodes,
    RawMotorModesEnum,
    RvrLedGroups,
    RvrStreamingServices,
    SerialAsyncDal,
    SpheroRvrAsync,
    SpheroRvrTargets,
)

PORT = sys.argv[1]
STEP_TIMEOUT = 3.0
failed = []


def say(step, ok, value=None):
    if not ok:
        failed.append(step)
    print(json.dumps({"step": step, "ok": bool(ok), "value": value}, default=str), flush=True)


# The SDK checks RVR's firmware against Sphero's web service when it starts, at most once a
# week (a timestamp file beside the package), and waits for a key press when it finds newer
# firmware. The test must not reach the network: the timestamp says "just checked". The
# version requests it would have sent are sent below, explicitly.
site = os.path.abspath(os.path.join(os.path.dirname(sphero_sdk.__file__), ".."))
with open(os.path.join(site, ".fw"), "w") as f:
    f.write(str(datetime.datetime.now().timestamp()))

loop = asyncio.new_event_loop()
asyncio.set_event_loop(loop)
rvr = SpheroRvrAsync(dal=SerialAsyncDal(loop, device=PORT))


async def ask(step, coro, check=lambda v: v is not None):
    try:
        v = await asyncio.wait_for(coro, STEP_TIMEOUT + 1)
    except Exception as e:  # a timeout, a parse error: the step failed
        say(step, False, repr(e))
        return None
    say(step, check(v), v)
    return v


async def main():
    primary, secondary = SpheroRvrTargets.primary.value, SpheroRvrTargets.secondary.value
    await ask("echo", rvr.echo(data=[1, 2, 3], target=secondary, timeout=STEP_TIMEOUT),
              lambda v: v and list(v["data"]) == [1, 2, 3])
    await ask("wake", rvr.wake(timeout=STEP_TIMEOUT), lambda v: True)
    await asyncio.sleep(0.3)
    for name, target in (("nordic", primary), ("st", secondary)):
        await ask("version " + name,
                  rvr.get_main_application_version(target=target, timeout=STEP_TIMEOUT),
                  lambda v: v and "major" in v)

    # Battery.
    await ask("battery percentage", rvr.get_battery_percentage(timeout=STEP_TIMEOUT),
              lambda v: v and 0 <= v["percentage"] <= 100)
    await ask("battery voltage state", rvr.get_battery_voltage_state(timeout=STEP_TIMEOUT),
              lambda v: v and "state" in v)
    await ask("battery volts", rvr.get_battery_voltage_in_volts(reading_type=1, timeout=STEP_TIMEOUT),
              lambda v: v and 2.0 < v["voltage"] < 20.0)

    # Sensor streaming: IMU and locator (RVR's secondary processor streams them) and the
    # ambient light (its primary), four samples each at least.
    samples = {"imu": 0, "locator": 0, "ambient light": 0}

    async def on_imu(data):
        samples["imu"] += 1

    async def on_locator(data):
        samples["locator"] += 1

    await rvr.sensor_control.add_sensor_data_handler(service=RvrStreamingServices.imu, handler=on_imu)
    await rvr.sensor_control.add_sensor_data_handler(service=RvrStreamingServices.locator, handler=on_locator)

    async def on_light(data):
        samples["ambient light"] += 1

    await rvr.sensor_control.add_sensor_data_handler(service=RvrStreamingServices.ambient_light,
                                                     handler=on_light)
    await rvr.sensor_control.start(interval=100)

    # Drive with a heading, then raw motors, then stop.
    await rvr.reset_yaw(timeout=STEP_TIMEOUT)
    await ask("drive with heading", rvr.drive_with_heading(speed=64, heading=90, flags=0,
                                                           timeout=STEP_TIMEOUT), lambda v: True)
    await asyncio.sleep(1.0)
    await ask("raw motors", rvr.raw_motors(left_mode=RawMotorModesEnum.forward.value, left_speed=80,
                                           right_mode=RawMotorModesEnum.reverse.value, right_speed=80,
                                           timeout=STEP_TIMEOUT), lambda v: True)
    await asyncio.sleep(0.5)
    await ask("stop", rvr.drive_with_heading(speed=0, heading=90, flags=0, timeout=STEP_TIMEOUT),
              lambda v: True)
    await asyncio.sleep(0.5)
    await rvr.sensor_control.clear()
    await asyncio.sleep(0.3)
    say("streamed imu", samples["imu"] >= 4, samples["imu"])
    say("streamed locator", samples["locator"] >= 4, samples["locator"])
    say("streamed ambient light", samples["ambient light"] >= 4, samples["ambient light"])

    # LEDs: every light, and the SDK's colour helpers.
    await ask("set all leds", rvr.set_all_leds(led_group=RvrLedGroups.all_lights.value,
                                               led_brightness_values=[255, 0, 0] * 10,
                                               timeout=STEP_TIMEOUT), lambda v: True)
    await rvr.led_control.set_all_leds_color(color=Colors.green)
    await rvr.led_control.turn_leds_off()

    # Infrared: broadcast, follow, send a message, listen.
    heard = []

    async def on_ir(data):
        heard.append(data)

    await rvr.infrared_control.start_infrared_broadcasting(far_code=InfraredCodes.one,
                                                           near_code=InfraredCodes.two)
    await rvr.infrared_control.stop_infrared_broadcasting()
    await rvr.infrared_control.start_infrared_following(far_code=InfraredCodes.three,
                                                        near_code=InfraredCodes.four)
    await rvr.infrared_control.stop_infrared_following()
    await rvr.infrared_control.listen_for_infrared_message(handler=on_ir)
    await rvr.infrared_control.send_infrared_messages(messages=[InfraredCodes.five], strength=64)
    await ask("bot to bot infrared readings", rvr.get_bot_to_bot_infrared_readings(timeout=STEP_TIMEOUT))

    # Colour detection: the sensor, one reading, the notifications.
    colours = []

    async def on_colour(data):
        colours.append(data)

    await ask("enable color detection", rvr.enable_color_detection(is_enabled=True, timeout=STEP_TIMEOUT),
              lambda v: True)
    await rvr.on_color_detection_notify(handler=on_colour)
    await ask("color detection notify", rvr.enable_color_detection_notify(
        is_enabled=True, interval=100, minimum_confidence_threshold=0, timeout=STEP_TIMEOUT), lambda v: True)
    await asyncio.sleep(1.0)
    await ask("current detected color", rvr.get_current_detected_color_reading(timeout=STEP_TIMEOUT),
              lambda v: True)
    await ask("rgbc sensor values", rvr.get_rgbc_sensor_values(timeout=STEP_TIMEOUT),
              lambda v: v and "redChannelValue" in v)
    await ask("ambient light", rvr.get_ambient_light_sensor_value(timeout=STEP_TIMEOUT),
              lambda v: v and v["ambientLightValue"] > 0)
    await rvr.enable_color_detection_notify(is_enabled=False, interval=0, minimum_confidence_threshold=0)
    await rvr.enable_color_detection(is_enabled=False)
    say("color notifications", len(colours) >= 2, len(colours))

    await rvr.close()
    await asyncio.sleep(0.2)


loop.run_until_complete(main())
print(json.dumps({"done": True, "failed": failed}), flush=True)
sys.exit(1 if failed else 0)
