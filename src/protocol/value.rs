//! Decoded field values: what the packet log, `packet decode` and JSON output show.

use serde::ser::{Serialize, SerializeSeq, Serializer};
use std::fmt;

/// One decoded field value.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Bool(bool),
    Int(i64),
    Float(f64),
    /// A mask or id better read in hex; `width` is the number of bytes.
    Hex {
        value: u64,
        width: u8,
    },
    /// An enumerated value and its name when known (unknown values are kept, not lost).
    Enum {
        value: u64,
        name: Option<&'static str>,
    },
    /// A set of flag names plus the raw bits.
    Flags {
        bits: u64,
        names: Vec<&'static str>,
    },
    Text(String),
    Bytes(Vec<u8>),
    List(Vec<Value>),
}

impl Value {
    pub fn as_f64(&self) -> Option<f64> {
        match *self {
            Value::Int(i) => Some(i as f64),
            Value::Float(f) => Some(f),
            Value::Hex { value, .. }
            | Value::Enum { value, .. }
            | Value::Flags { bits: value, .. } => Some(value as f64),
            Value::Bool(b) => Some(b as u8 as f64),
            _ => None,
        }
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Bool(b) => write!(f, "{b}"),
            Value::Int(i) => write!(f, "{i}"),
            Value::Float(x) => {
                if x.fract() == 0.0 && x.abs() < 1e9 {
                    write!(f, "{}", crate::units::fixed(*x, 1))
                } else {
                    // Rounded: -0.00001 would print as -0.
                    write!(f, "{}", crate::units::signless((x * 1e4).round() / 1e4))
                }
            }
            Value::Hex { value, width } => write!(f, "0x{:0w$X}", value, w = *width as usize * 2),
            Value::Enum {
                value,
                name: Some(n),
            } => write!(f, "{n} ({value})"),
            Value::Enum { value, name: None } => write!(f, "unknown ({value})"),
            Value::Flags { bits, names } if names.is_empty() => write!(f, "none (0x{bits:02X})"),
            Value::Flags { bits, names } => write!(f, "{} (0x{bits:02X})", names.join("|")),
            Value::Text(s) => write!(f, "{s:?}"),
            Value::Bytes(b) => write!(f, "[{}]", crate::hex::spaced(b)),
            Value::List(items) => {
                write!(f, "[")?;
                for (i, v) in items.iter().enumerate() {
                    if i > 0 {
                        write!(f, ", ")?;
                    }
                    write!(f, "{v}")?;
                }
                write!(f, "]")
            }
        }
    }
}

impl Serialize for Value {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Value::Bool(b) => s.serialize_bool(*b),
            Value::Int(i) => s.serialize_i64(*i),
            // Most fields are f32 on the wire, widened: printed at f32's shortest round trip
            // (`-125.6943`, not `-125.69429779052734`: noise, and most of the cost of JSON
            // output; issue 27 point 10). A value f32 cannot hold exactly keeps f64's.
            Value::Float(x) if x.is_finite() && (*x as f32) as f64 == *x => {
                s.serialize_f32(crate::units::signless32(*x as f32))
            }
            Value::Float(x) if x.is_finite() => s.serialize_f64(crate::units::signless(*x)),
            Value::Float(_) => s.serialize_none(),
            Value::Hex { value, .. } => s.serialize_u64(*value),
            Value::Enum { name: Some(n), .. } => s.serialize_str(n),
            Value::Enum { value, name: None } => s.serialize_u64(*value),
            Value::Flags { names, .. } => {
                let mut seq = s.serialize_seq(Some(names.len()))?;
                for n in names {
                    seq.serialize_element(n)?;
                }
                seq.end()
            }
            Value::Text(t) => s.serialize_str(t),
            Value::Bytes(b) => s.serialize_str(&crate::hex::compact(b)),
            Value::List(items) => {
                let mut seq = s.serialize_seq(Some(items.len()))?;
                for v in items {
                    seq.serialize_element(v)?;
                }
                seq.end()
            }
        }
    }
}

/// Named field values in wire order.
pub type Fields = Vec<(&'static str, Value)>;

/// Fields serialized straight to a JSON object (order kept), without building a
/// `serde_json::Value` tree: what every JSON output of packets writes.
pub struct FieldsJson<'a>(pub &'a [(&'static str, Value)]);

impl Serialize for FieldsJson<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (name, value) in self.0 {
            m.serialize_entry(name, value)?;
        }
        m.end()
    }
}

/// Bytes serialized as a lower-case hex string without separators (`8d0a13`).
pub struct HexJson<'a>(pub &'a [u8]);

impl Serialize for HexJson<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        // On the stack up to the longest body a decoder takes by default (512 bytes): a
        // sensor notification of 17 floats is 68 bytes, longer than the 64 this once held.
        let mut buf = [0u8; 1024];
        match buf.get_mut(..self.0.len() * 2) {
            Some(digits) => {
                crate::hex::compact_into(self.0, digits);
                // Only ASCII hex digits were written.
                s.serialize_str(std::str::from_utf8(digits).unwrap_or_default())
            }
            None => s.serialize_str(&crate::hex::compact(self.0)),
        }
    }
}

/// Fields as a JSON object (order kept as inserted).
pub fn fields_json(fields: &Fields) -> serde_json::Value {
    let mut map = serde_json::Map::new();
    for (name, value) in fields {
        map.insert(
            (*name).to_string(),
            serde_json::to_value(value).unwrap_or(serde_json::Value::Null),
        );
    }
    serde_json::Value::Object(map)
}

/// Fields as `name=value` pairs for one line of human output.
pub fn fields_line(fields: &Fields) -> String {
    fields
        .iter()
        .map(|(n, v)| format!("{n}={v}"))
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_negative_zeros_in_text_or_json() {
        let json = |v: Value| serde_json::to_string(&v).unwrap();
        assert_eq!(Value::Float(-0.0).to_string(), "0.0");
        assert_eq!(Value::Float(-0.000_01).to_string(), "0");
        assert_eq!(json(Value::Float(-0.0)), "0.0");
        assert_eq!(json(Value::Float(-0.0_f32 as f64)), "0.0");
        assert_eq!(Value::Float(-1.5).to_string(), "-1.5");
    }

    #[test]
    fn floats_print_at_their_own_precision() {
        let json = |v: Value| serde_json::to_string(&v).unwrap();
        assert_eq!(json(Value::Float(-125.694_3_f32 as f64)), "-125.6943");
        assert_eq!(json(Value::Float(0.1_f32 as f64)), "0.1");
        // A value computed in f64 keeps its digits.
        assert_eq!(json(Value::Float(4.1)), "4.1");
        assert_eq!(json(Value::Float(1.0 / 3.0)), "0.3333333333333333");
        assert_eq!(json(Value::Float(f64::NAN)), "null");
        for x in [1.0e-7_f32, 3.402_823_5e38, -0.0, 12_345.679] {
            let back: f32 = json(Value::Float(x as f64)).parse().unwrap();
            assert_eq!(back, x);
        }
    }
}
