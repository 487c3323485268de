//! What the bridge's topics and lines say, as a client relies on it (issue 40 points 8, 9
//! and 10): a paho-mqtt client's persistent session on droidctl's broker as on mosquitto;
//! the rate in `hello`, the retained `bridge` and `info` topics and the samples agree after
//! a `stream`, and samples come evenly at that rate (RVR's reports come as several
//! notifications: one sample each); a retained command is carried out exactly when
//! docs/bridge.md says.

use crate::common::bridge_proc::{BridgeProc, scratch};
use crate::common::mosquitto::{Broker, Kind, Sub, publish};
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// RVR over stdio with `--rate 50`: `hello` says the rate it offers, and the samples come at
/// that rate, evenly (they came in pairs and threes, 10-20 ms apart, twice as many).
#[test]
fn rvr_samples_come_evenly_at_the_rate_hello_says() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["bridge", "--stdio", "--sim", "rvr", "--rate", "50"])
        .env("DROIDCTL_CONFIG", "/dev/null")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("run droidctl bridge");
    let stdin = child.stdin.take().unwrap();
    let out = BufReader::new(child.stdout.take().unwrap());
    let mut hz = None;
    let mut t = Vec::new();
    for line in out.lines() {
        let v: Value = serde_json::from_str(&line.unwrap()).unwrap();
        match v["type"].as_str() {
            Some("hello") => hz = v["droids"][0]["telemetry_hz"].as_u64(),
            Some("telemetry") => t.push(v["t_ms"].as_u64().unwrap()),
            _ => {}
        }
        if t.len() > 1 && t[t.len() - 1] - t[1] >= 4000 {
            break;
        }
    }
    drop(stdin);
    let _ = child.kill();
    let _ = child.wait();
    let hz = hz.expect("hello first") as f64;
    assert!(hz > 0.0);
    // From the second sample on (the first comes whenever the stream starts).
    let span = (t[t.len() - 1] - t[1]) as f64 / 1000.0;
    let rate = (t.len() - 2) as f64 / span;
    assert!(
        (rate - hz).abs() <= hz * 0.2,
        "{rate:.1} samples/s, hello says {hz}: {t:?}"
    );
    let interval = 1000.0 / hz;
    let gaps: Vec<u64> = t[1..].windows(2).map(|w| w[1] - w[0]).collect();
    assert!(
        gaps.iter().all(|g| *g as f64 >= interval * 0.5),
        "bursts: gaps {gaps:?} at {hz}/s"
    );
}

/// A `stream` changes a droid's rate: its reply, then the retained `info` and the bridge's
/// retained `hello` (`bridge/ID`) say the same rate (the `hello` kept the old one).
#[test]
fn after_a_stream_info_and_the_bridge_topic_agree_on_the_rate() {
    let dir = scratch("rates");
    let broker = Broker::start(&dir);
    let p = broker.port;
    let sub = Sub::start(p, "droidctl/#", &[]);
    let _bridge = BridgeProc::start(
        &dir,
        &[
            "--mqtt",
            &broker.url(),
            "--sim",
            "bolt",
            "--rate",
            "100",
            "--bridge-id",
            "rates",
        ],
    );
    sub.wait(20, "droidctl/SB-0001/state", |v| v["ready"] == true);
    // The bridge's own `hello`, under its id.
    let topic = "droidctl/bridge/rates";
    let before = Sub::start(p, topic, &[]);
    let hello = before.wait(5, topic, |_| true);
    let was = hello["droids"][0]["telemetry_hz"].as_u64().unwrap();
    let want = if was == 20 { 10 } else { 20 };
    assert!(publish(
        p,
        "droidctl/SB-0001/cmd",
        &format!(r#"{{"v":1,"cmd":"stream","rate_hz":{want},"id":"s"}}"#),
        &[]
    ));
    sub.wait(10, "droidctl/SB-0001/reply", |v| {
        v["id"] == "s" && v["ok"] == true
    });
    let info = sub.wait(5, "droidctl/SB-0001/info", |v| {
        v["telemetry_hz"].as_u64() != Some(was)
    });
    let rate = info["telemetry_hz"].as_u64().unwrap();
    assert_eq!(rate, want, "{info}");
    // A client arriving now reads the same rate on both retained topics.
    let late = Sub::start(p, topic, &[]);
    let bridge = late.wait(5, topic, |_| true);
    let late = Sub::start(p, "droidctl/SB-0001/info", &[]);
    let info = late.wait(5, "droidctl/SB-0001/info", |_| true);
    assert_eq!(
        bridge["droids"][0]["telemetry_hz"].as_u64(),
        Some(rate),
        "{bridge}"
    );
    assert_eq!(bridge["telemetry_hz"].as_u64(), Some(rate), "{bridge}");
    assert_eq!(info["telemetry_hz"].as_u64(), Some(rate), "{info}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 40 point 10, as docs/bridge.md says it: a command published retained while the
/// bridge is subscribed reaches it as a live message (MQTT clears the flag on live
/// delivery) and is carried out, once; it stays on the broker, and the next bridge to
/// connect gets it flagged retained and ignores it (the `retained` error).
#[test]
fn a_retained_command_runs_once_when_the_bridge_listens_and_never_again() {
    let dir = scratch("retained-live");
    let broker = Broker::start(&dir);
    let p = broker.port;
    let sub = Sub::start(p, "droidctl/BB-0001/reply", &[]);
    let mut bridge = BridgeProc::start(&dir, &["--mqtt", &broker.url(), "--sim", "bb8"]);
    let state = Sub::start(p, "droidctl/BB-0001/state", &[]);
    state.wait(20, "droidctl/BB-0001/state", |v| v["ready"] == true);
    let cmd = r#"{"v":1,"cmd":"lights","group":"front","rgb":[0,0,255],"id":"kept"}"#;
    assert!(publish(p, "droidctl/BB-0001/cmd", cmd, &["-r"]));
    let r = sub.wait(10, "droidctl/BB-0001/reply", |v| v["id"] == "kept");
    assert_eq!(r["type"], "reply", "carried out: {r}");
    let _ = bridge.child.kill();
    let _ = bridge.child.wait();
    // The next bridge: the broker hands it the retained command, flagged: ignored.
    let again = BridgeProc::start(&dir, &["--mqtt", &broker.url(), "--sim", "bb8"]);
    let e = sub.wait(20, "droidctl/BB-0001/reply", |v| v["type"] == "error");
    assert_eq!(e["code"], "retained", "{e}");
    let end = Instant::now() + Duration::from_secs(2);
    while let Some(left) = end.checked_duration_since(Instant::now()) {
        if let Ok((_, v)) = sub.rx.recv_timeout(left) {
            assert_ne!(v["id"], "kept", "carried out again: {v}");
        }
    }
    assert!(
        again.stderr().contains("retained message"),
        "{}",
        again.stderr()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// paho-mqtt as a ROS node would run it, `clean_session=False`, away while two QoS 1
/// messages are published, then back: its `on_connect` flags say the session is present,
/// and both messages arrive without a new SUBSCRIBE (issue 40 point 8), on droidctl's
/// broker as on mosquitto.
const PAHO_SESSION: &str = r#"
import sys, time, paho.mqtt.client as m
port = int(sys.argv[1])
def connect():
    got, flags = [], {}
    c = m.Client(m.CallbackAPIVersion.VERSION2, client_id="ros-node", clean_session=False)
    c.on_connect = lambda c, u, f, rc, p: flags.update(present=f.session_present)
    c.on_message = lambda c, u, msg: got.append(msg.payload.decode())
    c.connect("127.0.0.1", port)
    c.loop_start()
    end = time.time() + 10
    while "present" not in flags and time.time() < end:
        time.sleep(0.02)
    return c, got, flags
c, got, flags = connect()
print("first", flags.get("present"), flush=True)
c.subscribe("droidctl/+/odom", 1)
time.sleep(0.5)
c.disconnect()
c.loop_stop()
print("away", flush=True)
sys.stdin.readline()
c, got, flags = connect()
end = time.time() + 5
while len(got) < 2 and time.time() < end:
    time.sleep(0.02)
print("again", flags.get("present"), ",".join(got), flush=True)
c.disconnect()
"#;

#[test]
fn a_paho_client_keeps_its_session_on_droidctls_broker() {
    paho_keeps_its_session(Kind::Embedded);
}

#[test]
fn a_paho_client_keeps_its_session_on_mosquitto() {
    if crate::common::mosquitto::mosquitto_here() {
        paho_keeps_its_session(Kind::Mosquitto);
    }
}

fn paho_keeps_its_session(kind: Kind) {
    let python = match crate::bridge_integrators::python_with_paho() {
        Ok(p) => p,
        Err(why) => {
            eprintln!("SKIPPED: {why}");
            return;
        }
    };
    let dir = scratch(&format!("session-{kind:?}"));
    let broker = Broker::start_kind(&dir, kind);
    let p = broker.port;
    let mut py = Command::new(python)
        .args(["-c", PAHO_SESSION, &p.to_string()])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("python");
    let mut stdin = py.stdin.take().unwrap();
    let mut lines = BufReader::new(py.stdout.take().unwrap()).lines();
    let mut next = || lines.next().expect("a line from paho").unwrap();
    assert_eq!(next(), "first False", "no session at first");
    assert_eq!(next(), "away");
    for n in ["one", "two"] {
        assert!(publish(p, "droidctl/BB-0001/odom", n, &[]));
    }
    use std::io::Write;
    writeln!(stdin).unwrap();
    assert_eq!(next(), "again True one,two");
    let _ = py.wait();
    let _ = std::fs::remove_dir_all(&dir);
}
