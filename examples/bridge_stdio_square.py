#!/usr/bin/env python3
"""Drive a square through `droidctl bridge --stdio`, then stop: Python's standard library only.

    python3 examples/bridge_stdio_square.py --sim bb8          # a simulated BB-8
    python3 examples/bridge_stdio_square.py --name BB-1234     # a real droid

It starts the bridge itself, reads `hello`, waits until the droid's link says
`"ready":true` (a drive before that is held until the droid can move), drives four sides
(heading 0, 90, 180, 270), re-sending each drive well within the command timeout, stops and
waits for the stop's reply, then closes the bridge's input (which stops every droid too).
Each corner is printed as `corner N x_cm=… y_cm=…`. See docs/bridge-integrators.md.
"""

import argparse
import json
import queue
import subprocess
import sys
import threading
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--droidctl", default="droidctl", help="the droidctl program")
    ap.add_argument("--sim", help="simulated model (bb8, r2d2, bolt …)")
    ap.add_argument("--name", help="a real droid's name")
    ap.add_argument("--speed", type=int, default=80, help="0..255")
    ap.add_argument("--side", type=float, default=1.5, help="seconds per side")
    a = ap.parse_args()
    cmd = [a.droidctl, "bridge", "--stdio"]
    cmd += ["--sim", a.sim] if a.sim else ["--name", a.name] if a.name else ["--sim", "bb8"]
    bridge = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    lines = queue.Queue()

    def read():
        for line in bridge.stdout:
            lines.put(json.loads(line))
        lines.put(None)

    threading.Thread(target=read, daemon=True).start()
    latest = {}

    def send(obj):
        bridge.stdin.write(json.dumps(dict(v=1, **obj)) + "\n")
        bridge.stdin.flush()

    def take(until, timeout):
        """Read objects (keeping the latest sample) until `until(obj)` holds."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            try:
                o = lines.get(timeout=max(0.0, end - time.monotonic()))
            except queue.Empty:
                break
            if o is None:
                sys.exit("the bridge ended")
            if o["type"] == "telemetry":
                latest.update(o)
            if o["type"] == "error":
                print("error:", o["error"], file=sys.stderr)
            if until(o):
                return o
        return None

    hello = take(lambda o: o["type"] == "hello", 30)
    if hello is None:
        sys.exit("no hello from the bridge")
    droid = hello["droids"][0]
    timeout_s = hello["command_timeout_ms"] / 1000.0
    print(f"driving {droid['droid']} ({droid['robot']}), command timeout {timeout_s} s")
    ready = lambda o: o["type"] == "link" and o["droid"] == droid["droid"] and o["ready"]
    if take(ready, 30) is None:
        sys.exit("the droid did not become ready")
    for n, heading in enumerate([0, 90, 180, 270], start=1):
        end = time.monotonic() + a.side
        while time.monotonic() < end:
            send({"cmd": "drive", "speed": a.speed, "heading": heading})
            take(lambda o: False, min(timeout_s / 3, end - time.monotonic()))
        print(f"corner {n} x_cm={latest.get('x_cm')} y_cm={latest.get('y_cm')}")
    send({"cmd": "stop", "id": "stop"})
    if take(lambda o: o["type"] == "reply" and o["id"] == "stop", 5) is None:
        sys.exit("no reply to stop")
    take(lambda o: False, 1.0)
    print(f"stopped speed={latest.get('speed')}")
    bridge.stdin.close()
    return bridge.wait(timeout=15)


if __name__ == "__main__":
    sys.exit(main())
