//! The bridge's wire schema, version 1 (sans-IO: text in, typed values out, and back).
//!
//! A command is one JSON object: `{"v":1,"cmd":"drive","speed":100,"heading":90}`, with an
//! optional `droid` (which droid of a fleet) and `id` (a string or integer echoed in the
//! reply). Fields a verb does not take are refused (a typo must not be ignored while the
//! droid does something else). What goes out ([`Out`]) are objects with `"v":1` and a
//! `type`: `hello`, `telemetry` (the sample `run --json` prints, [`Sample`], with `droid`),
//! `collision`, `battery`, `link`, `stopped`, `reply` and `error`.
//!
//! `assets/bridge.schema.json` is the same contract as a JSON Schema; the tests validate
//! both directions against it.

use crate::family::catalog::Palette;
use crate::mission::Sample;
use crate::protocol::wire::LegAction;
use crate::script::{Action, LedGroup, MatrixAction};
use crate::tuning::SensorSet;
use crate::units::{HeadAngle, Heading};
use serde::Serialize;
use serde_json::{Map, Value};

/// The schema version this bridge speaks.
pub const VERSION: u64 = 1;

/// The longest command accepted, in bytes (a line on stdin, a payload over MQTT).
pub const MAX_COMMAND_BYTES: usize = 4096;

/// The longest `id` string echoed back.
pub const MAX_ID_CHARS: usize = 128;

/// A command as received: who it is for and what.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// Echoed in the reply: a string (at most [`MAX_ID_CHARS`]) or an integer.
    pub id: Option<Value>,
    /// The droid it is for (a name as `--name` takes it); `None`: the only droid, or the
    /// topic's droid over MQTT.
    pub droid: Option<String>,
    pub cmd: Cmd,
}

/// What a command asks for.
#[derive(Debug, Clone, PartialEq)]
pub enum Cmd {
    /// Roll at `speed` (0..=255) toward `heading` (degrees, clockwise); re-sent by the client
    /// within the command timeout to keep rolling. No `speed`: the droid's cruise speed
    /// ([`Cmd::Cruise`]), 0 until one is set (the droid turns to face the heading).
    Drive {
        speed: Option<u8>,
        heading: Heading,
    },
    /// The droid's cruise speed (0..=255): the speed of a `drive` that gives none (Home
    /// Assistant's Speed number, which its Heading number then rolls at). It moves nothing
    /// by itself; kept until changed, across reconnects, for the bridge's life.
    Cruise(u8),
    /// ROS's `cmd_vel`: forward m/s (negative backs up) and yaw rad/s (positive turns left);
    /// as flat numbers or as ROS's `geometry_msgs/Twist` (`linear.x`, `angular.z`).
    Twist {
        linear: f32,
        angular: f32,
    },
    /// Speed 0 at the last heading.
    Stop,
    /// Every droid of the bridge stops now, whatever `droid` says.
    Estop,
    /// A latched stop (issue 40 point 6): the droid stops and refuses whatever moves it
    /// (drive, twist, head, stance, animation: code `held`) until [`Cmd::Release`].
    Hold,
    /// Motion allowed again after [`Cmd::Hold`].
    Release,
    Head(HeadAngle),
    Stance(LegAction),
    /// A light: `LedRgb` or `LedBrightness` ([`Action`], as mission lines make them).
    Lights(Action),
    Animation(u16),
    Sound(u16),
    Matrix(MatrixAction),
    /// The droid's sensor streaming: samples per second (0 off) and groups (`None`: all).
    Stream {
        rate_hz: u16,
        sensors: Option<SensorSet>,
    },
}

impl Cmd {
    /// What the command asks of the droid as the families' one vocabulary, for the commands
    /// that are one (`None`: driving, stopping and streaming, which the bridge runs itself).
    pub fn intent(&self) -> Option<crate::family::intent::Intent> {
        use crate::family::intent::{Intent, Matrix};
        Some(match self {
            Cmd::Head(a) => Intent::Head(*a),
            Cmd::Stance(a) => Intent::Stance(*a),
            Cmd::Lights(a) => Intent::of_action(a)?,
            Cmd::Animation(id) => Intent::Animation(*id),
            Cmd::Sound(id) => Intent::Sound(*id),
            Cmd::Matrix(m) => Intent::Matrix(Matrix::from(m)),
            Cmd::Drive { .. }
            | Cmd::Cruise(_)
            | Cmd::Twist { .. }
            | Cmd::Stop
            | Cmd::Estop
            | Cmd::Hold
            | Cmd::Release
            | Cmd::Stream { .. } => {
                return None;
            }
        })
    }

    /// The verb as written.
    pub fn verb(&self) -> &'static str {
        match self {
            Cmd::Drive { .. } => "drive",
            Cmd::Cruise(_) => "cruise",
            Cmd::Twist { .. } => "twist",
            Cmd::Stop => "stop",
            Cmd::Estop => "estop",
            Cmd::Hold => "hold",
            Cmd::Release => "release",
            Cmd::Head(_) => "head",
            Cmd::Stance(_) => "stance",
            Cmd::Lights(_) => "lights",
            Cmd::Animation(_) => "animation",
            Cmd::Sound(_) => "sound",
            Cmd::Matrix(_) => "matrix",
            Cmd::Stream { .. } => "stream",
        }
    }

    /// Whether this is a continuous motion command (the command timeout watches these).
    pub fn is_motion(&self) -> bool {
        matches!(self, Cmd::Drive { .. } | Cmd::Twist { .. })
    }

    /// Whether a held droid refuses it: whatever moves the droid's body (an animation
    /// may roll it; a stop, lights or sounds do not).
    pub fn moves(&self) -> bool {
        matches!(
            self,
            Cmd::Drive { .. }
                | Cmd::Twist { .. }
                | Cmd::Head(_)
                | Cmd::Stance(_)
                | Cmd::Animation(_)
        )
    }
}

/// The verbs, with the fields each takes besides `v`, `cmd`, `droid` and `id`.
pub const VERBS: &[(&str, &[&str])] = &[
    ("drive", &["speed", "heading"]),
    ("cruise", &["speed"]),
    ("twist", &["linear", "angular"]),
    ("stop", &[]),
    ("estop", &[]),
    ("hold", &[]),
    ("release", &[]),
    ("head", &["angle"]),
    ("stance", &["stance"]),
    ("lights", &["group", "rgb", "brightness"]),
    ("animation", &["animation"]),
    ("sound", &["sound"]),
    (
        "matrix",
        &["op", "text", "char", "rgb", "x", "y", "degrees"],
    ),
    ("stream", &["rate_hz", "sensors"]),
];

/// Why a command was refused before it reached a droid.
#[derive(Debug, Clone, PartialEq)]
pub struct BadCommand {
    /// The command's `id` when it could be read.
    pub id: Option<Value>,
    pub droid: Option<String>,
    pub cmd: Option<String>,
    pub code: ErrorCode,
    pub message: String,
}

/// What kind of error an [`Out::Error`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorCode {
    /// Not JSON, not an object, too long.
    BadJson,
    /// `v` missing or not a version this bridge speaks.
    BadVersion,
    /// `cmd` missing or not a verb.
    UnknownCmd,
    /// A field missing, out of range, of the wrong type, or not one the verb takes.
    BadField,
    /// `droid` names no droid of the bridge, or several, or none was named with several.
    NoSuchDroid,
    /// The robot cannot do that (`robot` and `capability` say what).
    Unsupported,
    /// The droid answered with an error, did not answer, or its link is down.
    Droid,
    /// Too many commands waiting for that droid.
    Busy,
    /// A retained MQTT message on a `cmd` topic: never executed (said once per droid).
    Retained,
    /// The droid is held (`hold`): what would move it is refused until `release`.
    Held,
}

/// Why a command is refused, before what could be read of it is added.
#[derive(Debug, Clone, PartialEq)]
struct Refusal {
    code: ErrorCode,
    message: String,
}

fn bad(code: ErrorCode, message: impl Into<String>) -> Refusal {
    Refusal {
        code,
        message: message.into(),
    }
}

fn field_err(message: impl Into<String>) -> Refusal {
    bad(ErrorCode::BadField, message)
}

/// Parse one command (a line on stdin, an MQTT payload).
pub fn parse(text: &[u8]) -> Result<Request, Box<BadCommand>> {
    parse_text(text).map_err(|(e, obj)| {
        // What can be read is kept for the error, so the client can match it.
        let get = |k: &str| obj.as_ref().and_then(|o: &Map<String, Value>| o.get(k));
        Box::new(BadCommand {
            id: get("id").cloned().filter(valid_id),
            droid: get("droid").and_then(Value::as_str).map(str::to_string),
            cmd: get("cmd")
                .and_then(Value::as_str)
                .filter(|v| VERBS.iter().any(|(n, _)| n == v))
                .map(str::to_string),
            code: e.code,
            message: e.message,
        })
    })
}

type Refused = (Refusal, Option<Map<String, Value>>);

/// A UTF-8 byte-order mark, as some editors and Windows tools start a file with: not part
/// of the command (issue 27 point 8).
const BOM: &[u8] = b"\xEF\xBB\xBF";

fn parse_text(text: &[u8]) -> Result<Request, Refused> {
    let text = text.strip_prefix(BOM).unwrap_or(text);
    if text.len() > MAX_COMMAND_BYTES {
        return Err((
            bad(
                ErrorCode::BadJson,
                format!(
                    "a command of {} bytes: at most {MAX_COMMAND_BYTES}",
                    text.len()
                ),
            ),
            None,
        ));
    }
    let value: Value = serde_json::from_slice(text)
        .map_err(|e| (bad(ErrorCode::BadJson, format!("not JSON: {e}")), None))?;
    let Value::Object(obj) = value else {
        return Err((
            bad(
                ErrorCode::BadJson,
                "a command is a JSON object, e.g. {\"v\":1,\"cmd\":\"stop\"}",
            ),
            None,
        ));
    };
    match parse_object(&obj) {
        Ok(r) => Ok(r),
        Err(e) => Err((e, Some(obj))),
    }
}

fn valid_id(v: &Value) -> bool {
    match v {
        Value::String(s) => s.chars().count() <= MAX_ID_CHARS,
        Value::Number(_) => integer(v).is_some(),
        _ => false,
    }
}

fn parse_object(obj: &Map<String, Value>) -> Result<Request, Refusal> {
    match obj.get("v") {
        // `1.0` too: README and the schema take integers written as floats.
        Some(v) if integer(v) == Some(VERSION as i64) => {}
        Some(v) => {
            return Err(bad(
                ErrorCode::BadVersion,
                format!("schema version {v} is not spoken here: this bridge speaks v {VERSION}"),
            ));
        }
        None => {
            return Err(bad(
                ErrorCode::BadVersion,
                format!("`v` is missing: say which schema version, e.g. \"v\":{VERSION}"),
            ));
        }
    }
    let verb = match obj.get("cmd") {
        Some(Value::String(s)) => s.as_str(),
        Some(_) => return Err(bad(ErrorCode::UnknownCmd, "`cmd` is a string")),
        None => {
            return Err(bad(
                ErrorCode::UnknownCmd,
                "`cmd` is missing: say what to do, e.g. \"cmd\":\"stop\"",
            ));
        }
    };
    let names: Vec<&str> = VERBS.iter().map(|(n, _)| *n).collect();
    let Some((_, fields)) = VERBS.iter().find(|(n, _)| *n == verb) else {
        return Err(bad(
            ErrorCode::UnknownCmd,
            format!("unknown cmd {verb:?}: one of {}", names.join(", ")),
        ));
    };
    let id = match obj.get("id") {
        None => None,
        Some(v) if valid_id(v) => Some(v.clone()),
        Some(_) => {
            return Err(field_err(format!(
                "`id` is a string of at most {MAX_ID_CHARS} characters or an integer"
            )));
        }
    };
    let droid = match obj.get("droid") {
        None => None,
        Some(Value::String(s)) if !s.trim().is_empty() && s.len() <= 248 => {
            Some(s.trim().to_string())
        }
        Some(_) => return Err(field_err("`droid` is a droid's name (a non-empty string)")),
    };
    for k in obj.keys() {
        if !matches!(k.as_str(), "v" | "cmd" | "droid" | "id") && !fields.contains(&k.as_str()) {
            let takes = if fields.is_empty() {
                "no fields".to_string()
            } else {
                fields.join(", ")
            };
            return Err(field_err(format!(
                "{verb} takes no `{k}` (it takes {takes})"
            )));
        }
    }
    let f = Fields { obj, verb };
    let cmd = match verb {
        "drive" => Cmd::Drive {
            speed: match obj.get("speed") {
                None => None,
                Some(_) => Some(f.int("speed", 0, 255)? as u8),
            },
            heading: Heading::new(f.int("heading", 0, 359)? as u16)
                .ok_or_else(|| field_err("heading is 0..=359"))?,
        },
        "cruise" => Cmd::Cruise(f.int("speed", 0, 255)? as u8),
        "twist" => Cmd::Twist {
            linear: f.vector("linear", 'x', 5.0)?,
            angular: f.vector("angular", 'z', 20.0)?,
        },
        "stop" => Cmd::Stop,
        "estop" => Cmd::Estop,
        "hold" => Cmd::Hold,
        "release" => Cmd::Release,
        "head" => {
            // One range in every refusal: the dome's own (a number past ±180 was once
            // refused with the generic ±180 and one inside it with the dome's).
            let v = f.get("angle")?;
            let range = || {
                field_err(format!(
                    "`angle` is a number in {}..={} degrees, not {v}",
                    crate::units::HEAD_MIN_DEG,
                    crate::units::HEAD_MAX_DEG
                ))
            };
            let a = v.as_f64().filter(|n| n.is_finite()).ok_or_else(range)?;
            Cmd::Head(HeadAngle::new(a as f32).ok_or_else(range)?)
        }
        "stance" => Cmd::Stance(
            match f.word("stance", &["tripod", "bipod", "waddle", "stop"])? {
                "tripod" => LegAction::Tripod,
                "bipod" => LegAction::Bipod,
                "waddle" => LegAction::Waddle,
                _ => LegAction::Stop,
            },
        ),
        "lights" => Cmd::Lights(f.lights()?),
        "animation" => Cmd::Animation(f.palette("animation", Palette::Animations)?),
        "sound" => Cmd::Sound(f.palette("sound", Palette::Sounds)?),
        "matrix" => Cmd::Matrix(f.matrix()?),
        "stream" => Cmd::Stream {
            rate_hz: f.int("rate_hz", 0, 100)? as u16,
            sensors: f.sensors()?,
        },
        _ => unreachable!("every verb of VERBS is parsed"),
    };
    Ok(Request { id, droid, cmd })
}

/// A command's fields, read with messages that name the field and its range.
struct Fields<'a> {
    obj: &'a Map<String, Value>,
    verb: &'a str,
}

impl Fields<'_> {
    fn get(&self, k: &str) -> Result<&Value, Refusal> {
        self.obj
            .get(k)
            .ok_or_else(|| field_err(format!("{} needs `{k}`", self.verb)))
    }

    fn int(&self, k: &str, lo: i64, hi: i64) -> Result<i64, Refusal> {
        let v = self.get(k)?;
        integer(v)
            .filter(|n| (lo..=hi).contains(n))
            .ok_or_else(|| field_err(format!("`{k}` is an integer in {lo}..={hi}, not {v}")))
    }

    /// An animation's or a sound's id, or its name in the catalogue (as the app and Home
    /// Assistant's selects offer them: [`Palette`]).
    fn palette(&self, k: &str, palette: Palette) -> Result<u16, Refusal> {
        let v = self.get(k)?;
        if let Value::String(name) = v {
            return palette.id_of(name).ok_or_else(|| {
                let names: Vec<&str> = palette.entries().iter().map(|e| e.name.as_str()).collect();
                field_err(format!(
                    "no {k} is named {name:?}: one of {}, or an id 0..=65535",
                    names.join(", ")
                ))
            });
        }
        integer(v)
            .and_then(|n| u16::try_from(n).ok())
            .ok_or_else(|| {
                field_err(format!(
                    "`{k}` is an id 0..=65535 or a name from the catalogue, not {v}"
                ))
            })
    }

    /// A finite number within ±`limit`.
    fn number(&self, k: &str, limit: f64) -> Result<f32, Refusal> {
        let v = self.get(k)?;
        v.as_f64()
            .filter(|n| n.is_finite() && n.abs() <= limit)
            .map(|n| n as f32)
            .ok_or_else(|| field_err(format!("`{k}` is a number in -{limit}..={limit}, not {v}")))
    }

    /// A number within ±`limit`, or ROS's vector `{"x":…,"y":…,"z":…}` whose `axis` is
    /// that number and whose other components are 0 (a droid rolls on the ground: it
    /// cannot move sideways, climb, pitch or roll). Missing components are 0.
    fn vector(&self, k: &str, axis: char, limit: f64) -> Result<f32, Refusal> {
        let Value::Object(v) = self.get(k)? else {
            return self.number(k, limit);
        };
        let mut out = 0.0;
        for (c, x) in v {
            let n = x.as_f64().filter(|n| n.is_finite());
            match (c.as_str(), n) {
                ("x" | "y" | "z", None) => {
                    return Err(field_err(format!("`{k}.{c}` is a number, not {x}")));
                }
                (c1, Some(n)) if c1.len() == 1 && c1.starts_with(axis) => {
                    if n.abs() > limit {
                        return Err(field_err(format!(
                            "`{k}.{c}` is a number in -{limit}..={limit}, not {x}"
                        )));
                    }
                    out = n as f32;
                }
                ("x" | "y" | "z", Some(0.0)) => {}
                ("x" | "y" | "z", Some(_)) => {
                    return Err(field_err(format!(
                        "`{k}.{c}` is {x}: droidctl's droids roll on the ground and move only \
                         by linear.x (forward) and angular.z (turn left); the other components \
                         must be 0"
                    )));
                }
                _ => {
                    return Err(field_err(format!(
                        "`{k}` takes x, y and z (ROS geometry_msgs/Vector3), not `{c}`"
                    )));
                }
            }
        }
        Ok(out)
    }

    fn word<'w>(&self, k: &str, words: &[&'w str]) -> Result<&'w str, Refusal> {
        let v = self.get(k)?;
        v.as_str()
            .and_then(|s| words.iter().find(|w| **w == s).copied())
            .ok_or_else(|| field_err(format!("`{k}` is one of {}, not {v}", words.join(", "))))
    }

    fn rgb(&self, k: &str) -> Result<[u8; 3], Refusal> {
        let v = self.get(k)?;
        let parts = v.as_array().filter(|a| a.len() == 3);
        let mut out = [0u8; 3];
        match parts {
            Some(a) => {
                for (o, c) in out.iter_mut().zip(a) {
                    *o = integer(c)
                        .filter(|c| (0..=255).contains(c))
                        .ok_or_else(|| field_err(format!("`{k}` is [R, G, B], each 0..=255")))?
                        as u8;
                }
                Ok(out)
            }
            None => Err(field_err(format!("`{k}` is [R, G, B], each 0..=255"))),
        }
    }

    fn rgb_or_white(&self, k: &str) -> Result<[u8; 3], Refusal> {
        if self.obj.contains_key(k) {
            self.rgb(k)
        } else {
            Ok([255, 255, 255])
        }
    }

    fn lights(&self) -> Result<Action, Refusal> {
        let group = match self.word("group", &["front", "back", "logic", "holo"])? {
            "front" => LedGroup::Front,
            "back" => LedGroup::Back,
            "logic" => LedGroup::Logic,
            _ => LedGroup::Holo,
        };
        match (
            self.obj.contains_key("rgb"),
            self.obj.contains_key("brightness"),
        ) {
            (true, false) => Ok(Action::LedRgb(group, self.rgb("rgb")?)),
            (false, true) => Ok(Action::LedBrightness(
                group,
                self.int("brightness", 0, 255)? as u8,
            )),
            _ => Err(field_err(
                "lights takes either `rgb` ([R, G, B]) or `brightness` (0..=255)",
            )),
        }
    }

    fn matrix(&self) -> Result<MatrixAction, Refusal> {
        let op = self.word("op", &["text", "char", "fill", "pixel", "clear", "rotate"])?;
        // Only the fields of the op: `{"op":"clear","text":"x"}` is a mistake worth saying.
        let allowed: &[&str] = match op {
            "text" => &["text", "rgb"],
            "char" => &["char", "rgb"],
            "fill" => &["rgb"],
            "pixel" => &["x", "y", "rgb"],
            "rotate" => &["degrees"],
            _ => &[],
        };
        for k in ["text", "char", "rgb", "x", "y", "degrees"] {
            if self.obj.contains_key(k) && !allowed.contains(&k) {
                return Err(field_err(format!("matrix {op} takes no `{k}`")));
            }
        }
        Ok(match op {
            "text" => {
                let v = self.get("text")?;
                let text = v
                    .as_str()
                    .filter(|t| !t.is_empty() && t.len() <= 25 && t.is_ascii())
                    .ok_or_else(|| field_err("`text` is 1 to 25 ASCII characters"))?;
                MatrixAction::Text {
                    text: text.to_string(),
                    rgb: self.rgb_or_white("rgb")?,
                }
            }
            "char" => {
                let v = self.get("char")?;
                let mut chars = v.as_str().unwrap_or("").chars();
                let ch = match (chars.next(), chars.next()) {
                    (Some(c), None) if c.is_ascii_graphic() => c,
                    _ => return Err(field_err("`char` is one printable ASCII character")),
                };
                MatrixAction::Char {
                    ch,
                    rgb: self.rgb_or_white("rgb")?,
                }
            }
            "fill" => MatrixAction::Fill(self.rgb("rgb")?),
            "pixel" => MatrixAction::Pixel {
                x: self.int("x", 0, 7)? as u8,
                y: self.int("y", 0, 7)? as u8,
                rgb: self.rgb_or_white("rgb")?,
            },
            "clear" => MatrixAction::Clear,
            _ => {
                let d = self.int("degrees", 0, 270)?;
                if d % 90 != 0 {
                    return Err(field_err("`degrees` is 0, 90, 180 or 270"));
                }
                MatrixAction::Rotate(d as u16)
            }
        })
    }

    fn sensors(&self) -> Result<Option<SensorSet>, Refusal> {
        let Some(v) = self.obj.get("sensors") else {
            return Ok(None);
        };
        let names: Option<Vec<&str>> = v
            .as_array()
            .filter(|a| a.len() <= 16)
            .and_then(|a| a.iter().map(Value::as_str).collect());
        let known = |n: &&str| {
            *n == "accel"
                || crate::tuning::SensorGroup::ALL
                    .iter()
                    .any(|g| g.name() == *n)
        };
        let names = names.filter(|n| n.iter().all(known)).ok_or_else(|| {
            let all: Vec<&str> = crate::tuning::SensorGroup::ALL
                .iter()
                .map(|g| g.name())
                .collect();
            field_err(format!(
                "`sensors` is a list of sensor group names: {}",
                all.join(", ")
            ))
        })?;
        SensorSet::parse(names).map(Some).map_err(field_err)
    }
}

/// A JSON integer, also written as a float with no fraction (`100.0`, as Python's `json`
/// writes a float), as JSON Schema counts it.
fn integer(v: &Value) -> Option<i64> {
    v.as_i64().or_else(|| {
        v.as_f64()
            .filter(|f| f.fract() == 0.0 && f.abs() < 9.0e15)
            .map(|f| f as i64)
    })
}

/// A droid as `hello` lists it (and its MQTT `info` topic says).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DroidInfo {
    pub droid: String,
    /// The model's id (`r2d2`, `bb8`, `robi` …).
    pub model: &'static str,
    /// The model's name for people.
    pub robot: &'static str,
    /// Where it is: `simulated`, `Bluetooth hci0`, `relay pi.local:50004`.
    pub origin: String,
    /// The MQTT topic level the droid's topics use.
    pub topic: String,
    /// What it can do, in the words an `unsupported` error's `capability` uses (`dome`,
    /// `legs`, `lights`, `animations`, `sounds`, `matrix`, `streaming`, `reverse`).
    pub capabilities: Vec<&'static str>,
    /// New telemetry samples a second this droid offers at most: the bridge's `--rate`, or
    /// the droid's own streaming rate when that is slower (a sample goes out only when the
    /// droid reported something new).
    pub telemetry_hz: u16,
    /// Its speed at 255 in m/s: a twist's `linear` beyond it is capped (the reply says so).
    pub top_speed_m_s: f32,
}

/// Where a droid is, as a ROS user reads it (REP-103, REP-105 `odom`): metres and radians in
/// a frame fixed where the droid's heading was last reset (its power-on or aim), x forward
/// (heading 0, droidctl's +y), y left (droidctl's −x), yaw counter-clockwise from x.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Odom {
    pub x_m: f32,
    pub y_m: f32,
    /// −π..=π; `null` before the droid reported a heading.
    pub yaw_rad: Option<f32>,
}

impl Odom {
    /// From droidctl's frame: `x_cm`, `y_cm` (heading 0 is +y) and the heading in degrees
    /// clockwise.
    pub fn from_droid(x_cm: f32, y_cm: f32, heading_deg: Option<f32>) -> Odom {
        Odom {
            x_m: y_cm / 100.0,
            y_m: -x_cm / 100.0,
            yaw_rad: heading_deg.map(|h| {
                let ccw = (-h).to_radians();
                // Wrapped to −π..=π.
                let w = ccw.rem_euclid(std::f32::consts::TAU);
                if w > std::f32::consts::PI {
                    w - std::f32::consts::TAU
                } else {
                    w
                }
            }),
        }
    }
}

/// Everything the bridge sends.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Out {
    /// First, on stdio: the droids and the settings that bind a client.
    Hello {
        droidctl: &'static str,
        droids: Vec<DroidInfo>,
        command_timeout_ms: u64,
        telemetry_hz: u16,
    },
    /// A sample as `run --json` prints it, naming its droid, and the same position as a
    /// ROS user reads it ([`Odom`]; `null` before the droid reported a position).
    Telemetry {
        droid: String,
        #[serde(flatten)]
        sample: Sample,
        odom: Option<Odom>,
    },
    /// One droid (retained on its MQTT `info` topic): what `hello` says of it, and the
    /// settings that bind a client.
    Info {
        droidctl: &'static str,
        #[serde(flatten)]
        info: DroidInfo,
        command_timeout_ms: u64,
    },
    Collision {
        droid: String,
        t_ms: u64,
        /// The axes that tripped: `x`, `y` or `xy`.
        axis: &'static str,
        /// Impact power per axis (x, y).
        power: [i16; 2],
        /// The droid's speed at the impact (0..=255).
        speed: u8,
        /// Collisions so far.
        collisions: u32,
    },
    Battery {
        droid: String,
        t_ms: u64,
        volts: f32,
    },
    /// The droid's link: `connecting`, `connected`, `reconnecting`, `closed`; `offline` is
    /// the MQTT last will (the bridge is gone). `ready`: connected and its connect setup
    /// done, so a drive sent now moves it (R2-D2 stands on three legs first).
    Link {
        droid: String,
        state: &'static str,
        ready: bool,
        #[serde(skip_serializing_if = "Option::is_none")]
        attempt: Option<u32>,
        #[serde(skip_serializing_if = "Option::is_none")]
        reason: Option<String>,
    },
    /// The bridge stopped a droid by itself: `timeout` (no drive command within the command
    /// timeout), `input_closed` (stdin ended), `broker_lost`, `link_lost` (the droid's link
    /// went down: what it held is dropped).
    Stopped {
        droid: String,
        reason: &'static str,
        message: String,
    },
    /// Whether the droid is held (`hold`, `release`; issue 40 point 6): sent at each
    /// change, retained on MQTT's `hold` topic.
    Hold { droid: String, held: bool },
    /// The droid's cruise speed ([`Cmd::Cruise`]): sent at each change, retained on MQTT's
    /// `cruise` topic (Home Assistant's Speed number reads it).
    Cruise { droid: String, speed: u8 },
    /// An animation or a sound the droid played (it answered the command): retained on
    /// MQTT's `animation` or `sound` topic, which Home Assistant's selects read. `name` is
    /// the catalogue's ([`crate::family::catalog`]), `null` for an id it does not name.
    Played {
        droid: String,
        /// `animation` or `sound`.
        what: &'static str,
        id: u16,
        name: Option<&'static str>,
    },
    /// A command done (sent only for commands with an `id`).
    Reply {
        id: Value,
        #[serde(skip_serializing_if = "Option::is_none")]
        droid: Option<String>,
        cmd: &'static str,
        ok: bool,
        /// What the bridge changed of it (a capped streaming rate).
        #[serde(skip_serializing_if = "Option::is_none")]
        note: Option<String>,
    },
    /// A command refused or failed.
    Error {
        #[serde(skip_serializing_if = "Option::is_none")]
        id: Option<Value>,
        #[serde(skip_serializing_if = "Option::is_none")]
        droid: Option<String>,
        #[serde(skip_serializing_if = "Option::is_none")]
        cmd: Option<String>,
        code: ErrorCode,
        /// The robot (model name) that cannot do it, for `unsupported`.
        #[serde(skip_serializing_if = "Option::is_none")]
        robot: Option<&'static str>,
        /// What it lacks, for `unsupported`: `dome`, `legs`, `lights`, `animations`, `sounds`,
        /// `matrix`, `streaming`, `reverse`.
        #[serde(skip_serializing_if = "Option::is_none")]
        capability: Option<&'static str>,
        error: String,
    },
}

impl Out {
    /// The droid it is about, if one.
    pub fn droid(&self) -> Option<&str> {
        match self {
            Out::Hello { .. } => None,
            Out::Info { info, .. } => Some(&info.droid),
            Out::Telemetry { droid, .. }
            | Out::Collision { droid, .. }
            | Out::Battery { droid, .. }
            | Out::Link { droid, .. }
            | Out::Hold { droid, .. }
            | Out::Cruise { droid, .. }
            | Out::Played { droid, .. }
            | Out::Stopped { droid, .. } => Some(droid),
            Out::Reply { droid, .. } | Out::Error { droid, .. } => droid.as_deref(),
        }
    }

    /// The error object for a refused command.
    pub fn error(e: BadCommand) -> Out {
        Out::Error {
            id: e.id,
            droid: e.droid,
            cmd: e.cmd,
            code: e.code,
            robot: None,
            capability: None,
            error: e.message,
        }
    }

    /// One JSON line (no newline), `v` first.
    pub fn to_json(&self) -> String {
        #[derive(Serialize)]
        struct Versioned<'a> {
            v: u64,
            #[serde(flatten)]
            out: &'a Out,
        }
        serde_json::to_string(&Versioned {
            v: VERSION,
            out: self,
        })
        .unwrap_or_else(|e| {
            // Only a non-string map key could fail, and there is none.
            format!(
                "{{\"v\":{VERSION},\"type\":\"error\",\"code\":\"bad_json\",\"error\":\"{e}\"}}"
            )
        })
    }
}

/// The axis label of a collision.
pub fn axis_label(x: bool, y: bool) -> &'static str {
    match (x, y) {
        (true, true) => "xy",
        (true, false) => "x",
        (false, true) => "y",
        (false, false) => "none",
    }
}
