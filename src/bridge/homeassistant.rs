//! Home Assistant MQTT discovery (issue 31 point 6, issue 40 points 3–6), with
//! `--homeassistant` (off by default): the bridge appears in Home Assistant as a device of
//! its own (its version, its droid count), and each droid as a device connected through it
//! (`via_device`), made by Sphero, with its battery (volts and percent), its connection and
//! collisions (diagnostic), a stop button, a "Motion enabled" switch (the latched stop:
//! [`super::hold`]), its main light in colour and brightness (JSON schema:
//! [`super::ha_light`]), a stance select where it has legs, animation and sound selects
//! where it plays them (the catalogue's names: [`crate::family::catalog`]), and speed
//! ([`super::cruise`]) and heading numbers where it rolls toward a heading.
//!
//! Sans-IO: [`configs`] and [`bridge_configs`] make the retained discovery messages; the
//! MQTT transport publishes them at each connection to the broker and again when Home
//! Assistant says it started (its birth message, `online` on `<discovery_prefix>/status`).
//! A clean exit keeps them (as Zigbee2MQTT and ESPHome do: history and customisations stay,
//! availability says the droid is gone); `--homeassistant-remove` clears them (an empty
//! retained message, which Home Assistant reads as "remove"). Home Assistant's documented
//! discovery topic is `<discovery_prefix>/<component>/[<node_id>/]<object_id>/config`
//! (<https://www.home-assistant.io/integrations/mqtt/#mqtt-discovery>); the payload keys are
//! those of the MQTT sensor, binary sensor, button, switch, select and light (JSON schema)
//! integrations. The entities read the bridge's own topics: nothing is published twice.

use super::topics::topic;
use crate::family::catalog::Palette;
use crate::family::intent::{Intent, lower};
use crate::model::Model;
use serde_json::{Value, json};

/// Home Assistant's default discovery prefix.
pub const DEFAULT_PREFIX: &str = "homeassistant";

/// What a droid's entities are made of.
pub struct Droid<'a> {
    /// The bridge's first topic level (`droidctl`).
    pub prefix: &'a str,
    /// The droid's topic level.
    pub topic: &'a str,
    pub name: &'a str,
    pub model: Model,
    /// The id of the bridge it is connected through ([`super::presence`]).
    pub bridge: &'a str,
}

/// The `origin` of every discovery message: who publishes it (Home Assistant logs it).
fn origin() -> Value {
    json!({
        "name": "droidctl",
        "sw_version": env!("CARGO_PKG_VERSION"),
    })
}

/// The identifier of bridge `id`'s device under `prefix` (the droids' `via_device`).
pub fn bridge_node(prefix: &str, id: &str) -> String {
    node_of(prefix, &format!("bridge-{id}"))
}

/// The bridge's own discovery messages: its device (version in `sw_version`) and a droid
/// count, read from its `hello` on `PREFIX/bridge/ID`, available while its
/// `PREFIX/bridge/ID/state` says online.
pub fn bridge_configs(ha: &str, prefix: &str, id: &str) -> Vec<(String, String)> {
    let node = bridge_node(prefix, id);
    let hello = super::presence::hello_topic(prefix, id);
    let device = json!({
        "identifiers": [node.clone()],
        "name": format!("droidctl bridge {id}"),
        "manufacturer": "droidctl",
        "model": "bridge",
        "sw_version": env!("CARGO_PKG_VERSION"),
    });
    let payload = json!({
        "name": "Droids",
        "unique_id": format!("{node}_droids"),
        "state_topic": hello,
        "value_template": "{{ value_json.droids | length }}",
        "icon": "mdi:robot",
        "entity_category": "diagnostic",
        "availability": [{
            "topic": super::presence::state_topic(prefix, id),
            "value_template": "{{ value_json.state }}",
        }],
        "device": device,
        "origin": origin(),
    });
    vec![(
        format!("{ha}/sensor/{node}/droids/config"),
        payload.to_string(),
    )]
}

/// Battery percent from a one-cell LiPo's volts, as a Home Assistant template: linear
/// from 3.4 V (empty) to 4.2 V (full). No spec gives the curve (droid-facts.md says only
/// how volts are encoded): these are the simulator's own end points (`sim::body`), which
/// also answer Get Battery Percentage. RVR's pack is not one cell: no percent for it (the
/// model table tells it by its processors that each command names, `Caps::TARGETED`, the
/// one rover among the droids; spherov2's RVR reads its own percentage instead).
const PERCENT_TEMPLATE: &str =
    "{{ ((value_json.volts - 3.4) / 0.8 * 100) | round(0) | int | max(0) | min(100) }}";

/// The light group Home Assistant switches: the first the droid lights in colour.
pub fn main_light(model: Model) -> Option<&'static str> {
    use crate::script::LedGroup;
    [
        (LedGroup::Front, "front"),
        (LedGroup::Back, "back"),
        (LedGroup::Logic, "logic"),
        (LedGroup::Holo, "holo"),
    ]
    .into_iter()
    .find(|(g, _)| lower(model, &Intent::LedRgb(*g, [0, 0, 0])).is_ok())
    .map(|(_, n)| n)
}

/// A command as the bridge takes it, for a payload Home Assistant sends.
fn command(cmd: Value) -> String {
    let mut c = json!({"v": super::schema::VERSION});
    if let (Some(c), Value::Object(m)) = (c.as_object_mut(), cmd) {
        c.extend(m);
    }
    c.to_string()
}

/// The node id of droid `d`'s entities: the bridge's prefix and the droid's topic level, as
/// discovery allows (`[A-Za-z0-9_-]+`), and injective (issue 37 point 12): two bridges with
/// different prefixes never share discovery topics, so one's clean exit (which clears its
/// own) never removes the other's entities. Replacing what discovery does not allow by `-`
/// made `lab/a` and `lab-a` one node.
///
/// When both are made of `[A-Za-z0-9-]` only (the usual `droidctl` and `D2-0001`) the id is
/// `PREFIX_TOPIC`, as before: the one `_` splits it back. Otherwise each byte outside
/// `[A-Za-z0-9-]` (`_` included) is `_` and two lowercase hex digits, and the two parts are
/// joined by `__`, which no escape starts with: `lab/a` and `D2-0001` give
/// `lab_2fa__D2-0001`. Both forms read back one way only, and a plain id holds one `_` where
/// an escaped one holds `__`, so no two (prefix, topic) pairs share an id.
pub fn node_id(d: &Droid) -> String {
    node_of(d.prefix, d.topic)
}

fn node_of(prefix: &str, topic: &str) -> String {
    let plain =
        |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'-');
    if plain(prefix) && plain(topic) {
        format!("{prefix}_{topic}")
    } else {
        format!("{}__{}", escaped(prefix), escaped(topic))
    }
}

/// `s` with each byte outside `[A-Za-z0-9-]` as `_XX` (lowercase hex).
fn escaped(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for b in s.bytes() {
        if b.is_ascii_alphanumeric() || b == b'-' {
            out.push(char::from(b));
        } else {
            out.push_str(&format!("_{b:02x}"));
        }
    }
    out
}

/// Droid `d`'s discovery messages under `ha` (the discovery prefix): (topic, payload).
pub fn configs(ha: &str, d: &Droid) -> Vec<(String, String)> {
    let node = node_id(d);
    let at = |leaf: &str| topic(d.prefix, d.topic, leaf);
    let (state, cmd) = (at("state"), at("cmd"));
    // A droid that took a distinct topic (its name was live on the broker already) is
    // named by it: two devices called alike would be told apart by nothing.
    let name = if super::topic_name(d.name) == d.topic {
        d.name
    } else {
        d.topic
    };
    let mut device = json!({
        "identifiers": [node.clone()],
        "name": name,
        "model": d.model.display_name(),
        "sw_version": concat!("droidctl ", env!("CARGO_PKG_VERSION")),
        "via_device": bridge_node(d.prefix, d.bridge),
    });
    if let (Some(m), Some(dev)) = (manufacturer(d.model), device.as_object_mut()) {
        dev.insert("manufacturer".into(), json!(m));
    }
    // Unavailable unless the droid's link is up (the last will says offline).
    let availability = json!([{
        "topic": state,
        "value_template": "{{ 'online' if value_json.state == 'connected' else 'offline' }}",
    }]);
    let family = crate::family::for_model(d.model);
    let mut entities: Vec<(&str, &str, Value)> = Vec::new();
    if family.battery_request_for(d.model).is_some() {
        entities.push((
            "sensor",
            "battery",
            json!({
                "name": "Battery voltage",
                "state_topic": at("battery"),
                "value_template": "{{ value_json.volts }}",
                "device_class": "voltage",
                "unit_of_measurement": "V",
                "state_class": "measurement",
                "entity_category": "diagnostic",
                "availability": availability,
            }),
        ));
        if !d.model.has(crate::model::Caps::TARGETED) {
            entities.push((
                "sensor",
                "battery_level",
                json!({
                    "name": "Battery",
                    "state_topic": at("battery"),
                    "value_template": PERCENT_TEMPLATE,
                    "device_class": "battery",
                    "unit_of_measurement": "%",
                    "state_class": "measurement",
                    "entity_category": "diagnostic",
                    "availability": availability,
                }),
            ));
        }
    }
    entities.push((
        "binary_sensor",
        "connection",
        json!({
            "name": "Connection",
            "state_topic": state,
            "value_template": "{{ 'ON' if value_json.state == 'connected' else 'OFF' }}",
            "device_class": "connectivity",
            "entity_category": "diagnostic",
        }),
    ));
    entities.push((
        "sensor",
        "collisions",
        json!({
            "name": "Collisions",
            // Retained (issue 40 point 5): Home Assistant restarted reads the count at once.
            "state_topic": at("collisions"),
            "value_template": "{{ value_json.collisions }}",
            "state_class": "total_increasing",
            "icon": "mdi:car-brake-alert",
            "entity_category": "diagnostic",
            "availability": availability,
        }),
    ));
    entities.push((
        "button",
        "stop",
        json!({
            "name": "Stop",
            "command_topic": cmd,
            "payload_press": command(json!({"cmd": "stop"})),
            "icon": "mdi:stop-circle",
            "availability": availability,
        }),
    ));
    entities.push((
        "switch",
        "motion",
        json!({
            "name": "Motion enabled",
            "command_topic": cmd,
            "payload_on": command(json!({"cmd": "release"})),
            "payload_off": command(json!({"cmd": "hold"})),
            "state_topic": at("hold"),
            "value_template": "{{ 'OFF' if value_json.held else 'ON' }}",
            "state_on": "ON",
            "state_off": "OFF",
            "icon": "mdi:hand-back-left",
            "availability": availability,
        }),
    ));
    if let Some(group) = main_light(d.model) {
        entities.push((
            "light",
            "light",
            json!({
                "name": "Light",
                "schema": "json",
                "command_topic": at(super::ha_light::SET_LEAF),
                "state_topic": at(super::ha_light::STATE_LEAF),
                "supported_color_modes": ["rgb"],
                "brightness": true,
                "brightness_scale": 255,
                "icon": format!("mdi:lightbulb-{}", if group == "front" { "on" } else { "outline" }),
                "availability": availability,
            }),
        ));
    }
    let stance = crate::family::intent::Intent::Stance(crate::protocol::wire::LegAction::Tripod);
    if d.model.has(crate::model::Caps::LEGS) && family.lower(d.model, &stance).is_ok() {
        entities.push((
            "select",
            "stance",
            json!({
                "name": "Stance",
                "command_topic": cmd,
                "command_template": format!(
                    "{{\"v\":{},\"cmd\":\"stance\",\"stance\":\"{{{{ value }}}}\"}}",
                    super::schema::VERSION
                ),
                "options": ["bipod", "tripod", "waddle", "stop"],
                "optimistic": true,
                "icon": "mdi:human-male",
                "availability": availability,
            }),
        ));
    }
    for (palette, what, object, name, icon) in [
        (
            Palette::Animations,
            "animation",
            "animation",
            "Animation",
            "mdi:robot-excited",
        ),
        (
            Palette::Sounds,
            "sound",
            "sound",
            "Sound",
            "mdi:volume-high",
        ),
    ] {
        // Offered as the app offers them: where the droid's family plays them.
        let plays = match palette {
            Palette::Animations => lower(d.model, &Intent::Animation(0)).is_ok(),
            Palette::Sounds => lower(d.model, &Intent::Sound(0)).is_ok(),
        };
        if !plays {
            continue;
        }
        let options: Vec<&str> = palette.entries().iter().map(|e| e.name.as_str()).collect();
        entities.push((
            "select",
            object,
            json!({
                "name": name,
                "command_topic": cmd,
                // The name as JSON (`tojson`): the bridge takes it as the catalogue's.
                "command_template": format!(
                    "{{\"v\":{},\"cmd\":\"{what}\",\"{what}\":{{{{ value | tojson }}}}}}",
                    super::schema::VERSION
                ),
                "options": options,
                // What the droid played (said once it answered), retained.
                "state_topic": at(what),
                "value_template": "{{ value_json.name }}",
                "icon": icon,
                "availability": availability,
            }),
        ));
    }
    if d.model.has(crate::model::Caps::HEADING) {
        entities.push((
            "number",
            "speed",
            json!({
                "name": "Speed",
                "command_topic": cmd,
                // The cruise speed ([`super::cruise`]): what the Heading number rolls at.
                // It moves nothing by itself (a drive alone stops after the command
                // timeout); retained, so Home Assistant shows it after a restart.
                "command_template": format!(
                    "{{\"v\":{},\"cmd\":\"cruise\",\"speed\":{{{{ value | int }}}}}}",
                    super::schema::VERSION
                ),
                "state_topic": at(super::cruise::CRUISE_LEAF),
                "value_template": "{{ value_json.speed }}",
                "min": 0,
                "max": 255,
                "step": 1,
                "mode": "slider",
                "icon": "mdi:speedometer",
                "availability": availability,
            }),
        ));
        entities.push((
            "number",
            "heading",
            json!({
                "name": "Heading",
                "command_topic": cmd,
                // A drive without a speed: at the cruise speed (the Speed number) toward the
                // heading, until the command timeout stops it; at cruise 0 (the default)
                // the droid turns in place to face it.
                "command_template": format!(
                    "{{\"v\":{},\"cmd\":\"drive\",\"heading\":{{{{ value | int }}}}}}",
                    super::schema::VERSION
                ),
                "min": 0,
                "max": 359,
                "step": 1,
                "mode": "slider",
                "unit_of_measurement": "°",
                "optimistic": true,
                "icon": "mdi:compass",
                "availability": availability,
            }),
        ));
    }
    entities
        .into_iter()
        .map(|(component, object, mut payload)| {
            if let Some(p) = payload.as_object_mut() {
                p.insert("unique_id".into(), json!(format!("{node}_{object}")));
                p.insert("device".into(), device.clone());
                p.insert("origin".into(), origin());
            }
            (
                format!("{ha}/{component}/{node}/{object}/config"),
                payload.to_string(),
            )
        })
        .collect()
}

/// Who makes droid `model` (the device's `manufacturer`): Sphero for the robots that speak
/// Sphero's protocols (the Star Wars droids included, made by Sphero under licence). Robi
/// 42 (RSRCP) is not Sphero's and no spec here names its maker: none said.
fn manufacturer(model: Model) -> Option<&'static str> {
    use crate::model::Protocol;
    matches!(model.protocol(), Protocol::SpheroV1 | Protocol::SpheroV2).then_some("Sphero")
}

/// The topics a droid's connection takes from Home Assistant: its birth message and the
/// light's commands (JSON schema: [`super::ha_light`]).
pub struct Topics {
    pub birth: Option<String>,
    /// The light's command topic and the light group it sets.
    pub light: Option<(String, &'static str)>,
}

impl Topics {
    /// Droid `i`'s, under the bridge's topic prefix `prefix`.
    pub fn new(bridge: &super::Bridge, prefix: &str, i: usize) -> Topics {
        let Some(ha) = bridge.settings().homeassistant.as_deref() else {
            return Topics {
                birth: None,
                light: None,
            };
        };
        let t = bridge.topic(i).unwrap_or("droid");
        let group = bridge.fleet().member(i).and_then(|m| main_light(m.model));
        Topics {
            birth: Some(format!("{ha}/status")),
            light: group.map(|g| (topic(prefix, t, super::ha_light::SET_LEAF), g)),
        }
    }

    /// What the connection subscribes to.
    pub fn filters(&self) -> Vec<String> {
        let light = self.light.as_ref().map(|(t, _)| t.clone());
        self.birth.iter().cloned().chain(light).collect()
    }

    /// Whether `t` is one of them.
    pub fn owns(&self, t: &str) -> bool {
        self.birth.as_deref() == Some(t) || self.light.as_ref().is_some_and(|(l, _)| l == t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// R2-D2, by its id (a robot is named in its own files only).
    fn r2() -> Model {
        Model::from_id("r2d2").unwrap()
    }

    fn node(prefix: &str, topic: &str) -> String {
        node_id(&Droid {
            prefix,
            topic,
            name: topic,
            model: r2(),
            bridge: "b",
        })
    }

    /// What Home Assistant takes as a node id.
    fn valid(id: &str) -> bool {
        !id.is_empty()
            && id
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-')
    }

    #[test]
    fn prefixes_that_looked_alike_are_distinct_nodes() {
        assert_ne!(node("lab/a", "SB-0001"), node("lab-a", "SB-0001"));
        assert_eq!(node("lab-a", "SB-0001"), "lab-a_SB-0001");
        assert_eq!(node("lab/a", "SB-0001"), "lab_2fa__SB-0001");
        // The split between prefix and topic is not ambiguous either.
        assert_ne!(node("droidctl_a", "b"), node("droidctl", "a_b"));
        assert_ne!(node("a", "b_c"), node("a_b", "c"));
        // The usual ids are the ones Home Assistant already knows.
        assert_eq!(node("droidctl", "D2-0001"), "droidctl_D2-0001");
        for (p, t) in [("", ""), ("", "x"), ("é/#+", "Robi 42"), ("a__b", "_")] {
            assert!(valid(&node(p, t)), "{p:?} {t:?}: {}", node(p, t));
        }
    }

    proptest! {
        /// Many pairs from a small alphabet: near misses (`/` for `-`, `_` at the join,
        /// an escape spelt out) are bound to meet.
        #[test]
        fn distinct_prefixes_and_topics_never_share_a_node(
            pairs in proptest::collection::vec(("[a2f_/-]{0,3}", "[a2f_/ -]{0,3}"), 1..80),
        ) {
            let mut seen = std::collections::HashMap::new();
            for (p, t) in &pairs {
                let n = node(p, t);
                prop_assert!(valid(&n), "{p:?} {t:?}: {n}");
                if let Some(other) = seen.insert(n.clone(), (p, t)) {
                    prop_assert_eq!(other, (p, t), "both are {}", n);
                }
            }
        }

        #[test]
        fn any_text_gives_a_valid_node_that_no_other_shares(
            a in ("\\PC{0,8}", "\\PC{0,8}"),
            b in ("\\PC{0,8}", "\\PC{0,8}"),
        ) {
            let (na, nb) = (node(&a.0, &a.1), node(&b.0, &b.1));
            prop_assert!(valid(&na) && valid(&nb), "{na} {nb}");
            prop_assert_eq!(a == b, na == nb, "{:?} {:?}: {} {}", a, b, na, nb);
        }
    }

    #[test]
    fn r2d2_has_every_entity_and_robi_no_battery_poll() {
        let d = Droid {
            prefix: "droidctl",
            topic: "D2-0001",
            name: "D2-0001",
            model: r2(),
            bridge: "pi",
        };
        let topics: Vec<String> = configs("homeassistant", &d)
            .into_iter()
            .map(|(t, _)| t)
            .collect();
        assert_eq!(
            topics,
            [
                "homeassistant/sensor/droidctl_D2-0001/battery/config",
                "homeassistant/sensor/droidctl_D2-0001/battery_level/config",
                "homeassistant/binary_sensor/droidctl_D2-0001/connection/config",
                "homeassistant/sensor/droidctl_D2-0001/collisions/config",
                "homeassistant/button/droidctl_D2-0001/stop/config",
                "homeassistant/switch/droidctl_D2-0001/motion/config",
                "homeassistant/light/droidctl_D2-0001/light/config",
                "homeassistant/select/droidctl_D2-0001/stance/config",
                "homeassistant/select/droidctl_D2-0001/animation/config",
                "homeassistant/select/droidctl_D2-0001/sound/config",
                "homeassistant/number/droidctl_D2-0001/speed/config",
                "homeassistant/number/droidctl_D2-0001/heading/config",
            ]
        );
        // RVR's pack is not one cell: volts, no percent.
        let rvr = Droid {
            model: Model::from_id("rvr").unwrap(),
            ..d
        };
        let rvr: Vec<String> = configs("homeassistant", &rvr)
            .into_iter()
            .map(|(t, _)| t)
            .collect();
        assert!(rvr.iter().any(|t| t.contains("/battery/")), "{rvr:?}");
        assert!(!rvr.iter().any(|t| t.contains("battery_level")), "{rvr:?}");
        for (_, p) in configs("homeassistant", &d) {
            let v: Value = serde_json::from_str(&p).unwrap();
            assert!(
                v["unique_id"]
                    .as_str()
                    .unwrap()
                    .starts_with("droidctl_D2-0001_")
            );
        }
    }
}
