//! Payload types of the commands BOLT, Mini and RVR added to API v2: the LED matrix's
//! characters, scrolling text, rotations, palettes and frame lists, and the streaming
//! service's slots. Layouts follow spherov2.py's `commands/io.py` and `commands/sensor.py`
//! (no seed spec covers them; `droid-facts.md` §6).

use super::value::{Fields, Value};
use super::wire::{FieldError, Reader, Size, Wire, parse_uint, wire_enum};
use crate::protocol::error::ParamError;

/// One ASCII character (the matrix's Set Single Character).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Char(pub u8);

impl Wire for Char {
    const DESCRIPTION: &'static str = "one ASCII character";
    const SIZE: Size = Size::Fixed(1);
    fn put(&self, out: &mut Vec<u8>) {
        out.push(self.0);
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        Ok(Char(r.array::<1>(field)?[0]))
    }
    fn value(&self) -> Value {
        Value::Text(char::from(self.0).to_string())
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        let mut chars = text.chars();
        match (chars.next(), chars.next()) {
            (Some(c), None) if c.is_ascii() && !c.is_ascii_control() => Ok(Char(c as u8)),
            _ => Err(ParamError::NotPrintableChar {
                text: text.to_string(),
            }),
        }
    }
}

/// The longest text the matrix scrolls: spherov2 cuts at 25 characters (`commands/io.py`).
pub const SCROLL_TEXT_MAX: usize = 25;

/// Scrolling text: up to 25 ASCII characters, NUL-terminated on the wire.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct ScrollText(pub String);

impl Wire for ScrollText {
    const DESCRIPTION: &'static str = "text, up to 25 ASCII characters";
    const SIZE: Size = Size::Rest { min: 1 };
    fn put(&self, out: &mut Vec<u8>) {
        out.extend(self.0.bytes().take(SCROLL_TEXT_MAX));
        out.push(0);
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        let raw = r.rest();
        match raw.split_last() {
            Some((0, text)) if text.len() <= SCROLL_TEXT_MAX && !text.contains(&0) => {
                Ok(ScrollText(String::from_utf8_lossy(text).into_owned()))
            }
            _ => Err(FieldError::Invalid {
                field,
                reason: "expected up to 25 characters and a NUL".into(),
            }),
        }
    }
    fn value(&self) -> Value {
        Value::Text(self.0.clone())
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        if !text.is_ascii() || text.bytes().any(|b| b.is_ascii_control()) {
            return Err(ParamError::NotPrintableText);
        }
        if text.len() > SCROLL_TEXT_MAX {
            return Err(ParamError::TextChars {
                max: SCROLL_TEXT_MAX,
            });
        }
        Ok(ScrollText(text.to_string()))
    }
}

wire_enum!(
    /// The matrix's rotation (IO 0x3A).
    FrameRotation { Normal = 0 => "normal" | "0", Rotate90 = 1 => "90", Rotate180 = 2 => "180", Rotate270 = 3 => "270" }
);
wire_enum!(
    /// Fading override of the matrix's animations (IO 0x39).
    FadeOverride { None = 0 => "none", NoFading = 1 => "no-fading", Fading = 2 => "fading" }
);
wire_enum!(
    /// Why scrolling text reports (IO 0x3C notification).
    TextScrollReason { Done = 0 => "done", Looping = 1 => "looping" }
);
wire_enum!(
    /// The frame formats the matrix stores (IO 0x4C).
    FrameInfoType { Bits8 = 0 => "8-bit", Bits16 = 1 => "16-bit", Bits32 = 2 => "32-bit", Bits64 = 3 => "64-bit" }
);

/// A palette: a count of colours, then R G B for each.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Palette(pub Vec<[u8; 3]>);

impl Wire for Palette {
    const DESCRIPTION: &'static str = "colours as hex RRGGBB joined by ','";
    const SIZE: Size = Size::Rest { min: 1 };
    fn put(&self, out: &mut Vec<u8>) {
        out.push(self.0.len().min(255) as u8);
        for c in self.0.iter().take(255) {
            out.extend_from_slice(c);
        }
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        let n = r.array::<1>(field)?[0] as usize;
        let mut colours = Vec::with_capacity(n);
        for _ in 0..n {
            colours.push(r.array::<3>(field)?);
        }
        Ok(Palette(colours))
    }
    fn value(&self) -> Value {
        Value::List(self.0.iter().map(|c| Value::Bytes(c.to_vec())).collect())
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        text.split(',')
            .filter(|s| !s.trim().is_empty())
            .map(|s| {
                let b = crate::hex::parse(s).map_err(ParamError::Hex)?;
                <[u8; 3]>::try_from(b.as_slice()).map_err(|_| ParamError::NotRgb {
                    text: s.to_string(),
                })
            })
            .collect::<Result<Vec<_>, _>>()
            .map(Palette)
    }
}

/// Frame indexes: a big-endian u16 count, then that many u16 indexes.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct FrameList(pub Vec<u16>);

impl Wire for FrameList {
    const DESCRIPTION: &'static str = "frame indexes joined by ','";
    const SIZE: Size = Size::Rest { min: 2 };
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&(self.0.len().min(u16::MAX as usize) as u16).to_be_bytes());
        for i in &self.0 {
            out.extend_from_slice(&i.to_be_bytes());
        }
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        let n = u16::from_be_bytes(r.array::<2>(field)?) as usize;
        let mut out = Vec::with_capacity(n.min(r.remaining() / 2));
        for _ in 0..n {
            out.push(u16::from_be_bytes(r.array::<2>(field)?));
        }
        Ok(FrameList(out))
    }
    fn value(&self) -> Value {
        Value::List(self.0.iter().map(|i| Value::Int(*i as i64)).collect())
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        text.split(',')
            .filter(|s| !s.trim().is_empty())
            .map(|s| parse_uint(s, u16::MAX as u64).map(|v| v as u16))
            .collect::<Result<Vec<_>, _>>()
            .map(FrameList)
    }
}

/// Big-endian u16 values filling the rest of the payload.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct U16List(pub Vec<u16>);

impl Wire for U16List {
    const DESCRIPTION: &'static str = "u16 values joined by ','";
    const SIZE: Size = Size::Rest { min: 0 };
    fn put(&self, out: &mut Vec<u8>) {
        for i in &self.0 {
            out.extend_from_slice(&i.to_be_bytes());
        }
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        if !r.remaining().is_multiple_of(2) {
            return Err(FieldError::Invalid {
                field,
                reason: "an odd number of bytes".into(),
            });
        }
        let raw = r.rest();
        Ok(U16List(
            raw.chunks_exact(2)
                .map(|c| u16::from_be_bytes([c[0], c[1]]))
                .collect(),
        ))
    }
    fn value(&self) -> Value {
        Value::List(self.0.iter().map(|i| Value::Int(*i as i64)).collect())
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        FrameList::parse(text).map(|l| U16List(l.0))
    }
}

wire_enum!(
    /// The width of one streamed value (streaming service configuration).
    StreamWidth { Bits8 = 0 => "8" | "8-bit", Bits16 = 1 => "16" | "16-bit", Bits32 = 2 => "32" | "32-bit" }
);

impl StreamWidth {
    /// Bytes per value on the wire.
    pub fn bytes(self) -> usize {
        1 << self.to_byte()
    }
}

/// The sensors of one streaming token: for each, its sensor id (u16) and value width.
/// On the command line `ID:WIDTH` pairs joined by ',' (`6:32,7:32`).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct StreamSlots(pub Vec<(u16, StreamWidth)>);

impl Wire for StreamSlots {
    const DESCRIPTION: &'static str = "sensor id:width (8, 16 or 32) pairs joined by ','";
    const SIZE: Size = Size::Rest { min: 3 };
    fn put(&self, out: &mut Vec<u8>) {
        for (id, w) in &self.0 {
            out.extend_from_slice(&id.to_be_bytes());
            out.push(w.to_byte());
        }
    }
    fn get(r: &mut Reader<'_>, field: &'static str) -> Result<Self, FieldError> {
        if r.remaining() == 0 || !r.remaining().is_multiple_of(3) {
            return Err(FieldError::Invalid {
                field,
                reason: "expected sensor id (2 bytes) and width (1 byte) per sensor".into(),
            });
        }
        let mut out = Vec::new();
        while r.remaining() > 0 {
            let id = u16::from_be_bytes(r.array::<2>(field)?);
            let w = StreamWidth::get(r, field)?;
            out.push((id, w));
        }
        Ok(StreamSlots(out))
    }
    fn value(&self) -> Value {
        Value::List(
            self.0
                .iter()
                .map(|(id, w)| Value::Text(format!("{id}:{}", 8 * w.bytes())))
                .collect(),
        )
    }
    fn parse(text: &str) -> Result<Self, ParamError> {
        text.split(',')
            .filter(|s| !s.trim().is_empty())
            .map(|pair| {
                let (id, w) = pair.split_once(':').ok_or_else(|| ParamError::NotIdWidth {
                    text: pair.to_string(),
                })?;
                Ok((
                    parse_uint(id, u16::MAX as u64)? as u16,
                    StreamWidth::parse(w)?,
                ))
            })
            .collect::<Result<Vec<_>, ParamError>>()
            .map(StreamSlots)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::schema::{FieldDef, decode_fields};

    #[test]
    fn types_round_trip() {
        let mut out = Vec::new();
        ScrollText::parse("HI").unwrap().put(&mut out);
        assert_eq!(out, b"HI\0");
        assert!(ScrollText::parse(&"x".repeat(26)).is_err());
        assert_eq!(Char::parse("A"), Ok(Char(b'A')));
        assert!(Char::parse("AB").is_err());
        let slots = StreamSlots::parse("6:32,7:8").unwrap();
        out.clear();
        slots.put(&mut out);
        assert_eq!(out, [0, 6, 2, 0, 7, 0]);
        static S: &[FieldDef] = &[FieldDef::of::<StreamSlots>("slots")];
        assert!(decode_fields(S, &out).is_ok());
        assert!(decode_fields(S, &[0, 6]).is_err());
        out.clear();
        FrameList(vec![1, 2]).put(&mut out);
        assert_eq!(out, [0, 2, 0, 1, 0, 2]);
        let pal = Palette::parse("ff0000,00ff00").unwrap();
        out.clear();
        pal.put(&mut out);
        assert_eq!(out, [2, 255, 0, 0, 0, 255, 0]);
    }
}
