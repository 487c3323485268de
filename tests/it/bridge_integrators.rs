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
/// button.mqtt/, switch.mqtt/, select.mqtt/, number.mqtt/, light.mqtt/ JSON schema):
/// (component, required, optional). Every entity may carry these too.
const COMMON_KEYS: &[&str] = &[
    "name",
    "unique_id",
    "device",
    "origin",
    "availability",
    "entity_category",
    "icon",
    "optimistic",
];
const HA_KEYS: &[(&str, &[&str], &[&str])] = &[
    (
        "sensor",
        &["state_topic"],
        &[
            "value_template",
            "device_class",
            "unit_of_measurement",
            "state_class",
        ],
    ),
    (
        "binary_sensor",
        &["state_topic"],
        &[
            "value_template",
            "device_class",
            "payload_on",
            "payload_off",
        ],
    ),
    ("button", &["command_topic"], &["payload_press"]),
    (
        "switch",
        &["command_topic"],
        &[
            "payload_on",
            "payload_off",
            "state_topic",
            "value_template",
            "state_on",
            "state_off",
        ],
    ),
    (
        "select",
        &["command_topic", "options"],
        &["command_template", "state_topic", "value_template"],
    ),
    (
        "number",
        &["command_topic"],
        &[
            "command_template",
            "state_topic",
            "value_template",
            "min",
            "max",
            "step",
            "mode",
            "unit_of_measurement",
        ],
    ),
    (
        "light",
        &["command_topic", "schema"],
        &[
            "state_topic",
            "supported_color_modes",
            "brightness",
            "brightness_scale",
        ],
    ),
];

/// Keys of a discovery payload's `device`, `origin` and of an `availability` entry, as
/// documented.
const DEVICE_KEYS: &[&str] = &[
    "identifiers",
    "name",
    "model",
    "manufacturer",
    "sw_version",
    "via_device",
];
const ORIGIN_KEYS: &[&str] = &["name", "sw_version", "support_url"];
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
            "--bridge-id",
            "lab-1",
        ],
    );
    let both = [
        "droidctl/D2-0001/state".into(),
        "droidctl/Robi-42/state".into(),
    ];
    sub.wait_all(20, &both, |v| v["ready"] == true);
    // Retained: a subscriber that comes later gets every config: R2-D2's 12, Robi's 4, the
    // bridge's 1.
    let ha = Sub::start(p, "homeassistant/#", &[]);
    let configs = gather(&ha, 5, |got| got.len() >= 17);
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
                required.contains(&k.as_str())
                    || optional.contains(&k.as_str())
                    || COMMON_KEYS.contains(&k.as_str()),
                "{topic}: {k} is not a documented {component} key"
            );
        }
        for k in payload["device"].as_object().expect("device").keys() {
            assert!(DEVICE_KEYS.contains(&k.as_str()), "{topic}: device.{k}");
        }
        for k in payload["origin"].as_object().expect("origin").keys() {
            assert!(ORIGIN_KEYS.contains(&k.as_str()), "{topic}: origin.{k}");
        }
        if let Some(c) = obj.get("entity_category") {
            assert!(c == "diagnostic" || c == "config", "{topic}: {c}");
        }
        for a in payload["availability"].as_array().into_iter().flatten() {
            for k in a.as_object().unwrap().keys() {
                assert!(
                    AVAILABILITY_KEYS.contains(&k.as_str()),
                    "{topic}: availability.{k}"
                );
            }
        }
        // Every entity reads or writes the bridge's own topics.
        for (k, v) in obj.iter().filter(|(k, _)| k.ends_with("topic")) {
            let t = v.as_str().unwrap();
            assert!(t.starts_with("droidctl/"), "{topic}: {k} {t}");
        }
        seen.push(format!("{node}/{object}"));
    }
    for want in [
        "droidctl_D2-0001/battery",
        "droidctl_D2-0001/battery_level",
        "droidctl_D2-0001/connection",
        "droidctl_D2-0001/collisions",
        "droidctl_D2-0001/stop",
        "droidctl_D2-0001/motion",
        "droidctl_D2-0001/light",
        "droidctl_D2-0001/stance",
        "droidctl_D2-0001/heading",
        "droidctl_D2-0001/speed",
        "droidctl_D2-0001/animation",
        "droidctl_D2-0001/sound",
        "droidctl_Robi-42/connection",
        "droidctl_Robi-42/stop",
        "droidctl_Robi-42/motion",
        "droidctl_bridge-lab-1/droids",
    ] {
        assert!(seen.iter().any(|s| s == want), "no {want} in {seen:?}");
    }
    let config = |end: &str| {
        configs
            .iter()
            .find(|(t, _)| t.ends_with(end))
            .unwrap_or_else(|| panic!("no {end}"))
            .1
            .clone()
    };
    // Each droid points to the bridge's device, which counts them; made by Sphero (Robi
    // 42 is not).
    let bridge_dev = config("bridge-lab-1/droids/config");
    let bridge_node = &bridge_dev["device"]["identifiers"][0];
    assert_eq!(
        config("D2-0001/stop/config")["device"]["via_device"],
        *bridge_node
    );
    assert_eq!(
        config("Robi-42/stop/config")["device"]["via_device"],
        *bridge_node
    );
    assert_eq!(
        config("D2-0001/stop/config")["device"]["manufacturer"],
        "Sphero"
    );
    assert!(config("Robi-42/stop/config")["device"]["manufacturer"].is_null());
    let hello_topic = bridge_dev["state_topic"].as_str().unwrap();
    assert_eq!(hello_topic, "droidctl/bridge/lab-1");
    let hello = Sub::start(p, hello_topic, &[]).wait(5, hello_topic, |_| true);
    assert_eq!(hello["droids"].as_array().map(Vec::len), Some(2), "{hello}");
    for d in ["battery", "battery_level", "connection", "collisions"] {
        assert_eq!(
            config(&format!("D2-0001/{d}/config"))["entity_category"],
            "diagnostic",
            "{d}"
        );
    }
    let level = config("D2-0001/battery_level/config");
    assert_eq!(
        (&level["device_class"], &level["unit_of_measurement"]),
        (&Value::from("battery"), &Value::from("%"))
    );
    // The collision count is retained (0 before any).
    let count = Sub::start(p, "droidctl/D2-0001/collisions", &[]);
    let c = count.wait(5, "droidctl/D2-0001/collisions", |_| true);
    assert_eq!(c["collisions"], 0, "{c}");
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
    // The light, in Home Assistant's JSON schema: a colour and a brightness arrive as one
    // colour (brightness scales it), and the state is retained once the droid said done.
    let light = config("D2-0001/light/config");
    assert_eq!(light["schema"], "json");
    let (set, state) = (
        light["command_topic"].as_str().unwrap(),
        light["state_topic"].as_str().unwrap(),
    );
    assert!(publish(
        p,
        set,
        r#"{"state":"ON","color":{"r":255,"g":0,"b":0},"brightness":128}"#,
        &[]
    ));
    // The droid's answer, then the state (published on it).
    let r = sub.wait(5, "droidctl/D2-0001/reply", |v| v["cmd"] == "lights");
    assert_eq!(r["ok"], true, "{r}");
    let s = sub.wait(5, state, |v| v["state"] == "ON");
    assert_eq!(
        (&s["brightness"], &s["color"]["r"], &s["color"]["g"]),
        (&Value::from(128), &Value::from(255), &Value::from(0)),
        "{s}"
    );
    // A light command Home Assistant would not send is said, not guessed.
    assert!(publish(p, set, r#"{"brightness":9}"#, &[]));
    let e = sub.wait(5, "droidctl/D2-0001/reply", |v| v["type"] == "error");
    assert!(e["error"].as_str().unwrap().contains("state"), "{e}");
    // Motion enabled off: a latched stop, each drive refused (code held) until on again.
    let motion = config("D2-0001/motion/config");
    let (off, on) = (
        motion["payload_off"].as_str().unwrap(),
        motion["payload_on"].as_str().unwrap(),
    );
    assert!(publish(p, cmd_topic, off, &[]));
    let h = sub.wait(5, "droidctl/D2-0001/hold", |v| v["held"] == true);
    assert_eq!(h["type"], "hold");
    let held_drive = r#"{"v":1,"cmd":"drive","speed":120,"heading":90,"id":"d1"}"#;
    assert!(publish(p, cmd_topic, held_drive, &[]));
    let e = sub.wait(5, "droidctl/D2-0001/reply", |v| v["id"] == "d1");
    assert_eq!(
        (&e["type"], &e["code"]),
        (&Value::from("error"), &Value::from("held"))
    );
    assert!(publish(p, cmd_topic, on, &[]));
    sub.wait(5, "droidctl/D2-0001/hold", |v| v["held"] == false);
    let free = r#"{"v":1,"cmd":"drive","speed":0,"heading":90,"id":"d2"}"#;
    assert!(publish(p, cmd_topic, free, &[]));
    let r = sub.wait(5, "droidctl/D2-0001/reply", |v| v["id"] == "d2");
    assert_eq!(r["type"], "reply", "{r}");
    // The Speed number sets the cruise speed (retained, read back), moving nothing; the
    // Heading number then rolls at it until the command timeout.
    let speed_n = config("D2-0001/speed/config");
    let heading_n = config("D2-0001/heading/config");
    let render = |c: &Value, v: u32| {
        c["command_template"]
            .as_str()
            .unwrap()
            .replace("{{ value | int }}", &v.to_string())
    };
    assert!(publish(p, cmd_topic, &render(&speed_n, 150), &[]));
    let cruise_topic = speed_n["state_topic"].as_str().unwrap();
    let c = sub.wait(5, cruise_topic, |v| v["speed"] == 150);
    assert_eq!(c["type"], "cruise", "{c}");
    assert_eq!(speed_n["value_template"], "{{ value_json.speed }}");
    std::thread::sleep(Duration::from_millis(600));
    let _ = sub.drain();
    let t = sub.wait(3, "droidctl/D2-0001/telemetry", |_| true);
    assert!(
        speed(&t) < 3.0,
        "the speed number alone moved the droid: {t}"
    );
    // A drive (held until the command timeout stops it); that it rolls at the cruise
    // speed is shown in src/bridge/cruise_tests.rs.
    assert!(publish(p, cmd_topic, &render(&heading_n, 180), &[]));
    sub.wait(5, "droidctl/D2-0001/reply", |v| {
        v["type"] == "stopped" && v["reason"] == "timeout"
    });
    // The animation select (issue 40 point 5), after the drives (R2 plays it for a while): an option, sent through the command template
    // as Home Assistant renders it, plays that animation, and the state is retained.
    let select = config("D2-0001/animation/config");
    let option = select["options"]
        .as_array()
        .and_then(|o| o.iter().find(|o| *o == "Frustrated"))
        .expect("the catalogue's names as options");
    let template = select["command_template"].as_str().unwrap();
    assert!(template.contains("{{ value | tojson }}"), "{template}");
    let payload = template.replace("{{ value | tojson }}", &option.to_string());
    assert!(publish(p, cmd_topic, &payload, &[]));
    let state = select["state_topic"].as_str().unwrap();
    let played = sub.wait(5, state, |v| v["type"] == "played");
    assert_eq!(
        (&played["id"], &played["name"]),
        (&Value::from(10), option),
        "{played}"
    );
    assert_eq!(select["value_template"], "{{ value_json.name }}");
    let later = Sub::start(p, state, &[]).wait(5, state, |_| true);
    assert_eq!(later["name"], *option, "retained: {later}");
    // Home Assistant's birth message: every config published again.
    let _ = ha.drain();
    assert!(publish(p, "homeassistant/status", "online", &[]));
    let again = gather(&ha, 5, |got| got.len() >= 17);
    assert!(again.len() >= 17, "{} configs again", again.len());
    // A clean end keeps the entities (availability says offline) …
    drop(ha);
    interrupt(&mut bridge);
    std::thread::sleep(Duration::from_millis(500));
    let after = Sub::start(p, "homeassistant/#", &[]);
    let kept = gather(&after, 5, |got| got.len() >= 17);
    assert_eq!(kept.len(), 17, "{kept:?}");
    drop(after);
    // … and --homeassistant-remove removes them.
    let mut bridge = BridgeProc::start(
        &dir,
        &[
            "--mqtt",
            &broker.url(),
            "--sim",
            "r2d2,robi",
            "--homeassistant",
            "--homeassistant-remove",
            "--bridge-id",
            "lab-1",
        ],
    );
    sub.wait_all(20, &both, |v| v["ready"] == true);
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
