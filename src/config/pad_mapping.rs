//! SDL game-controller mappings as written: one line of SDL's controller database
//! (`GUID,name,a:b0,leftx:a0,dpup:h0.1,…`) read into which raw element (button N, axis N, hat
//! N) is which of gilrs's named buttons and axes. The configuration's `gamepad.mappings` are
//! read here when it loads (a mistyped line is an error with its key, not a pad that silently
//! does nothing); [`crate::teleop::gamepad_map`] turns raw events into gilrs's events with
//! them, and gilrs is given the same lines for the devices it reads.
//!
//! Facts from SDL2's `SDL_gamecontroller.c` (the format's definition) and gilrs 0.11.2's
//! `mapping/parser.rs` (its names): `bN` a button, `aN` an axis (`+aN` / `-aN` its half, `aN~`
//! inverted), `hH.M` hat H with mask M (1 up, 2 right, 4 down, 8 left); outputs may be halves
//! too (`+leftx`); output names SDL does not know are skipped, as SDL skips them.

use gilrs::{Axis, Button};
use std::fmt;

/// Longest mapping line read (SDL's own lines are under 400 bytes).
pub const MAX_LINE: usize = 2048;
/// Most bindings in one line (SDL names 26 outputs; halves can double some).
const MAX_BINDS: usize = 64;

/// Most lines `gamepad.mappings` may hold.
pub const MAX_LINES: usize = 32;

/// The configured lines, each read (the first that does not read is the error, with its
/// place in the list).
pub fn checked(lines: Vec<String>) -> Result<Vec<String>, String> {
    if lines.len() > MAX_LINES {
        return Err(format!(
            "{} mapping lines (at most {MAX_LINES}): keep those of the pads you use",
            lines.len()
        ));
    }
    for (i, line) in lines.iter().enumerate() {
        SdlMapping::parse(line).map_err(|e| format!("line {} of the list: {e}", i + 1))?;
    }
    Ok(lines)
}

/// Which part of an axis an element or output is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Half {
    Whole,
    Positive,
    Negative,
}

/// A controller's raw element, as the mapping line names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Element {
    Button(u8),
    Axis {
        index: u8,
        half: Half,
        inverted: bool,
    },
    Hat {
        index: u8,
        mask: u8,
    },
}

/// What an element becomes: a gilrs button (triggers included) or (part of) a gilrs axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    Button(Button),
    Axis(Axis, Half),
}

/// Why a mapping line was refused.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MappingError {
    TooLong(usize),
    /// Fewer than the GUID and the name.
    Incomplete,
    /// A line break inside: gilrs would read each part as a line of its own.
    SeveralLines,
    BadGuid(String),
    /// A `name:element` field whose element does not read.
    BadElement {
        field: String,
    },
    TooManyBindings,
}

impl fmt::Display for MappingError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MappingError::TooLong(n) => write!(
                f,
                "mapping line of {n} bytes (at most {MAX_LINE}): paste one line of SDL's gamecontrollerdb.txt"
            ),
            MappingError::Incomplete => f.write_str(
                "mapping line needs GUID,name,bindings… (one line of SDL's gamecontrollerdb.txt)",
            ),
            MappingError::SeveralLines => {
                f.write_str("mapping has a line break inside: give each line as its own entry")
            }
            MappingError::BadGuid(g) => {
                write!(f, "mapping GUID {g:?} is not 32 hex digits")
            }
            MappingError::BadElement { field } => write!(
                f,
                "mapping field {field:?}: use bN (button), aN / +aN / -aN / aN~ (axis) or hH.M (hat)"
            ),
            MappingError::TooManyBindings => {
                write!(f, "mapping has more than {MAX_BINDS} bindings")
            }
        }
    }
}

impl std::error::Error for MappingError {}

/// A parsed mapping line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SdlMapping {
    pub guid: String,
    pub name: String,
    binds: Vec<(Element, Target)>,
}

/// An SDL output name as gilrs names it (`a` is gilrs's South, `leftshoulder` its
/// LeftTrigger, `lefttrigger` its LeftTrigger2: gilrs's `mapping/parser.rs`).
fn target(name: &str) -> Option<Target> {
    let (half, base) = match name.as_bytes().first() {
        Some(b'+') => (Half::Positive, &name[1..]),
        Some(b'-') => (Half::Negative, &name[1..]),
        _ => (Half::Whole, name),
    };
    let axis = |a| Some(Target::Axis(a, half));
    let button = |b| (half == Half::Whole).then_some(Target::Button(b));
    match base {
        "leftx" => axis(Axis::LeftStickX),
        "lefty" => axis(Axis::LeftStickY),
        "rightx" => axis(Axis::RightStickX),
        "righty" => axis(Axis::RightStickY),
        "a" => button(Button::South),
        "b" => button(Button::East),
        "x" => button(Button::West),
        "y" => button(Button::North),
        "back" => button(Button::Select),
        "start" => button(Button::Start),
        "guide" => button(Button::Mode),
        "leftstick" => button(Button::LeftThumb),
        "rightstick" => button(Button::RightThumb),
        "leftshoulder" => button(Button::LeftTrigger),
        "rightshoulder" => button(Button::RightTrigger),
        "lefttrigger" => button(Button::LeftTrigger2),
        "righttrigger" => button(Button::RightTrigger2),
        "dpup" => button(Button::DPadUp),
        "dpdown" => button(Button::DPadDown),
        "dpleft" => button(Button::DPadLeft),
        "dpright" => button(Button::DPadRight),
        // misc1, paddle1…4, touchpad, platform, crc, hint, sdk…: not read (SDL skips what it
        // does not know too).
        _ => None,
    }
}

fn element(s: &str) -> Option<Element> {
    let (half, rest) = match s.as_bytes().first() {
        Some(b'+') => (Half::Positive, &s[1..]),
        Some(b'-') => (Half::Negative, &s[1..]),
        _ => (Half::Whole, s),
    };
    let (inverted, rest) = match rest.strip_suffix('~') {
        Some(r) => (true, r),
        None => (false, rest),
    };
    let plain = half == Half::Whole && !inverted;
    if let Some(n) = rest.strip_prefix('b') {
        return if plain {
            n.parse().ok().map(Element::Button)
        } else {
            None
        };
    }
    if let Some(n) = rest.strip_prefix('a') {
        let index = n.parse().ok()?;
        return Some(Element::Axis {
            index,
            half,
            inverted,
        });
    }
    if let Some(h) = rest.strip_prefix('h') {
        let (index, mask) = h.split_once('.')?;
        let mask: u8 = mask.parse().ok()?;
        if !plain || mask == 0 || mask > 15 {
            return None;
        }
        return Some(Element::Hat {
            index: index.parse().ok()?,
            mask,
        });
    }
    None
}

impl SdlMapping {
    /// Read one line of SDL's database (a trailing comma and spaces are fine).
    pub fn parse(line: &str) -> Result<SdlMapping, MappingError> {
        if line.len() > MAX_LINE {
            return Err(MappingError::TooLong(line.len()));
        }
        let line = line.trim();
        if line.contains(['\n', '\r']) {
            return Err(MappingError::SeveralLines);
        }
        let mut fields = line.split(',');
        let (Some(guid), Some(name)) = (fields.next(), fields.next()) else {
            return Err(MappingError::Incomplete);
        };
        let guid = guid.trim();
        if guid.len() != 32 || !guid.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(MappingError::BadGuid(guid.chars().take(40).collect()));
        }
        let mut binds = Vec::new();
        for field in fields.map(str::trim).filter(|f| !f.is_empty()) {
            let Some((out, el)) = field.split_once(':') else {
                return Err(MappingError::BadElement {
                    field: field.chars().take(40).collect(),
                });
            };
            let Some(t) = target(out.trim()) else {
                continue;
            };
            let e = element(el.trim()).ok_or_else(|| MappingError::BadElement {
                field: field.chars().take(40).collect(),
            })?;
            if binds.len() == MAX_BINDS {
                return Err(MappingError::TooManyBindings);
            }
            binds.push((e, t));
        }
        Ok(SdlMapping {
            guid: guid.to_ascii_lowercase(),
            name: name.trim().to_string(),
            binds,
        })
    }

    /// Every binding, in the line's order.
    pub fn binds(&self) -> &[(Element, Target)] {
        &self.binds
    }

    /// The element bound to `t`, if any.
    pub fn element_of(&self, t: Target) -> Option<Element> {
        self.binds.iter().find(|(_, x)| *x == t).map(|(e, _)| *e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SDL_GameControllerDB's Linux line for the Xbox 360 controller (045e:028e), as vendored
    /// in gilrs 0.11.2 (`SDL_GameControllerDB/gamecontrollerdb.txt`).
    const XBOX: &str = "030000005e0400008e02000010010000,Xbox 360 Controller,a:b0,b:b1,back:b6,dpdown:h0.4,dpleft:h0.8,dpright:h0.2,dpup:h0.1,guide:b8,leftshoulder:b4,leftstick:b9,lefttrigger:a2,leftx:a0,lefty:a1,rightshoulder:b5,rightstick:b10,righttrigger:a5,rightx:a3,righty:a4,start:b7,x:b2,y:b3,platform:Linux,";

    #[test]
    fn reads_a_database_line() {
        let m = SdlMapping::parse(XBOX).unwrap();
        assert_eq!(m.name, "Xbox 360 Controller");
        assert_eq!(
            m.element_of(Target::Button(Button::DPadUp)),
            Some(Element::Hat { index: 0, mask: 1 })
        );
        assert_eq!(
            m.element_of(Target::Axis(Axis::LeftStickY, Half::Whole)),
            Some(Element::Axis {
                index: 1,
                half: Half::Whole,
                inverted: false
            })
        );
    }

    #[test]
    fn refuses_what_does_not_read() {
        assert_eq!(SdlMapping::parse("x"), Err(MappingError::Incomplete));
        assert!(matches!(
            SdlMapping::parse("0300zz,Pad,a:b0"),
            Err(MappingError::BadGuid(_))
        ));
        for bad in ["a:c0", "a:b", "a:+b0", "dpup:h0.0", "dpup:h0.16", "leftx"] {
            let line = format!("030000005e0400008e02000010010000,Pad,{bad}");
            assert!(
                matches!(
                    SdlMapping::parse(&line),
                    Err(MappingError::BadElement { .. })
                ),
                "{bad}"
            );
        }
        assert_eq!(
            SdlMapping::parse(
                "030000005e0400008e02000010010000,Pad,a:b0\n030000005e0400008e02000010010000,Pad,a:b1"
            ),
            Err(MappingError::SeveralLines)
        );
        let long = "0".repeat(MAX_LINE + 1);
        assert_eq!(
            SdlMapping::parse(&long),
            Err(MappingError::TooLong(MAX_LINE + 1))
        );
    }
}
