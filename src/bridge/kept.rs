//! What the MQTT transport keeps per droid to publish retained beside the bridge's own
//! objects (issue 40 points 3 and 5): the collision count (so a client or Home Assistant
//! restarted reads it at once, where `collision` events are not retained) and the light as
//! Home Assistant set it ([`super::ha_light`]), published once the droid said done.

use super::ha_light::{self, Light};
use super::schema::Out;
use crate::sync::lock;
use serde_json::{Value, json};
use std::sync::Mutex;

/// The collision count's topic leaf (retained).
pub const COLLISIONS_LEAF: &str = "collisions";

#[derive(Debug, Default)]
struct Droid {
    light: Light,
    /// A light Home Assistant asked for, waiting for the droid's answer.
    pending: Option<Light>,
    collisions: u32,
}

/// Per droid, in the fleet's order.
#[derive(Debug)]
pub struct Kept {
    droids: Vec<Mutex<Droid>>,
}

/// The `collisions` object: droid `droid`'s collision count.
fn collisions_json(droid: &str, n: u32) -> String {
    json!({
        "v": super::schema::VERSION,
        "type": "collisions",
        "droid": droid,
        "collisions": n,
    })
    .to_string()
}

impl Kept {
    pub fn new(droids: usize) -> Kept {
        Kept {
            droids: (0..droids).map(|_| Mutex::default()).collect(),
        }
    }

    /// Home Assistant's light command for droid `i`: the bridge command it becomes (for
    /// light group `group`), or why it cannot be read.
    pub fn light_set(&self, i: usize, group: &str, payload: &[u8]) -> Result<String, String> {
        let d = self.droids.get(i).ok_or("no such droid")?;
        let mut d = lock(d);
        let next = d.pending.unwrap_or(d.light).apply(payload)?;
        d.pending = Some(next);
        Ok(next.command(group))
    }

    /// What object `o` about droid `i` (named `name`) adds, retained: (topic leaf,
    /// payload).
    pub fn after(&self, i: usize, o: &Out) -> Option<(&'static str, String)> {
        let mut d = lock(self.droids.get(i)?);
        let is_light =
            |id: &Option<Value>| id.as_ref().and_then(Value::as_str) == Some(ha_light::REPLY_ID);
        match o {
            Out::Collision {
                droid, collisions, ..
            } => {
                d.collisions = *collisions;
                Some((COLLISIONS_LEAF, collisions_json(droid, *collisions)))
            }
            Out::Reply { id, .. } if is_light(&Some(id.clone())) => {
                d.light = d.pending.take()?;
                Some((ha_light::STATE_LEAF, d.light.state()))
            }
            Out::Error { id, .. } if is_light(id) => {
                d.pending = None;
                None
            }
            _ => None,
        }
    }

    /// What droid `i` (named `name`) has retained, published anew at each connection: its
    /// collision count and, with Home Assistant's light, the light.
    pub fn at_connect(&self, i: usize, name: &str, light: bool) -> Vec<(&'static str, String)> {
        let Some(d) = self.droids.get(i) else {
            return Vec::new();
        };
        let d = lock(d);
        let mut out = vec![(COLLISIONS_LEAF, collisions_json(name, d.collisions))];
        if light {
            out.push((ha_light::STATE_LEAF, d.light.state()));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_light_state_follows_the_droids_answer_and_the_count_each_collision() {
        let k = Kept::new(1);
        let cmd = k
            .light_set(
                0,
                "front",
                br#"{"state":"ON","color":{"r":0,"g":0,"b":255}}"#,
            )
            .unwrap();
        assert!(cmd.contains("\"rgb\":[0,0,255]"), "{cmd}");
        // Not yet said: the droid has not answered.
        assert_eq!(k.at_connect(0, "D", true)[1].1, Light::default().state());
        let failed = Out::Error {
            id: Some(ha_light::REPLY_ID.into()),
            droid: None,
            cmd: None,
            code: super::super::schema::ErrorCode::Droid,
            robot: None,
            capability: None,
            error: String::new(),
        };
        assert_eq!(k.after(0, &failed), None);
        k.light_set(0, "front", br#"{"state":"ON","brightness":51}"#)
            .unwrap();
        let done = Out::Reply {
            id: ha_light::REPLY_ID.into(),
            droid: None,
            cmd: "lights",
            ok: true,
            note: None,
        };
        let (leaf, state) = k.after(0, &done).unwrap();
        assert_eq!(leaf, "light");
        let s: Value = serde_json::from_str(&state).unwrap();
        // The failed blue was not kept: white at 51.
        assert_eq!(s["color"], json!({"r":255,"g":255,"b":255}));
        assert_eq!(s["brightness"], 51);
        let hit = Out::Collision {
            droid: "D".into(),
            t_ms: 0,
            axis: "x",
            power: [1, 0],
            speed: 0,
            collisions: 3,
        };
        let (leaf, c) = k.after(0, &hit).unwrap();
        assert_eq!((leaf, c.contains("\"collisions\":3")), ("collisions", true));
        assert!(
            k.at_connect(0, "D", false)[0]
                .1
                .contains("\"collisions\":3")
        );
    }
}
