//! The bridge as integrators use it (issue 31): Home Assistant's MQTT discovery through
//! mosquitto, checked against the discovery topics and payload keys Home Assistant documents;
//! and the programs under `examples/` (paho-mqtt and stdio) driving a simulated droid.

#[path = "common/bridge_proc.rs"]
mod bridge_proc;
#[path = "common/mosquitto.rs"]
mod mosquitto;

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
