//! A streaming v1 decoder: bytes in any chunking in, packets and typed errors out.
//!
//! v1 has no escaping and no end marker: a packet is found by its SOP1/SOP2, its DLEN and its
//! checksum. `FF FF` occurs inside data (`droid-facts.md` §4), so the only proof of a packet
//! boundary is a valid checksum. The decoder therefore treats every `FF` + valid SOP2 as a
//! *candidate*, waits for the length it announces, and:
//!
//! - checksum valid: the packet is emitted and its bytes consumed;
//! - checksum invalid (or DLEN impossible): one error is reported, ONE byte (the SOP1) is
//!   dropped and the hunt resumes at the next byte, so a real packet starting inside the
//!   rejected one is still found. The rest of the rejected candidate's extent is "quiet":
//!   bytes dropped there are counted as skipped but not reported again (as garbage or as
//!   nested bad candidates), so one damaged packet gives one error.
//!
//! A command and a response both start `FF FF`, so the decoder is told which side it reads
//! ([`Source`]). Decisions depend only on the byte sequence, never on how it was chunked.
//!
//! The price of resynchronising only on a checksum: after corruption, a bogus candidate with
//! a large DLEN holds back the packets behind it until its announced length has arrived (at
//! most 261 bytes for commands and responses, `5 + max_async_dlen` for async messages; lower
//! that bound with [`Decoder::with_max_async_dlen`] to shorten the wait).
//!
//! Memory is bounded: only the current candidate is buffered, never more than
//! [`Decoder::max_packet_len`] bytes. Bytes outside any candidate are never copied.

use super::packet::{
    ASYNC_HEADER, AsyncPacket, COMMAND_HEADER, CommandPacket, Mrsp, Packet, RESPONSE_HEADER,
    Response, SOP1, SOP2_ASYNC, SOP2_COMMAND_BASE, SOP2_RESPONSE, checksum,
};

/// Default bound on an async message's DLEN. The longest async message droidctl asks for is
/// sensor streaming: M frames of up to 2 × 64 bytes; 1024 covers 8 full frames.
pub const DEFAULT_MAX_ASYNC_DLEN: usize = 1024;

/// Which side of the link the bytes come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Source {
    /// Client → droid: commands (SOP2 F8..FF).
    Host,
    /// Droid → client: responses (SOP2 FF) and async messages (SOP2 FE).
    Droid,
}

pub use crate::protocol::decode::{DecodeStats, ErrorKind};

/// The kinds of error a v1 decoder reports, in the order summaries list them.
pub const ERROR_KINDS: [ErrorKind; 5] = [
    ErrorKind::BadChecksum,
    ErrorKind::BadLength,
    ErrorKind::Oversize,
    ErrorKind::Garbage,
    ErrorKind::Truncated,
];

/// A v1 decode error; for a bad checksum it keeps the candidate as it was read, for
/// diagnostics.
pub type DecodeError = crate::protocol::decode::DecodeError<Packet>;

type Event = Result<Packet, DecodeError>;

/// What the bytes at the head of the buffer are.
enum Head {
    /// Need this many more bytes before anything can be decided.
    NeedMore(usize),
    /// Decided: an event to report (possibly after a pending garbage run), and the stream
    /// offset of its packet.
    Event(Event, u64),
    /// Something was dropped silently; look again.
    Again,
}

/// The streaming decoder. Feed it with [`Decoder::feed`], end with [`Decoder::finish`].
#[derive(Debug, Clone)]
pub struct Decoder {
    source: Source,
    max_async_dlen: usize,
    /// The current candidate's bytes live in `buf[head..]`.
    buf: Vec<u8>,
    head: usize,
    /// Bytes fed so far (the stream offset of the next byte to arrive).
    fed: u64,
    /// Bytes dropped below this offset are part of an already reported rejection.
    quiet_until: u64,
    garbage_start: Option<u64>,
    garbage_len: u64,
    /// An event decided together with a garbage report, returned right after it, with the
    /// stream offset of its packet.
    pending: Option<(Event, u64)>,
    /// The stream offset of the last packet returned.
    packet_at: u64,
    /// How many more bytes the head candidate needs (at least 1).
    need: usize,
    stats: DecodeStats,
}

impl Decoder {
    pub fn new(source: Source) -> Self {
        Self::with_max_async_dlen(source, DEFAULT_MAX_ASYNC_DLEN)
    }

    /// A decoder that rejects async messages whose DLEN is above `max` (clamped to
    /// 1..=65535). Ignored for [`Source::Host`], which sees no async messages.
    pub fn with_max_async_dlen(source: Source, max: usize) -> Self {
        let max_async_dlen = max.clamp(1, u16::MAX as usize);
        let mut d = Decoder {
            source,
            max_async_dlen,
            buf: Vec::new(),
            head: 0,
            fed: 0,
            quiet_until: 0,
            garbage_start: None,
            garbage_len: 0,
            pending: None,
            packet_at: 0,
            need: 1,
            stats: DecodeStats::default(),
        };
        d.buf.reserve(d.max_packet_len());
        d
    }

    pub fn source(&self) -> Source {
        self.source
    }

    /// The longest packet this decoder accepts, which bounds [`Decoder::buffered`].
    pub fn max_packet_len(&self) -> usize {
        match self.source {
            Source::Host => COMMAND_HEADER + 255,
            Source::Droid => (RESPONSE_HEADER + 255).max(ASYNC_HEADER + self.max_async_dlen),
        }
    }

    pub fn stats(&self) -> &DecodeStats {
        &self.stats
    }

    /// Bytes currently buffered for an unfinished candidate.
    pub fn buffered(&self) -> usize {
        self.buf.len() - self.head
    }

    /// Decode `bytes`, yielding every packet and error they complete. The iterator must be
    /// drained for all of `bytes` to be consumed (dropping it drains it); state carries over
    /// to the next call.
    pub fn feed<'a>(&'a mut self, bytes: &'a [u8]) -> Feed<'a> {
        Feed {
            decoder: self,
            bytes,
            pos: 0,
        }
    }

    /// Convenience for tests and tools: decode a whole slice into a vector.
    pub fn decode_all(&mut self, bytes: &[u8]) -> Vec<Event> {
        self.feed(bytes).collect()
    }

    /// The stream has ended. The unfinished candidate, if any, is reported as truncated and
    /// the bytes after its SOP1 are searched again: a complete packet may sit inside a bogus
    /// candidate that was waiting for more bytes. Hence packets as well as errors come out.
    /// A pending garbage run is reported last. The decoder can be fed again afterwards.
    pub fn finish(&mut self) -> Vec<Event> {
        let mut out = Vec::new();
        loop {
            if let Some(e) = self.next_event() {
                out.push(e);
                continue;
            }
            if self.buffered() == 0 {
                break;
            }
            let extent = self.buffered();
            let detail = format!("{extent} byte(s) of a packet before the stream ended");
            if let Some(e) = self.reject(ErrorKind::Truncated, extent, detail, None) {
                let at = e.offset;
                let e = self.emit(Err(e), at);
                out.push(e);
            }
        }
        if let Some(e) = self.take_garbage() {
            out.push(Err(e));
        }
        self.buf.clear();
        self.head = 0;
        self.need = 1;
        out
    }

    // ---------------------------------------------------------------------------------------

    fn live(&self) -> &[u8] {
        &self.buf[self.head..]
    }

    /// Stream offset of the first buffered byte.
    fn live_start(&self) -> u64 {
        self.fed - self.buffered() as u64
    }

    /// The stream offset of the first byte of the last packet the decoder returned.
    pub fn packet_offset(&self) -> u64 {
        self.packet_at
    }

    fn next_event(&mut self) -> Option<Event> {
        if let Some((e, at)) = self.pending.take() {
            self.packet_at = at;
            return Some(e);
        }
        loop {
            match self.examine() {
                Head::NeedMore(n) => {
                    self.need = n.max(1);
                    return None;
                }
                Head::Event(e, at) => return Some(self.emit(e, at)),
                Head::Again => {}
            }
        }
    }

    /// Report `e` (its packet at stream offset `at`), after the garbage run it ends if there
    /// is one.
    fn emit(&mut self, e: Event, at: u64) -> Event {
        match self.take_garbage() {
            Some(g) => {
                self.pending = Some((e, at));
                Err(g)
            }
            None => {
                self.packet_at = at;
                e
            }
        }
    }

    fn take_garbage(&mut self) -> Option<DecodeError> {
        let start = self.garbage_start.take()?;
        let len = std::mem::take(&mut self.garbage_len);
        let detail = format!("{len} byte(s) outside any packet");
        Some(self.error(ErrorKind::Garbage, start, detail))
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

    /// Account for `n` dropped bytes starting at stream offset `at`: skipped, and garbage
    /// unless inside a reported rejection.
    fn account_skipped(&mut self, at: u64, n: u64) {
        self.stats.skipped_bytes += n;
        let quiet = self.quiet_until.saturating_sub(at).min(n);
        let loud = n - quiet;
        if loud > 0 {
            self.garbage_start.get_or_insert(at + quiet);
            self.garbage_len += loud;
        }
    }

    /// Drop `n` buffered bytes from the head.
    fn skip(&mut self, n: usize) {
        let at = self.live_start();
        self.account_skipped(at, n as u64);
        self.head += n;
        if self.head == self.buf.len() {
            self.buf.clear();
            self.head = 0;
        }
    }

    /// Reject the head candidate, whose claimed extent is `extent` bytes: drop its SOP1 only
    /// (the hunt resumes at the next byte) and return the error to report, or `None` when the
    /// candidate starts inside an already reported rejection.
    fn reject(
        &mut self,
        kind: ErrorKind,
        extent: usize,
        detail: String,
        packet: Option<Packet>,
    ) -> Option<DecodeError> {
        let at = self.live_start();
        let quiet = at < self.quiet_until;
        self.quiet_until = self.quiet_until.max(at + extent as u64);
        self.skip(1);
        if quiet {
            return None;
        }
        let mut e = self.error(kind, at, detail);
        e.packet = packet.map(Box::new);
        Some(e)
    }

    /// Look at the head of the buffer and decide what it is, if the bytes allow.
    fn examine(&mut self) -> Head {
        let live = self.live();
        let Some(&first) = live.first() else {
            return Head::NeedMore(1);
        };
        if first != SOP1 {
            let n = live.iter().position(|&b| b == SOP1).unwrap_or(live.len());
            self.skip(n);
            return Head::Again;
        }
        let Some(&sop2) = live.get(1) else {
            return Head::NeedMore(1);
        };
        let header = match (self.source, sop2) {
            (Source::Host, s) if s >= SOP2_COMMAND_BASE => COMMAND_HEADER,
            (Source::Droid, SOP2_RESPONSE) => RESPONSE_HEADER,
            (Source::Droid, SOP2_ASYNC) => ASYNC_HEADER,
            _ => {
                // An FF that starts nothing: garbage.
                self.skip(1);
                return Head::Again;
            }
        };
        if live.len() < header {
            return Head::NeedMore(header - live.len());
        }
        let is_async = self.source == Source::Droid && sop2 == SOP2_ASYNC;
        let dlen = if is_async {
            u16::from_be_bytes([live[3], live[4]]) as usize
        } else {
            live[header - 1] as usize
        };
        if dlen == 0 {
            let detail = "DLEN 0 (it always counts the checksum byte)".to_string();
            return self.decided(ErrorKind::BadLength, header, detail, None);
        }
        if is_async && dlen > self.max_async_dlen {
            let detail = format!(
                "async DLEN {dlen} is above the bound {}",
                self.max_async_dlen
            );
            return self.decided(ErrorKind::Oversize, header, detail, None);
        }
        let total = header + dlen;
        if live.len() < total {
            return Head::NeedMore(total - live.len());
        }
        let data = live[header..total - 1].to_vec();
        let packet = match (self.source, sop2) {
            (Source::Host, _) => Packet::Command(CommandPacket {
                sop2,
                did: live[2],
                cid: live[3],
                seq: live[4],
                data,
            }),
            (Source::Droid, SOP2_RESPONSE) => Packet::Response(Response {
                mrsp: Mrsp::from_byte(live[2]),
                seq: live[3],
                data,
            }),
            _ => Packet::Async(AsyncPacket {
                id_code: live[2],
                data,
            }),
        };
        let expected = checksum(&live[2..total - 1]);
        let got = live[total - 1];
        if expected != got {
            let detail = format!("checksum 0x{got:02X}, expected 0x{expected:02X}");
            return self.decided(ErrorKind::BadChecksum, total, detail, Some(packet));
        }
        let at = self.live_start();
        self.head += total;
        if self.head == self.buf.len() {
            self.buf.clear();
            self.head = 0;
        }
        self.stats.packets += 1;
        Head::Event(Ok(packet), at)
    }

    fn decided(
        &mut self,
        kind: ErrorKind,
        extent: usize,
        detail: String,
        packet: Option<Packet>,
    ) -> Head {
        match self.reject(kind, extent, detail, packet) {
            Some(e) => {
                let at = e.offset;
                Head::Event(Err(e), at)
            }
            None => Head::Again,
        }
    }

    /// Take bytes from `input` into the decoder; returns how many were used. Garbage before a
    /// candidate is accounted for without being buffered; a candidate is buffered only up to
    /// what it needs next, which keeps the buffer within `max_packet_len`.
    fn take_input(&mut self, input: &[u8]) -> usize {
        if self.buffered() == 0 {
            let n = input.iter().position(|&b| b == SOP1).unwrap_or(input.len());
            if n > 0 {
                let at = self.fed;
                self.fed += n as u64;
                self.stats.bytes += n as u64;
                self.account_skipped(at, n as u64);
                return n;
            }
        }
        if self.head > 0 {
            self.buf.drain(..self.head);
            self.head = 0;
        }
        let n = self.need.max(1).min(input.len());
        self.buf.extend_from_slice(&input[..n]);
        self.fed += n as u64;
        self.stats.bytes += n as u64;
        n
    }
}

/// Iterator returned by [`Decoder::feed`].
pub struct Feed<'a> {
    decoder: &'a mut Decoder,
    bytes: &'a [u8],
    pos: usize,
}

impl Feed<'_> {
    /// The stream offset of the last packet this iterator returned.
    pub fn packet_offset(&self) -> u64 {
        self.decoder.packet_at
    }
}

impl Iterator for Feed<'_> {
    type Item = Event;

    fn next(&mut self) -> Option<Event> {
        loop {
            if let Some(e) = self.decoder.next_event() {
                return Some(e);
            }
            if self.pos >= self.bytes.len() {
                return None;
            }
            self.pos += self.decoder.take_input(&self.bytes[self.pos..]);
        }
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

    fn h(s: &str) -> Vec<u8> {
        hex::parse(s).unwrap()
    }

    fn kinds(events: &[Event]) -> Vec<Result<super::super::packet::Kind, ErrorKind>> {
        events
            .iter()
            .map(|e| match e {
                Ok(p) => Ok(p.kind()),
                Err(e) => Err(e.kind),
            })
            .collect()
    }

    #[test]
    fn decodes_golden_commands_byte_at_a_time() {
        let bytes = h("FF FF 00 01 52 01 AB FF FF 02 30 00 05 80 00 5A 01 ED");
        let mut d = Decoder::new(Source::Host);
        let mut got = Vec::new();
        for b in &bytes {
            got.extend(d.feed(std::slice::from_ref(b)));
        }
        assert_eq!(got.len(), 2);
        let Ok(Packet::Command(c)) = &got[1] else {
            panic!("{got:?}")
        };
        assert_eq!((c.did, c.cid, c.seq), (0x02, 0x30, 0));
        assert_eq!(c.data, vec![0x80, 0x00, 0x5A, 0x01]);
        assert_eq!(d.stats().packets, 2);
    }

    #[test]
    fn response_and_async_from_the_droid() {
        let bytes = h("FF FF 00 52 01 AC FF FE 01 00 02 02 FA");
        let mut d = Decoder::new(Source::Droid);
        let out = d.decode_all(&bytes);
        assert_eq!(
            kinds(&out),
            vec![
                Ok(super::super::packet::Kind::Response),
                Ok(super::super::packet::Kind::Async)
            ]
        );
    }

    #[test]
    fn sides_do_not_mix() {
        // A command's SOP2 FE is "no answer" from the host; from the droid it is async.
        let mut d = Decoder::new(Source::Droid);
        assert!(
            d.decode_all(&h("FF FC 00 01 52 01 AB"))
                .iter()
                .all(|e| e.is_err())
        );
    }

    #[test]
    fn bad_checksum_then_valid_packet() {
        let bytes = h("FF FF 00 01 52 01 AA FF FF 00 01 52 01 AB");
        let mut d = Decoder::new(Source::Host);
        let out = d.decode_all(&bytes);
        assert_eq!(
            kinds(&out),
            vec![
                Err(ErrorKind::BadChecksum),
                Ok(super::super::packet::Kind::Command)
            ]
        );
        let Err(e) = &out[0] else { panic!() };
        assert_eq!(e.offset, 0);
        assert!(e.packet.is_some());
        assert_eq!(d.stats().skipped_bytes, 7);
    }

    #[test]
    fn garbage_is_reported_once_per_run() {
        let mut d = Decoder::new(Source::Host);
        let out = d.decode_all(&h("01 02 FF 03 FF FF 00 01 52 01 AB 09"));
        assert_eq!(
            kinds(&out),
            vec![
                Err(ErrorKind::Garbage),
                Ok(super::super::packet::Kind::Command)
            ]
        );
        let Err(e) = &out[0] else { panic!() };
        assert_eq!(
            (e.offset, e.detail.as_str()),
            (0, "4 byte(s) outside any packet")
        );
        let tail = d.finish();
        assert_eq!(tail.len(), 1);
        assert!(matches!(&tail[0], Err(e) if e.kind == ErrorKind::Garbage && e.offset == 11));
    }

    #[test]
    fn dlen_zero_and_oversize() {
        let mut d = Decoder::with_max_async_dlen(Source::Droid, 16);
        let out = d.decode_all(&h("FF FF 00 00 00 FF FE 03 00 20"));
        assert_eq!(
            kinds(&out),
            vec![Err(ErrorKind::BadLength), Err(ErrorKind::Oversize)]
        );
    }

    #[test]
    fn truncated_tail_is_reported_and_searched() {
        // A bogus async candidate swallowing a complete ping response, then the stream ends.
        let mut d = Decoder::new(Source::Droid);
        let out = d.decode_all(&h("FF FE 07 00 40 FF FF 00 52 01 AC"));
        assert!(out.is_empty());
        let tail = d.finish();
        assert_eq!(
            kinds(&tail),
            vec![
                Err(ErrorKind::Truncated),
                Ok(super::super::packet::Kind::Response)
            ]
        );
        assert_eq!(d.buffered(), 0);
        assert_eq!(d.stats().skipped_bytes, 5);
    }

    #[test]
    fn buffer_is_bounded() {
        let mut d = Decoder::with_max_async_dlen(Source::Droid, 40);
        let mut bytes = h("FF FE 03 00 28");
        bytes.extend(std::iter::repeat_n(0x11, 5000));
        for chunk in bytes.chunks(33) {
            for _ in d.feed(chunk) {}
            assert!(d.buffered() <= d.max_packet_len());
        }
    }

    #[test]
    fn dropping_feed_consumes_input() {
        let mut d = Decoder::new(Source::Host);
        let bytes = h("FF FF 00 01 52 01 AB FF FF 00 01 52 01 AB");
        assert!(d.feed(&bytes).next().is_some());
        assert_eq!(d.stats().packets, 2);
    }
}
