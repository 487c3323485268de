//! A streaming v2 decoder: bytes in any chunking in, packets and typed errors out.
//!
//! BLE notifications are not packet boundaries (`droid-facts.md` §1), so the decoder treats
//! its input as one byte stream. It never panics, never holds more than `max_body` bytes,
//! resynchronises on the next SOP after any error, and counts every error kind so the UI can
//! show them. Bytes are unescaped into one reused buffer: nothing is allocated per byte.
//! [`Decoder::feed`] yields owned packets (one `Vec` per packet for its payload);
//! [`Decoder::feed_with`] hands out [`PacketRef`]s borrowing that buffer, allocating nothing per
//! packet, and skips from one framing byte to the next with `memchr`.

use super::packet::{
    BodyError, EOP, ESC, ESC_EOP, ESC_ESC, ESC_SOP, Packet, PacketRef, SOP, body_ref_unchecked,
    parse_body, parse_body_ref,
};

/// Default bound on an unescaped body. Real packets are far shorter (the longest documented
/// response is 46 bytes of data); anything larger is line noise.
pub const DEFAULT_MAX_BODY: usize = 512;

pub use crate::protocol::decode::{DecodeStats, ErrorKind};

/// The kinds of error a v2 decoder reports, in the order summaries list them.
pub const ERROR_KINDS: [ErrorKind; 7] = [
    ErrorKind::BadChecksum,
    ErrorKind::BadEscape,
    ErrorKind::SopInsidePacket,
    ErrorKind::TooShort,
    ErrorKind::Oversize,
    ErrorKind::Garbage,
    ErrorKind::Truncated,
];

/// A v2 decode error; for a bad checksum it keeps the packet as it was read, for diagnostics.
pub type DecodeError = crate::protocol::decode::DecodeError<Packet>;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    /// Looking for SOP; `garbage_start` marks a pending run of garbage.
    Hunting,
    /// Inside a packet; `escaped` after ESC.
    Body { escaped: bool },
    /// After an error inside a packet: drop bytes until EOP or SOP, silently (the error
    /// was already reported once).
    Discarding,
}

/// Where [`Decoder::whole_body`] put a packet that lies whole in the input.
enum Whole<'b> {
    /// The body is the input itself (no escapes).
    Input(&'b [u8]),
    /// The body was unescaped into the decoder's buffer.
    Unescaped,
}

/// The streaming decoder. Feed it with [`Decoder::feed`].
#[derive(Debug, Clone)]
pub struct Decoder {
    state: State,
    buf: Vec<u8>,
    max_body: usize,
    offset: u64,
    packet_start: u64,
    /// Wire bytes of the current packet so far, SOP and escapes included: what is counted as
    /// skipped when the packet is abandoned (`buf` holds the unescaped body, which is shorter).
    packet_wire_len: u64,
    garbage_start: Option<u64>,
    garbage_len: u64,
    stats: DecodeStats,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    pub fn new() -> Self {
        Self::with_max_body(DEFAULT_MAX_BODY)
    }

    /// A decoder that rejects bodies longer than `max_body` unescaped bytes (at least 8).
    pub fn with_max_body(max_body: usize) -> Self {
        let max_body = max_body.max(8);
        Decoder {
            state: State::Hunting,
            buf: Vec::with_capacity(max_body),
            max_body,
            offset: 0,
            packet_start: 0,
            packet_wire_len: 0,
            garbage_start: None,
            garbage_len: 0,
            stats: DecodeStats::default(),
        }
    }

    pub fn stats(&self) -> &DecodeStats {
        &self.stats
    }

    /// Bytes currently buffered for an unfinished packet (never more than the bound).
    pub fn buffered(&self) -> usize {
        match self.state {
            State::Body { .. } => self.buf.len(),
            _ => 0,
        }
    }

    /// Decode `bytes`, calling `f` with every packet and error they complete, in order. The
    /// same decoding as [`Decoder::feed`] (same errors, offsets and statistics), but a packet
    /// borrows the decoder's buffer for the duration of the call: nothing is allocated per
    /// packet (errors still carry their detail text).
    pub fn feed_with<F>(&mut self, bytes: &[u8], mut f: F)
    where
        F: FnMut(Decoded<'_>),
    {
        let mut pos = 0;
        while let Some(d) = self.next_in(bytes, &mut pos) {
            f(d);
        }
    }

    /// The next packet or error in `bytes[*pos..]`, moving `pos` past what it consumed. A
    /// packet borrows the input itself when it lies whole in it without escapes, else the
    /// decoder's buffer.
    fn next_in<'s>(&'s mut self, bytes: &'s [u8], pos: &mut usize) -> Option<Decoded<'s>> {
        match self.whole_body(bytes, pos) {
            Some(Whole::Input(body)) => {
                if let Ok(packet) = parse_body_ref(body) {
                    self.stats.packets += 1;
                    let offset = self.packet_start;
                    return Some(Decoded::Packet { offset, packet });
                }
                // Not a packet: reported as the buffered path reports it.
                self.buf.clear();
                self.buf.extend_from_slice(body);
                return self.buffered_body();
            }
            Some(Whole::Unescaped) => return self.buffered_body(),
            None => {}
        }
        match self.scan(bytes, pos)? {
            Err(e) => Some(Decoded::Error(e)),
            // A body ended: `buf` holds it until the next packet starts.
            Ok(()) => self.buffered_body(),
        }
    }

    /// The fast path of a clean stream: at `bytes[*pos]` a packet starts (no garbage
    /// pending) and ends in `bytes`, with no SOP inside, every escape a good one, within the
    /// bound. Without escapes its body is the input itself (nothing copied); with them it is
    /// unescaped into `buf` in one pass. `pos`, the offsets and the statistics move on exactly
    /// as [`Decoder::scan`] would move them; anything else (an error to report, a packet that
    /// goes on past the input) is left to `scan`, from the same place, nothing changed.
    fn whole_body<'b>(&mut self, bytes: &'b [u8], pos: &mut usize) -> Option<Whole<'b>> {
        if self.state != State::Hunting || self.garbage_start.is_some() {
            return None;
        }
        let rest = bytes.get(*pos..)?;
        if rest.first() != Some(&SOP) {
            return None;
        }
        let body = &rest[1..];
        let first = memchr::memchr3(SOP, EOP, ESC, body)?;
        if first > self.max_body {
            return None;
        }
        let (end, whole) = match body[first] {
            EOP => (first, Whole::Input(&body[..first])),
            ESC => (self.unescape_whole(body, first)?, Whole::Unescaped),
            _ => return None,
        };
        // SOP, the body with its escapes, EOP.
        let wire = end + 2;
        self.packet_start = self.offset;
        self.packet_wire_len = wire as u64;
        self.advance(pos, wire);
        Some(whole)
    }

    /// `body` (the bytes after a SOP, the first framing byte in them an ESC at `esc`)
    /// unescaped into `buf`, up to its EOP, whose index in `body` comes back; `None` when it
    /// has a SOP or a bad escape before its end, outgrows the bound or goes on past `body`
    /// (`buf` is then left for `scan` to clear).
    fn unescape_whole(&mut self, body: &[u8], esc: usize) -> Option<usize> {
        self.buf.clear();
        self.buf.extend_from_slice(&body[..esc]);
        let mut i = esc;
        loop {
            // `body[i]` is a framing byte: an escape, the end, or a SOP that should not be.
            match body[i] {
                EOP => return Some(i),
                ESC => {
                    let v = match *body.get(i + 1)? {
                        ESC_ESC => ESC,
                        ESC_SOP => SOP,
                        ESC_EOP => EOP,
                        _ => return None,
                    };
                    self.buf.push(v);
                    i += 2;
                }
                _ => return None,
            }
            // The run up to the next framing byte, copied whole.
            let rest = body.get(i..)?;
            let run = memchr::memchr3(SOP, EOP, ESC, rest)?;
            self.buf.extend_from_slice(&rest[..run]);
            i += run;
            if self.buf.len() > self.max_body {
                return None;
            }
        }
    }

    /// The body in `buf` as a packet, or the error it is.
    fn buffered_body(&mut self) -> Option<Decoded<'_>> {
        // Checked first, then handed out: a packet borrows `buf`, an error needs the
        // decoder mutably.
        if let Err((e, packet)) = parse_body_ref(&self.buf) {
            let packet = packet.map(|p| p.to_packet());
            let e = self.body_error(e, packet);
            self.buf.clear();
            return Some(Decoded::Error(e));
        }
        self.stats.packets += 1;
        let offset = self.packet_start;
        body_ref_unchecked(&self.buf).map(|packet| Decoded::Packet { offset, packet })
    }

    /// Consume `n` bytes of the input.
    fn advance(&mut self, pos: &mut usize, n: usize) {
        *pos += n;
        self.offset += n as u64;
        self.stats.bytes += n as u64;
    }

    /// Run through `bytes[*pos..]` until a body ends (`Ok`) or an error is due, skipping from
    /// one framing byte to the next; `None` when the input is used up.
    fn scan(&mut self, bytes: &[u8], pos: &mut usize) -> Option<Result<(), DecodeError>> {
        while *pos < bytes.len() {
            let rest = &bytes[*pos..];
            let at = self.offset;
            match self.state {
                State::Hunting => match memchr::memchr(SOP, rest) {
                    None => {
                        self.garbage(at, rest.len() as u64);
                        self.advance(pos, rest.len());
                    }
                    Some(k) => {
                        if k > 0 {
                            self.garbage(at, k as u64);
                        }
                        self.advance(pos, k + 1);
                        let garbage = self.take_garbage();
                        self.start_packet(at + k as u64);
                        if let Some(e) = garbage {
                            return Some(Err(e));
                        }
                    }
                },
                State::Discarding => match memchr::memchr2(SOP, EOP, rest) {
                    None => {
                        self.stats.skipped_bytes += rest.len() as u64;
                        self.advance(pos, rest.len());
                    }
                    Some(k) => {
                        self.stats.skipped_bytes += k as u64;
                        self.advance(pos, k + 1);
                        if rest[k] == SOP {
                            self.start_packet(at + k as u64);
                        } else {
                            self.stats.skipped_bytes += 1;
                            self.state = State::Hunting;
                        }
                    }
                },
                State::Body { escaped: false } => {
                    let run = memchr::memchr3(SOP, EOP, ESC, rest).unwrap_or(rest.len());
                    let room = self.max_body - self.buf.len();
                    if run > room {
                        // The byte after the room is the one that does not fit.
                        self.buf.extend_from_slice(&rest[..room]);
                        self.packet_wire_len += room as u64 + 1;
                        self.advance(pos, room + 1);
                        let detail = format!("body longer than {} bytes", self.max_body);
                        return Some(Err(self.abandon(ErrorKind::Oversize, detail)));
                    }
                    self.buf.extend_from_slice(&rest[..run]);
                    self.packet_wire_len += run as u64;
                    self.advance(pos, run);
                    let Some(&b) = rest.get(run) else {
                        continue;
                    };
                    let at = self.offset;
                    self.advance(pos, 1);
                    if b == EOP {
                        self.packet_wire_len += 1;
                        self.state = State::Hunting;
                        return Some(Ok(()));
                    }
                    if let Some(Err(e)) = self.step(b, at) {
                        return Some(Err(e));
                    }
                }
                State::Body { escaped: true } => {
                    let b = rest[0];
                    self.advance(pos, 1);
                    if let Some(Err(e)) = self.step(b, at) {
                        return Some(Err(e));
                    }
                }
            }
        }
        None
    }

    /// `len` bytes outside any packet from `at`: one pending run, reported when it ends.
    fn garbage(&mut self, at: u64, len: u64) {
        self.stats.skipped_bytes += len;
        if self.garbage_start.is_none() {
            self.garbage_start = Some(at);
        }
        self.garbage_len += len;
    }

    /// Decode `bytes`, yielding every packet and error they complete. The iterator must be
    /// drained for all of `bytes` to be consumed; state carries over to the next call.
    pub fn feed<'a>(&'a mut self, bytes: &'a [u8]) -> Feed<'a> {
        Feed {
            decoder: self,
            bytes,
            pos: 0,
        }
    }

    /// Convenience for tests and tools: decode a whole slice into a vector.
    pub fn decode_all(&mut self, bytes: &[u8]) -> Vec<Result<Packet, DecodeError>> {
        self.feed(bytes).collect()
    }

    /// The stream has ended: report a pending garbage run or an unfinished packet.
    pub fn finish(&mut self) -> Vec<DecodeError> {
        let mut out = Vec::new();
        if let Some(e) = self.take_garbage() {
            out.push(e);
        }
        if let State::Body { .. } = self.state {
            // A packet whose end byte is wrong reads as one that never ended: say both, and
            // the last byte, so `8D … D9` is not taken for a cut-short capture alone.
            let detail = match self.buf.last() {
                Some(last) => format!(
                    "{} body bytes before the stream ended, no end byte (D8): cut short, or \
                     its end byte is wrong (the last byte is {last:02X})",
                    self.buf.len()
                ),
                None => "the stream ended right after a start byte".to_string(),
            };
            out.push(self.error(ErrorKind::Truncated, self.packet_start, detail));
            self.stats.skipped_bytes += self.packet_wire_len;
        }
        self.buf.clear();
        self.state = State::Hunting;
        out
    }

    fn error(&mut self, kind: ErrorKind, offset: u64, detail: String) -> DecodeError {
        self.stats.count_error(kind);
        DecodeError {
            kind,
            offset,
            detail,
            packet: None,
        }
    }

    fn take_garbage(&mut self) -> Option<DecodeError> {
        let start = self.garbage_start.take()?;
        let len = std::mem::take(&mut self.garbage_len);
        let detail = format!("{len} byte(s) outside any packet");
        Some(self.error(ErrorKind::Garbage, start, detail))
    }

    fn start_packet(&mut self, at: u64) {
        self.buf.clear();
        self.packet_start = at;
        self.packet_wire_len = 1;
        self.state = State::Body { escaped: false };
    }

    /// Abandon the current packet after an error inside it.
    fn abandon(&mut self, kind: ErrorKind, detail: String) -> DecodeError {
        self.stats.skipped_bytes += self.packet_wire_len;
        self.buf.clear();
        self.state = State::Discarding;
        self.error(kind, self.packet_start, detail)
    }

    fn push_body(&mut self, b: u8) -> Option<DecodeError> {
        if self.buf.len() >= self.max_body {
            let detail = format!("body longer than {} bytes", self.max_body);
            return Some(self.abandon(ErrorKind::Oversize, detail));
        }
        self.buf.push(b);
        None
    }

    fn end_packet(&mut self) -> Result<Packet, DecodeError> {
        self.state = State::Hunting;
        let result = parse_body(&self.buf);
        self.buf.clear();
        match result {
            Ok(p) => {
                self.stats.packets += 1;
                Ok(p)
            }
            Err((e, packet)) => Err(self.body_error(e, packet)),
        }
    }

    /// The error for a complete body that is not a packet; its wire bytes are skipped.
    fn body_error(&mut self, e: BodyError, packet: Option<Packet>) -> DecodeError {
        self.stats.skipped_bytes += self.packet_wire_len;
        match e {
            BodyError::TooShort { needed, got } => {
                let detail = format!("{got} body byte(s), its flags need at least {needed}");
                self.error(ErrorKind::TooShort, self.packet_start, detail)
            }
            BodyError::BadChecksum { expected, got } => {
                let detail = format!("checksum 0x{got:02X}, expected 0x{expected:02X}");
                let mut e = self.error(ErrorKind::BadChecksum, self.packet_start, detail);
                e.packet = packet.map(Box::new);
                e
            }
        }
    }

    /// Process one byte at stream offset `at`; returns at most one event, except that a SOP
    /// ending a garbage run may need to report the run *and* start a packet (the run is
    /// reported, the packet starts silently).
    fn step(&mut self, b: u8, at: u64) -> Option<Result<Packet, DecodeError>> {
        match self.state {
            State::Hunting => {
                if b == SOP {
                    let garbage = self.take_garbage();
                    self.start_packet(at);
                    return garbage.map(Err);
                }
                self.stats.skipped_bytes += 1;
                if self.garbage_start.is_none() {
                    self.garbage_start = Some(at);
                }
                self.garbage_len += 1;
                None
            }
            State::Discarding => {
                match b {
                    SOP => self.start_packet(at),
                    EOP => {
                        self.stats.skipped_bytes += 1;
                        self.state = State::Hunting;
                    }
                    _ => self.stats.skipped_bytes += 1,
                }
                None
            }
            State::Body { escaped } => {
                if b == SOP {
                    // Drop the partial packet, restart here.
                    self.stats.skipped_bytes += self.packet_wire_len;
                    let detail = format!("new SOP after {} body byte(s)", self.buf.len());
                    let e = self.error(ErrorKind::SopInsidePacket, self.packet_start, detail);
                    self.start_packet(at);
                    return Some(Err(e));
                }
                self.packet_wire_len += 1;
                if escaped {
                    let unescaped = match b {
                        ESC_ESC => ESC,
                        ESC_SOP => SOP,
                        ESC_EOP => EOP,
                        other => {
                            let detail = format!("ESC followed by 0x{other:02X}");
                            let e = self.abandon(ErrorKind::BadEscape, detail);
                            if other == EOP {
                                self.state = State::Hunting;
                            }
                            return Some(Err(e));
                        }
                    };
                    self.state = State::Body { escaped: false };
                    return self.push_body(unescaped).map(Err);
                }
                match b {
                    EOP => Some(self.end_packet()),
                    ESC => {
                        self.state = State::Body { escaped: true };
                        None
                    }
                    other => self.push_body(other).map(Err),
                }
            }
        }
    }
}

/// What [`Decoder::feed_with`] reports.
#[derive(Debug, Clone, PartialEq)]
pub enum Decoded<'a> {
    /// A packet, borrowing the decoder's buffer; `offset` is its SOP's stream offset.
    Packet {
        offset: u64,
        packet: PacketRef<'a>,
    },
    Error(DecodeError),
}

/// Iterator returned by [`Decoder::feed`].
pub struct Feed<'a> {
    decoder: &'a mut Decoder,
    bytes: &'a [u8],
    pos: usize,
}

impl Iterator for Feed<'_> {
    type Item = Result<Packet, DecodeError>;

    fn next(&mut self) -> Option<Self::Item> {
        let d = self.decoder.next_in(self.bytes, &mut self.pos)?;
        Some(match d {
            Decoded::Packet { packet, .. } => Ok(packet.to_packet()),
            Decoded::Error(e) => Err(e),
        })
    }
}

impl Drop for Feed<'_> {
    /// Consume whatever the caller did not iterate, so no input is silently lost.
    fn drop(&mut self) {
        for _ in self.by_ref() {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hex;

    fn kinds(events: &[Result<Packet, DecodeError>]) -> Vec<Result<(u8, u8), ErrorKind>> {
        events
            .iter()
            .map(|e| match e {
                Ok(p) => Ok((p.did, p.cid)),
                Err(e) => Err(e.kind),
            })
            .collect()
    }

    #[test]
    fn decodes_wake_and_response() {
        let mut d = Decoder::new();
        let bytes = hex::parse("8D 0A 13 0D 00 D5 D8 8D 09 13 0D 00 00 D6 D8").unwrap();
        let out = d.decode_all(&bytes);
        assert_eq!(kinds(&out), vec![Ok((0x13, 0x0D)), Ok((0x13, 0x0D))]);
        assert_eq!(d.stats().packets, 2);
    }

    #[test]
    fn byte_at_a_time() {
        let mut d = Decoder::new();
        let bytes = hex::parse("8D 0A 1A 0E AB 05 00 AB 23 AB 50 BD D8").unwrap();
        let mut got = Vec::new();
        for b in &bytes {
            got.extend(d.feed(std::slice::from_ref(b)));
        }
        let p = got.pop().unwrap().unwrap();
        assert_eq!(p.seq, 0x8D);
        assert_eq!(p.data, vec![0x00, 0xAB, 0xD8]);
    }

    #[test]
    fn bad_checksum_reports_and_resyncs() {
        let mut d = Decoder::new();
        let bytes = hex::parse("8D 0A 13 0D 00 D4 D8 8D 0A 13 0D 00 D5 D8").unwrap();
        let out = d.decode_all(&bytes);
        assert_eq!(
            kinds(&out),
            vec![Err(ErrorKind::BadChecksum), Ok((0x13, 0x0D))]
        );
        let Err(e) = &out[0] else { panic!() };
        assert_eq!(e.offset, 0);
        assert!(e.packet.is_some());
        assert_eq!(d.stats().errors(ErrorKind::BadChecksum), 1);
    }

    #[test]
    fn sop_inside_packet_restarts() {
        let mut d = Decoder::new();
        let bytes = hex::parse("8D 0A 13 8D 0A 13 0D 00 D5 D8").unwrap();
        let out = d.decode_all(&bytes);
        assert_eq!(
            kinds(&out),
            vec![Err(ErrorKind::SopInsidePacket), Ok((0x13, 0x0D))]
        );
    }

    #[test]
    fn bad_escape_discards_rest_of_packet_once() {
        let mut d = Decoder::new();
        let bytes = hex::parse("8D 0A AB 11 13 0D 00 D5 D8 8D 0A 13 0D 00 D5 D8").unwrap();
        let out = d.decode_all(&bytes);
        assert_eq!(
            kinds(&out),
            vec![Err(ErrorKind::BadEscape), Ok((0x13, 0x0D))]
        );
    }

    #[test]
    fn garbage_reported_once_per_run() {
        let mut d = Decoder::new();
        let bytes = hex::parse("01 02 03 8D 0A 13 0D 00 D5 D8 FF").unwrap();
        let out = d.decode_all(&bytes);
        assert_eq!(kinds(&out), vec![Err(ErrorKind::Garbage), Ok((0x13, 0x0D))]);
        let Err(e) = &out[0] else { panic!() };
        assert_eq!(e.offset, 0);
        let tail = d.finish();
        assert_eq!(tail.len(), 1);
        assert_eq!(tail[0].kind, ErrorKind::Garbage);
        assert_eq!(tail[0].offset, 10);
    }

    #[test]
    fn too_short_and_truncated() {
        let mut d = Decoder::new();
        let out = d.decode_all(&hex::parse("8D 0A 13 D8 8D 0A").unwrap());
        assert_eq!(kinds(&out), vec![Err(ErrorKind::TooShort)]);
        let tail = d.finish();
        assert_eq!(tail[0].kind, ErrorKind::Truncated);
        assert_eq!(tail[0].offset, 4);
    }

    #[test]
    fn oversize_is_bounded() {
        let mut d = Decoder::with_max_body(16);
        let mut bytes = vec![SOP];
        bytes.extend(std::iter::repeat_n(0x11, 1000));
        bytes.push(EOP);
        bytes.extend(hex::parse("8D 0A 13 0D 00 D5 D8").unwrap());
        let mut max_buffered = 0;
        let mut out = Vec::new();
        for chunk in bytes.chunks(7) {
            out.extend(d.feed(chunk));
            max_buffered = max_buffered.max(d.buffered());
        }
        assert!(max_buffered <= 16);
        assert_eq!(
            kinds(&out),
            vec![Err(ErrorKind::Oversize), Ok((0x13, 0x0D))]
        );
    }

    #[test]
    fn skipped_bytes_count_escapes_of_abandoned_packets() {
        // Every byte fed ends up in a packet or in skipped_bytes, escapes included.
        // Too short, bad checksum, bad escape after a good one, truncated inside an escape,
        // SOP inside a packet: each with escapes in the abandoned bytes.
        for stream in [
            "8D 0A AB 23 D8",
            "8D 0A AB 05 13 0D 00 00 D8",
            "8D 0A AB 23 AB 11 22 D8",
            "8D 0A AB 23 AB",
            "8D 0A AB 23 8D 0A 13 0D 00 D5 D8",
        ] {
            let bytes = hex::parse(stream).unwrap();
            let mut d = Decoder::new();
            let packets: u64 = d
                .decode_all(&bytes)
                .iter()
                .filter_map(|e| e.as_ref().ok())
                .map(|p| p.encode().len() as u64)
                .sum();
            d.finish();
            assert_eq!(
                packets + d.stats().skipped_bytes,
                bytes.len() as u64,
                "{stream}"
            );
        }
    }

    #[test]
    fn dropping_feed_consumes_input() {
        let mut d = Decoder::new();
        let bytes = hex::parse("8D 0A 13 0D 00 D5 D8 8D 0A 13 0D 00 D5 D8").unwrap();
        let first = d.feed(&bytes).next();
        assert!(first.is_some());
        assert_eq!(d.stats().packets, 2);
    }
}

#[cfg(test)]
mod feed_with_tests {
    use super::*;
    use crate::hex;
    use proptest::prelude::*;

    /// The decoder one byte at a time through `step` (the plain state machine the fast path
    /// must agree with).
    fn via_bytes(
        bytes: &[u8],
        chunk: usize,
        max: usize,
    ) -> (Vec<Result<Packet, DecodeError>>, DecodeStats) {
        let mut d = Decoder::with_max_body(max);
        let mut out = Vec::new();
        for c in bytes.chunks(chunk.max(1)) {
            for &b in c {
                let at = d.offset;
                d.offset += 1;
                d.stats.bytes += 1;
                out.extend(d.step(b, at));
            }
        }
        out.extend(d.finish().into_iter().map(Err));
        (out, *d.stats())
    }

    /// Everything `feed` reports, with `feed_with`'s packet offsets left out.
    fn via_feed(
        bytes: &[u8],
        chunk: usize,
        max: usize,
    ) -> (Vec<Result<Packet, DecodeError>>, DecodeStats) {
        let mut d = Decoder::with_max_body(max);
        let mut out = Vec::new();
        for c in bytes.chunks(chunk.max(1)) {
            out.extend(d.feed(c));
        }
        out.extend(d.finish().into_iter().map(Err));
        (out, *d.stats())
    }

    fn via_feed_with(
        bytes: &[u8],
        chunk: usize,
        max: usize,
    ) -> (Vec<Result<Packet, DecodeError>>, DecodeStats) {
        let mut d = Decoder::with_max_body(max);
        let mut out = Vec::new();
        for c in bytes.chunks(chunk.max(1)) {
            d.feed_with(c, |e| {
                out.push(match e {
                    Decoded::Packet { packet, .. } => Ok(packet.to_packet()),
                    Decoded::Error(e) => Err(e),
                })
            });
            assert!(d.buffered() <= max.max(8));
        }
        out.extend(d.finish().into_iter().map(Err));
        (out, *d.stats())
    }

    #[test]
    fn packet_offsets_are_their_sops() {
        let bytes =
            hex::parse("01 8D 0A 13 0D 00 D5 D8 8D 0A 1A 0E AB 05 00 AB 23 AB 50 BD D8").unwrap();
        let mut d = Decoder::new();
        let mut offsets = Vec::new();
        d.feed_with(&bytes, |e| {
            if let Decoded::Packet { offset, packet } = e {
                offsets.push((offset, packet.data.len()));
            }
        });
        assert_eq!(offsets, vec![(1, 0), (8, 3)]);
    }

    fn framing_heavy() -> impl Strategy<Value = Vec<u8>> {
        // Mostly real packets, with framing bytes and noise in between.
        let packet = (
            any::<u8>(),
            any::<u8>(),
            any::<u8>(),
            proptest::collection::vec(any::<u8>(), 0..24),
        )
            .prop_map(|(did, cid, seq, data)| Packet::command(did, cid, seq, data).encode());
        let noise = proptest::collection::vec(
            prop_oneof![
                Just(SOP),
                Just(EOP),
                Just(ESC),
                Just(0x05u8),
                Just(0x23u8),
                any::<u8>()
            ],
            0..6,
        );
        proptest::collection::vec((packet, noise), 0..12).prop_map(|v| {
            v.into_iter()
                .flat_map(|(mut p, n)| {
                    p.extend(n);
                    p
                })
                .collect()
        })
    }

    proptest! {
        #[test]
        fn feed_with_agrees_with_feed(bytes in framing_heavy(), chunk in 1usize..40, max in 8usize..40) {
            let reference = via_bytes(&bytes, chunk, max);
            prop_assert_eq!(&via_feed(&bytes, chunk, max), &reference);
            prop_assert_eq!(&via_feed_with(&bytes, chunk, max), &reference);
        }

        #[test]
        fn feed_with_agrees_on_noise(bytes in proptest::collection::vec(any::<u8>(), 0..300), chunk in 1usize..64) {
            let reference = via_bytes(&bytes, chunk, 16);
            prop_assert_eq!(&via_feed(&bytes, chunk, 16), &reference);
            prop_assert_eq!(&via_feed_with(&bytes, chunk, 16), &reference);
        }
    }
}
