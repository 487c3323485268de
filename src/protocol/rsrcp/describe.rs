//! Explaining handshakes, frames and errors: JSON, one-line summaries and packet-log fields.
//!
//! The JSON object always has the same keys, `null` where they do not apply, so scripts can
//! read any line of a capture the same way.

use super::Item;
use super::error::FrameError;
use super::frame::{Frame, Handshake};
use crate::protocol::notify::SensorSample;
use crate::protocol::value::{Fields, Value};
use serde_json::{Map, Value as Json, json};

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
fn rad_s(x: f32) -> Json {
    let v = (f64::from(x) * 100.0).round() / 100.0;
    serde_json::Number::from_f64(v).map_or(Json::Null, Json::Number)
}

fn empty() -> Map<String, Json> {
    JSON_KEYS
        .iter()
        .map(|k| ((*k).to_string(), Json::Null))
        .collect()
}

fn put_handshake(m: &mut Map<String, Json>, h: &Handshake) {
    m.insert("kind".into(), json!("handshake"));
    m.insert("version".into(), json!(h.version));
    m.insert("msdt_ms".into(), json!(h.msdt_ms));
}

fn put_frame(m: &mut Map<String, Json>, f: &Frame) {
    m.insert("kind".into(), json!("frame"));
    m.insert("frame_id".into(), json!(f.frame_id));
    m.insert("efs".into(), json!(f.efs.bits()));
    m.insert("features".into(), json!(f.efs.names()));
    if let Some(mo) = &f.motors {
        m.insert("motor_left_rad_s".into(), rad_s(mo.left_rad_s));
        m.insert("motor_right_rad_s".into(), rad_s(mo.right_rad_s));
    }
    if let Some(p) = f.poti {
        m.insert("poti".into(), json!(p));
    }
    if let Some(b) = f.buttons {
        m.insert("buttons".into(), json!(b.names()));
    }
    if let Some(l) = f.leds {
        m.insert("leds".into(), json!(l.names()));
    }
    if let Some(p) = &f.piezo {
        m.insert("piezo_on".into(), json!(p.on));
        m.insert("piezo_hz".into(), json!(p.hz));
    }
}

fn put_error(m: &mut Map<String, Json>, e: &FrameError) {
    if let Some(f) = &e.partial {
        put_frame(m, f);
    }
    m.insert("error".into(), json!(e.kind.name()));
    m.insert("offset".into(), json!(e.offset));
    m.insert("detail".into(), json!(e.detail));
}

/// JSON for whatever a decoder or the framer produced.
pub fn to_json(r: &Result<Item, FrameError>) -> Json {
    match r {
        Ok(item) => item.to_json(),
        Err(e) => e.to_json(),
    }
}

impl Item {
    pub fn to_json(&self) -> Json {
        match self {
            Item::Handshake(h) => h.to_json(),
            Item::Frame(f) => f.to_json(),
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
    pub fn to_json(&self) -> Json {
        let mut m = empty();
        put_handshake(&mut m, self);
        Json::Object(m)
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
    pub fn to_json(&self) -> Json {
        let mut m = empty();
        put_frame(&mut m, self);
        Json::Object(m)
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
    /// JSON with `error`, `offset` and `detail`; a partial frame fills the frame keys too.
    pub fn to_json(&self) -> Json {
        let mut m = empty();
        put_error(&mut m, self);
        Json::Object(m)
    }

    /// `bad_eop at offset 12: …`, followed by what was decoded for a partial frame.
    pub fn summary(&self) -> String {
        match &self.partial {
            Some(f) => format!("{self}; decoded {}", f.summary()),
            None => self.to_string(),
        }
    }
}
