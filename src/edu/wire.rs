//! The engine's turn protocol across the pipe between droidctl and its engine child
//! ([`super::child`]): each message one frame, a 4-byte little-endian length then that many
//! bytes of JSON.
//!
//! Why bounded frames: the child runs whatever program it is given, and droidctl must outlive
//! whatever the child sends (a crash mid-frame, garbage, a length of 4 GiB). A frame longer
//! than its direction's bound is refused before anything is allocated for it; a frame that
//! is not a message is an error, never a panic (`fuzzing::edu_wire` holds the parent's
//! decoder to that).

use super::engine::{Event, Readings, Reply, SyntaxError};
use serde::{Deserialize, Serialize};
use std::io::{Read, Write};

/// The protocol's version: the child says it first, so droidctl knows it started its own
/// engine (and not, say, a test binary) before it hands it a program.
pub const VERSION: u32 = 1;
/// A frame droidctl sends: the program's source (4 MiB at most, JSON-escaped) and its path.
pub const MAX_TO_CHILD: usize = 32 << 20;
/// A frame the child sends: a turn's calls (1,000 at most, a matrix animation's thousands of
/// numbers each) or a syntax error.
pub const MAX_FROM_CHILD: usize = 32 << 20;

/// What droidctl asks of its engine child; the first message says which job the child has.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum ToChild {
    /// Parse the program without running it; the child answers [`FromChild::Checked`] and
    /// ends.
    Check { source: String, path: String },
    /// Run the program on a droid of this model (`Model::id`); turns follow.
    Start {
        source: String,
        path: String,
        model: String,
    },
    /// One turn ([`super::engine`]).
    Turn {
        fired: Vec<u64>,
        events: Vec<Event>,
        readings: Readings,
    },
}

/// What the child answers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum FromChild {
    /// The first frame: the child is droidctl's engine, speaking this version.
    Ready {
        version: u32,
    },
    Checked(Option<SyntaxError>),
    Done(Reply),
}

/// Why a frame could not be read.
#[derive(Debug, thiserror::Error)]
pub enum FrameError {
    /// The other side closed the pipe between frames.
    #[error("the pipe closed")]
    Closed,
    #[error("the pipe closed in the middle of a frame")]
    Truncated,
    #[error("a frame of {0} bytes, more than the {1} allowed")]
    TooLong(usize, usize),
    #[error("a frame that is not a message: {0}")]
    Garbled(String),
    #[error("cannot read or write the pipe: {0}")]
    Io(std::io::Error),
}

/// Write `message` as one frame (refused, and nothing written, past `max` bytes).
pub fn write<T: Serialize>(
    out: &mut impl Write,
    message: &T,
    max: usize,
) -> Result<(), FrameError> {
    let body = serde_json::to_vec(message).map_err(|e| FrameError::Garbled(e.to_string()))?;
    if body.len() > max {
        return Err(FrameError::TooLong(body.len(), max));
    }
    let len = u32::try_from(body.len()).map_err(|_| FrameError::TooLong(body.len(), max))?;
    out.write_all(&len.to_le_bytes())
        .and_then(|_| out.write_all(&body))
        .and_then(|_| out.flush())
        .map_err(FrameError::Io)
}

/// Read one frame of at most `max` bytes and decode it.
pub fn read<T: for<'de> Deserialize<'de>>(
    input: &mut impl Read,
    max: usize,
) -> Result<T, FrameError> {
    let mut len = [0u8; 4];
    let mut got = 0;
    while got < 4 {
        match input.read(&mut len[got..]) {
            Ok(0) if got == 0 => return Err(FrameError::Closed),
            Ok(0) => return Err(FrameError::Truncated),
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(FrameError::Io(e)),
        }
    }
    let len = u32::from_le_bytes(len) as usize;
    if len > max {
        return Err(FrameError::TooLong(len, max));
    }
    let mut body = vec![0u8; len];
    input.read_exact(&mut body).map_err(|e| match e.kind() {
        std::io::ErrorKind::UnexpectedEof => FrameError::Truncated,
        _ => FrameError::Io(e),
    })?;
    decode(&body)
}

/// A frame's body as a message.
pub fn decode<T: for<'de> Deserialize<'de>>(body: &[u8]) -> Result<T, FrameError> {
    serde_json::from_slice(body).map_err(|e| FrameError::Garbled(e.to_string()))
}

/// Readings as JSON can carry them: a non-finite number (JSON has none) is no reading.
pub fn finite(mut r: Readings) -> Readings {
    fn all<const N: usize>(v: Option<[f32; N]>) -> Option<[f32; N]> {
        v.filter(|a| a.iter().all(|x| x.is_finite()))
    }
    fn one(v: Option<f32>) -> Option<f32> {
        v.filter(|x| x.is_finite())
    }
    r.location = all(r.location);
    r.velocity = all(r.velocity);
    r.orientation = all(r.orientation);
    r.acceleration = all(r.acceleration);
    r.gyroscope = all(r.gyroscope);
    r.vertical_acceleration = one(r.vertical_acceleration);
    r.luminosity = one(r.luminosity);
    r.battery_v = one(r.battery_v);
    if !r.distance.is_finite() {
        r.distance = 0.0;
    }
    if !r.elapsed_s.is_finite() {
        r.elapsed_s = 0.0;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::edu::engine::{Call, CallArg, Status};

    #[test]
    fn a_reply_goes_through_a_frame_and_back() {
        let reply = FromChild::Done(Reply {
            calls: vec![Call {
                line: 3,
                name: "roll".into(),
                args: vec![CallArg::Num(f64::NAN.to_bits()), CallArg::Text("hi".into())],
                promise: Some(7),
            }],
            status: Status::Running,
            listening: vec!["onCollision".into()],
        });
        let mut buf = Vec::new();
        write(&mut buf, &reply, MAX_FROM_CHILD).unwrap();
        let back: FromChild = read(&mut buf.as_slice(), MAX_FROM_CHILD).unwrap();
        assert_eq!(back, reply);
    }

    #[test]
    fn a_long_frame_is_refused_before_it_is_read() {
        // 4 GiB announced, four bytes there: refused at once, nothing allocated.
        let bytes = [0xff, 0xff, 0xff, 0xff, 1, 2, 3, 4];
        let r: Result<FromChild, _> = read(&mut &bytes[..], MAX_FROM_CHILD);
        assert!(matches!(r, Err(FrameError::TooLong(..))), "{r:?}");
        let r: Result<FromChild, _> = read(&mut &[3u8, 0][..], MAX_FROM_CHILD);
        assert!(matches!(r, Err(FrameError::Truncated)), "{r:?}");
        let r: Result<FromChild, _> = read(&mut &[][..], MAX_FROM_CHILD);
        assert!(matches!(r, Err(FrameError::Closed)), "{r:?}");
    }

    #[test]
    fn readings_without_numbers_json_cannot_spell_are_sent() {
        let r = finite(Readings {
            location: Some([f32::NAN, 1.0]),
            distance: f32::INFINITY,
            battery_v: Some(3.9),
            ..Readings::default()
        });
        assert_eq!(r.location, None);
        assert_eq!(r.distance, 0.0);
        assert_eq!(r.battery_v, Some(3.9));
        let mut buf = Vec::new();
        let t = ToChild::Turn {
            fired: vec![],
            events: vec![],
            readings: r.clone(),
        };
        write(&mut buf, &t, MAX_TO_CHILD).unwrap();
        assert_eq!(
            read::<ToChild>(&mut buf.as_slice(), MAX_TO_CHILD).unwrap(),
            t
        );
    }
}
