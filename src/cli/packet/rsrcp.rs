//! `droidctl packet --protocol rsrcp`: the Robi 42's state reports (RSRCP 1.0.0): decode the
//! handshake and frames, build them as test input, list the features.
//!
//! RSRCP only flows robot → central; droidctl drives the robot through the remote-control
//! service's two one-byte characteristics, which carry no packets (see [`list`]).

use super::{CliError, Output, io_err, uint_opt};
use crate::link::gatt::GattUuid;
use crate::protocol::rsrcp::frame::{MOTOR_LIMIT_RAD_S, PIEZO_MAX_HZ};
use crate::protocol::rsrcp::{
    Buttons, EOP, FRAME_ID_MASK, Feature, Frame, FrameError, Framer, HANDSHAKE_LEN, Handshake,
    Item, Leds, ROBI_FRAMES, ROBI_HANDSHAKE, ROBI_RC_SERVICE, ROBI_RSRC_SERVICE, ROBI_START,
    ROBI_STEERING, ROBI_VELOCITY, STEERING_STRAIGHT, decode_frame, decode_handshake, to_json,
};
use std::io::Write;

pub(super) fn decode(bytes: &[u8], output: Output, out: &mut dyn Write) -> Result<i32, CliError> {
    let Output { stream, json } = output;
    let results = if stream {
        frame_stream(bytes)
    } else {
        vec![single(bytes)?]
    };
    let mut status = 0;
    for r in &results {
        if r.is_err() {
            status = 1;
        }
        if json {
            writeln!(out, "{}", to_json(r)).map_err(io_err)?;
        } else {
            match r {
                Ok(item) => writeln!(out, "{}", item.summary()),
                Err(e) => writeln!(out, "decode error: {}", e.summary()),
            }
            .map_err(io_err)?;
        }
    }
    // A stream with garbage is still a successful decode of what was there.
    Ok(if stream { 0 } else { status })
}

fn frame_stream(bytes: &[u8]) -> Vec<Result<Item, FrameError>> {
    let mut framer = Framer::new();
    let mut all: Vec<_> = framer.feed(bytes).collect();
    all.extend(framer.finish());
    all
}

/// One BLE value: the handshake characteristic's 5 bytes or one frames notification, which
/// must be exactly one handshake or frame (too short, too long, a bad EOP, an unsized feature
/// are errors). Input holding several is refused in favour of `--stream`.
fn single(bytes: &[u8]) -> Result<Result<Item, FrameError>, CliError> {
    if bytes.is_empty() {
        return Err(CliError::usage("no bytes to decode"));
    }
    let found = frame_stream(bytes).iter().filter(|r| r.is_ok()).count();
    if found > 1 {
        return Err(CliError::usage(format!(
            "the input holds {found} handshakes or frames, not one; use --stream to decode a byte stream"
        )));
    }
    // Byte 4 is 7F in a handshake; in a frame it is the EFS high byte, where 7F enables the
    // unsized gyro, so such a frame could not be read anyway (the framer's rule too).
    Ok(if bytes.get(HANDSHAKE_LEN - 1) == Some(&EOP) {
        decode_handshake(bytes).map(Item::Handshake)
    } else {
        decode_frame(bytes).map(Item::Frame)
    })
}

/// What the robot sends, built from options: `frame` or `handshake`. Anything else is a usage
/// error that says how the robot is actually driven.
pub(super) fn encode(name: &str, given: Vec<(String, String)>) -> Result<Vec<u8>, CliError> {
    match name {
        "frame" => encode_frame(given),
        "handshake" => encode_handshake(given),
        _ => Err(CliError::usage(format!(
            "RSRCP has no command {name:?}: the Robi 42 sends the handshake and state frames, \
             and is driven by writing one velocity byte (0..=255 = 0..1 forward, \
             characteristic 0x6B2F) and one steering byte (0 left, 128 straight, 255 right, \
             0x3F4A) to the remote-control service 0xBA73; `encode --protocol rsrcp frame` or \
             `handshake` builds test input"
        ))),
    }
}

fn encode_handshake(given: Vec<(String, String)>) -> Result<Vec<u8>, CliError> {
    let mut h = Handshake {
        version: 1,
        msdt_ms: 10,
    };
    for (k, v) in given {
        match k.as_str() {
            "version" => h.version = uint_opt(&k, &v, u8::MAX as u64)? as u8,
            "msdt" => h.msdt_ms = uint_opt(&k, &v, u16::MAX as u64)? as u16,
            _ => {
                return Err(CliError::usage(format!(
                    "handshake has no parameter --{k} (expected --version --msdt)"
                )));
            }
        }
    }
    Ok(h.encode().to_vec())
}

fn encode_frame(given: Vec<(String, String)>) -> Result<Vec<u8>, CliError> {
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
                return Err(CliError::usage(format!(
                    "frame has no parameter --{k} (expected --frame-id --motors --poti \
                     --buttons --leds --piezo)"
                )));
            }
        };
    }
    Ok(f.encode())
}

/// `--motors L,R` in rad/s, each within ±300.
fn motors(text: &str) -> Result<(f32, f32), CliError> {
    let bad = |why: &str| CliError::usage(format!("--motors: {why} (expected L,R in rad/s)"));
    let (l, r) = text
        .split_once(',')
        .ok_or_else(|| bad(&format!("{text:?} is not two numbers")))?;
    let speed = |s: &str| -> Result<f32, CliError> {
        let v: f32 = s
            .trim()
            .parse()
            .map_err(|_| bad(&format!("{s:?} is not a number")))?;
        if !v.is_finite() {
            return Err(bad(&format!("{s:?} is not a finite number")));
        }
        if v.abs() > MOTOR_LIMIT_RAD_S {
            return Err(bad(&format!("{s} is out of range -300..=300")));
        }
        Ok(v)
    };
    Ok((speed(l)?, speed(r)?))
}

/// `--piezo HZ` (sounding), `--piezo HZ,off` (silent at HZ) or `--piezo off` (silent, 0 Hz).
fn piezo(text: &str) -> Result<(bool, u16), CliError> {
    let (hz, on) = match text.split_once(',') {
        _ if text.eq_ignore_ascii_case("off") => return Ok((false, 0)),
        Some((hz, state)) if state.trim().eq_ignore_ascii_case("off") => (hz, false),
        Some((hz, state)) if state.trim().eq_ignore_ascii_case("on") => (hz, true),
        Some((_, state)) => {
            return Err(CliError::usage(format!(
                "--piezo: {state:?} is neither on nor off (expected HZ, HZ,off or off)"
            )));
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
fn bits(key: &str, text: &str, table: &[(u8, &str)]) -> Result<u8, CliError> {
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
                    CliError::usage(format!(
                        "--{key}: unknown name {name:?} (expected {}, none or a number)",
                        names.join(", ")
                    ))
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

pub(super) fn list(filter: Option<&str>, out: &mut dyn Write) -> std::io::Result<()> {
    let keep = |n: &str| filter.is_none_or(|f| n.contains(f));
    writeln!(
        out,
        "Robot -> central (RSRC service {}; characteristic  name  bytes):",
        short(ROBI_RSRC_SERVICE)
    )?;
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
        writeln!(out, "  {:<6}  {name:<9} {what}", short(*uuid))?;
    }
    writeln!(
        out,
        "EFS features (bit  name  payload bytes  payload), payloads in this order:"
    )?;
    for f in Feature::ALL.into_iter().filter(|f| keep(f.name())) {
        let size = f.size().map_or_else(|| "-".to_string(), |n| n.to_string());
        writeln!(
            out,
            "  0x{:04X}  {:<9} {size:<2} {}",
            f.flag().bits(),
            f.name(),
            payload(f)
        )?;
    }
    if keep("reserved") {
        writeln!(
            out,
            "  0x001F  reserved  -  the frame's end is unknown: reported, not read past"
        )?;
    }
    writeln!(
        out,
        "Central -> robot (remote-control service {}; characteristic  name  byte):",
        short(ROBI_RC_SERVICE)
    )?;
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
        writeln!(out, "  {:<6}  {name:<9} {what}", short(*uuid))?;
    }
    Ok(())
}
