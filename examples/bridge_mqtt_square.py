#!/usr/bin/env python3
"""Drive a square through `droidctl bridge --mqtt`, then stop, with paho-mqtt.

    droidctl bridge --mqtt --sim r2d2 &          # a bridge on droidctl's own broker
    pip install paho-mqtt
    python3 examples/bridge_mqtt_square.py --port 1883

It finds the droids on the retained `PREFIX/bridge/+` topics (each bridge's `hello` object,
under its own id: several bridges may share a broker), waits until
the droid's retained `state` says `"ready":true` (a drive before that is held until the
droid can move), drives four sides (heading 0, 90, 180, 270), re-sending each drive well
within the command timeout, stops and waits for the stop's reply on `PREFIX/DROID/reply`.
Each corner is printed as `corner N x_cm=… y_cm=…`. See docs/bridge-integrators.md.
"""

import argparse
import json
import queue
import sys
import time

import paho.mqtt.client as mqtt


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument("--port", type=int, default=1883)
    ap.add_argument("--prefix", default="droidctl", help="the bridge's --topic-prefix")
    ap.add_argument("--droid", help="its topic level (the first droid without)")
    ap.add_argument("--speed", type=int, default=80, help="0..255")
    ap.add_argument("--side", type=float, default=1.5, help="seconds per side")
    a = ap.parse_args()
    inbox = queue.Queue()
    if hasattr(mqtt, "CallbackAPIVersion"):  # paho-mqtt 2
        client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2)
    else:  # paho-mqtt 1
        client = mqtt.Client()
    client.on_message = lambda c, u, m: inbox.put((m.topic, m.payload))
    client.connect(a.host, a.port, keepalive=10)
    client.loop_start()
    latest = {}

    def take(until, timeout):
        """Read messages (keeping the latest sample) until `until(topic, obj)` holds."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            try:
                topic, payload = inbox.get(timeout=max(0.0, end - time.monotonic()))
            except queue.Empty:
                break
            if not payload:
                continue  # a retained topic cleared
            o = json.loads(payload)
            if topic.endswith("/telemetry"):
                latest.update(o)
            if o.get("type") == "error":
                print("error:", o["error"], file=sys.stderr)
            if until(topic, o):
                return o
        return None

    client.subscribe(f"{a.prefix}/bridge/+", qos=1)
    wanted = lambda o: o.get("type") == "hello" and any(
        a.droid in (None, d["topic"]) for d in o["droids"]
    )
    hello = take(lambda t, o: wanted(o), 30)
    if hello is None:
        sys.exit(f"no bridge on {a.prefix}/bridge/+")
    droid = next(d for d in hello["droids"] if a.droid in (None, d["topic"]))
    base = f"{a.prefix}/{droid['topic']}"
    timeout_s = hello["command_timeout_ms"] / 1000.0
    print(f"driving {droid['droid']} ({droid['robot']}), command timeout {timeout_s} s")
    for leaf in ["state", "telemetry", "reply"]:
        client.subscribe(f"{base}/{leaf}", qos=1)
    if take(lambda t, o: t == f"{base}/state" and o.get("ready"), 30) is None:
        sys.exit("the droid did not become ready")

    def send(obj):
        client.publish(f"{base}/cmd", json.dumps(dict(v=1, **obj)), qos=1)

    for n, heading in enumerate([0, 90, 180, 270], start=1):
        end = time.monotonic() + a.side
        while time.monotonic() < end:
            send({"cmd": "drive", "speed": a.speed, "heading": heading})
            take(lambda t, o: False, min(timeout_s / 3, end - time.monotonic()))
        print(f"corner {n} x_cm={latest.get('x_cm')} y_cm={latest.get('y_cm')}")
    send({"cmd": "stop", "id": "stop"})
    if take(lambda t, o: o.get("type") == "reply" and o.get("id") == "stop", 5) is None:
        sys.exit("no reply to stop")
    take(lambda t, o: False, 1.0)
    print(f"stopped speed={latest.get('speed')}")
    client.loop_stop()
    client.disconnect()
    return 0


if __name__ == "__main__":
    sys.exit(main())
