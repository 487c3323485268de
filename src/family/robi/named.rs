//! `packet encode --protocol rsrcp` and `packet list --protocol rsrcp`: what the Robi 42
//! sends (a handshake, state frames), built from options as test input, and the protocol's
//! characteristics and features listed. RSRCP only flows robot → central; droidctl drives the
//! robot through the remote-control service's two one-byte characteristics, which carry no
//! packets.

use super::gatt::{
    ROBI_FRAMES, ROBI_HANDSHAKE, ROBI_RC_SERVICE, ROBI_RSRC_SERVICE, ROBI_START, ROBI_STEERING,
    ROBI_VELOCITY,
};
use crate::family::error::{MotorsError, NamedError};
use crate::family::named::{keep, uint_opt};
use crate::gatt::GattUuid;
use crate::protocol::error::ParamError;
use crate::protocol::rsrcp::frame::{MOTOR_LIMIT_RAD_S, PIEZO_MAX_HZ};
use crate::protocol::rsrcp::{
    Buttons, FRAME_ID_MASK, Feature, Frame, Handshake, Leds, STEERING_STRAIGHT,
};
use std::io::Write;

/// The names [`encode`] takes, with what each builds.
pub const NAMES: [(&str, &str); 2] = [
    ("frame", "a state frame, as the robot sends it"),
    ("handshake", "the handshake, as the robot sends it"),
];

/// What the robot sends, built from options: `frame` or `handshake`. Anything else is a usage
/// error that says how the robot is actually driven.
pub fn encode(name: &str, given: Vec<(String, String)>) -> Result<Vec<u8>, NamedError> {
    match name {
        "frame" => encode_frame(given),
        "handshake" => encode_handshake(given),
        _ => Err(NamedError::NoRsrcpCommand(name.to_string())),
    }
}

fn encode_handshake(given: Vec<(String, String)>) -> Result<Vec<u8>, NamedError> {
    let mut h = Handshake {
        version: 1,
        msdt_ms: 10,
    };
    for (k, v) in given {
        match k.as_str() {
            "version" => h.version = uint_opt(&k, &v, u8::MAX as u64)? as u8,
            "msdt" => h.msdt_ms = uint_opt(&k, &v, u16::MAX as u64)? as u16,
            _ => {
                return Err(NamedError::HandshakeParameter(k));
            }
        }
    }
    Ok(h.encode().to_vec())
}

fn encode_frame(given: Vec<(String, String)>) -> Result<Vec<u8>, NamedError> {
    let mut f = Frame::default();
    for (k, v) in given {
        f = match k.as_str() {
            "frame-id" => Frame {
                frame_id: uint_opt(&k, &v, FRAME_ID_MASK as u64)? as u32,
                ..f
            },
            "motors" => {
                let (l, r) = motors(&v)?;
                f.with_motors(l, r)
            }
            "poti" => f.with_poti(uint_opt(&k, &v, u8::MAX as u64)? as u8),
            "buttons" => f.with_buttons(Buttons::from_bits_retain(bits(
                &k,
                &v,
                &named_bits(|b| Buttons::from_bits_retain(b).names()),
            )?)),
            "leds" => f.with_leds(Leds::from_bits_retain(bits(
                &k,
                &v,
                &named_bits(|b| Leds::from_bits_retain(b).names()),
            )?)),
            "piezo" => {
                let (on, hz) = piezo(&v)?;
                f.with_piezo(on, hz)
            }
            _ => {
                return Err(NamedError::FrameParameter(k));
            }
        };
    }
    Ok(f.encode())
}

/// `--motors L,R` in rad/s, each within ±300.
fn motors(text: &str) -> Result<(f32, f32), NamedError> {
    let (l, r) = text
        .split_once(',')
        .ok_or_else(|| MotorsError::NotTwo(text.to_string()))
        .map_err(NamedError::Motors)?;
    let speed = |s: &str| -> Result<f32, MotorsError> {
        let v: f32 = s.trim().parse().map_err(|_| ParamError::NotNumber {
            text: s.to_string(),
        })?;
        if !v.is_finite() {
            return Err(ParamError::NotFinite {
                text: s.to_string(),
            }
            .into());
        }
        if v.abs() > MOTOR_LIMIT_RAD_S {
            return Err(MotorsError::Range(s.to_string()));
        }
        Ok(v)
    };
    Ok((
        speed(l).map_err(NamedError::Motors)?,
        speed(r).map_err(NamedError::Motors)?,
    ))
}

/// `--piezo HZ` (sounding), `--piezo HZ,off` (silent at HZ) or `--piezo off` (silent, 0 Hz).
fn piezo(text: &str) -> Result<(bool, u16), NamedError> {
    let (hz, on) = match text.split_once(',') {
        _ if text.eq_ignore_ascii_case("off") => return Ok((false, 0)),
        Some((hz, state)) if state.trim().eq_ignore_ascii_case("off") => (hz, false),
        Some((hz, state)) if state.trim().eq_ignore_ascii_case("on") => (hz, true),
        Some((_, state)) => {
            return Err(NamedError::PiezoState(state.to_string()));
        }
        None => (text, true),
    };
    Ok((
        on,
        uint_opt("piezo", hz.trim(), u64::from(PIEZO_MAX_HZ))? as u16,
    ))
}

/// Each single bit of a byte with its name, MSB first, as the codec names them.
fn named_bits(names_of: impl Fn(u8) -> Vec<&'static str>) -> Vec<(u8, &'static str)> {
    (0..8)
        .rev()
        .map(|i| 1u8 << i)
        .filter_map(|b| names_of(b).first().map(|n| (b, *n)))
        .collect()
}

/// A byte of named bits: names joined by `,` or `|`, `none`, or a number.
fn bits(key: &str, text: &str, table: &[(u8, &str)]) -> Result<u8, NamedError> {
    if text.eq_ignore_ascii_case("none") {
        return Ok(0);
    }
    if text.starts_with(|c: char| c.is_ascii_digit()) {
        return uint_opt(key, text, u8::MAX as u64).map(|n| n as u8);
    }
    text.split([',', '|'])
        .map(str::trim)
        .filter(|n| !n.is_empty())
        .try_fold(0u8, |acc, name| {
            table
                .iter()
                .find(|(_, n)| n.eq_ignore_ascii_case(name))
                .map(|(b, _)| acc | b)
                .ok_or_else(|| {
                    let names: Vec<&str> = table.iter().map(|(_, n)| *n).collect();
                    NamedError::UnknownBitName {
                        key: key.to_string(),
                        name: name.to_string(),
                        expected: names.join(", "),
                    }
                })
        })
}

/// `0x2579` for a 16-bit UUID, the full form otherwise.
fn short(u: GattUuid) -> String {
    u.as_u16()
        .map_or_else(|| u.to_string(), |v| format!("0x{v:04X}"))
}

/// What a feature's payload holds, for `packet list`.
fn payload(f: Feature) -> String {
    let names = |t: Vec<(u8, &str)>| {
        t.iter()
            .map(|(b, n)| format!("{n} 0x{b:02X}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    match f {
        Feature::Motors => "left, right: i16 rad/s x 100 each (±300)".into(),
        Feature::Poti => "u8 0..=255".into(),
        Feature::Buttons => names(named_bits(|b| Buttons::from_bits_retain(b).names())),
        Feature::Leds => names(named_bits(|b| Leds::from_bits_retain(b).names())),
        Feature::Piezo => "u16: bit 15 on, bits 0..14 frequency in Hz".into(),
        _ => "size not defined: a frame enabling it is reported, not read past it".into(),
    }
}

/// `packet list --protocol rsrcp`: the characteristics, the EFS features with their bits and
/// payload sizes, and the remote-control bytes.
pub fn list(filter: Option<&str>, out: &mut dyn Write) -> std::io::Result<usize> {
    let keep = |n: &str| keep(filter, n);
    let mut l = crate::family::listing::Listing::new(out);
    l.heading(format_args!(
        "Robot -> central (RSRC service {}; characteristic  name  bytes):",
        short(ROBI_RSRC_SERVICE)
    ));
    let rows = [
        (
            ROBI_HANDSHAKE,
            "handshake",
            "read: 7E version:u8 msdt_ms:u16 7F (5 bytes)",
        ),
        (
            ROBI_START,
            "start",
            "write 01 to start the frames (after reading the handshake)",
        ),
        (
            ROBI_FRAMES,
            "frame",
            "notify, one frame each: 7E frame_id:u24 efs:u16 payloads 7F (7..=16 bytes)",
        ),
    ];
    for (uuid, name, what) in rows.iter().filter(|r| keep(r.1)) {
        l.entry(format_args!("  {:<6}  {name:<9} {what}", short(*uuid)))?;
    }
    l.heading(format_args!(
        "EFS features (bit  name  payload bytes  payload), payloads in this order:"
    ));
    for f in Feature::ALL.into_iter().filter(|f| keep(f.name())) {
        let size = f.size().map_or_else(|| "-".to_string(), |n| n.to_string());
        l.entry(format_args!(
            "  0x{:04X}  {:<9} {size:<2} {}",
            f.flag().bits(),
            f.name(),
            payload(f)
        ))?;
    }
    if keep("reserved") {
        l.entry(format_args!(
            "  0x001F  reserved  -  the frame's end is unknown: reported, not read past"
        ))?;
    }
    l.heading(format_args!(
        "Central -> robot (remote-control service {}; characteristic  name  byte):",
        short(ROBI_RC_SERVICE)
    ));
    let rows = [
        (
            ROBI_VELOCITY,
            "velocity",
            "u8 / 255 = forward speed 0..1 (forward only)".to_string(),
        ),
        (
            ROBI_STEERING,
            "steering",
            format!("u8 / 255: 0 full left, {STEERING_STRAIGHT} straight, 255 full right"),
        ),
    ];
    for (uuid, name, what) in rows.iter().filter(|r| keep(r.1)) {
        l.entry(format_args!("  {:<6}  {name:<9} {what}", short(*uuid)))?;
    }
    Ok(l.entries())
}
