//! Reading a link's traffic from outside the session: `packet decode` (hex, files, phone
//! logs), replay's mirror of a capture, and the virtual droids' traces all hand a family the
//! bytes one side sent and get packets and decode errors back, each explained as text or
//! JSON. The family does the framing, keeps what the stream itself says about how to read it
//! (the sensor masks its own streaming commands set) and formats its packets; callers never
//! look inside a packet.
//!
//! Sans-IO: bytes in, explained packets out. Output goes through `io::Write` so JSON is
//! serialized straight into the caller's buffer.

use super::{DecodeError, Packet};
use crate::gatt::Endpoint;
use crate::protocol::decode::{DecodeStats, ErrorKind};
use std::io;

/// Which side of a link sent the bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Side {
    /// Host → droid: commands (and, for Robi 42, remote-control bytes).
    #[default]
    Host,
    /// Droid → host: responses, notifications, state frames.
    Droid,
}

/// How to read: what the caller knows that the bytes do not say. A family refuses the
/// options it has no use for (see [`ReadOption`]) rather than ignore them.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// Who sent the bytes; `None`: the family's usual reading (v1: the host's commands,
    /// RSRCP: the robot's frames). v2 packets say what they are; a v1 command and a v1
    /// response both start `FF FF`, so v1 reads one side; Robi's host side is its remote
    /// control's bytes.
    pub side: Option<Side>,
    /// The sensor-streaming masks in effect: v2's standard mask, v1's MASK.
    pub sensor_mask: Option<u32>,
    /// v2's extended mask.
    pub ext_mask: Option<u32>,
    /// v1's MASK2.
    pub mask2: Option<u32>,
    /// v1: sensor frames per packet (Set Data Streaming's M).
    pub frames: Option<u16>,
    /// v1: the catalogue name of the command the responses answer.
    pub request: Option<String>,
    /// Without given masks, take them from the stream's own streaming commands, as the
    /// droid does (`packet decode --file`); otherwise sensor data is shown raw.
    pub follow: bool,
    /// Every feed is one whole BLE value (RSRCP sends one frame per notification) rather than
    /// a piece of a byte stream.
    pub whole_values: bool,
}

/// An option of [`ReadOptions`] that only some families read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReadOption {
    Side,
    SensorMask,
    ExtMask,
    Mask2,
    Frames,
    Request,
}

impl ReadOption {
    /// The command-line flag that sets it.
    pub fn flag(self) -> &'static str {
        match self {
            ReadOption::Side => "--from",
            ReadOption::SensorMask => "--sensor-mask",
            ReadOption::ExtMask => "--ext-mask",
            ReadOption::Mask2 => "--mask2",
            ReadOption::Frames => "--frames",
            ReadOption::Request => "--request",
        }
    }

    /// The options `opts` sets.
    pub fn given(opts: &ReadOptions) -> Vec<ReadOption> {
        [
            (ReadOption::SensorMask, opts.sensor_mask.is_some()),
            (ReadOption::ExtMask, opts.ext_mask.is_some()),
            (ReadOption::Mask2, opts.mask2.is_some()),
            (ReadOption::Frames, opts.frames.is_some()),
            (ReadOption::Request, opts.request.is_some()),
        ]
        .into_iter()
        .filter_map(|(o, given)| given.then_some(o))
        .collect()
    }
}

/// One packet or decode error found in the bytes, explained with what the reader knew when it
/// found it (the masks in effect then).
pub trait Found {
    /// Stream offset of the packet's first byte (or of the error).
    fn offset(&self) -> u64;
    /// The error's kind when this is a decode error.
    fn error_kind(&self) -> Option<ErrorKind>;
    /// The decode error, when this is one.
    fn decode_error(&self) -> Option<DecodeError>;
    /// The packet, when this is one (a packet whose checksum failed, shown by a single decode,
    /// included).
    fn packet(&self) -> Option<Packet>;
    /// Append the JSON object `packet decode --json` prints for it, without a line end;
    /// `offset` first when `with_offset`. Into memory, whole: the caller writes lines out in
    /// one piece.
    fn write_json(&self, with_offset: bool, out: &mut Vec<u8>);
    /// `packet decode`'s multi-line text (ends with a line end).
    fn text(&self) -> String;
    /// One line for a trace.
    fn line(&self) -> String;
    /// Whether the bytes were not a good packet (a decode error, or a packet shown despite a
    /// bad checksum).
    fn is_bad(&self) -> bool {
        self.error_kind().is_some()
    }
}

/// Where a reader hands what it found; `None` to only count.
pub type Emit<'a> = Option<&'a mut dyn FnMut(&dyn Found) -> io::Result<()>>;

/// A family's reader of one side's bytes.
pub trait Reader: Send {
    /// Bytes the side sent (to the command channel, or notified), in any chunking.
    fn feed(&mut self, bytes: &[u8], emit: Emit<'_>) -> io::Result<()>;
    /// Bytes the host wrote to `to`. Sphero families write packets to the command channel
    /// only; Robi 42's remote control is one byte to each input.
    fn write(&mut self, to: Endpoint, bytes: &[u8], emit: Emit<'_>) -> io::Result<()> {
        let _ = to;
        self.feed(bytes, emit)
    }
    /// The input ended: what was left half-read is reported.
    fn finish(&mut self, emit: Emit<'_>) -> io::Result<()>;
    /// What the reader saw so far.
    fn stats(&self) -> DecodeStats;
    /// Packets per kind, named as the family names them (`command`, `async`, `frame`).
    fn kinds(&self) -> Vec<(&'static str, u64)>;
    /// The input as exactly one packet (a packet whose checksum fails is still shown, with
    /// the verdict); `Err` says why the input is not one packet.
    fn one(&mut self, bytes: &[u8]) -> Result<Box<dyn Found>, super::error::ReadError>;
    /// What to try when a single packet does not decode.
    fn hint(&self) -> Option<&'static str> {
        None
    }
}

/// "the input holds N WHAT, not one packet; use --stream …" for a single decode of several.
pub fn not_one(n: usize, what: &'static str) -> super::error::ReadError {
    if n == 0 {
        super::error::ReadError::NoBytes
    } else {
        super::error::ReadError::NotOne { n, what }
    }
}

/// Append `value` as JSON to `out`.
pub fn write_json(value: &impl serde::Serialize, out: &mut Vec<u8>) {
    let start = out.len();
    // Serializing plain data into memory cannot fail; a failure would leave a partial
    // object, so it is taken back.
    if serde_json::to_writer(&mut *out, value).is_err() {
        out.truncate(start);
        out.extend_from_slice(b"null");
    }
}

/// A decode error of any family as [`Found`]: `{"error", "offset", "detail"}` and
/// `decode error: …`.
pub struct FoundError(pub DecodeError);

impl Found for FoundError {
    fn offset(&self) -> u64 {
        self.0.offset
    }

    fn error_kind(&self) -> Option<ErrorKind> {
        Some(self.0.kind)
    }

    fn packet(&self) -> Option<Packet> {
        None
    }

    fn decode_error(&self) -> Option<DecodeError> {
        Some(self.0.clone())
    }

    fn write_json(&self, _with_offset: bool, out: &mut Vec<u8>) {
        // An error's object has its offset already.
        write_json(&self.0.json(), out)
    }

    fn text(&self) -> String {
        format!("decode error: {}\n", self.0)
    }

    fn line(&self) -> String {
        format!("decode error: {} ({})", self.0.kind.name(), self.0.detail)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn given_options_are_listed_with_their_flags() {
        let o = ReadOptions {
            ext_mask: Some(1),
            request: Some("ping".into()),
            ..ReadOptions::default()
        };
        let flags: Vec<&str> = ReadOption::given(&o)
            .into_iter()
            .map(ReadOption::flag)
            .collect();
        assert_eq!(flags, ["--ext-mask", "--request"]);
        assert_eq!(not_one(0, "packets").to_string(), "no bytes to decode");
        assert!(
            not_one(3, "packets or errors")
                .to_string()
                .contains("holds 3 packets or errors")
        );
    }
}
