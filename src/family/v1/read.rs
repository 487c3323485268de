//! Reading v1 traffic from outside a session (see [`crate::family::read`]). A v1 command and
//! a v1 response both start `FF FF`, so a reader reads one side; a response does not name its
//! command, so a request given by name (`--request`) decodes their payloads.

use crate::family::error::ReadError;
use crate::family::read::{
    Emit, Found, FoundError, ReadOptions, Reader, Side, not_one, write_json,
};
use crate::family::{DecodeError, Packet};
use crate::protocol::decode::{DecodeStats, ErrorKind};
use crate::protocol::table::unknown_command;
use crate::protocol::v1::{self, Decoder, Described, Kind, Source, StreamingConfig, describe};
use std::io;

/// A v1 reader of one side.
pub struct V1Reader {
    decoder: Decoder,
    seen: Seen,
}

/// What the reader knows beyond the decoder: its side, the masks, the request, the counts.
struct Seen {
    source: Source,
    streaming: Option<StreamingConfig>,
    follow: bool,
    request: Option<v1::Command>,
    /// Packets per kind: command, response, async.
    kinds: [u64; 3],
}

impl V1Reader {
    /// A reader of `side` told nothing else: sensor data raw, responses unnamed.
    pub fn for_side(side: Side) -> V1Reader {
        let source = match side {
            Side::Host => Source::Host,
            Side::Droid => Source::Droid,
        };
        V1Reader {
            decoder: Decoder::new(source),
            seen: Seen {
                source,
                streaming: None,
                follow: false,
                request: None,
                kinds: [0; 3],
            },
        }
    }

    /// `Err` says which option makes no sense (`--frames` without masks, an unknown request).
    pub fn new(opts: &ReadOptions) -> Result<V1Reader, ReadError> {
        let streaming = if opts.sensor_mask.is_none() && opts.mask2.is_none() {
            if opts.frames.is_some() {
                return Err(ReadError::FramesWithoutMasks);
            }
            None
        } else {
            Some(StreamingConfig {
                n: 1,
                m: opts.frames.unwrap_or(1),
                mask: opts.sensor_mask.unwrap_or(0),
                pcnt: 0,
                mask2: opts.mask2.unwrap_or(0),
            })
        };
        let request = opts
            .request
            .as_deref()
            .map(|name| {
                let def = v1::catalog::by_name(name).ok_or_else(|| {
                    ReadError::Request(unknown_command(
                        name,
                        v1::catalog::suggestions(name),
                        " --protocol v1",
                    ))
                })?;
                Ok::<_, ReadError>(v1::Command {
                    did: def.did,
                    cid: def.cid,
                    data: Vec::new(),
                })
            })
            .transpose()?;
        let source = match opts.side.unwrap_or(Side::Host) {
            Side::Host => Source::Host,
            Side::Droid => Source::Droid,
        };
        Ok(V1Reader {
            decoder: Decoder::new(source),
            seen: Seen {
                source,
                follow: opts.follow && streaming.is_none(),
                streaming,
                request,
                kinds: [0; 3],
            },
        })
    }
}

impl Seen {
    fn found(&self, offset: u64, packet: v1::Packet, received: Option<Vec<u8>>) -> V1Found {
        let described = describe(&packet, self.streaming.as_ref(), self.request.as_ref());
        V1Found {
            offset,
            packet,
            described,
            received,
        }
    }

    /// Count a packet and learn what it tells the droid to stream.
    fn saw(&mut self, p: &v1::Packet) {
        let i = match p.kind() {
            Kind::Command => 0,
            Kind::Response => 1,
            Kind::Async => 2,
        };
        self.kinds[i] += 1;
        if self.follow
            && let v1::Packet::Command(c) = p
            && (c.did, c.cid) == (0x02, 0x11)
            && let Some(s) = StreamingConfig::from_command_data(&c.data)
        {
            self.streaming = Some(s);
        }
    }

    fn item(
        &mut self,
        r: Result<v1::Packet, v1::DecodeError>,
        at: u64,
        emit: &mut Emit<'_>,
    ) -> io::Result<()> {
        match r {
            Ok(p) => {
                self.saw(&p);
                match emit.as_mut() {
                    Some(emit) => emit(&self.found(at, p, None)),
                    None => Ok(()),
                }
            }
            Err(e) => match emit.as_mut() {
                Some(emit) => emit(&FoundError(seam_error(e))),
                None => Ok(()),
            },
        }
    }
}

/// A v1 decode error in the seam's terms.
pub fn seam_error(e: v1::DecodeError) -> DecodeError {
    e.map_packet(|p| Some(Packet::V1(p)))
}

impl Reader for V1Reader {
    fn feed(&mut self, bytes: &[u8], mut emit: Emit<'_>) -> io::Result<()> {
        let mut result = Ok(());
        let mut found = self.decoder.feed(bytes);
        while let Some(r) = found.next() {
            let at = found.packet_offset();
            if result.is_ok() {
                result = self.seen.item(r, at, &mut emit);
            }
        }
        result
    }

    fn finish(&mut self, mut emit: Emit<'_>) -> io::Result<()> {
        // What finish finds after a truncated candidate comes without offsets: the decoder
        // has let go of those bytes.
        for r in self.decoder.finish() {
            let at = r
                .as_ref()
                .map_or_else(|e| e.offset, |_| self.decoder.packet_offset());
            self.seen.item(r, at, &mut emit)?;
        }
        Ok(())
    }

    fn stats(&self) -> DecodeStats {
        *self.decoder.stats()
    }

    fn kinds(&self) -> Vec<(&'static str, u64)> {
        vec![
            ("command", self.seen.kinds[0]),
            ("response", self.seen.kinds[1]),
            ("async", self.seen.kinds[2]),
        ]
    }

    fn one(&mut self, bytes: &[u8]) -> Result<Box<dyn Found>, crate::family::error::ReadError> {
        let mut items: Vec<_> = self.decoder.feed(bytes).collect();
        items.extend(self.decoder.finish());
        if items.len() != 1 {
            return Err(not_one(items.len(), "packets or errors"));
        }
        Ok(match items.remove(0) {
            Ok(p) => Box::new(self.seen.found(0, p, None)),
            // A bad checksum still shows the packet, with the verdict, as it was received.
            Err(v1::DecodeError {
                kind: ErrorKind::BadChecksum,
                packet: Some(p),
                ..
            }) => Box::new(self.seen.found(0, *p, Some(bytes.to_vec()))),
            Err(e) => Box::new(FoundError(seam_error(e))),
        })
    }

    /// The same bytes read from the other side may make sense.
    fn hint(&self) -> Option<&'static str> {
        Some(match self.seen.source {
            Source::Host => {
                "read as sent by the host (commands); responses and async messages need --from droid"
            }
            Source::Droid => {
                "read as sent by the droid (responses, async messages); commands need --from host"
            }
        })
    }
}

/// A v1 packet and how it reads.
struct V1Found {
    offset: u64,
    packet: v1::Packet,
    described: Described,
    /// The wire as received, for a packet whose checksum failed.
    received: Option<Vec<u8>>,
}

impl Found for V1Found {
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
        Some(Packet::V1(self.packet.clone()))
    }

    fn is_bad(&self) -> bool {
        self.received.is_some()
    }

    fn write_json(&self, with_offset: bool, out: &mut Vec<u8>) {
        let j = v1::describe::json(&self.packet, &self.described, self.received.is_none());
        write_json(&if with_offset { j.at(self.offset) } else { j }, out)
    }

    fn text(&self) -> String {
        v1::describe::text(&self.packet, self.received.as_deref(), &self.described)
    }

    fn line(&self) -> String {
        v1::describe::line(&self.packet, &self.described)
    }
}
