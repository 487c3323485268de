//! Framing RSRCP out of a byte stream (a capture, a TCP relay), where notification boundaries
//! are lost.
//!
//! RSRCP has no length field, escaping or checksum, and `7E`/`7F` occur inside frames
//! (`droid-facts.md` §5). So a `7E` is only a *candidate* SOP: the framer reads the EFS,
//! computes the length it implies and requires `7F` exactly there. A rejected candidate costs
//! one byte: the hunt resumes one byte after its SOP, so a real frame that started inside the
//! rejected bytes is still found.
//!
//! **Handshake or frame?** A candidate whose fifth byte (index 4) is `7F` is a handshake:
//! `7E version MSDT 7F`. In a frame that byte is the EFS high byte, and `0x7F` there enables
//! the gyroscope, which has no defined size, so such a frame could never be framed anyway:
//! the rule loses nothing and needs no look-ahead. Any version byte is accepted (the spec
//! defines only 1; see [`super::Handshake::version_name`]).
//!
//! **Errors** are reported once: a rejected candidate gives one error at its SOP's offset,
//! and the bytes it claimed (up to where it was rejected) are skipped silently while hunting.
//! Other skipped bytes are reported as one `garbage` error per run, when the run ends.
//! Every byte fed ends up in exactly one accepted item or in `skipped_bytes`, once
//! [`Framer::finish`] has run.
//!
//! **Bounded**: at most [`MAX_FRAME_LEN`] bytes are buffered, the longest a candidate can need
//! before it is accepted or rejected. Results do not depend on how the input is chunked: the
//! framer works byte by byte and only [`Framer::finish`] treats "no more input" specially.

use super::Item;
use super::efs::Efs;
use super::error::{DecodeStats, ErrorKind, FrameError, frame_error};
use super::frame::{
    EOP, HANDSHAKE_LEN, HEADER_LEN, Layout, MAX_FRAME_LEN, SOP, decode_frame, decode_handshake,
    layout,
};
use std::collections::VecDeque;

/// What to do with the candidate at the head of the buffer.
enum Verdict {
    NeedMore,
    Accept(Item, usize),
    /// Reject it; the error, and how many bytes it claimed (silently skipped afterwards).
    Reject(FrameError, usize),
}

/// The streaming framer. Feed it with [`Framer::feed`], end with [`Framer::finish`].
#[derive(Debug, Clone, Default)]
pub struct Framer {
    /// The candidate: empty, or starting with SOP. Never longer than [`MAX_FRAME_LEN`].
    buf: Vec<u8>,
    /// Stream offset of `buf[0]`.
    buf_start: u64,
    /// Stream offset of the next byte fed.
    offset: u64,
    /// Bytes before this offset belong to an already reported rejection.
    covered_until: u64,
    garbage_start: Option<u64>,
    garbage_len: u64,
    /// Events completed by the last byte, not yet handed out, with the stream offset where
    /// each starts.
    pending: VecDeque<(u64, Result<Item, FrameError>)>,
    /// The stream offset of the last event handed out.
    event_at: u64,
    stats: DecodeStats,
}

impl Framer {
    pub fn new() -> Self {
        Framer {
            buf: Vec::with_capacity(MAX_FRAME_LEN),
            ..Framer::default()
        }
    }

    pub fn stats(&self) -> &DecodeStats {
        &self.stats
    }

    /// Bytes held for an undecided candidate (never more than [`MAX_FRAME_LEN`]).
    pub fn buffered(&self) -> usize {
        self.buf.len()
    }

    /// Frame `bytes`, yielding every item and error they complete. Dropping the iterator
    /// early still consumes all of `bytes` (the events are then lost); state carries over to
    /// the next call.
    pub fn feed<'a>(&'a mut self, bytes: &'a [u8]) -> Feed<'a> {
        Feed {
            framer: self,
            bytes,
            pos: 0,
        }
    }

    /// Convenience for tests and tools: frame a whole slice into a vector (without
    /// [`Framer::finish`]).
    pub fn decode_all(&mut self, bytes: &[u8]) -> Vec<Result<Item, FrameError>> {
        self.feed(bytes).collect()
    }

    /// The stream has ended: an undecided candidate is `truncated` (and the hunt resumes one
    /// byte after it, so a handshake or frame that is complete inside it is still found); a
    /// pending garbage run is reported. The framer can be fed again afterwards.
    pub fn finish(&mut self) -> Vec<Result<Item, FrameError>> {
        self.finish_with_offsets()
            .into_iter()
            .map(|(_, e)| e)
            .collect()
    }

    /// [`Framer::finish`], each event with the stream offset where it starts.
    pub fn finish_with_offsets(&mut self) -> Vec<(u64, Result<Item, FrameError>)> {
        self.process(true);
        self.flush_garbage();
        self.pending.drain(..).collect()
    }

    fn push(&mut self, b: u8) {
        let at = self.offset;
        self.offset += 1;
        self.stats.bytes += 1;
        if self.buf.is_empty() {
            if b != SOP {
                self.skip(at);
                return;
            }
            self.flush_garbage();
            self.buf_start = at;
        }
        self.buf.push(b);
        self.process(false);
    }

    /// Decide candidates at the head of the buffer until one needs more bytes.
    fn process(&mut self, eof: bool) {
        while !self.buf.is_empty() {
            match self.verdict(eof) {
                Verdict::NeedMore => return,
                Verdict::Accept(item, len) => {
                    self.stats.packets += 1;
                    self.pending.push_back((self.buf_start, Ok(item)));
                    self.consume(len);
                }
                Verdict::Reject(mut e, span) => {
                    e.offset = self.buf_start;
                    self.stats.count_error(e.kind);
                    self.pending.push_back((self.buf_start, Err(e)));
                    self.covered_until = self.covered_until.max(self.buf_start + span as u64);
                    self.stats.skipped_bytes += 1;
                    self.consume(1);
                }
            }
            self.rehunt();
        }
    }

    fn consume(&mut self, n: usize) {
        let n = n.min(self.buf.len());
        self.buf.drain(..n);
        self.buf_start += n as u64;
    }

    /// Drop buffered bytes up to the next SOP.
    fn rehunt(&mut self) {
        let n = self
            .buf
            .iter()
            .position(|&b| b == SOP)
            .unwrap_or(self.buf.len());
        for i in 0..n {
            self.skip(self.buf_start + i as u64);
        }
        self.consume(n);
        if !self.buf.is_empty() {
            self.flush_garbage();
        }
    }

    /// A byte outside any candidate: silent if an earlier rejection claimed it, else garbage.
    fn skip(&mut self, at: u64) {
        self.stats.skipped_bytes += 1;
        if at < self.covered_until {
            return;
        }
        if self.garbage_start.is_none() {
            self.garbage_start = Some(at);
        }
        self.garbage_len += 1;
    }

    fn flush_garbage(&mut self) {
        let Some(start) = self.garbage_start.take() else {
            return;
        };
        let len = std::mem::take(&mut self.garbage_len);
        let e = FrameError::new(
            ErrorKind::Garbage,
            start,
            format!("{len} byte(s) outside any frame"),
        );
        self.stats.count_error(e.kind);
        self.pending.push_back((start, Err(e)));
    }

    fn verdict(&self, eof: bool) -> Verdict {
        let buf = &self.buf[..];
        let have = buf.len();
        let short = |needed: usize, what: &str| {
            if eof {
                Verdict::Reject(
                    frame_error(
                        ErrorKind::Truncated,
                        have,
                        format!("stream ended {have} byte(s) into a {what} of {needed}"),
                    ),
                    have,
                )
            } else {
                Verdict::NeedMore
            }
        };
        if have < HANDSHAKE_LEN {
            return short(HANDSHAKE_LEN, "frame or handshake");
        }
        if buf[HANDSHAKE_LEN - 1] == EOP {
            // Byte 4 is 7F: a handshake (see the module docs for why this is unambiguous).
            return match decode_handshake(&buf[..HANDSHAKE_LEN]) {
                Ok(h) => Verdict::Accept(Item::Handshake(h), HANDSHAKE_LEN),
                Err(e) => Verdict::Reject(e, HANDSHAKE_LEN),
            };
        }
        if have < HEADER_LEN {
            return short(HEADER_LEN, "frame header");
        }
        let efs = Efs::from_bits_retain(u16::from_be_bytes([buf[4], buf[5]]));
        let needed = match layout(efs) {
            Layout::Sized(total) => total,
            Layout::Unframable { prefix, .. } => prefix,
        };
        if have < needed {
            return short(needed, "frame");
        }
        match decode_frame(&buf[..needed]) {
            Ok(f) => Verdict::Accept(Item::Frame(f), needed),
            Err(e) => Verdict::Reject(e, needed),
        }
    }
}

/// Iterator returned by [`Framer::feed`].
pub struct Feed<'a> {
    framer: &'a mut Framer,
    bytes: &'a [u8],
    pos: usize,
}

impl Feed<'_> {
    /// The stream offset where the last event handed out starts.
    pub fn event_offset(&self) -> u64 {
        self.framer.event_at
    }
}

impl Iterator for Feed<'_> {
    type Item = Result<Item, FrameError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if let Some((at, event)) = self.framer.pending.pop_front() {
                self.framer.event_at = at;
                return Some(event);
            }
            let &b = self.bytes.get(self.pos)?;
            self.pos += 1;
            self.framer.push(b);
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

    fn kinds(events: &[Result<Item, FrameError>]) -> Vec<Result<&'static str, &'static str>> {
        events
            .iter()
            .map(|e| match e {
                Ok(Item::Handshake(_)) => Ok("handshake"),
                Ok(Item::Frame(_)) => Ok("frame"),
                Err(e) => Err(e.kind.name()),
            })
            .collect()
    }

    #[test]
    fn handshake_then_frame() {
        let mut f = Framer::new();
        let bytes = hex::parse("7E 01 00 0A 7F 7E 00 00 01 02 00 80 7F").unwrap();
        let out = f.decode_all(&bytes);
        assert_eq!(kinds(&out), vec![Ok("handshake"), Ok("frame")]);
        assert_eq!(f.buffered(), 0);
        assert_eq!(f.stats().skipped_bytes, 0);
    }

    #[test]
    fn bad_eop_resumes_one_byte_after_sop() {
        // The false candidate at 0 (EFS 0x0000, so 7 bytes) claims the real frame's SOP at 3.
        let mut f = Framer::new();
        let bytes = hex::parse("7E 02 00 7E 00 00 05 02 00 2A 7F").unwrap();
        let out = f.decode_all(&bytes);
        assert_eq!(kinds(&out), vec![Err("bad_eop"), Ok("frame")]);
        let Err(e) = &out[0] else { panic!() };
        assert_eq!(e.offset, 0);
        let Ok(Item::Frame(fr)) = &out[1] else {
            panic!()
        };
        assert_eq!((fr.frame_id, fr.poti), (5, Some(0x2A)));
        assert_eq!(f.stats().skipped_bytes, 3);
        assert_eq!(f.stats().errors(ErrorKind::Garbage), 0);
    }

    #[test]
    fn finish_truncates_and_rehunts() {
        let mut f = Framer::new();
        // Candidate wants 13 bytes (EFS 0x4300); a complete handshake sits inside its tail.
        let bytes = hex::parse("7E 00 00 01 43 00 7E 01 00 0A 7F").unwrap();
        assert!(f.decode_all(&bytes).is_empty());
        let tail = f.finish();
        assert_eq!(kinds(&tail), vec![Err("truncated"), Ok("handshake")]);
        assert_eq!(f.stats().skipped_bytes, 6);
        assert_eq!(f.buffered(), 0);
    }
}
