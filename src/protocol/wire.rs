//! How each parameter and field type travels on the wire.
//!
//! Every type used in the catalogue implements [`Wire`]: big-endian encoding
//! (`sphero-v2-api.md`, "Endianness"), decoding into a [`Value`] for display, and parsing from
//! command-line text with range checks. The catalogue stores these as function pointers, so the
//! CLI, the packet log and the simulator all read one schema.

use super::error::ParamError;
use super::value::{Fields, Value};
use crate::units::{HEAD_MAX_DEG, HEAD_MIN_DEG, HeadAngle, Heading};

/// Why a payload does not fit its schema.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FieldError {
    /// The payload ended before field `field` (needed `needed` more bytes).
    Short { field: &'static str, needed: usize },
    /// Bytes left over after the last field.
    Trailing(usize),
    /// A value the type does not allow.
    Invalid { field: &'static str, reason: String },
}

impl std::fmt::Display for FieldError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FieldError::Short { field, needed } => {
                write!(
                    f,
                    "payload too short: field {field} needs {needed} more byte(s)"
                )
            }
            FieldError::Trailing(n) => write!(f, "{n} unexpected trailing byte(s)"),
            FieldError::Invalid { field, reason } => write!(f, "field {field}: {reason}"),
        }
    }
}

/// A cursor over a payload.
#[derive(Debug)]
pub struct Reader<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Reader { data, pos: 0 }
    }

    pub fn take(&mut self, n: usize, field: &'static str) -> Result<&'a [u8], FieldError> {
        let rest = &self.data[self.pos..];
        if rest.len() < n {
            return Err(FieldError::Short {
                field,
                needed: n - rest.len(),
            });
        }
        self.pos += n;
        Ok(&rest[..n])
    }

    pub fn array<const N: usize>(&mut self, field: &'static str) -> Result<[u8; N], FieldError> {
        let s = self.take(N, field)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    pub fn rest(&mut self) -> &'a [u8] {
        let r = &self.data[self.pos..];
        self.pos = self.data.len();
        r
    }

    pub fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }

    pub fn finish(&self) -> Result<(), FieldError> {
        match self.remaining() {
            0 => Ok(()),
            n => Err(FieldError::Trailing(n)),
        }
    }
}

/// Size of a type on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Size {
    Fixed(usize),
    /// Consumes the rest of the payload (at least `min` bytes).
    Rest {
        min: usize,
    },
}

/// A parameter or field type.
pub trait Wire: Sized {
    /// For help text: the type and its range or choices.
    const DESCRIPTION: &'static str;
    const SIZE: Size;
    fn put(&self, out: &mut Vec<u8>);
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError>;
    fn value(&self) -> Value;
    /// Parse command-line text (decimal, `0x` hex, or a name for enums).
    fn parse(text: &str) -> Result<Self, ParamError>;

    /// Decode into named values; most types give one, some (collision axis) give several.
    fn decode_into(
        r: &mut Reader<'_>,
        name: &'static str,
        out: &mut Fields,
    ) -> Result<(), FieldError> {
        let v = Self::get(r, name)?;
        out.push((name, v.value()));
        Ok(())
    }

    fn parse_put(text: &str, out: &mut Vec<u8>) -> Result<(), ParamError> {
        Self::parse(text)?.put(out);
        Ok(())
    }
}

/// Parse an unsigned integer in decimal or `0x` hex, within `max`.
pub fn parse_uint(text: &str, max: u64) -> Result<u64, ParamError> {
    let t = text.trim();
    let (digits, radix) = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(h) => (h, 16),
        None => (t, 10),
    };
    let v =
        u64::from_str_radix(&digits.replace('_', ""), radix).map_err(|_| ParamError::NotUint {
            text: text.to_string(),
        })?;
    if v > max {
        return Err(ParamError::UintRange { value: v, max });
    }
    Ok(v)
}

fn parse_f32(text: &str) -> Result<f32, ParamError> {
    let v: f32 = text.trim().parse().map_err(|_| ParamError::NotNumber {
        text: text.to_string(),
    })?;
    if !v.is_finite() {
        return Err(ParamError::NotFinite {
            text: text.to_string(),
        });
    }
    Ok(v)
}

macro_rules! wire_uint {
    ($t:ty, $n:expr, $desc:expr) => {
        impl Wire for $t {
            const DESCRIPTION: &'static str = $desc;
            const SIZE: Size = Size::Fixed($n);
            fn put(&self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_be_bytes());
            }
            fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
                Ok(<$t>::from_be_bytes(r.array::<$n>(field)?))
            }
            fn value(&self) -> Value {
                Value::Int(*self as i64)
            }
            fn parse(text: &str) -> Result<Self, ParamError> {
                Ok(parse_uint(text, <$t>::MAX as u64)? as $t)
            }
        }
    };
}
wire_uint!(u8, 1, "u8 0..=255");
wire_uint!(u16, 2, "u16 0..=65535");
wire_uint!(u32, 4, "u32");

impl Wire for i16 {
    const DESCRIPTION: &'static str = "i16";
    const SIZE: Size = Size::Fixed(2);
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_be_bytes());
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        Ok(i16::from_be_bytes(r.array::<2>(field)?))
    }
    fn value(&self) -> Value {
        Value::Int(*self as i64)
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        text.trim().parse().map_err(|_| ParamError::NotI16 {
            text: text.to_string(),
        })
    }
}

impl Wire for f32 {
    const DESCRIPTION: &'static str = "f32";
    const SIZE: Size = Size::Fixed(4);
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_be_bytes());
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        Ok(f32::from_be_bytes(r.array::<4>(field)?))
    }
    fn value(&self) -> Value {
        Value::Float(*self as f64)
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        parse_f32(text)
    }
}

impl Wire for bool {
    const DESCRIPTION: &'static str = "bool (true/false, on/off, 1/0)";
    const SIZE: Size = Size::Fixed(1);
    fn put(&self, out: &mut Vec<u8>) {
        out.push(*self as u8);
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        Ok(r.array::<1>(field)?[0] != 0)
    }
    fn value(&self) -> Value {
        Value::Bool(*self)
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        match text.trim().to_ascii_lowercase().as_str() {
            "1" | "true" | "on" | "yes" => Ok(true),
            "0" | "false" | "off" | "no" => Ok(false),
            _ => Err(ParamError::NotBool {
                text: text.to_string(),
            }),
        }
    }
}

impl Wire for Heading {
    const DESCRIPTION: &'static str = "u16 heading in degrees 0..=359";
    const SIZE: Size = Size::Fixed(2);
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.degrees().to_be_bytes());
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        let v = u16::from_be_bytes(r.array::<2>(field)?);
        Heading::new(v).ok_or(FieldError::Invalid {
            field,
            reason: format!("heading {v} is outside 0..=359"),
        })
    }
    fn value(&self) -> Value {
        Value::Int(self.degrees() as i64)
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        let v = parse_uint(text, u16::MAX as u64)?;
        Heading::new(v as u16).ok_or(ParamError::Heading(v))
    }
}

impl Wire for HeadAngle {
    const DESCRIPTION: &'static str = "f32 dome angle in degrees -160..=180";
    const SIZE: Size = Size::Fixed(4);
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.degrees().to_be_bytes());
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        let v = f32::from_be_bytes(r.array::<4>(field)?);
        HeadAngle::new(v).ok_or(FieldError::Invalid {
            field,
            reason: format!("dome angle {v} is outside {HEAD_MIN_DEG}..={HEAD_MAX_DEG}"),
        })
    }
    fn value(&self) -> Value {
        Value::Float(self.degrees() as f64)
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        let v = parse_f32(text)?;
        HeadAngle::new(v).ok_or(ParamError::DomeAngle(v))
    }
}

/// A mask shown in hex, `N` bytes wide.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Mask<const N: usize>(pub u32);

impl<const N: usize> Wire for Mask<N> {
    const DESCRIPTION: &'static str = "bit mask (0x hex or decimal)";
    const SIZE: Size = Size::Fixed(N);
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.0.to_be_bytes()[4 - N..]);
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        let b = r.take(N, field)?;
        Ok(Mask(b.iter().fold(0u32, |acc, &x| (acc << 8) | x as u32)))
    }
    fn value(&self) -> Value {
        Value::Hex {
            value: self.0 as u64,
            width: N as u8,
        }
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        let max = if N >= 4 {
            u32::MAX as u64
        } else {
            (1u64 << (8 * N)) - 1
        };
        Ok(Mask(parse_uint(text, max)? as u32))
    }
}

/// Battery voltage as u16 volts×100 (`droid-facts.md` §2).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CentiVolts(pub u16);

impl Wire for CentiVolts {
    const DESCRIPTION: &'static str = "u16 volts×100";
    const SIZE: Size = Size::Fixed(2);
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.0.to_be_bytes());
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        Ok(CentiVolts(u16::from_be_bytes(r.array::<2>(field)?)))
    }
    fn value(&self) -> Value {
        Value::Float(self.0 as f64 / 100.0)
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        let v = parse_f32(text)?;
        if !(0.0..=655.35).contains(&v) {
            return Err(ParamError::Volts(v));
        }
        Ok(CentiVolts((v * 100.0).round() as u16))
    }
}

/// Fixed-size raw bytes.
impl<const N: usize> Wire for [u8; N] {
    const DESCRIPTION: &'static str = "raw bytes as hex (fixed length)";
    const SIZE: Size = Size::Fixed(N);
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(self);
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        r.array::<N>(field)
    }
    fn value(&self) -> Value {
        Value::Bytes(self.to_vec())
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        let b = crate::hex::parse(text).map_err(ParamError::Hex)?;
        let got = b.len();
        b.try_into()
            .map_err(|_| ParamError::ByteCount { expected: N, got })
    }
}

/// Raw bytes filling the rest of the payload.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Bytes(pub Vec<u8>);

impl Wire for Bytes {
    const DESCRIPTION: &'static str = "raw bytes as hex (rest of payload)";
    const SIZE: Size = Size::Rest { min: 0 };
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.0);
    }
    fn get(r: &mut Reader<'_>, _field: &'static str) -> Result<Self, FieldError> {
        Ok(Bytes(r.rest().to_vec()))
    }
    fn value(&self) -> Value {
        Value::Bytes(self.0.clone())
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        crate::hex::parse(text).map(Bytes).map_err(ParamError::Hex)
    }
}

/// A string filling the rest of the payload, NUL-terminated on the wire
/// (`sphero-v2-api.md`: strings are "generally null-terminated").
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Text(pub String);

impl Wire for Text {
    const DESCRIPTION: &'static str = "text (NUL-terminated on the wire)";
    const SIZE: Size = Size::Rest { min: 0 };
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(self.0.as_bytes());
        out.push(0);
    }
    fn get(r: &mut Reader<'_>, _field: &'static str) -> Result<Self, FieldError> {
        let raw = r.rest();
        Ok(Text(nul_strings(raw).join(" / ")))
    }
    fn value(&self) -> Value {
        Value::Text(self.0.clone())
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        if text.contains('\0') {
            return Err(ParamError::TextNul);
        }
        Ok(Text(text.to_string()))
    }
}

/// Split NUL-separated strings, dropping empty ones, replacing invalid UTF-8.
fn nul_strings(raw: &[u8]) -> Vec<String> {
    raw.split(|&b| b == 0)
        .filter(|s| !s.is_empty())
        .map(|s| String::from_utf8_lossy(s).into_owned())
        .collect()
}

/// A fixed-size, NUL-padded string field.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct FixedText<const N: usize>(pub String);

impl<const N: usize> Wire for FixedText<N> {
    const DESCRIPTION: &'static str = "fixed-size text";
    const SIZE: Size = Size::Fixed(N);
    fn put(&self, out: &mut Vec<u8>) {
        let mut b = self.0.as_bytes().to_vec();
        b.resize(N, 0);
        out.extend_from_slice(&b);
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        let raw = r.take(N, field)?;
        Ok(FixedText(nul_strings(raw).join(" ")))
    }
    fn value(&self) -> Value {
        Value::Text(self.0.clone())
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        if text.len() > N {
            return Err(ParamError::TextBytes { max: N });
        }
        Ok(FixedText(text.to_string()))
    }
}

/// The rest of the payload as big-endian f32 values, all of it taken.
fn f32s<'a>(
    r: &mut Reader<'a>,
    field: &'static str,
) -> Result<impl Iterator<Item = f32> + 'a, FieldError> {
    let n = r.remaining();
    if !n.is_multiple_of(4) {
        return Err(FieldError::Invalid {
            field,
            reason: format!("{n} bytes is not a whole number of f32 values"),
        });
    }
    Ok(r.rest()
        .chunks_exact(4)
        .map(|c| f32::from_be_bytes([c[0], c[1], c[2], c[3]])))
}

/// Big-endian f32 values filling the rest of the payload.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct F32List(pub Vec<f32>);

impl Wire for F32List {
    const DESCRIPTION: &'static str = "comma-separated f32 values";
    const SIZE: Size = Size::Rest { min: 0 };
    fn put(&self, out: &mut Vec<u8>) {
        for v in &self.0 {
            out.extend_from_slice(&v.to_be_bytes());
        }
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        Ok(F32List(f32s(r, field)?.collect()))
    }
    fn value(&self) -> Value {
        Value::List(self.0.iter().map(|v| Value::Float(*v as f64)).collect())
    }
    /// Straight to the values, without the `Vec<f32>` in between: a sensor notification
    /// decoded without masks is 17 of them, on every other packet of a busy stream.
    fn decode_into(
        r: &mut Reader<'_>,
        name: &'static str,
        out: &mut Fields,
    ) -> Result<(), FieldError> {
        let values = f32s(r, name)?.map(|v| Value::Float(v as f64)).collect();
        out.push((name, Value::List(values)));
        Ok(())
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        text.split(',')
            .filter(|s| !s.trim().is_empty())
            .map(parse_f32)
            .collect::<Result<Vec<_>, _>>()
            .map(F32List)
    }
}

/// Acceleration as i16 ÷ 4096 = g (`droid-facts.md` §2, collision notification).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct AccelRaw(pub i16);

impl AccelRaw {
    pub fn g(self) -> f32 {
        self.0 as f32 / 4096.0
    }
}

impl Wire for AccelRaw {
    const DESCRIPTION: &'static str = "i16 acceleration, 1/4096 g";
    const SIZE: Size = Size::Fixed(2);
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.0.to_be_bytes());
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        Ok(AccelRaw(i16::from_be_bytes(r.array::<2>(field)?)))
    }
    fn value(&self) -> Value {
        Value::Float(self.g() as f64)
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        let g = parse_f32(text)?;
        let raw = (g * 4096.0).round();
        if !(i16::MIN as f32..=i16::MAX as f32).contains(&raw) {
            return Err(ParamError::Accel(g));
        }
        Ok(AccelRaw(raw as i16))
    }
}

/// The collision axis byte: bit 0 x, bit 1 y. Decodes into two booleans `x_axis`, `y_axis`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CollisionAxis {
    pub x: bool,
    pub y: bool,
}

impl Wire for CollisionAxis {
    const DESCRIPTION: &'static str = "axis bits (bit0 x, bit1 y)";
    const SIZE: Size = Size::Fixed(1);
    fn put(&self, out: &mut Vec<u8>) {
        out.push(self.x as u8 | (self.y as u8) << 1);
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        let b = r.array::<1>(field)?[0];
        Ok(CollisionAxis {
            x: b & 1 != 0,
            y: b & 2 != 0,
        })
    }
    fn value(&self) -> Value {
        Value::Int(self.x as i64 | (self.y as i64) << 1)
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        let b = parse_uint(text, 3)? as u8;
        Ok(CollisionAxis {
            x: b & 1 != 0,
            y: b & 2 != 0,
        })
    }
    fn decode_into(
        r: &mut Reader<'_>,
        name: &'static str,
        out: &mut Fields,
    ) -> Result<(), FieldError> {
        let a = Self::get(r, name)?;
        out.push(("x_axis", Value::Bool(a.x)));
        out.push(("y_axis", Value::Bool(a.y)));
        Ok(())
    }
}

/// Define a u8 enumeration with names for humans and the CLI. Unknown wire values decode to
/// `Value::Enum { name: None }` rather than failing, so nothing from a droid is lost.
macro_rules! wire_enum {
    ($(#[$m:meta])* $name:ident { $($variant:ident = $v:literal => $label:literal $(| $alias:literal)*),+ $(,)? }) => {
        $(#[$m])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum $name { $($variant),+ }

        impl $name {
            pub const ALL: &'static [$name] = &[$($name::$variant),+];
            pub fn to_byte(self) -> u8 { match self { $($name::$variant => $v),+ } }
            pub fn from_byte(b: u8) -> Option<Self> { match b { $($v => Some($name::$variant),)+ _ => None } }
            pub fn label(self) -> &'static str { match self { $($name::$variant => $label),+ } }
            fn label_of(b: u8) -> Option<&'static str> { Self::from_byte(b).map(Self::label) }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result { f.write_str(self.label()) }
        }

        impl Wire for $name {
            const DESCRIPTION: &'static str = concat!("one of: ", $($label, " "),+);
            const SIZE: Size = Size::Fixed(1);
            fn put(&self, out: &mut Vec<u8>) { out.push(self.to_byte()); }
            fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
                let b = r.array::<1>(field)?[0];
                Self::from_byte(b).ok_or(FieldError::Invalid { field, reason: format!("unknown value {b}") })
            }
            fn value(&self) -> Value { Value::Enum { value: self.to_byte() as u64, name: Some(self.label()) } }
            fn parse(text: &str) -> Result<Self, ParamError> {
                let t = text.trim().to_ascii_lowercase().replace('_', "-");
                $( if t == $label $(|| t == $alias)* { return Ok($name::$variant); } )+
                if let Ok(n) = parse_uint(&t, 255) {
                    if let Some(v) = Self::from_byte(n as u8) { return Ok(v); }
                }
                Err(ParamError::NotOneOf { text: text.to_string(), choices: [$($label),+].join(", ") })
            }
            fn decode_into(r: &mut Reader<'_>, name: &'static str, out: &mut Fields) -> Result<(), FieldError> {
                let b = r.array::<1>(name)?[0];
                out.push((name, Value::Enum { value: b as u64, name: Self::label_of(b) }));
                Ok(())
            }
        }
    };
}
/// For the other families' own enumerations (v1's Roll state, motor modes).
pub(crate) use wire_enum;

wire_enum!(
    /// R2 leg actions (Animatronic 0x0D). Waddle starts from bipod (`droid-facts.md` §2).
    LegAction { Stop = 0 => "stop", Tripod = 1 => "tripod" | "three-legs", Bipod = 2 => "bipod" | "two-legs", Waddle = 3 => "waddle" }
);
wire_enum!(
    /// The stance the droid reports (Get Leg Action).
    LegState { Unknown = 0 => "unknown", Tripod = 1 => "tripod" | "three-legs", Bipod = 2 => "bipod" | "two-legs", Waddle = 3 => "waddle", Transitioning = 4 => "transitioning" }
);
wire_enum!(
    /// Audio playback modes (IO 0x07).
    AudioMode { Immediate = 0 => "immediate" | "play-immediately", IfIdle = 1 => "if-idle" | "only-if-not-playing", AfterCurrent = 2 => "after-current" | "play-after-current-sound" }
);
wire_enum!(
    BatteryState { Charged = 0 => "charged", Charging = 1 => "charging", NotCharging = 2 => "not-charging", Ok = 3 => "ok", Low = 4 => "low", Critical = 5 => "critical", Unknown = 255 => "unknown" }
);
wire_enum!(
    BatteryVoltageState { Unknown = 0 => "unknown", Ok = 1 => "ok", Low = 2 => "low", Critical = 3 => "critical" }
);
wire_enum!(
    /// Battery state as sent by the battery-state-changed notification (Power 0x06).
    BatteryVoltageAndState { Charged = 0 => "charged", Charging = 1 => "charging", NotCharging = 2 => "not-charging", Ok = 3 => "ok", Low = 4 => "low", Critical = 5 => "critical", Reserved = 6 => "reserved", Unused = 7 => "unused" }
);
wire_enum!(
    /// Charger state of the Power device (0x1F).
    ChargerState { Unknown = 0 => "unknown", NotCharging = 1 => "not-charging", Charging = 2 => "charging", Charged = 3 => "charged" }
);
wire_enum!(
    /// Charger state of the Core device (0x26), as in API v1.
    CoreChargerState { Out = 0 => "out", In = 1 => "in", Unknown = 2 => "unknown" }
);
wire_enum!(
    /// Power state of Core Get Power State, as in API v1.
    PowerState { Unknown = 0 => "unknown", Charging = 1 => "charging", Ok = 2 => "ok", Low = 3 => "low", Critical = 4 => "critical" }
);
wire_enum!(
    CollisionMethod { None = 0 => "none" | "no-collision-detection", Accelerometer = 1 => "accelerometer", Filtered = 2 => "accelerometer-filtered", Hybrid = 3 => "hybrid" }
);
wire_enum!(
    StabilizationIndex { None = 0 => "none", Full = 1 => "full", Pitch = 2 => "pitch", Roll = 3 => "roll", Yaw = 4 => "yaw", SpeedAndYaw = 5 => "speed-and-yaw" }
);
wire_enum!(
    RawMotorMode { Off = 0 => "off", Forward = 1 => "forward", Reverse = 2 => "reverse" }
);
wire_enum!(
    /// Motor indexes of Generic Raw Motor on R2-D2.
    MotorIndex { LeftDrive = 0 => "left-drive", RightDrive = 1 => "right-drive", Head = 2 => "head", Leg = 3 => "leg" }
);
wire_enum!(
    BootReason { ColdBoot = 0 => "cold-boot", UnexpectedReset = 1 => "unexpected-reset", ErrorReset = 2 => "error-reset", FirmwareUpdate = 3 => "firmware-update", FromSleep = 4 => "from-sleep", NonErrorReset = 5 => "non-error-reset" }
);
wire_enum!(
    VoltageReadingType { CalibratedFiltered = 0 => "calibrated-filtered", CalibratedUnfiltered = 1 => "calibrated-unfiltered", Uncalibrated = 2 => "uncalibrated" }
);
wire_enum!(
    AmplifierId { LeftMotor = 0 => "left-motor", RightMotor = 1 => "right-motor" }
);

bitflags::bitflags! {
    /// Drive With Heading flags (Drive 0x07).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct DriveFlags: u8 {
        const BACKWARD = 0x01;
        const TURBO = 0x02;
        const FAST_TURN = 0x04;
        const LEFT_DIRECTION = 0x08;
        const RIGHT_DIRECTION = 0x10;
        const ENABLE_DRIFT = 0x20;
    }
}

const DRIVE_FLAG_NAMES: [(DriveFlags, &str); 6] = [
    (DriveFlags::BACKWARD, "backward"),
    (DriveFlags::TURBO, "turbo"),
    (DriveFlags::FAST_TURN, "fast-turn"),
    (DriveFlags::LEFT_DIRECTION, "left-direction"),
    (DriveFlags::RIGHT_DIRECTION, "right-direction"),
    (DriveFlags::ENABLE_DRIFT, "enable-drift"),
];

impl Wire for DriveFlags {
    const DESCRIPTION: &'static str = "flags: number, or names joined by ',' or '|': backward turbo fast-turn left-direction right-direction enable-drift";
    const SIZE: Size = Size::Fixed(1);
    fn put(&self, out: &mut Vec<u8>) {
        out.push(self.bits());
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        Ok(DriveFlags::from_bits_retain(r.array::<1>(field)?[0]))
    }
    fn value(&self) -> Value {
        Value::Flags {
            bits: self.bits() as u64,
            names: DRIVE_FLAG_NAMES
                .iter()
                .filter(|(f, _)| self.contains(*f))
                .map(|(_, n)| *n)
                .collect(),
        }
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        if let Ok(n) = parse_uint(text, 255) {
            return Ok(DriveFlags::from_bits_retain(n as u8));
        }
        let mut flags = DriveFlags::empty();
        for part in text
            .split([',', '|', '+'])
            .map(str::trim)
            .filter(|p| !p.is_empty())
        {
            let p = part.to_ascii_lowercase().replace('_', "-");
            match DRIVE_FLAG_NAMES.iter().find(|(_, n)| *n == p) {
                Some((f, _)) => flags |= *f,
                None if p == "forward" || p == "none" => {}
                None => {
                    return Err(ParamError::NotDriveFlag {
                        part: part.to_string(),
                        description: Self::DESCRIPTION,
                    });
                }
            }
        }
        Ok(flags)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn enums_parse_names_aliases_numbers() {
        assert_eq!(LegAction::parse("tripod"), Ok(LegAction::Tripod));
        assert_eq!(LegAction::parse("THREE_LEGS"), Ok(LegAction::Tripod));
        assert_eq!(LegAction::parse("3"), Ok(LegAction::Waddle));
        assert!(LegAction::parse("4").is_err());
        assert!(
            LegAction::parse("fly")
                .unwrap_err()
                .to_string()
                .contains("tripod")
        );
        assert_eq!(AudioMode::parse("immediate"), Ok(AudioMode::Immediate));
    }

    #[test]
    fn unknown_enum_values_are_kept() {
        let mut out = Fields::new();
        LegState::decode_into(&mut Reader::new(&[9]), "state", &mut out).unwrap();
        assert_eq!(
            out[0].1,
            Value::Enum {
                value: 9,
                name: None
            }
        );
    }

    #[test]
    fn drive_flags_parse() {
        assert_eq!(DriveFlags::parse("0x01"), Ok(DriveFlags::BACKWARD));
        assert_eq!(
            DriveFlags::parse("backward,turbo"),
            Ok(DriveFlags::BACKWARD | DriveFlags::TURBO)
        );
        assert!(DriveFlags::parse("sideways").is_err());
    }

    #[test]
    fn uint_ranges() {
        assert_eq!(u8::parse("0xff"), Ok(255));
        assert!(
            u8::parse("256")
                .unwrap_err()
                .to_string()
                .contains("out of range")
        );
        assert!(u16::parse("abc").is_err());
        assert_eq!(Mask::<2>::parse("0x0080"), Ok(Mask(0x80)));
        assert!(Mask::<2>::parse("0x10000").is_err());
    }

    #[test]
    fn heading_and_head_angle_ranges() {
        assert!(
            Heading::parse("360")
                .unwrap_err()
                .to_string()
                .contains("0..=359")
        );
        assert!(HeadAngle::parse("181").is_err());
        assert_eq!(HeadAngle::parse("-160").map(|h| h.degrees()), Ok(-160.0));
    }

    #[test]
    fn short_payload_names_field() {
        let err = u16::get(&mut Reader::new(&[1]), "sound").unwrap_err();
        assert_eq!(
            err,
            FieldError::Short {
                field: "sound",
                needed: 1
            }
        );
    }
}
