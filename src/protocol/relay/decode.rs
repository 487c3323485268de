//! The incremental decoders: requests (the server's side) and replies (a client's), from
//! bytes in any chunking, every length checked before its bytes are read.

use super::{DecodeError, Device, Field, Limits, Reply, Request, Side, rep, req};
use std::collections::VecDeque;

/// Outcome of parsing from a buffer.
enum Step<T> {
    /// Not enough bytes yet.
    More,
    /// A value, and the bytes it took.
    Done(T, usize),
    /// An error; `usize` is the bytes to skip when it is recoverable.
    Fail(DecodeError, usize),
}

/// A reader over buffered bytes; `None` means "not enough bytes yet".
struct Cur<'a> {
    b: &'a [u8],
    i: usize,
}

impl<'a> Cur<'a> {
    fn new(b: &'a [u8]) -> Self {
        Cur { b, i: 0 }
    }
    fn u8(&mut self) -> Option<u8> {
        let v = *self.b.get(self.i)?;
        self.i += 1;
        Some(v)
    }
    fn u16(&mut self) -> Option<usize> {
        let s = self.b.get(self.i..self.i + 2)?;
        self.i += 2;
        Some(u16::from_be_bytes([s[0], s[1]]) as usize)
    }
    fn f32(&mut self) -> Option<f32> {
        let s = self.b.get(self.i..self.i + 4)?;
        self.i += 4;
        Some(f32::from_be_bytes([s[0], s[1], s[2], s[3]]))
    }
    fn bytes(&mut self, n: usize) -> Option<&'a [u8]> {
        let s = self.b.get(self.i..self.i.checked_add(n)?)?;
        self.i += n;
        Some(s)
    }
}

/// Read a length prefix and check it against `max`.
macro_rules! len {
    ($cur:expr, $read:ident, $field:expr, $max:expr, $seq:expr) => {{
        let Some(n) = $cur.$read() else {
            return Step::More;
        };
        let n = n as usize;
        if n > $max {
            return Step::Fail(
                DecodeError::TooLong {
                    field: $field,
                    len: n,
                    max: $max,
                    seq: $seq,
                },
                0,
            );
        }
        n
    }};
}

macro_rules! need {
    ($e:expr) => {
        match $e {
            Some(v) => v,
            None => return Step::More,
        }
    };
}

fn text(bytes: &[u8], ascii: bool) -> Option<String> {
    if ascii && !bytes.is_ascii() {
        return None;
    }
    std::str::from_utf8(bytes).ok().map(str::to_string)
}

fn parse_request(b: &[u8], lim: &Limits) -> Step<Request> {
    let mut c = Cur::new(b);
    let op = need!(c.u8());
    match op {
        req::SCAN => {
            let timeout = need!(c.f32());
            Step::Done(Request::Scan { timeout }, c.i)
        }
        req::FIND => {
            let n = len!(c, u16, Field::Name, lim.name, None);
            let raw = need!(c.bytes(n));
            let timeout = need!(c.f32());
            match text(raw, false) {
                Some(name) => Step::Done(Request::Find { name, timeout }, c.i),
                None => Step::Fail(
                    DecodeError::BadText {
                        field: Field::Name,
                        ascii: false,
                        seq: None,
                    },
                    c.i,
                ),
            }
        }
        req::INIT | req::SET_CALLBACK | req::WRITE => {
            let seq = need!(c.u8());
            let field = if op == req::INIT {
                Field::Address
            } else {
                Field::Characteristic
            };
            let n = len!(c, u16, field, lim.text, Some(seq));
            let raw = need!(c.bytes(n));
            let data = if op == req::WRITE {
                let m = len!(c, u16, Field::Data, lim.data, Some(seq));
                Some(need!(c.bytes(m)).to_vec())
            } else {
                None
            };
            let Some(s) = text(raw, true) else {
                return Step::Fail(
                    DecodeError::BadText {
                        field,
                        ascii: true,
                        seq: Some(seq),
                    },
                    c.i,
                );
            };
            let r = match (op, data) {
                (req::INIT, _) => Request::Init { seq, address: s },
                (req::SET_CALLBACK, _) => Request::SetCallback {
                    seq,
                    characteristic: s,
                },
                (_, data) => Request::Write {
                    seq,
                    characteristic: s,
                    data: data.unwrap_or_default(),
                },
            };
            Step::Done(r, c.i)
        }
        req::END => Step::Done(Request::End, 1),
        op => Step::Fail(
            DecodeError::UnknownOpcode {
                side: Side::Request,
                op,
            },
            0,
        ),
    }
}

/// Buffered input shared by both decoders: bytes are appended, parsed from `start`, and the
/// consumed prefix is dropped once it is large.
#[derive(Debug, Default)]
struct Buf {
    b: Vec<u8>,
    start: usize,
}

impl Buf {
    fn push(&mut self, bytes: &[u8]) {
        if self.start > 0 && self.start >= self.b.len() / 2 {
            self.b.drain(..self.start);
            self.start = 0;
        }
        self.b.extend_from_slice(bytes);
    }
    fn pending(&self) -> &[u8] {
        &self.b[self.start..]
    }
    fn consume(&mut self, n: usize) {
        self.start = (self.start + n).min(self.b.len());
        if self.start == self.b.len() {
            self.b.clear();
            self.start = 0;
        }
    }
    fn clear(&mut self) {
        self.b = Vec::new();
        self.start = 0;
    }
}

/// Requests from bytes in any chunking (the server's side).
///
/// Memory: at most one incomplete request (bounded by the [`Limits`]) plus the last chunk
/// pushed. After an error that is not [`DecodeError::recoverable`] the decoder yields nothing
/// more: the connection should be closed.
#[derive(Debug)]
pub struct RequestDecoder {
    buf: Buf,
    limits: Limits,
    failed: bool,
}

impl RequestDecoder {
    pub fn new(limits: Limits) -> Self {
        RequestDecoder {
            buf: Buf::default(),
            limits,
            failed: false,
        }
    }

    pub fn push(&mut self, bytes: &[u8]) {
        if !self.failed {
            self.buf.push(bytes);
        }
    }

    /// The next whole request, or an error; `None` until more bytes arrive.
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> Option<Result<Request, DecodeError>> {
        if self.failed {
            return None;
        }
        match parse_request(self.buf.pending(), &self.limits) {
            Step::More => None,
            Step::Done(r, n) => {
                self.buf.consume(n);
                Some(Ok(r))
            }
            Step::Fail(e, n) => {
                if e.recoverable() {
                    self.buf.consume(n);
                } else {
                    self.failed = true;
                    self.buf.clear();
                }
                Some(Err(e))
            }
        }
    }

    /// Bytes of an incomplete request.
    pub fn buffered(&self) -> usize {
        self.buf.pending().len()
    }

    /// At the end of the stream: an error when it stopped inside a request.
    pub fn finish(&self) -> Option<DecodeError> {
        let have = self.buffered();
        (have > 0 && !self.failed).then_some(DecodeError::Truncated {
            what: "request",
            have,
        })
    }
}

/// What an OK or ERROR reply answers, and so how it is laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Expect {
    /// INIT, SET_CALLBACK or WRITE: OK and ERROR end with the seq.
    Seq,
    /// SCAN: OK carries a device list, ERROR no seq.
    Scan,
    /// FIND: OK carries one device, ERROR no seq.
    Find,
}

/// A SCAN answer being read device by device, so a long list is parsed once.
#[derive(Debug)]
struct PartialList {
    remaining: usize,
    devices: Vec<Device>,
}

/// Replies from bytes in any chunking (the client's side). Tell it what each request sent
/// expects with [`ReplyDecoder::expect`], in the order they were sent.
#[derive(Debug)]
pub struct ReplyDecoder {
    buf: Buf,
    limits: Limits,
    expect: VecDeque<Expect>,
    list: Option<PartialList>,
    failed: bool,
}

/// Bound of the queue of expected answers: a client waits for its replies.
const MAX_EXPECTED: usize = 1024;

impl ReplyDecoder {
    pub fn new(limits: Limits) -> Self {
        ReplyDecoder {
            buf: Buf::default(),
            limits,
            expect: VecDeque::new(),
            list: None,
            failed: false,
        }
    }

    /// A request was sent; its OK or ERROR comes after those of the requests sent before.
    /// Requests without a layout of their own need not be announced: an unannounced OK or
    /// ERROR is read as [`Expect::Seq`].
    pub fn expect(&mut self, e: Expect) {
        if self.expect.len() < MAX_EXPECTED {
            self.expect.push_back(e);
        }
    }

    pub fn push(&mut self, bytes: &[u8]) {
        if !self.failed {
            self.buf.push(bytes);
        }
    }

    fn front(&self) -> Expect {
        self.expect.front().copied().unwrap_or(Expect::Seq)
    }

    /// The next whole reply, or an error; `None` until more bytes arrive.
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> Option<Result<Reply, DecodeError>> {
        if self.failed {
            return None;
        }
        loop {
            if let Some(list) = &mut self.list {
                // Inside a SCAN answer: one device at a time.
                if list.remaining == 0 {
                    let devices = std::mem::take(&mut list.devices);
                    self.list = None;
                    self.expect.pop_front();
                    return Some(Ok(Reply::Devices(devices)));
                }
                match parse_device(self.buf.pending(), &self.limits) {
                    Step::More => return None,
                    Step::Done(d, n) => {
                        self.buf.consume(n);
                        list.remaining -= 1;
                        list.devices.push(d);
                        continue;
                    }
                    Step::Fail(e, _) => return Some(Err(self.fail(e))),
                }
            }
            let front = self.front();
            return match parse_reply(self.buf.pending(), &self.limits, front) {
                Step::More => None,
                Step::Done(Parsed::ListStart(count), n) => {
                    self.buf.consume(n);
                    self.list = Some(PartialList {
                        remaining: count,
                        devices: Vec::with_capacity(count.min(16)),
                    });
                    continue;
                }
                Step::Done(Parsed::Reply(r), n) => {
                    self.buf.consume(n);
                    if !matches!(r, Reply::Data { .. }) {
                        self.expect.pop_front();
                    }
                    Some(Ok(r))
                }
                Step::Fail(e, n) => {
                    if e.recoverable() {
                        self.buf.consume(n);
                        // A whole OK or ERROR with bad text still answered its request.
                        if !matches!(
                            e,
                            DecodeError::BadText {
                                field: Field::Characteristic,
                                ..
                            }
                        ) {
                            self.expect.pop_front();
                        }
                        Some(Err(e))
                    } else {
                        Some(Err(self.fail(e)))
                    }
                }
            };
        }
    }

    fn fail(&mut self, e: DecodeError) -> DecodeError {
        self.failed = true;
        self.buf.clear();
        self.list = None;
        e
    }

    /// At the end of the stream: what was cut off. When the server closed the connection
    /// right after an ERROR's message (a server-wide failure has no seq to give), the message
    /// is returned so it can be shown.
    pub fn finish(&self) -> Option<Result<String, DecodeError>> {
        let b = self.buf.pending();
        if self.failed || (b.is_empty() && self.list.is_none()) {
            return None;
        }
        if b.first() == Some(&rep::ERROR) && b.len() >= 3 {
            let n = u16::from_be_bytes([b[1], b[2]]) as usize;
            if b.len() >= 3 + n && n <= self.limits.message {
                return Some(Ok(String::from_utf8_lossy(&b[3..3 + n]).into_owned()));
            }
        }
        Some(Err(DecodeError::Truncated {
            what: "reply",
            have: b.len(),
        }))
    }
}

enum Parsed {
    Reply(Reply),
    ListStart(usize),
}

fn parse_device(b: &[u8], lim: &Limits) -> Step<Device> {
    let mut c = Cur::new(b);
    let n = len!(c, u16, Field::Name, lim.name, None);
    let name = need!(c.bytes(n));
    let m = len!(c, u16, Field::Address, lim.text, None);
    let address = need!(c.bytes(m));
    let Some(name) = text(name, false) else {
        return Step::Fail(
            DecodeError::BadText {
                field: Field::Name,
                ascii: false,
                seq: None,
            },
            c.i,
        );
    };
    let Some(address) = text(address, true) else {
        return Step::Fail(
            DecodeError::BadText {
                field: Field::Address,
                ascii: true,
                seq: None,
            },
            c.i,
        );
    };
    Step::Done(Device { name, address }, c.i)
}

fn parse_reply(b: &[u8], lim: &Limits, expect: Expect) -> Step<Parsed> {
    let mut c = Cur::new(b);
    let op = need!(c.u8());
    match (op, expect) {
        (rep::OK, Expect::Seq) => {
            let seq = need!(c.u8());
            Step::Done(Parsed::Reply(Reply::Ok { seq }), c.i)
        }
        (rep::OK, Expect::Scan) => {
            let count = len!(c, u16, Field::Devices, lim.devices, None);
            Step::Done(Parsed::ListStart(count), c.i)
        }
        (rep::OK, Expect::Find) => match parse_device(&b[1..], lim) {
            Step::More => Step::More,
            Step::Done(d, n) => Step::Done(Parsed::Reply(Reply::Found(d)), n + 1),
            Step::Fail(e, n) => Step::Fail(e, n + 1),
        },
        (rep::ON_DATA, _) => {
            let n = len!(c, u16, Field::Characteristic, lim.text, None);
            let raw = need!(c.bytes(n));
            let m = need!(c.u8()) as usize;
            let data = need!(c.bytes(m)).to_vec();
            match text(raw, true) {
                Some(characteristic) => Step::Done(
                    Parsed::Reply(Reply::Data {
                        characteristic,
                        data,
                    }),
                    c.i,
                ),
                None => Step::Fail(
                    DecodeError::BadText {
                        field: Field::Characteristic,
                        ascii: true,
                        seq: None,
                    },
                    c.i,
                ),
            }
        }
        (rep::ERROR, _) => {
            let n = len!(c, u16, Field::Message, lim.message, None);
            let raw = need!(c.bytes(n));
            let seq = match expect {
                Expect::Seq => Some(need!(c.u8())),
                _ => None,
            };
            match text(raw, false) {
                Some(message) => Step::Done(Parsed::Reply(Reply::Error { message, seq }), c.i),
                None => Step::Fail(
                    DecodeError::BadText {
                        field: Field::Message,
                        ascii: false,
                        seq,
                    },
                    c.i,
                ),
            }
        }
        (op, _) => Step::Fail(
            DecodeError::UnknownOpcode {
                side: Side::Reply,
                op,
            },
            0,
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode_all(bytes: &[u8]) -> Vec<Result<Request, DecodeError>> {
        let mut d = RequestDecoder::new(Limits::default());
        d.push(bytes);
        std::iter::from_fn(|| d.next()).collect()
    }

    #[test]
    fn spherov2_request_bytes() {
        // What tcp_adapter.py sends: INIT with seq 0 and an address, SET_CALLBACK, WRITE.
        let init = Request::Init {
            seq: 0,
            address: "AA:BB".into(),
        };
        assert_eq!(init.to_bytes().unwrap(), b"\x01\x00\x00\x05AA:BB");
        let w = Request::Write {
            seq: 7,
            characteristic: "ab".into(),
            data: vec![1, 2, 3],
        };
        assert_eq!(
            w.to_bytes().unwrap(),
            b"\x03\x07\x00\x02ab\x00\x03\x01\x02\x03"
        );
        let scan = Request::Scan { timeout: 5.0 };
        assert_eq!(scan.to_bytes().unwrap(), [0x00, 0x40, 0xa0, 0, 0]);
        assert_eq!(decode_all(b"\xff"), vec![Ok(Request::End)]);
    }

    #[test]
    fn oversized_length_fails_before_the_bytes() {
        // INIT claiming a 60000-byte address: rejected after 4 bytes.
        let got = decode_all(&[0x01, 0x09, 0xea, 0x60]);
        assert!(matches!(
            got.as_slice(),
            [Err(DecodeError::TooLong {
                field: Field::Address,
                seq: Some(9),
                ..
            })]
        ));
    }

    #[test]
    fn bad_text_is_skipped() {
        let mut b = vec![0x02, 0x03, 0x00, 0x02, 0xc3, 0xa9];
        b.push(0xff);
        let got = decode_all(&b);
        assert_eq!(got.len(), 2);
        assert_eq!(got[0].as_ref().unwrap_err().seq(), Some(3));
        assert_eq!(got[1], Ok(Request::End));
    }

    #[test]
    fn replies_in_context() {
        let mut d = ReplyDecoder::new(Limits::default());
        d.expect(Expect::Seq);
        d.expect(Expect::Scan);
        d.expect(Expect::Find);
        let mut b = Vec::new();
        Reply::Data {
            characteristic: "x".into(),
            data: vec![9],
        }
        .encode(&mut b)
        .unwrap();
        Reply::Ok { seq: 4 }.encode(&mut b).unwrap();
        let devs = vec![
            Device {
                name: "D2-1A2B".into(),
                address: "AA:BB:CC:DD:EE:FF".into(),
            },
            Device {
                name: "".into(),
                address: "x".into(),
            },
        ];
        Reply::Devices(devs.clone()).encode(&mut b).unwrap();
        Reply::Error {
            message: String::new(),
            seq: None,
        }
        .encode(&mut b)
        .unwrap();
        d.push(&b);
        let got: Vec<_> = std::iter::from_fn(|| d.next()).collect();
        assert_eq!(got.len(), 4);
        assert_eq!(got[1], Ok(Reply::Ok { seq: 4 }));
        assert_eq!(got[2], Ok(Reply::Devices(devs)));
        assert_eq!(
            got[3],
            Ok(Reply::Error {
                message: String::new(),
                seq: None
            })
        );
    }

    #[test]
    fn error_without_seq_before_close_is_shown() {
        let mut d = ReplyDecoder::new(Limits::default());
        d.expect(Expect::Seq);
        d.push(&Reply::error("too many clients", None).to_bytes().unwrap());
        assert_eq!(d.next(), None);
        assert_eq!(d.finish(), Some(Ok("too many clients".to_string())));
    }
}
