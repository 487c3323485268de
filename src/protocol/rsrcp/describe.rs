//! Explaining handshakes, frames and errors: JSON, one-line summaries and packet-log fields.
//!
//! The JSON object always has the same keys, `null` where they do not apply, so scripts can
//! read any line of a capture the same way.

use super::Item;
use super::error::FrameError;
use super::frame::{Frame, Handshake};
use crate::protocol::notify::SensorSample;
use crate::protocol::value::{Fields, Value};
use serde::Serialize;

/// Every key of the JSON form, in order.
pub const JSON_KEYS: [&str; 16] = [
    "kind",
    "version",
    "msdt_ms",
    "frame_id",
    "efs",
    "features",
    "motor_left_rad_s",
    "motor_right_rad_s",
    "poti",
    "buttons",
    "leds",
    "piezo_on",
    "piezo_hz",
    "error",
    "offset",
    "detail",
];

/// A motor speed as JSON: rounded to the wire's hundredths in f64, so 0.8 prints as 0.8 and
/// not as f32's 0.800000011920929.
fn rad_s(x: f32) -> Option<f64> {
    let v = (f64::from(x) * 100.0).round() / 100.0;
    v.is_finite().then_some(v)
}

/// The JSON object for a handshake, a frame or an error: always every key of [`JSON_KEYS`],
/// null where it does not apply. Written straight to the output with
/// `serde_json::to_writer`.
#[derive(Serialize, Default)]
pub struct Json<'a> {
    kind: Option<&'static str>,
    version: Option<u8>,
    msdt_ms: Option<u16>,
    frame_id: Option<u32>,
    efs: Option<u16>,
    features: Option<Vec<&'static str>>,
    motor_left_rad_s: Option<f64>,
    motor_right_rad_s: Option<f64>,
    poti: Option<u8>,
    buttons: Option<Vec<&'static str>>,
    leds: Option<Vec<&'static str>>,
    piezo_on: Option<bool>,
    piezo_hz: Option<u16>,
    error: Option<&'static str>,
    offset: Option<u64>,
    detail: Option<&'a str>,
}

impl Json<'_> {
    /// The same object with the stream offset where the item starts (`packet decode --file`).
    pub fn at(mut self, offset: u64) -> Self {
        self.offset = Some(offset);
        self
    }

    fn handshake(h: &Handshake) -> Self {
        Json {
            kind: Some("handshake"),
            version: Some(h.version),
            msdt_ms: Some(h.msdt_ms),
            ..Json::default()
        }
    }

    fn frame(f: &Frame) -> Self {
        Json {
            kind: Some("frame"),
            frame_id: Some(f.frame_id),
            efs: Some(f.efs.bits()),
            features: Some(f.efs.names()),
            motor_left_rad_s: f.motors.as_ref().and_then(|m| rad_s(m.left_rad_s)),
            motor_right_rad_s: f.motors.as_ref().and_then(|m| rad_s(m.right_rad_s)),
            poti: f.poti,
            buttons: f.buttons.map(|b| b.names()),
            leds: f.leds.map(|l| l.names()),
            piezo_on: f.piezo.as_ref().map(|p| p.on),
            piezo_hz: f.piezo.as_ref().map(|p| p.hz),
            ..Json::default()
        }
    }
}

/// The JSON form of whatever a decoder or the framer produced.
pub fn json(r: &Result<Item, FrameError>) -> Json<'_> {
    match r {
        Ok(item) => item.json(),
        Err(e) => e.json_object(),
    }
}

/// JSON for whatever a decoder or the framer produced, as a value (for tests and tools
/// that want to look inside; output goes through [`json`]).
pub fn to_json(r: &Result<Item, FrameError>) -> serde_json::Value {
    value(&json(r))
}

fn value(j: &Json<'_>) -> serde_json::Value {
    serde_json::to_value(j).unwrap_or(serde_json::Value::Null)
}

impl Item {
    /// The JSON object as a value (see [`to_json`]).
    pub fn to_json(&self) -> serde_json::Value {
        value(&self.json())
    }

    pub fn json(&self) -> Json<'static> {
        match self {
            Item::Handshake(h) => Json::handshake(h),
            Item::Frame(f) => Json::frame(f),
        }
    }

    pub fn summary(&self) -> String {
        match self {
            Item::Handshake(h) => h.summary(),
            Item::Frame(f) => f.summary(),
        }
    }

    pub fn fields(&self) -> Fields {
        match self {
            Item::Handshake(h) => h.fields(),
            Item::Frame(f) => f.fields(),
        }
    }
}

impl Handshake {
    /// The JSON object as a value (see [`to_json`]).
    pub fn to_json(&self) -> serde_json::Value {
        value(&Json::handshake(self))
    }

    /// `handshake v1 (1.0.0) msdt 10 ms`.
    pub fn summary(&self) -> String {
        format!(
            "handshake v{} ({}) msdt {} ms",
            self.version,
            self.version_name().unwrap_or("unknown version"),
            self.msdt_ms
        )
    }

    pub fn fields(&self) -> Fields {
        vec![
            ("version", Value::Int(i64::from(self.version))),
            ("msdt_ms", Value::Int(i64::from(self.msdt_ms))),
        ]
    }
}

impl Frame {
    /// The JSON object as a value (see [`to_json`]).
    pub fn to_json(&self) -> serde_json::Value {
        value(&Json::frame(self))
    }

    /// `frame 1234 motors L 1.25 R 0.80 rad/s poti 128 buttons center,left`: the frame id,
    /// then each decoded feature in wire order.
    pub fn summary(&self) -> String {
        let mut s = format!("frame {}", self.frame_id);
        let list = |names: Vec<&str>| {
            if names.is_empty() {
                "none".to_string()
            } else {
                names.join(",")
            }
        };
        if let Some(m) = &self.motors {
            s += &format!(" motors L {:.2} R {:.2} rad/s", m.left_rad_s, m.right_rad_s);
        }
        if let Some(p) = self.poti {
            s += &format!(" poti {p}");
        }
        if let Some(b) = self.buttons {
            s += &format!(" buttons {}", list(b.names()));
        }
        if let Some(l) = self.leds {
            s += &format!(" leds {}", list(l.names()));
        }
        if let Some(p) = &self.piezo {
            let state = if p.on { "on" } else { "off" };
            s += &format!(" piezo {state} {} Hz", p.hz);
        }
        if self.efs.is_empty() && self.efs.reserved() == 0 {
            s += " (no features)";
        }
        s
    }

    /// The packet log's fields, in wire order; only the decoded features appear.
    pub fn fields(&self) -> Fields {
        let mut f: Fields = vec![
            ("frame_id", Value::Int(i64::from(self.frame_id))),
            (
                "efs",
                Value::Flags {
                    bits: u64::from(self.efs.bits()),
                    names: self.efs.names(),
                },
            ),
        ];
        if let Some(m) = &self.motors {
            f.push(("motor_left_rad_s", Value::Float(f64::from(m.left_rad_s))));
            f.push(("motor_right_rad_s", Value::Float(f64::from(m.right_rad_s))));
        }
        if let Some(p) = self.poti {
            f.push(("poti", Value::Int(i64::from(p))));
        }
        if let Some(b) = self.buttons {
            f.push((
                "buttons",
                Value::Flags {
                    bits: u64::from(b.bits()),
                    names: b.names(),
                },
            ));
        }
        if let Some(l) = self.leds {
            f.push((
                "leds",
                Value::Flags {
                    bits: u64::from(l.bits()),
                    names: l.names(),
                },
            ));
        }
        if let Some(p) = &self.piezo {
            f.push(("piezo_on", Value::Bool(p.on)));
            f.push(("piezo_hz", Value::Int(i64::from(p.hz))));
        }
        f
    }

    /// The numeric values by name, for telemetry (the shared form every family reports
    /// sensors in): motor speeds in rad/s, the poti 0..255, the piezo frequency in Hz
    /// (0 while silent).
    pub fn sensor_sample(&self) -> SensorSample {
        let mut values = Vec::new();
        if let Some(m) = &self.motors {
            values.push(("motor_left_rad_s", m.left_rad_s));
            values.push(("motor_right_rad_s", m.right_rad_s));
        }
        if let Some(p) = self.poti {
            values.push(("poti", f32::from(p)));
        }
        if let Some(p) = &self.piezo {
            values.push(("piezo_hz", if p.on { f32::from(p.hz) } else { 0.0 }));
        }
        SensorSample { values }
    }
}

impl FrameError {
    /// The JSON object as a value (see [`to_json`]).
    pub fn to_json(&self) -> serde_json::Value {
        value(&self.json_object())
    }

    /// JSON with `error`, `offset` and `detail`; a partial frame fills the frame keys too.
    pub fn json_object(&self) -> Json<'_> {
        let mut j = self.partial().map(Json::frame).unwrap_or_default();
        j.error = Some(self.kind.name());
        j.offset = Some(self.offset);
        j.detail = Some(&self.detail);
        j
    }

    /// `bad_eop at offset 12: …`, followed by what was decoded for a partial frame.
    pub fn summary(&self) -> String {
        match self.partial() {
            Some(f) => format!("{self}; decoded {}", f.summary()),
            None => self.to_string(),
        }
    }
}
