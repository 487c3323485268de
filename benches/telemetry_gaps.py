#!/usr/bin/env python3
"""Telemetry smoothness of `droidctl bridge` (issue 31 point 7): the gap between one droid's
consecutive telemetry samples as a client receives them, p50 / p99 / max, over stdio, through
a default mosquitto, and through mosquitto with `set_tcp_nodelay true`.

    cargo build --release
    python3 -m venv target/bench-venv && target/bench-venv/bin/pip install paho-mqtt
    target/bench-venv/bin/python benches/telemetry_gaps.py --seconds 30

The droids are simulated; each streams attitude at the fastest rate its link carries
(`[streaming] rate_hz = 100, sensors = ["attitude"]`, capped by the BLE budget: 50/s), the
bridge runs with `--rate 100`, and every sample is timed where the client reads it. The
figures depend on the machine: docs/bridge-integrators.md has the ones measured for the
release. Stdio needs no paho-mqtt (`--modes stdio`).
"""

import argparse
import json
import os
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def summary(name, arrivals):
    """p50, p99 and max of the gaps between consecutive arrivals, per droid, pooled."""
    gaps = []
    for times in arrivals.values():
        gaps += [(b - a) * 1000.0 for a, b in zip(times, times[1:])]
    if len(gaps) < 10:
        return f"{name:<28} too few samples ({len(gaps)})"
    gaps.sort()
    q = lambda p: gaps[min(len(gaps) - 1, int(p * len(gaps)))]
    rate = len(gaps) / sum(gaps) * 1000.0
    return (
        f"{name:<28} samples {len(gaps):>6}  {rate:5.1f}/s  gap p50 {q(0.5):5.1f} ms  "
        f"p99 {q(0.99):5.1f} ms  max {gaps[-1]:6.1f} ms"
    )


def config_file(tmp):
    path = os.path.join(tmp, "droidctl.toml")
    with open(path, "w") as f:
        f.write('[streaming]\nrate_hz = 100\nsensors = ["attitude"]\n')
    return path


def bridge_env(tmp):
    return dict(os.environ, DROIDCTL_CONFIG=config_file(tmp))


def measure_stdio(a, tmp):
    p = subprocess.Popen(
        [a.droidctl, "bridge", "--stdio", "--sim", a.sim, "--rate", "100"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        env=bridge_env(tmp),
    )
    arrivals = {}
    start = None
    for line in p.stdout:
        now = time.monotonic()
        o = json.loads(line)
        if o["type"] == "link" and o.get("ready") and start is None:
            start = now + 1.0
        if start is not None and now >= start and o["type"] == "telemetry":
            arrivals.setdefault(o["droid"], []).append(now)
        if start is not None and now >= start + a.seconds:
            break
    p.stdin.close()
    p.wait(timeout=15)
    return arrivals


def measure_mosquitto(a, tmp, nodelay):
    import paho.mqtt.client as mqtt

    port = free_port()
    conf = os.path.join(tmp, f"mosquitto-{port}.conf")
    with open(conf, "w") as f:
        f.write(f"listener {port} 127.0.0.1\nallow_anonymous true\n")
        if nodelay:
            f.write("set_tcp_nodelay true\n")
    broker = subprocess.Popen(
        [a.mosquitto, "-c", conf], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    time.sleep(0.5)
    bridge = subprocess.Popen(
        [a.droidctl, "bridge", "--mqtt", f"mqtt://127.0.0.1:{port}", "--sim", a.sim,
         "--rate", "100"],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=bridge_env(tmp),
    )
    arrivals = {}
    lock = threading.Lock()
    state = {"start": None}

    def on_message(c, u, m):
        now = time.monotonic()
        if not m.payload:
            return
        o = json.loads(m.payload)
        with lock:
            if m.topic.endswith("/state") and o.get("ready") and state["start"] is None:
                state["start"] = now + 1.0
            s = state["start"]
            if s is not None and s <= now < s + a.seconds and m.topic.endswith("/telemetry"):
                arrivals.setdefault(o["droid"], []).append(now)

    if hasattr(mqtt, "CallbackAPIVersion"):
        client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2)
    else:
        client = mqtt.Client()
    client.on_message = on_message
    client.connect("127.0.0.1", port)
    client.subscribe("droidctl/+/telemetry", qos=0)
    client.subscribe("droidctl/+/state", qos=1)
    client.loop_start()
    end = time.monotonic() + 30 + a.seconds
    while time.monotonic() < end:
        time.sleep(0.2)
        with lock:
            s = state["start"]
        if s is not None and time.monotonic() > s + a.seconds + 0.2:
            break
    client.loop_stop()
    client.disconnect()
    bridge.terminate()
    bridge.wait(timeout=15)
    broker.terminate()
    broker.wait(timeout=5)
    return arrivals


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--droidctl", default=os.path.join(ROOT, "target/release/droidctl"))
    ap.add_argument("--mosquitto", default="/usr/sbin/mosquitto")
    ap.add_argument("--sim", default="bolt", help="the simulated droids (bolt, r2d2,bb8 …)")
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--modes", default="stdio,mosquitto,mosquitto-nodelay")
    a = ap.parse_args()
    print(f"{a.droidctl} bridge --sim {a.sim} --rate 100, {a.seconds} s each")
    with tempfile.TemporaryDirectory() as tmp:
        for mode in a.modes.split(","):
            if mode == "stdio":
                arr = measure_stdio(a, tmp)
            elif mode == "mosquitto":
                arr = measure_mosquitto(a, tmp, nodelay=False)
            elif mode == "mosquitto-nodelay":
                arr = measure_mosquitto(a, tmp, nodelay=True)
            else:
                sys.exit(f"unknown mode {mode}")
            print(summary(mode, arr), flush=True)


if __name__ == "__main__":
    main()
