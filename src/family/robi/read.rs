//! Reading Robi 42 traffic from outside a session (see [`crate::family::read`]). The robot's
//! side is RSRCP: a handshake, then state frames, one per BLE notification (read as whole
//! values) or cut from a byte stream by the [`Framer`]. The host's side is not packets but
//! the remote control's two one-byte inputs, put back together as the controls they were.

use super::super::types::{RobiControl, RobiPacket};
use crate::family::read::{Emit, Found, ReadOptions, Reader, Side, write_json};
use crate::family::{DecodeError, Packet};
use crate::gatt::Endpoint;
use crate::protocol::decode::{DecodeStats, ErrorKind};
use crate::protocol::rsrcp::{self, EOP, FrameError, Framer, HANDSHAKE_LEN, Item};
use serde::Serialize;
use std::io;

/// A Robi 42 reader.
pub struct RobiReader {
    side: Side,
    whole_values: bool,
    /// The byte-stream framer (robot side, not whole values).
    framer: Framer,
    /// What whole values and host writes counted (the framer counts its own).
    stats: DecodeStats,
    /// Handshakes, frames, remote-control writes.
    kinds: [u64; 3],
    /// Host side: a velocity write waiting for its steering write, and the last steering.
    velocity: Option<u8>,
    steering: u8,
}

impl RobiReader {
    pub fn new(opts: &ReadOptions) -> RobiReader {
        RobiReader {
            side: opts.side.unwrap_or(Side::Droid),
            whole_values: opts.whole_values,
            framer: Framer::new(),
            stats: DecodeStats::default(),
            kinds: [0; 3],
            velocity: None,
            steering: rsrcp::STEERING_STRAIGHT,
        }
    }

    fn count(&mut self, r: &Result<Item, FrameError>) {
        match r {
            Ok(Item::Handshake(_)) => self.kinds[0] += 1,
            Ok(Item::Frame(_)) => self.kinds[1] += 1,
            Err(_) => {}
        }
    }

    /// One whole BLE value: the 5-byte handshake or one frame.
    fn value(&mut self, bytes: &[u8]) -> Result<Item, FrameError> {
        self.stats.bytes += bytes.len() as u64;
        let r = decode_value(bytes);
        match &r {
            Ok(_) => self.stats.packets += 1,
            Err(e) => {
                self.stats.count_error(e.kind);
                self.stats.skipped_bytes += bytes.len() as u64;
            }
        }
        r
    }

    /// A remote-control write: a velocity waits for its steering, as the session writes them.
    fn control(&mut self, to: Endpoint, bytes: &[u8]) -> Vec<RobiControl> {
        self.stats.bytes += bytes.len() as u64;
        let mut out = Vec::new();
        match (to, bytes.first()) {
            (Endpoint::Velocity, Some(&v)) => {
                // Two velocities in a row: the first went without a steering write.
                if let Some(prev) = self.velocity.replace(v) {
                    out.push(RobiControl {
                        velocity: prev,
                        steering: self.steering,
                    });
                }
            }
            (Endpoint::Steering, Some(&s)) => {
                self.steering = s;
                out.push(RobiControl {
                    velocity: self.velocity.take().unwrap_or(0),
                    steering: s,
                });
            }
            _ => self.stats.skipped_bytes += bytes.len() as u64,
        }
        self.stats.packets += out.len() as u64;
        self.kinds[2] += out.len() as u64;
        out
    }
}

/// The handshake is 5 bytes ending in EOP where a frame has its EFS high byte; a frame with
/// 0x7F there would enable the unsized gyro, so the two cannot be confused.
pub fn decode_value(bytes: &[u8]) -> Result<Item, FrameError> {
    if bytes.len() == HANDSHAKE_LEN && bytes[HANDSHAKE_LEN - 1] == EOP {
        rsrcp::decode_handshake(bytes).map(Item::Handshake)
    } else {
        rsrcp::decode_frame(bytes).map(Item::Frame)
    }
}

/// A frame error in the seam's terms: what was decoded of the frame, as a frame packet.
pub fn seam_error(e: FrameError) -> DecodeError {
    e.map_packet(|d| {
        d.partial
            .map(|f| Packet::Robi(RobiPacket::Item(Item::Frame(f))))
    })
}

impl Reader for RobiReader {
    fn feed(&mut self, bytes: &[u8], mut emit: Emit<'_>) -> io::Result<()> {
        if self.side == Side::Host {
            return self.write(Endpoint::Api, bytes, emit);
        }
        if self.whole_values {
            let r = self.value(bytes);
            self.count(&r);
            return match emit.as_mut() {
                Some(emit) => emit(&RobiFound::Item { offset: 0, item: r }),
                None => Ok(()),
            };
        }
        let mut found = Vec::new();
        let mut feed = self.framer.feed(bytes);
        while let Some(r) = feed.next() {
            found.push((feed.event_offset(), r));
        }
        drop(feed);
        for (offset, r) in found {
            self.count(&r);
            if let Some(emit) = emit.as_mut() {
                emit(&RobiFound::Item { offset, item: r })?;
            }
        }
        Ok(())
    }

    fn write(&mut self, to: Endpoint, bytes: &[u8], mut emit: Emit<'_>) -> io::Result<()> {
        if self.side == Side::Droid {
            return self.feed(bytes, emit);
        }
        for c in self.control(to, bytes) {
            if let Some(emit) = emit.as_mut() {
                emit(&RobiFound::Control(c))?;
            }
        }
        Ok(())
    }

    fn finish(&mut self, mut emit: Emit<'_>) -> io::Result<()> {
        if self.side == Side::Host || self.whole_values {
            return Ok(());
        }
        for (offset, r) in self.framer.finish_with_offsets() {
            self.count(&r);
            if let Some(emit) = emit.as_mut() {
                emit(&RobiFound::Item { offset, item: r })?;
            }
        }
        Ok(())
    }

    fn stats(&self) -> DecodeStats {
        if self.side == Side::Droid && !self.whole_values {
            *self.framer.stats()
        } else {
            self.stats
        }
    }

    fn kinds(&self) -> Vec<(&'static str, u64)> {
        match self.side {
            Side::Droid => vec![("handshake", self.kinds[0]), ("frame", self.kinds[1])],
            Side::Host => vec![("remote-control", self.kinds[2])],
        }
    }

    /// One BLE value: the handshake characteristic's 5 bytes or one frames notification,
    /// which must be exactly one handshake or frame (too short, too long, a bad EOP, an
    /// unsized feature are errors). Input holding several is refused in favour of `--stream`.
    fn one(&mut self, bytes: &[u8]) -> Result<Box<dyn Found>, crate::family::error::ReadError> {
        if bytes.is_empty() {
            return Err(crate::family::error::ReadError::NoBytes);
        }
        let mut framer = Framer::new();
        let mut all: Vec<_> = framer.feed(bytes).collect();
        all.extend(framer.finish());
        let found = all.iter().filter(|r| r.is_ok()).count();
        if found > 1 {
            return Err(crate::family::error::ReadError::NotOneFrame(found));
        }
        let item = self.value(bytes);
        self.count(&item);
        Ok(Box::new(RobiFound::Item { offset: 0, item }))
    }
}

/// What a Robi reader found.
enum RobiFound {
    Item {
        offset: u64,
        item: Result<Item, FrameError>,
    },
    Control(RobiControl),
}

/// A remote-control write as JSON.
#[derive(Serialize)]
struct ControlJson {
    kind: &'static str,
    velocity: u8,
    steering: u8,
}

impl Found for RobiFound {
    fn offset(&self) -> u64 {
        match self {
            RobiFound::Item { offset, .. } => *offset,
            RobiFound::Control(_) => 0,
        }
    }

    fn error_kind(&self) -> Option<ErrorKind> {
        match self {
            RobiFound::Item { item: Err(e), .. } => Some(e.kind),
            _ => None,
        }
    }

    fn decode_error(&self) -> Option<DecodeError> {
        match self {
            RobiFound::Item { item: Err(e), .. } => Some(seam_error(e.clone())),
            _ => None,
        }
    }

    fn packet(&self) -> Option<Packet> {
        match self {
            RobiFound::Item { item: Ok(i), .. } => Some(Packet::Robi(RobiPacket::Item(i.clone()))),
            RobiFound::Item { item: Err(_), .. } => None,
            RobiFound::Control(c) => Some(Packet::Robi(RobiPacket::Control(*c))),
        }
    }

    fn write_json(&self, with_offset: bool, out: &mut Vec<u8>) {
        match self {
            // The object has an `offset` key of its own (an error's is always set).
            RobiFound::Item { offset, item } => {
                let j = rsrcp::json(item);
                write_json(&if with_offset { j.at(*offset) } else { j }, out)
            }
            RobiFound::Control(c) => write_json(
                &ControlJson {
                    kind: "remote-control",
                    velocity: c.velocity,
                    steering: c.steering,
                },
                out,
            ),
        }
    }

    fn text(&self) -> String {
        format!("{}\n", self.line())
    }

    fn line(&self) -> String {
        match self {
            RobiFound::Item { item: Ok(i), .. } => i.summary(),
            RobiFound::Item { item: Err(e), .. } => format!("decode error: {}", e.summary()),
            RobiFound::Control(c) => {
                format!(
                    "remote-control velocity={} steering={}",
                    c.velocity, c.steering
                )
            }
        }
    }
}
