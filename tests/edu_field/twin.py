#!/usr/bin/env python3
"""Run one Python twin of a field-style Sphero Edu program (tests/edu_field/NAME.py, beside
NAME.js) with spherov2.py's own SpheroEduAPI against `droidctl serve --sim MODEL`
(tests/it/edu_twins.rs compares where the simulated droid ends, and its lights and matrix,
with droidctl's run of NAME.js).

Usage: twin.py PORT NAME PROGRAM.py
A twin module defines `program(api)`, written line for line as its JavaScript, and may set
`HOLD` (seconds): a program whose events keep it going (no exitProgram) runs until HOLD
seconds after it started, as `droidctl run --timeout HOLD` ends the JavaScript. Sphero Edu
plays sounds on the phone or tablet, so a twin waits a waited sound's length (1 s, the
length droidctl takes: src/edu/sounds.rs) with time.sleep.
Prints nothing; the pose is read from serve's `droid_released` event.
"""

import importlib.util
import os
import sys
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

from spherov2.commands.animatronic import Animatronic  # noqa: E402
from spherov2.sphero_edu import SpheroEduAPI  # noqa: E402

from sphero_edu import find_toy  # noqa: E402


def quiet_background(api):
    """spherov2's API resends the speed every 0.8 s from a thread (`__background`), a
    keep-alive the simulated droids do not need; on a link with a 120 ms round trip (Mini's)
    a resend that falls just before a timed call's stop holds that stop back a round trip, and
    the roll goes 10 cm further, by chance. The twin keeps the thread but not the resends, so
    its runs are as repeatable as droidctl's."""
    api._SpheroEduAPI__stopped.wait()


def paced_from_write_start(toy):
    """spherov2's writer thread (toy/__init__.py `Toy.__process_packet`) writes a command,
    then sleeps the toy type's `cmd_safe_interval` (120 ms on Mini, 75 on BOLT, 60 on SPRK+):
    its pacing counts from the end of the write. Through serve a write waits for the relay's
    OK over TCP and the adapter's threads, 1-2 ms each time, so its commands went 121.5 ms
    apart on Mini where droidctl's simulated link (whose writes take no time) sends them
    120 ms apart: over a figure eight's 38 round trips that was 59 ms more rolling, 4.3 cm
    (captures, 2026-11-29). That is transport timing, not a semantic of Sphero Edu, so the
    twin counts the interval from the start of each write (as if writing took no time, as in
    droidctl's simulator). Everything else is spherov2's: one command at a time, in order."""
    toy_class = type(toy)
    interval = toy_class.toy_type.cmd_safe_interval

    def writer(self):
        queue = self._Toy__packet_queue
        while self._Toy__adapter is not None:
            payload = queue.get()
            if payload is None:
                break
            due = time.monotonic() + interval
            for at in range(0, len(payload), 20):
                self._Toy__adapter.write(self._send_uuid, payload[at : at + 20])
            time.sleep(max(0.0, due - time.monotonic()))

    toy_class._Toy__process_packet = writer


def on_tripod(toy):
    """An event set when a droid with legs has finished the tripod stance spherov2's
    SpheroEduAPI asks for as it starts (utils.py `set_robot_state_on_start`: THREE_LEGS, not
    waited for); `None` for a robot without legs. R2-D2 rolls only on three legs
    (shared/spec/droid-facts.md section 2) and droidctl's run waits for the tripod before the
    first roll; spherov2's first roll instead starts while the legs still move, and how much of
    it is lost depends on how long its setup's round trips took (5-10 cm on the simulated
    R2-D2). That is transport timing, not a semantic of Sphero Edu, so the twin starts its
    program once the droid stands, as droidctl's first roll does."""
    if not hasattr(toy, "perform_leg_action"):
        return None
    stood = threading.Event()
    # The notification's key (device 0x17, command 0x26, sequence 0xff), as spherov2 names it.
    toy._add_listener(
        (Animatronic.leg_action_complete_notify, lambda done, _packet: done()), stood.set
    )
    return stood


def main():
    port, name, path = sys.argv[1:4]
    spec = importlib.util.spec_from_file_location("twin", path)
    twin = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(twin)
    SpheroEduAPI._SpheroEduAPI__background = quiet_background
    toy = find_toy(["tcp", port, name])
    paced_from_write_start(toy)
    stood = on_tripod(toy)
    with SpheroEduAPI(toy) as api:
        if stood is not None and not stood.wait(10):
            sys.exit("the droid never said its tripod stance was complete")
        start = time.time()
        twin.program(api)
        hold = getattr(twin, "HOLD", 0)
        left = hold - (time.time() - start)
        if left > 0:
            time.sleep(left)


if __name__ == "__main__":
    main()
