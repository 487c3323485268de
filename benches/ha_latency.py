#!/usr/bin/env python3
"""Home Assistant command -> droid latency of `droidctl bridge --homeassistant` (issue 40):
what Home Assistant itself sends, timed until what Home Assistant reads back, p50 / p99.

    python3 -m venv target/bench-venv && target/bench-venv/bin/pip install paho-mqtt
    target/bench-venv/bin/python benches/ha_latency.py --droidctl target/release/droidctl

- light: `{"state":"ON","color":{…}}` on `droidctl/D2-0001/light/set` until the light's
  state arrives on `droidctl/D2-0001/light`, which the bridge publishes only once the
  (simulated) droid answered the colour command: a full round trip through the droid.
- stop: the "Motion enabled" switch off (`{"v":1,"cmd":"hold"}`, a latched stop) until the
  `hold` object arrives on `droidctl/D2-0001/hold`; the bridge publishes it after writing
  the stop into the droid's session (the droid's own answer is not waited for), then the
  switch on again.

Through mosquitto (`--broker mosquitto`, found on PATH or /usr/sbin) or droidctl's own broker
(`--broker embedded`). The figures depend on the machine: docs/bridge-integrators.md has the
ones measured for the release.
"""

import argparse
import json
import os
import queue
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import time

import paho.mqtt.client as mqtt

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def pct(xs, p):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(round(p / 100 * (len(xs) - 1))))]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--droidctl", default=os.path.join(ROOT, "target/release/droidctl"))
    ap.add_argument("--broker", choices=["mosquitto", "embedded"], default="mosquitto")
    ap.add_argument("-n", type=int, default=200, help="commands of each kind")
    a = ap.parse_args()
    port = free_port()
    procs = []
    tmp = tempfile.mkdtemp()
    env = dict(os.environ, DROIDCTL_CONFIG="/dev/null")
    if a.broker == "mosquitto":
        exe = shutil.which("mosquitto") or "/usr/sbin/mosquitto"
        conf = os.path.join(tmp, "m.conf")
        with open(conf, "w") as f:
            f.write(f"listener {port} 127.0.0.1\nallow_anonymous true\n")
        procs.append(subprocess.Popen([exe, "-c", conf], stderr=subprocess.DEVNULL))
        time.sleep(0.5)
        bridge = ["--mqtt", f"mqtt://127.0.0.1:{port}"]
    else:
        bridge = ["--mqtt", "--listen", f"127.0.0.1:{port}"]
    procs.append(
        subprocess.Popen(
            [a.droidctl, "bridge", *bridge, "--sim", "r2d2", "--homeassistant",
             "--bridge-id", "bench"],
            env=env,
            stderr=subprocess.DEVNULL,
        )
    )
    inbox = queue.Queue()
    c = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=f"ha-bench-{os.getpid()}")
    c.on_message = lambda _c, _u, m: inbox.put((time.perf_counter(), m.topic, m.payload))
    for _ in range(50):
        try:
            c.connect("127.0.0.1", port)
            break
        except OSError:
            time.sleep(0.2)
    c.loop_start()
    base = "droidctl/D2-0001"
    c.subscribe(f"{base}/#", qos=1)

    def wait(topic, ok, timeout=10):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            try:
                t, tp, p = inbox.get(timeout=0.2)
            except queue.Empty:
                continue
            if tp == topic and p:
                o = json.loads(p)
                if ok(o):
                    return t
        sys.exit(f"nothing on {topic} within {timeout} s")

    wait(f"{base}/state", lambda o: o.get("ready"), 30)
    light, stop = [], []
    for i in range(a.n):
        rgb = {"r": i % 256, "g": (7 * i) % 256, "b": 255}
        t0 = time.perf_counter()
        c.publish(f"{base}/light/set", json.dumps({"state": "ON", "color": rgb}), qos=1)
        t1 = wait(f"{base}/light", lambda o: o.get("color") == rgb)
        light.append((t1 - t0) * 1000)
        t0 = time.perf_counter()
        c.publish(f"{base}/cmd", '{"v":1,"cmd":"hold"}', qos=1)
        t1 = wait(f"{base}/hold", lambda o: o.get("held") is True)
        stop.append((t1 - t0) * 1000)
        c.publish(f"{base}/cmd", '{"v":1,"cmd":"release"}', qos=1)
        wait(f"{base}/hold", lambda o: o.get("held") is False)
    for name, xs in [("light", light), ("stop (hold)", stop)]:
        print(f"{a.broker} {name}: n={len(xs)} p50={statistics.median(xs):.1f} ms "
              f"p99={pct(xs, 99):.1f} ms max={max(xs):.1f} ms")
    c.loop_stop()
    for p in reversed(procs):
        p.terminate()
        p.wait()


if __name__ == "__main__":
    main()
