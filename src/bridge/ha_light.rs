//! A droid's main light as Home Assistant's MQTT light with the JSON schema (issue 40
//! point 3): Home Assistant sends `{"state":"ON","brightness":128,"color":{"r":255,"g":0,"b":0}}`
//! (each key only when it changes: a brightness alone keeps the colour) to
//! `PREFIX/DROID/light/set`, and reads the light back, retained, from `PREFIX/DROID/light`
//! (<https://www.home-assistant.io/integrations/light.mqtt/#json-schema>).
//!
//! The droids' colour lights have no brightness of their own (a family lowers only a colour
//! for the main light's group): brightness scales the colour, so 50 % red is `[128, 0, 0]`.
//! Sans-IO: [`Light::apply`] reads a command, [`Light::command`] is the bridge command it
//! becomes, [`Light::state`] what is published once the droid said done.

use serde_json::{Value, json};

/// The topic leaves: Home Assistant's commands in, the light's state out (retained).
pub const SET_LEAF: &str = "light/set";
pub const STATE_LEAF: &str = "light";

/// The `id` of the bridge commands a Home Assistant light command becomes: their reply
/// tells the MQTT transport to publish the new state.
pub const REPLY_ID: &str = "homeassistant-light";

/// The light as Home Assistant knows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Light {
    pub on: bool,
    /// The colour chosen, at full brightness.
    pub rgb: [u8; 3],
    pub brightness: u8,
}

impl Default for Light {
    /// Off; white at full brightness when switched on without a colour.
    fn default() -> Light {
        Light {
            on: false,
            rgb: [255, 255, 255],
            brightness: 255,
        }
    }
}

/// The largest command taken from Home Assistant (its own are under 200 bytes).
pub const MAX_SET_BYTES: usize = 1024;

impl Light {
    /// The light after Home Assistant's command `payload`, or why it cannot be read.
    pub fn apply(&self, payload: &[u8]) -> Result<Light, String> {
        if payload.len() > MAX_SET_BYTES {
            return Err(format!(
                "a light command of {} bytes: at most {MAX_SET_BYTES}",
                payload.len()
            ));
        }
        let v: Value = serde_json::from_slice(payload)
            .map_err(|e| format!("not Home Assistant's JSON light command: {e}"))?;
        let obj = v
            .as_object()
            .ok_or("a light command is a JSON object, e.g. {\"state\":\"ON\"}")?;
        let mut next = *self;
        match obj.get("state").and_then(Value::as_str) {
            Some("ON") => next.on = true,
            Some("OFF") => next.on = false,
            _ => return Err("`state` is \"ON\" or \"OFF\"".into()),
        }
        if let Some(b) = obj.get("brightness") {
            next.brightness = byte(b).ok_or("`brightness` is 0..=255")?;
        }
        if let Some(c) = obj.get("color") {
            let part = |k: &str| c.get(k).and_then(byte);
            next.rgb = match (part("r"), part("g"), part("b")) {
                (Some(r), Some(g), Some(b)) => [r, g, b],
                _ => return Err("`color` is {\"r\":…,\"g\":…,\"b\":…}, each 0..=255".into()),
            };
        }
        // Home Assistant's "on" at brightness 0 is off (its slider's bottom).
        if next.on && next.brightness == 0 {
            next.brightness = 255;
        }
        Ok(next)
    }

    /// The colour the droid shows: the chosen one scaled by brightness, black when off.
    pub fn shown(&self) -> [u8; 3] {
        if !self.on {
            return [0, 0, 0];
        }
        self.rgb
            .map(|c| ((c as u16 * self.brightness as u16 + 127) / 255) as u8)
    }

    /// The bridge command for group `group` (with [`REPLY_ID`]).
    pub fn command(&self, group: &str) -> String {
        json!({
            "v": super::schema::VERSION,
            "cmd": "lights",
            "group": group,
            "rgb": self.shown(),
            "id": REPLY_ID,
        })
        .to_string()
    }

    /// The state Home Assistant reads (retained on [`STATE_LEAF`]).
    pub fn state(&self) -> String {
        let [r, g, b] = self.rgb;
        json!({
            "state": if self.on { "ON" } else { "OFF" },
            "color_mode": "rgb",
            "brightness": self.brightness,
            "color": {"r": r, "g": g, "b": b},
        })
        .to_string()
    }
}

/// A colour channel or brightness: an integer 0..=255 (Home Assistant may write `128.0`).
fn byte(v: &Value) -> Option<u8> {
    let f = v.as_f64()?;
    (f.fract() == 0.0 && (0.0..=255.0).contains(&f)).then_some(f as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brightness_scales_the_colour_and_each_key_keeps_the_others() {
        let l = Light::default();
        let red = l
            .apply(br#"{"state":"ON","color":{"r":255,"g":0,"b":0}}"#)
            .unwrap();
        assert_eq!(red.shown(), [255, 0, 0]);
        let half = red.apply(br#"{"state":"ON","brightness":128}"#).unwrap();
        assert_eq!(half.shown(), [128, 0, 0], "the colour kept, scaled");
        let off = half.apply(br#"{"state":"OFF"}"#).unwrap();
        assert_eq!(off.shown(), [0, 0, 0]);
        let on = off.apply(br#"{"state":"ON"}"#).unwrap();
        assert_eq!(on.shown(), [128, 0, 0], "back on as it was");
        let c: Value = serde_json::from_str(&on.command("front")).unwrap();
        assert_eq!(c["rgb"], json!([128, 0, 0]));
        assert_eq!(c["id"], REPLY_ID);
        let s: Value = serde_json::from_str(&on.state()).unwrap();
        assert_eq!(
            s,
            json!({"state":"ON","color_mode":"rgb","brightness":128,"color":{"r":255,"g":0,"b":0}})
        );
    }

    #[test]
    fn what_home_assistant_would_not_send_is_refused_not_guessed() {
        let l = Light::default();
        for bad in [
            &b"not json"[..],
            br#"[1]"#,
            br#"{"brightness":3}"#,
            br#"{"state":"ON","brightness":300}"#,
            br#"{"state":"ON","color":{"r":1,"g":2}}"#,
            br#"{"state":"ON","color":{"r":1.5,"g":2,"b":3}}"#,
        ] {
            assert!(l.apply(bad).is_err(), "{}", String::from_utf8_lossy(bad));
        }
        assert!(l.apply(&vec![b' '; MAX_SET_BYTES + 1]).is_err());
    }
}
