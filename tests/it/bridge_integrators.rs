//! The bridge as integrators use it (issue 31): Home Assistant's MQTT discovery through
//! mosquitto, checked against the discovery topics and payload keys Home Assistant documents;
//! and the programs under `examples/` (paho-mqtt and stdio) driving a simulated droid.

use crate::common::bridge_proc;
use crate::common::mosquitto;

use bridge_proc::{BridgeProc, gather, interrupt, scratch, speed};
use mosquitto::{Broker, Kind, Sub, mosquitto_here, publish};
use serde_json::Value;
use std::time::Duration;

/// The payload keys Home Assistant documents for each MQTT platform discovery makes here
/// (https://www.home-assistant.io/integrations/sensor.mqtt/, binary_sensor.mqtt/,
/// button.mqtt/, light.mqtt/ template schema): (component, required, optional).
const HA_KEYS: &[(&str, &[&str], &[&str])] = &[
    (
        "sensor",
        &["state_topic"],
        &[
            "name",
            "unique_id",
            "device",
            "availability",
            "value_template",
            "device_class",
            "unit_of_measurement",
            "state_class",
            "icon",
        ],
    ),
    (
        "binary_sensor",
        &["state_topic"],
        &[
            "name",
            "unique_id",
            "device",
            "availability",
            "value_template",
            "device_class",
            "payload_on",
            "payload_off",
            "icon",
        ],
    ),
    (
        "button",
        &["command_topic"],
        &[
            "name",
            "unique_id",
            "device",
            "availability",
            "payload_press",
            "icon",
        ],
    ),
    (
        "light",
        &[
            "command_topic",
            "command_on_template",
            "command_off_template",
            "schema",
        ],
        &[
            "name",
            "unique_id",
            "device",
            "availability",
            "optimistic",
            "icon",
        ],
    ),
];

/// Keys of a discovery payload's `device` and of an `availability` entry, as documented.
const DEVICE_KEYS: &[&str] = &["identifiers", "name", "model", "manufacturer", "sw_version"];
const AVAILABILITY_KEYS: &[&str] = &[
    "topic",
    "value_template",
    "payload_available",
    "payload_not_available",
];

/// `<discovery_prefix>/<component>/[<node_id>/]<object_id>/config`, ids of
/// `[A-Za-z0-9_-]`.
fn discovery_topic(t: &str) -> Option<(&str, &str, &str)> {
    let id = |s: &str| {
        !s.is_empty()
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    };
    match t.split('/').collect::<Vec<_>>()[..] {
        ["homeassistant", component, node, object, "config"] if id(node) && id(object) => {
            Some((component, node, object))
        }
        _ => None,
    }
}

#[test]
fn home_assistant_discovery_through_mosquitto() {
    if !mosquitto_here() {
        return;
    }
    let dir = scratch("homeassistant");
    let broker = Broker::start_kind(&dir, Kind::Mosquitto);
    let p = broker.port;
    let sub = Sub::start(p, "droidctl/#", &[]);
    let mut bridge = BridgeProc::start(
        &dir,
        &[
            "--mqtt",
            &broker.url(),
            "--sim",
            "r2d2,robi",
            "--homeassistant",
        ],
    );
    sub.wait(20, "droidctl/D2-0001/state", |v| v["ready"] == true);
    // Retained: a subscriber that comes later gets every config.
    let ha = Sub::start(p, "homeassistant/#", &[]);
    let configs = gather(&ha, 5, |got| got.len() >= 9);
    let mut seen = Vec::new();
    for (topic, payload) in &configs {
        let (component, node, object) =
            discovery_topic(topic).unwrap_or_else(|| panic!("not a discovery topic: {topic}"));
        let (_, required, optional) = HA_KEYS
            .iter()
            .find(|(c, _, _)| *c == component)
            .unwrap_or_else(|| panic!("{topic}: component {component}"));
        let obj = payload
            .as_object()
            .unwrap_or_else(|| panic!("{topic}: {payload}"));
        for k in *required {
            assert!(obj.contains_key(*k), "{topic} lacks {k}: {payload}");
        }
        for k in obj.keys() {
            assert!(
                required.contains(&k.as_str()) || optional.contains(&k.as_str()),
                "{topic}: {k} is not a documented {component} key"
            );
        }
        for k in payload["device"].as_object().expect("device").keys() {
            assert!(DEVICE_KEYS.contains(&k.as_str()), "{topic}: device.{k}");
        }
        for a in payload["availability"].as_array().into_iter().flatten() {
            for k in a.as_object().unwrap().keys() {
                assert!(
                    AVAILABILITY_KEYS.contains(&k.as_str()),
                    "{topic}: availability.{k}"
                );
            }
        }
        // Every entity reads or writes the droid's own topics.
        for (k, v) in obj.iter().filter(|(k, _)| k.ends_with("topic")) {
            let t = v.as_str().unwrap();
            assert!(
                t.starts_with("droidctl/") && t.split('/').count() == 3,
                "{topic}: {k} {t}"
            );
        }
        seen.push(format!("{node}/{object}"));
    }
    for want in [
        "droidctl_D2-0001/battery",
        "droidctl_D2-0001/connection",
        "droidctl_D2-0001/collisions",
        "droidctl_D2-0001/stop",
        "droidctl_D2-0001/light",
        "droidctl_Robi-42/connection",
        "droidctl_Robi-42/stop",
    ] {
        assert!(seen.iter().any(|s| s == want), "no {want} in {seen:?}");
    }
    // The value templates read fields the state topics carry.
    let battery = configs
        .iter()
        .find(|(t, _)| t.ends_with("D2-0001/battery/config"))
        .unwrap();
    assert_eq!(battery.1["value_template"], "{{ value_json.volts }}");
    let v = sub.wait(20, "droidctl/D2-0001/battery", |_| true);
    assert!(v["volts"].is_number(), "{v}");
    // The stop button stops a driven droid (its payload is a bridge command).
    let stop = configs
        .iter()
        .find(|(t, _)| t.ends_with("D2-0001/stop/config"))
        .unwrap();
    let (cmd_topic, press) = (
        stop.1["command_topic"].as_str().unwrap(),
        stop.1["payload_press"].as_str().unwrap(),
    );
    let drive = r#"{"v":1,"cmd":"drive","speed":120,"heading":90}"#;
    for _ in 0..6 {
        assert!(publish(p, cmd_topic, drive, &[]));
        std::thread::sleep(Duration::from_millis(200));
    }
    sub.wait(5, "droidctl/D2-0001/telemetry", |v| speed(v) > 20.0);
    assert!(publish(p, cmd_topic, press, &[]));
    std::thread::sleep(Duration::from_millis(1200));
    let _ = sub.drain();
    let t = sub.wait(3, "droidctl/D2-0001/telemetry", |_| true);
    assert!(speed(&t) < 3.0, "still rolling after the stop button: {t}");
    // The light's payloads are commands the bridge takes (asked with an id: a reply).
    let light = configs
        .iter()
        .find(|(t, _)| t.ends_with("D2-0001/light/config"))
        .unwrap();
    for k in ["command_on_template", "command_off_template"] {
        let mut c: Value = serde_json::from_str(light.1[k].as_str().unwrap()).unwrap();
        c["id"] = k.into();
        assert!(publish(p, cmd_topic, &c.to_string(), &[]));
        let r = sub.wait(5, "droidctl/D2-0001/reply", |v| v["id"] == k);
        assert_eq!(r["type"], "reply", "{r}");
    }
    // A clean end removes the entities: nothing retained under homeassistant/ any more.
    drop(ha);
    interrupt(&mut bridge);
    std::thread::sleep(Duration::from_millis(500));
    let after = Sub::start(p, "homeassistant/#", &[]);
    let left = gather(&after, 2, |_| false);
    let left: Vec<&String> = left.iter().map(|(t, _)| t).collect();
    assert!(left.is_empty(), "still retained: {left:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The corners an example printed (`corner N x_cm=… y_cm=…`) and the speed it stopped at.
fn square(out: &str) -> (Vec<(f64, f64)>, f64) {
    let num = |s: &str, key: &str| -> Option<f64> {
        s.split_whitespace()
            .find_map(|w| w.strip_prefix(key))
            .and_then(|v| v.parse().ok())
    };
    let corners = out
        .lines()
        .filter(|l| l.starts_with("corner "))
        .filter_map(|l| Some((num(l, "x_cm=")?, num(l, "y_cm=")?)))
        .collect();
    let stopped = out
        .lines()
        .find(|l| l.starts_with("stopped "))
        .and_then(|l| num(l, "speed="))
        .unwrap_or(f64::NAN);
    (corners, stopped)
}

/// A square: up (+y, heading 0), right (+x, 90), down, left; then stopped.
fn assert_square(out: &str) {
    let (c, stopped) = square(out);
    assert_eq!(c.len(), 4, "{out}");
    assert!(c[0].1 > 30.0, "side 1 goes +y: {c:?}");
    assert!(c[1].0 - c[0].0 > 30.0, "side 2 goes +x: {c:?}");
    assert!(c[1].1 - c[2].1 > 30.0, "side 3 goes -y: {c:?}");
    assert!(c[2].0 - c[3].0 > 30.0, "side 4 goes -x: {c:?}");
    assert!(stopped < 3.0, "stopped at {stopped}: {out}");
}

fn example(name: &str) -> String {
    format!("{}/examples/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn run_python(python: &str, args: &[&str]) -> String {
    let out = std::process::Command::new(python)
        .args(args)
        .env("DROIDCTL_CONFIG", "/dev/null")
        .output()
        .unwrap_or_else(|e| panic!("cannot run {python}: {e}"));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{args:?}: {}\n{text}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    text
}

#[test]
fn the_stdio_example_drives_a_square_and_stops() {
    let out = run_python(
        "python3",
        &[
            &example("bridge_stdio_square.py"),
            "--droidctl",
            env!("CARGO_BIN_EXE_droidctl"),
            "--sim",
            "bb8",
        ],
    );
    assert_square(&out);
}

/// What pip says when it cannot reach the package registry.
const OFFLINE: &[&str] = &[
    "Could not fetch",
    "NewConnectionError",
    "Temporary failure in name resolution",
    "Network is unreachable",
    "No matching distribution found",
    "Connection refused",
    "timed out",
];

/// A Python that imports paho-mqtt: CI's venv (`.ci/run` installs it beside spherov2), or
/// one made under target/ with pip. `Err` (the test is skipped) only when the package
/// registry cannot be reached.
pub(crate) fn python_with_paho() -> Result<String, String> {
    let imports = |py: &str| {
        std::process::Command::new(py)
            .args(["-c", "import paho.mqtt.client"])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    let venv = format!("{}/target/bridge-examples-venv", env!("CARGO_MANIFEST_DIR"));
    let python = format!("{venv}/bin/python");
    let candidates = [
        std::env::var("DROIDCTL_TEST_SPHEROV2_PYTHON").ok(),
        Some(python.clone()),
    ];
    if let Some(py) = candidates.into_iter().flatten().find(|p| imports(p)) {
        return Ok(py);
    }
    if !std::path::Path::new(&python).exists() {
        let made = std::process::Command::new("python3")
            .args(["-m", "venv", &venv])
            .output()
            .expect("python3 (to make a venv for paho-mqtt)");
        assert!(
            made.status.success(),
            "python3 -m venv {venv}: {}",
            String::from_utf8_lossy(&made.stderr)
        );
    }
    let pip = std::process::Command::new(&python)
        .args([
            "-m",
            "pip",
            "install",
            "-q",
            "--disable-pip-version-check",
            "paho-mqtt",
        ])
        .output()
        .expect("pip");
    let said = String::from_utf8_lossy(&pip.stderr).into_owned();
    if !pip.status.success() {
        if OFFLINE.iter().any(|s| said.contains(s)) {
            return Err(format!("the package registry cannot be reached: {said}"));
        }
        panic!("pip install paho-mqtt failed: {said}");
    }
    assert!(imports(&python), "paho-mqtt installed but not importable");
    Ok(python)
}

#[test]
fn the_paho_mqtt_example_drives_a_square_and_stops() {
    let python = match python_with_paho() {
        Ok(p) => p,
        Err(why) => {
            eprintln!("SKIPPED: no paho-mqtt: {why}");
            return;
        }
    };
    let dir = scratch("paho-example");
    let broker = Broker::start_kind(&dir, Kind::Embedded);
    let p = broker.port;
    let _bridge = BridgeProc::start(&dir, &["--mqtt", &broker.url(), "--sim", "r2d2"]);
    let out = run_python(
        &python,
        &[&example("bridge_mqtt_square.py"), "--port", &p.to_string()],
    );
    assert!(out.contains("driving D2-0001 (R2-D2)"), "{out}");
    assert_square(&out);
    let _ = std::fs::remove_dir_all(&dir);
}
