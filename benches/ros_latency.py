#!/usr/bin/env python3
"""cmd_vel -> motion in odom, through a broker (issue 40): how long from a ROS Twist
published on droidctl/DROID/cmd_vel until droidctl/DROID/odom shows the droid moving.

Starts `droidctl bridge --mqtt` on a simulated droid (its own broker with --listen, or a
mosquitto already running with --broker), asks the droid to stream at 50/s, then repeats:
wait until odom says it stands still, publish a Twist (linear.x 0.5 m/s) at 10 Hz, and time
the first odom with linear.x above 0.05 m/s; then stop it. Prints p50/p99/max.

    python3 benches/ros_latency.py --droidctl target/release/droidctl --listen 18841
    python3 benches/ros_latency.py --droidctl target/release/droidctl --broker 1883

Needs paho-mqtt (pip install paho-mqtt).
"""

import argparse
import json
import os
import queue
import subprocess
import sys
import time

import paho.mqtt.client as mqtt


def pct(xs, p):
    xs = sorted(xs)
    k = (len(xs) - 1) * p / 100
    lo = int(k)
    hi = min(lo + 1, len(xs) - 1)
    return xs[lo] + (xs[hi] - xs[lo]) * (k - lo)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--droidctl", default="target/release/droidctl")
    ap.add_argument("--listen", type=int, help="the bridge hosts its broker on this port")
    ap.add_argument("--broker", type=int, help="a broker already on 127.0.0.1:PORT")
    ap.add_argument("--sim", default="bb8")
    ap.add_argument("--trials", type=int, default=40)
    a = ap.parse_args()
    if (a.listen is None) == (a.broker is None):
        sys.exit("give --listen PORT or --broker PORT")
    port = a.listen or a.broker
    args = [a.droidctl, "bridge", "--rate", "50", "--sim", a.sim]
    args += ["--mqtt", "--listen", f"127.0.0.1:{port}"] if a.listen else ["--mqtt", f"mqtt://127.0.0.1:{port}"]
    env = dict(os.environ, DROIDCTL_CONFIG="/dev/null")
    bridge = subprocess.Popen(args, env=env, stdin=subprocess.DEVNULL,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        run(a, port)
    finally:
        bridge.terminate()
        bridge.wait(10)


def run(a, port):
    odom = queue.Queue()
    ready = queue.Queue()
    c = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2)

    def on_message(_c, _u, m):
        now = time.monotonic()
        if m.topic.endswith("/odom"):
            odom.put((now, json.loads(m.payload)))
        elif m.topic.endswith("/state") and json.loads(m.payload).get("ready"):
            ready.put(True)

    c.on_message = on_message
    end = time.monotonic() + 20
    while True:
        try:
            c.connect("127.0.0.1", port)
            break
        except OSError:
            if time.monotonic() > end:
                raise
            time.sleep(0.2)
    c.loop_start()
    c.subscribe("droidctl/+/odom", 0)
    c.subscribe("droidctl/+/state", 0)
    c.subscribe("droidctl/bridge", 0)
    ready.get(timeout=30)
    droid = "BB-0001" if a.sim == "bb8" else None
    topic = f"droidctl/{droid}"
    c.publish(f"{topic}/cmd", json.dumps({"v": 1, "cmd": "stream", "rate_hz": 50}), 1)
    time.sleep(1.0)
    go = json.dumps({"linear": {"x": 0.5, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}})
    stop = json.dumps({"v": 1, "cmd": "stop"})
    lat = []
    for _ in range(a.trials):
        # Standing still for 300 ms.
        still_since = None
        while True:
            t, o = odom.get(timeout=10)
            if abs(o["twist"]["twist"]["linear"]["x"]) < 0.01:
                still_since = still_since or t
                if t - still_since > 0.3:
                    break
            else:
                still_since = None
        while not odom.empty():
            odom.get_nowait()
        t0 = time.monotonic()
        c.publish(f"{topic}/cmd_vel", go, 0)
        nxt = t0 + 0.1
        while True:
            try:
                t, o = odom.get(timeout=max(0.0, nxt - time.monotonic()))
            except queue.Empty:
                c.publish(f"{topic}/cmd_vel", go, 0)
                nxt += 0.1
                continue
            if o["twist"]["twist"]["linear"]["x"] > 0.05:
                lat.append((t - t0) * 1000)
                break
        c.publish(f"{topic}/cmd", stop, 1)
    print(f"{len(lat)} trials: p50 {pct(lat, 50):.1f} ms, p99 {pct(lat, 99):.1f} ms, max {max(lat):.1f} ms")
    c.loop_stop()


if __name__ == "__main__":
    main()
