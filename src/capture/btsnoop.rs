//! The btsnoop file format (RFC 1761's snoop, as Android's `btsnoop_hci.log` and BlueZ's
//! `btmon -w` write it), sans-IO: bytes in, in any pieces; the header and records out.
//!
//! Layout, all integers big-endian:
//! - header, 16 bytes: the magic `btsnoop\0`, version (1), datalink (1001 HCI UART H1: no
//!   packet type byte, the flags say; 1002 HCI UART H4: a packet type byte first; 2001 the
//!   Linux monitor format: the flags carry the opcode);
//! - records: original length, included length, flags (bit 0: 0 sent / 1 received; bit 1:
//!   0 data / 1 command or event), cumulative drops (all u32), timestamp (i64 microseconds
//!   since midnight, January 1st, 0 AD, with 1970-01-01 at `0x00DCDDB30F2F8000`), then the
//!   included bytes.
//!
//! A damaged file (wrong magic, a record cut short, impossible lengths) is reported with the
//! offset of the problem; the records before it are good. Nothing after an impossible length
//! can be trusted (records have no sync marker), so reading stops there. The reader never
//! buffers more than one record.

use std::fmt;

pub const MAGIC: &[u8; 8] = b"btsnoop\0";
pub const HEADER_LEN: usize = 16;
pub const RECORD_HEADER_LEN: usize = 24;
/// The timestamp of 1970-01-01T00:00:00Z.
pub const UNIX_EPOCH_US: i64 = 0x00DC_DDB3_0F2F_8000;
/// The largest record droidctl accepts: an HCI ACL packet is at most 4 + 65535 bytes, the
/// monitor format adds little. Anything longer is damage.
pub const MAX_RECORD: u32 = 1 << 20;

/// Whether `bytes` start with the btsnoop magic.
pub fn sniff(bytes: &[u8]) -> bool {
    bytes.starts_with(MAGIC)
}

/// How the records' bytes are framed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Datalink {
    /// HCI UART (H1): no packet type byte; the flags say command/event or data.
    H1,
    /// HCI UART (H4): a packet type byte first.
    H4,
    /// The Linux monitor format (BlueZ): the flags hold the adapter index and an opcode.
    Monitor,
}

impl Datalink {
    pub fn from_code(code: u32) -> Option<Datalink> {
        match code {
            1001 => Some(Datalink::H1),
            1002 => Some(Datalink::H4),
            2001 => Some(Datalink::Monitor),
            _ => None,
        }
    }

    pub fn code(self) -> u32 {
        match self {
            Datalink::H1 => 1001,
            Datalink::H4 => 1002,
            Datalink::Monitor => 2001,
        }
    }
}

/// The file header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Header {
    pub version: u32,
    pub datalink: Datalink,
}

/// One record.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Record {
    /// Where the record starts in the file.
    pub offset: u64,
    pub original_len: u32,
    pub flags: u32,
    pub drops: u32,
    /// Microseconds since 0 AD (see [`UNIX_EPOCH_US`]).
    pub timestamp_us: i64,
    pub data: Vec<u8>,
}

impl Record {
    /// Bit 0 of the flags: received (controller → host) rather than sent.
    pub fn received(&self) -> bool {
        self.flags & 1 != 0
    }

    /// Bit 1 of the flags: a command or event rather than data.
    pub fn command_or_event(&self) -> bool {
        self.flags & 2 != 0
    }

    /// Microseconds since 1970 (negative before).
    pub fn unix_us(&self) -> i64 {
        self.timestamp_us.saturating_sub(UNIX_EPOCH_US)
    }
}

/// What is wrong with a file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The file does not start with `btsnoop\0`.
    BadMagic,
    /// A version other than 1.
    BadVersion,
    /// A datalink droidctl does not read.
    UnknownDatalink,
    /// The file ends inside the header or a record.
    Truncated,
    /// A record's lengths cannot be: included longer than original, or beyond any HCI
    /// packet.
    ImpossibleLength,
}

impl ErrorKind {
    pub fn name(self) -> &'static str {
        match self {
            ErrorKind::BadMagic => "bad_magic",
            ErrorKind::BadVersion => "bad_version",
            ErrorKind::UnknownDatalink => "unknown_datalink",
            ErrorKind::Truncated => "truncated",
            ErrorKind::ImpossibleLength => "impossible_length",
        }
    }
}

/// A damaged file, and where.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Error {
    pub kind: ErrorKind,
    /// File offset of the header or record at fault.
    pub offset: u64,
    pub detail: String,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} at offset {}: {}",
            self.kind.name(),
            self.offset,
            self.detail
        )
    }
}

impl std::error::Error for Error {}

/// What the reader found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Item {
    Header(Header),
    Record(Record),
}

/// The push parser: [`Reader::feed`] bytes as they come, take items with [`Reader::next_item`]
/// until it returns `None`, and call [`Reader::finish`] at the end of the input.
#[derive(Debug, Default)]
pub struct Reader {
    /// Bytes fed and not yet read are `buf[head..]`: items are taken by moving `head`, and the
    /// read part is dropped only once it is most of the buffer, so a whole file fed at once
    /// is read in linear time (draining each record from the front was quadratic).
    buf: Vec<u8>,
    head: usize,
    /// Bytes moved to the front of `buf` so far (what reading costs beyond the bytes
    /// themselves; linear in the input).
    moved: u64,
    /// File offset of `buf[head]`.
    at: u64,
    header: Option<Header>,
    /// After an error nothing more is read.
    failed: bool,
    records: u64,
}

fn be32(b: &[u8]) -> u32 {
    u32::from_be_bytes([b[0], b[1], b[2], b[3]])
}

impl Reader {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn header(&self) -> Option<Header> {
        self.header
    }

    /// Records read so far.
    pub fn records(&self) -> u64 {
        self.records
    }

    /// File offset just past the last item read.
    pub fn offset(&self) -> u64 {
        self.at
    }

    pub fn feed(&mut self, bytes: &[u8]) {
        if !self.failed {
            self.buf.extend_from_slice(bytes);
        }
    }

    fn fail(&mut self, kind: ErrorKind, offset: u64, detail: String) -> Error {
        self.failed = true;
        self.buf = Vec::new();
        self.head = 0;
        Error {
            kind,
            offset,
            detail,
        }
    }

    /// The bytes fed and not yet read.
    fn live(&self) -> &[u8] {
        &self.buf[self.head..]
    }

    fn consume(&mut self, n: usize) {
        self.head += n;
        self.at += n as u64;
        if self.head == self.buf.len() {
            self.buf.clear();
            self.head = 0;
        } else if self.head >= 64 * 1024 && self.head * 2 >= self.buf.len() {
            self.moved += (self.buf.len() - self.head) as u64;
            self.buf.drain(..self.head);
            self.head = 0;
        }
    }

    /// Bytes moved within the buffer so far: at most about the input's size however it is
    /// fed (a whole file at once, or block by block).
    pub fn bytes_moved(&self) -> u64 {
        self.moved
    }

    /// The next header or record, an error, or `None` when more bytes are needed.
    pub fn next_item(&mut self) -> Option<Result<Item, Error>> {
        if self.failed {
            return None;
        }
        let Some(header) = self.header else {
            // The magic can be judged before the whole header is in.
            let n = self.live().len().min(MAGIC.len());
            if self.live()[..n] != MAGIC[..n] {
                let shown = crate::hex::spaced(&self.live()[..n]);
                return Some(Err(self.fail(
                    ErrorKind::BadMagic,
                    0,
                    format!("not a btsnoop file: it starts {shown}, not \"btsnoop\\0\""),
                )));
            }
            if self.live().len() < HEADER_LEN {
                return None;
            }
            let version = be32(&self.live()[8..12]);
            let code = be32(&self.live()[12..16]);
            if version != 1 {
                return Some(Err(self.fail(
                    ErrorKind::BadVersion,
                    8,
                    format!("btsnoop version {version}; only version 1 exists"),
                )));
            }
            let Some(datalink) = Datalink::from_code(code) else {
                return Some(Err(self.fail(
                    ErrorKind::UnknownDatalink,
                    12,
                    format!(
                        "datalink {code}; droidctl reads 1001 (HCI H1), 1002 (HCI H4) and 2001 (Linux monitor)"
                    ),
                )));
            };
            let h = Header { version, datalink };
            self.header = Some(h);
            self.consume(HEADER_LEN);
            return Some(Ok(Item::Header(h)));
        };
        let _ = header;
        if self.live().len() < RECORD_HEADER_LEN {
            return None;
        }
        let b = self.live();
        let original_len = be32(&b[0..4]);
        let included = be32(&b[4..8]);
        let flags = be32(&b[8..12]);
        let drops = be32(&b[12..16]);
        let timestamp_us =
            i64::from_be_bytes([b[16], b[17], b[18], b[19], b[20], b[21], b[22], b[23]]);
        if included > original_len || included > MAX_RECORD {
            let at = self.at;
            return Some(Err(self.fail(
                ErrorKind::ImpossibleLength,
                at,
                format!(
                    "record {} says {included} bytes included of {original_len} (at most {MAX_RECORD}, and never more than the original)",
                    self.records + 1
                ),
            )));
        }
        let total = RECORD_HEADER_LEN + included as usize;
        if self.live().len() < total {
            return None;
        }
        let record = Record {
            offset: self.at,
            original_len,
            flags,
            drops,
            timestamp_us,
            data: self.live()[RECORD_HEADER_LEN..total].to_vec(),
        };
        self.consume(total);
        self.records += 1;
        Some(Ok(Item::Record(record)))
    }

    /// The input has ended: an error if it ended inside the header or a record.
    pub fn finish(&mut self) -> Option<Error> {
        if self.failed {
            return None;
        }
        if self.header.is_none() {
            let got = self.live().len();
            return Some(self.fail(
                ErrorKind::Truncated,
                0,
                format!("the file ends after {got} of the header's {HEADER_LEN} bytes"),
            ));
        }
        if self.live().is_empty() {
            return None;
        }
        let at = self.at;
        let got = self.live().len();
        let detail = if got < RECORD_HEADER_LEN {
            format!(
                "record {} is cut short: {got} of its {RECORD_HEADER_LEN} header bytes",
                self.records + 1
            )
        } else {
            let included = be32(&self.live()[4..8]);
            format!(
                "record {} is cut short: {} of its {included} bytes",
                self.records + 1,
                got - RECORD_HEADER_LEN
            )
        };
        Some(self.fail(ErrorKind::Truncated, at, detail))
    }
}

/// Writing btsnoop files, for tests and tools: the header, then records.
pub mod write {
    use super::*;

    pub fn header(datalink: Datalink) -> Vec<u8> {
        let mut v = MAGIC.to_vec();
        v.extend(1u32.to_be_bytes());
        v.extend(datalink.code().to_be_bytes());
        v
    }

    /// A record of `data` whole (original length = included length), no drops.
    pub fn record(flags: u32, timestamp_us: i64, data: &[u8]) -> Vec<u8> {
        let mut v = Vec::with_capacity(RECORD_HEADER_LEN + data.len());
        v.extend((data.len() as u32).to_be_bytes());
        v.extend((data.len() as u32).to_be_bytes());
        v.extend(flags.to_be_bytes());
        v.extend(0u32.to_be_bytes());
        v.extend(timestamp_us.to_be_bytes());
        v.extend_from_slice(data);
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_whole_file_fed_at_once_is_read_in_linear_time() {
        // 200,000 small records (about 6 MB): draining each record from the front of the
        // buffer moved about 600 GB; reading by index moves nothing but the tail it keeps.
        let mut log = write::header(Datalink::H4);
        for i in 0..200_000i64 {
            log.extend(write::record(0, i, &[0x02, 0x40, 0x00, 0x01, 0x00]));
        }
        for piece in [log.len(), 64 * 1024, 4096] {
            let mut r = Reader::new();
            let mut records = 0;
            for p in log.chunks(piece) {
                r.feed(p);
                while let Some(i) = r.next_item() {
                    if let Ok(Item::Record(_)) = i {
                        records += 1;
                    }
                }
            }
            assert_eq!(records, 200_000);
            assert!(r.finish().is_none());
            assert!(
                r.bytes_moved() <= log.len() as u64,
                "moved {} bytes for a {}-byte log fed in pieces of {piece}",
                r.bytes_moved(),
                log.len()
            );
        }
    }

    fn read_all(bytes: &[u8], piece: usize) -> (Vec<Item>, Option<Error>) {
        let mut r = Reader::new();
        let mut items = Vec::new();
        for p in bytes.chunks(piece.max(1)) {
            r.feed(p);
            while let Some(i) = r.next_item() {
                match i {
                    Ok(i) => items.push(i),
                    Err(e) => return (items, Some(e)),
                }
            }
        }
        (items, r.finish())
    }

    /// Checked by hand against the published layout: magic, version 1, datalink 1002, then
    /// one record of 7 bytes (an H4 ACL packet), flags 0 (sent, data), no drops, at
    /// 2020-01-01T00:00:00Z = 1,577,836,800 s after 1970.
    const FIXTURE: [u8; 47] = [
        b'b', b't', b's', b'n', b'o', b'o', b'p', 0, // magic
        0, 0, 0, 1, // version 1
        0, 0, 0x03, 0xEA, // datalink 1002
        0, 0, 0, 7, // original length
        0, 0, 0, 7, // included length
        0, 0, 0, 0, // flags: sent, data
        0, 0, 0, 0, // drops
        // 0x00DCDDB30F2F8000 + 1_577_836_800_000_000 = 0x00E2_78BB_D129_C000
        0x00, 0xE2, 0x78, 0xBB, 0xD1, 0x29, 0xC0, 0x00, // timestamp
        0x02, 0x40, 0x00, 0x02, 0x00, 0xAA, 0xBB, // H4 ACL, handle 0x040, 2 bytes
    ];

    #[test]
    fn the_hand_checked_fixture() {
        assert_eq!(
            0x00DC_DDB3_0F2F_8000i64 + 1_577_836_800_000_000,
            0x00E2_78BB_D129_C000
        );
        for piece in [1, 5, 47] {
            let (items, err) = read_all(&FIXTURE, piece);
            assert_eq!(err, None);
            assert_eq!(
                items[0],
                Item::Header(Header {
                    version: 1,
                    datalink: Datalink::H4
                })
            );
            let Item::Record(r) = &items[1] else { panic!() };
            assert_eq!(r.offset, 16);
            assert_eq!(r.data, [0x02, 0x40, 0x00, 0x02, 0x00, 0xAA, 0xBB]);
            assert!(!r.received() && !r.command_or_event());
            assert_eq!(r.unix_us(), 1_577_836_800_000_000);
            assert_eq!(
                crate::capture::rfc3339(std::time::Duration::from_micros(r.unix_us() as u64)),
                "2020-01-01T00:00:00.000Z"
            );
        }
        // The writer makes the same bytes.
        let mut w = write::header(Datalink::H4);
        w.extend(write::record(0, 0x00E2_78BB_D129_C000, &FIXTURE[40..]));
        assert_eq!(w, FIXTURE);
    }

    #[test]
    fn damage_is_reported_with_its_offset_after_the_good_records() {
        // Wrong magic.
        let (items, err) = read_all(b"btsnoip\0\0\0\0\x01\0\0\x03\xea", 3);
        assert!(items.is_empty());
        let e = err.unwrap();
        assert_eq!((e.kind, e.offset), (ErrorKind::BadMagic, 0));
        // A cut header.
        let (_, err) = read_all(&FIXTURE[..10], 4);
        assert_eq!(err.unwrap().kind, ErrorKind::Truncated);
        // Unknown datalink.
        let mut f = FIXTURE;
        f[15] = 0xEE;
        let e = read_all(&f, 47).1.unwrap();
        assert_eq!((e.kind, e.offset), (ErrorKind::UnknownDatalink, 12));
        // A second record cut short: the first one still comes out.
        let mut two = FIXTURE.to_vec();
        two.extend_from_slice(&FIXTURE[16..40]);
        let (items, err) = read_all(&two, 8);
        assert_eq!(items.len(), 2);
        let e = err.unwrap();
        assert_eq!((e.kind, e.offset), (ErrorKind::Truncated, 47));
        assert!(e.detail.contains("record 2"), "{e}");
        // Included longer than original.
        let mut bad = FIXTURE.to_vec();
        bad.extend(write::record(1, 0, &[4, 0x0E]));
        let n = bad.len();
        bad[n - 2 - 24 + 3] = 1; // original length 1 < included 2
        let (items, err) = read_all(&bad, 64);
        assert_eq!(items.len(), 2);
        let e = err.unwrap();
        assert_eq!((e.kind, e.offset), (ErrorKind::ImpossibleLength, 47));
        // An absurd length is refused before waiting for its bytes.
        let mut huge = FIXTURE.to_vec();
        huge.extend([0xFF; 8]);
        huge.extend([0; 16]);
        let e = read_all(&huge, 64).1.unwrap();
        assert_eq!(e.kind, ErrorKind::ImpossibleLength);
    }
}
