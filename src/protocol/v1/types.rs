//! Wire types only API v1 needs. The shared ones (integers, bool, `Heading`, `Mask<N>`,
//! `AccelRaw`, `CollisionAxis`, `PowerState`, `CollisionMethod` …) live in
//! [`crate::protocol::wire`].
//!
//! The enumerations use the same `wire_enum!` as the shared ones.

use crate::protocol::error::ParamError;
use crate::protocol::value::{Fields, Value};
use crate::protocol::wire::{FieldError, Reader, Size, Wire, parse_uint};

use crate::protocol::wire::wire_enum;

wire_enum!(
    /// The state byte of Roll (Sphero 0x30). `droid-facts.md` §4 names 0 stop and 1 go.
    /// spherov2.py (`commands/sphero.py`, `RollModes`) calls 2 "calibrate" (it aims with it);
    /// older clients call the same value "fast rotate". Both names are accepted.
    RollState { Stop = 0 => "stop", Go = 1 => "go", Calibrate = 2 => "calibrate" | "fast-rotate" }
);

wire_enum!(
    /// Motor modes of Set Raw Motors (Sphero 0x33), as spherov2.py's `RawMotorModes`.
    MotorMode { Off = 0 => "off", Forward = 1 => "forward", Reverse = 2 => "reverse", Brake = 3 => "brake", Ignore = 4 => "ignore" }
);

/// An optional trailing u32 mask: MASK2 of Set Data Streaming, which firmware before MASK2
/// existed does not accept, so it is sent only when given. Absent = 0 bytes, present = 4.
/// On the command line `none` (the default) leaves it out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct OptionalMask(pub Option<u32>);

impl Wire for OptionalMask {
    const DESCRIPTION: &'static str = "optional trailing u32 bit mask (0x hex, decimal, or none)";
    const SIZE: Size = Size::Rest { min: 0 };
    fn put(&self, out: &mut Vec<u8>) {
        if let Some(m) = self.0 {
            out.extend_from_slice(&m.to_be_bytes());
        }
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        match r.remaining() {
            0 => Ok(OptionalMask(None)),
            4 => Ok(OptionalMask(Some(u32::from_be_bytes(r.array::<4>(field)?)))),
            n => Err(FieldError::Invalid {
                field,
                reason: format!("{n} trailing byte(s): expected none or a 4-byte mask"),
            }),
        }
    }
    fn value(&self) -> Value {
        Value::Hex {
            value: self.0.unwrap_or(0) as u64,
            width: 4,
        }
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        match text.trim().to_ascii_lowercase().as_str() {
            "" | "none" | "-" => Ok(OptionalMask(None)),
            t => Ok(OptionalMask(Some(parse_uint(t, u32::MAX as u64)? as u32))),
        }
    }
    /// Shown only when present, so a 13-byte payload does not grow a field it did not carry.
    fn decode_into(
        r: &mut Reader<'_>,
        name: &'static str,
        out: &mut Fields,
    ) -> Result<(), FieldError> {
        if let OptionalMask(Some(m)) = Self::get(r, name)? {
            out.push((
                name,
                Value::Hex {
                    value: m as u64,
                    width: 4,
                },
            ));
        }
        Ok(())
    }
}

/// The optional API version at the end of Get Versions: two bytes (major, minor) in the
/// Sphero API 1.50 document's layout, absent in the 8-byte record spherov2.py reads
/// (`commands/core.py`, `get_versions`). Decodes to `api_major`, `api_minor` when present.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ApiVersion(pub Option<(u8, u8)>);

impl Wire for ApiVersion {
    const DESCRIPTION: &'static str = "optional API version major.minor (two bytes)";
    const SIZE: Size = Size::Rest { min: 0 };
    fn put(&self, out: &mut Vec<u8>) {
        if let Some((major, minor)) = self.0 {
            out.extend([major, minor]);
        }
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        match r.remaining() {
            0 => Ok(ApiVersion(None)),
            2 => {
                let [major, minor] = r.array::<2>(field)?;
                Ok(ApiVersion(Some((major, minor))))
            }
            n => Err(FieldError::Invalid {
                field,
                reason: format!("{n} trailing byte(s): expected none or 2 (API major, minor)"),
            }),
        }
    }
    fn value(&self) -> Value {
        match self.0 {
            Some((major, minor)) => Value::Text(format!("{major}.{minor}")),
            None => Value::Text(String::new()),
        }
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        let t = text.trim();
        if t.is_empty() || t.eq_ignore_ascii_case("none") {
            return Ok(ApiVersion(None));
        }
        let (a, b) = t.split_once('.').ok_or_else(|| ParamError::NotVersion {
            text: text.to_string(),
        })?;
        Ok(ApiVersion(Some((
            parse_uint(a, 255)? as u8,
            parse_uint(b, 255)? as u8,
        ))))
    }
    fn decode_into(
        r: &mut Reader<'_>,
        name: &'static str,
        out: &mut Fields,
    ) -> Result<(), FieldError> {
        if let ApiVersion(Some((major, minor))) = Self::get(r, name)? {
            out.push(("api_major", Value::Int(major as i64)));
            out.push(("api_minor", Value::Int(minor as i64)));
        }
        Ok(())
    }
}

/// Big-endian i16 values filling the rest of the payload: sensor streaming data shown raw,
/// when the masks in effect are not known.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct I16List(pub Vec<i16>);

impl Wire for I16List {
    const DESCRIPTION: &'static str = "comma-separated i16 values";
    const SIZE: Size = Size::Rest { min: 0 };
    fn put(&self, out: &mut Vec<u8>) {
        for v in &self.0 {
            out.extend_from_slice(&v.to_be_bytes());
        }
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        let n = r.remaining();
        if !n.is_multiple_of(2) {
            return Err(FieldError::Invalid {
                field,
                reason: format!("{n} bytes is not a whole number of i16 values"),
            });
        }
        Ok(I16List(
            r.rest()
                .chunks_exact(2)
                .map(|c| i16::from_be_bytes([c[0], c[1]]))
                .collect(),
        ))
    }
    fn value(&self) -> Value {
        Value::List(self.0.iter().map(|v| Value::Int(*v as i64)).collect())
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        text.split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(|s| {
                s.parse::<i16>().map_err(|_| ParamError::NotI16 {
                    text: s.to_string(),
                })
            })
            .collect::<Result<Vec<_>, _>>()
            .map(I16List)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roll_state_names_and_aliases() {
        assert_eq!(RollState::parse("go"), Ok(RollState::Go));
        assert_eq!(RollState::parse("FAST_ROTATE"), Ok(RollState::Calibrate));
        assert_eq!(RollState::parse("0"), Ok(RollState::Stop));
        assert!(RollState::parse("3").is_err());
        assert_eq!(MotorMode::parse("brake"), Ok(MotorMode::Brake));
    }

    #[test]
    fn optional_mask_is_zero_or_four_bytes() {
        let mut out = Fields::new();
        OptionalMask::decode_into(&mut Reader::new(&[]), "mask2", &mut out).unwrap();
        assert!(out.is_empty());
        OptionalMask::decode_into(&mut Reader::new(&[0, 0, 0, 8]), "mask2", &mut out).unwrap();
        assert_eq!(out[0].1, Value::Hex { value: 8, width: 4 });
        assert!(OptionalMask::get(&mut Reader::new(&[1, 2]), "mask2").is_err());
        assert_eq!(OptionalMask::parse("none"), Ok(OptionalMask(None)));
        assert_eq!(OptionalMask::parse("0x10"), Ok(OptionalMask(Some(16))));
    }

    #[test]
    fn api_version_is_optional() {
        let mut out = Fields::new();
        ApiVersion::decode_into(&mut Reader::new(&[1, 50]), "api", &mut out).unwrap();
        assert_eq!(out.len(), 2);
        assert_eq!(out[1], ("api_minor", Value::Int(50)));
        assert!(ApiVersion::get(&mut Reader::new(&[1]), "api").is_err());
        assert_eq!(ApiVersion::parse("1.50"), Ok(ApiVersion(Some((1, 50)))));
    }
}
