//! Reading v2 traffic from outside a session (see [`crate::family::read`]): one decoder for
//! both directions (a v2 packet says whether it is a command, a response or a notification),
//! the masks in effect given or followed from the stream's own streaming commands.

use crate::family::read::{Emit, Found, FoundError, ReadOptions, Reader, not_one, write_json};
use crate::family::{DecodeError, Packet};
use crate::protocol::decode::{DecodeStats, ErrorKind};
use crate::protocol::v2::{self, Decoded, Decoder, Described, Kind, StreamingConfig, describe};
use std::io;

/// A v2 reader.
pub struct V2Reader {
    decoder: Decoder,
    seen: Seen,
    /// The payload buffer of the packet last shown, reused for the next one.
    spare: Vec<u8>,
}

/// What the reader learnt from the packets so far.
struct Seen {
    /// The masks in effect: given, or followed from the stream.
    streaming: StreamingConfig,
    follow: bool,
    /// Packets per kind: command, response, notification.
    kinds: [u64; 3],
}

impl V2Reader {
    pub fn new(opts: &ReadOptions) -> V2Reader {
        V2Reader {
            decoder: Decoder::new(),
            seen: Seen {
                streaming: StreamingConfig {
                    mask: opts.sensor_mask.unwrap_or(0),
                    ext_mask: opts.ext_mask.unwrap_or(0),
                    interval_ms: 1,
                },
                follow: opts.follow && opts.sensor_mask.is_none(),
                kinds: [0; 3],
            },
            spare: Vec::new(),
        }
    }
}

impl Seen {
    /// The masks to name sensor values with, when any are known.
    fn masks(&self) -> Option<&StreamingConfig> {
        (self.streaming.mask != 0 || self.streaming.ext_mask != 0).then_some(&self.streaming)
    }

    fn found(&self, offset: u64, packet: v2::Packet, received: Option<Vec<u8>>) -> V2Found {
        let described = describe(&packet, self.masks());
        V2Found {
            offset,
            packet,
            described,
            received,
        }
    }

    /// Count a packet and learn what it tells the droid to stream.
    fn saw(&mut self, kind: Kind, did: u8, cid: u8, data: &[u8]) {
        self.kinds[kind as usize] += 1;
        if self.follow && kind == Kind::Command {
            // What the stream itself tells the droid to stream (as the session tracks it).
            match (did, cid, data) {
                (0x18, 0x00, [i0, i1, _count, m @ ..]) if m.len() == 4 => {
                    self.streaming.interval_ms = u16::from_be_bytes([*i0, *i1]);
                    self.streaming.mask = u32::from_be_bytes([m[0], m[1], m[2], m[3]]);
                }
                (0x18, 0x0C, m) if m.len() == 4 => {
                    self.streaming.ext_mask = u32::from_be_bytes([m[0], m[1], m[2], m[3]]);
                }
                _ => {}
            }
        }
    }
}

/// A v2 packet's kind from its flags and SEQ, without building the packet.
fn kind_of(p: &v2::PacketRef<'_>) -> Kind {
    if p.is_response() {
        Kind::Response
    } else if p.is_notification() {
        Kind::Notification
    } else {
        Kind::Command
    }
}

/// A v2 decode error in the seam's terms.
pub fn seam_error(e: v2::DecodeError) -> DecodeError {
    e.map_packet(|p| Some(Packet::V2(p)))
}

impl Reader for V2Reader {
    fn feed(&mut self, bytes: &[u8], mut emit: Emit<'_>) -> io::Result<()> {
        let mut result = Ok(());
        let seen = &mut self.seen;
        let spare = &mut self.spare;
        // Borrowed packets: nothing is allocated per packet unless it is shown.
        self.decoder.feed_with(bytes, |d| {
            if result.is_err() {
                return;
            }
            match d {
                Decoded::Packet { offset, packet } => {
                    seen.saw(kind_of(&packet), packet.did, packet.cid, packet.data);
                    if let Some(emit) = emit.as_mut() {
                        let packet = packet.to_packet_in(std::mem::take(spare));
                        let found = seen.found(offset, packet, None);
                        result = emit(&found);
                        *spare = found.packet.data;
                    }
                }
                Decoded::Error(e) => {
                    if let Some(emit) = emit.as_mut() {
                        result = emit(&FoundError(seam_error(e)));
                    }
                }
            }
        });
        result
    }

    fn finish(&mut self, mut emit: Emit<'_>) -> io::Result<()> {
        for e in self.decoder.finish() {
            if let Some(emit) = emit.as_mut() {
                emit(&FoundError(seam_error(e)))?;
            }
        }
        Ok(())
    }

    fn stats(&self) -> DecodeStats {
        *self.decoder.stats()
    }

    fn kinds(&self) -> Vec<(&'static str, u64)> {
        [Kind::Command, Kind::Response, Kind::Notification]
            .into_iter()
            .map(|k| (k.name(), self.seen.kinds[k as usize]))
            .collect()
    }

    fn one(&mut self, bytes: &[u8]) -> Result<Box<dyn Found>, crate::family::error::ReadError> {
        let mut items: Vec<_> = self.decoder.feed(bytes).collect();
        items.extend(self.decoder.finish().into_iter().map(Err));
        if items.len() != 1 {
            return Err(not_one(items.len(), "packets or errors"));
        }
        Ok(match items.remove(0) {
            Ok(p) => Box::new(self.seen.found(0, p, None)),
            // A bad checksum still shows the packet, with the verdict, as it was received.
            Err(v2::DecodeError {
                kind: ErrorKind::BadChecksum,
                packet: Some(p),
                ..
            }) => Box::new(self.seen.found(0, *p, Some(bytes.to_vec()))),
            Err(e) => Box::new(FoundError(seam_error(e))),
        })
    }
}

/// A v2 packet and how it reads.
struct V2Found {
    offset: u64,
    packet: v2::Packet,
    described: Described,
    /// The wire as received, for a packet whose checksum failed.
    received: Option<Vec<u8>>,
}

impl Found for V2Found {
    fn offset(&self) -> u64 {
        self.offset
    }

    fn error_kind(&self) -> Option<ErrorKind> {
        None
    }

    fn decode_error(&self) -> Option<DecodeError> {
        None
    }

    fn packet(&self) -> Option<Packet> {
        Some(Packet::V2(self.packet.clone()))
    }

    fn is_bad(&self) -> bool {
        self.received.is_some()
    }

    fn write_json(&self, with_offset: bool, out: &mut Vec<u8>) {
        let j = v2::describe::json(&self.packet, self.received.is_none(), &self.described);
        write_json(&if with_offset { j.at(self.offset) } else { j }, out)
    }

    fn text(&self) -> String {
        v2::describe::text(&self.packet, self.received.as_deref(), &self.described)
    }

    fn line(&self) -> String {
        v2::describe::line(&self.packet, &self.described)
    }
}
