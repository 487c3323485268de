//! What every streaming decoder reports besides packets: typed decode errors and counters.
//!
//! Sphero API v2, API v1 and RSRCP frame their packets differently, so their decoders fail in
//! different ways, but a failure is always a kind, a stream offset and a detail for people,
//! and every decoder counts what it saw. One type for each lets the packet log, `packet
//! decode`'s summary, captures and the fuzz targets treat the three families alike; each
//! family lists the kinds it can produce ([`crate::protocol::v2::ERROR_KINDS`] …) so a summary
//! shows exactly its own, zeros included.

use std::fmt;

/// What went wrong, without the details: every family's kinds in one enum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ErrorKind {
    /// The checksum byte does not match the body (v2, v1).
    BadChecksum,
    /// ESC followed by something other than an escapable byte (v2).
    BadEscape,
    /// A new SOP arrived before the current packet's EOP (v2).
    SopInsidePacket,
    /// A body too short for the header its flags announce (v2).
    TooShort,
    /// A length field that cannot be right: v1's DLEN 0.
    BadLength,
    /// A packet longer than the decoder's bound (v2, v1).
    Oversize,
    /// A notification that does not start with the start-of-packet byte (RSRCP).
    BadSop,
    /// The byte where the end of the frame should be is not EOP (RSRCP).
    BadEop,
    /// A notification longer than its feature set implies (RSRCP).
    Overlong,
    /// The frame enables a feature whose size the spec does not define (RSRCP): decoded up to
    /// it and no further.
    UnsizedFeature,
    /// The frame sets reserved feature bits (RSRCP): where it ends is unknown.
    ReservedBits,
    /// Bytes outside any packet.
    Garbage,
    /// The stream (or the notification) ended inside a packet.
    Truncated,
}

impl ErrorKind {
    pub const COUNT: usize = 13;

    pub const ALL: [ErrorKind; ErrorKind::COUNT] = [
        ErrorKind::BadChecksum,
        ErrorKind::BadEscape,
        ErrorKind::SopInsidePacket,
        ErrorKind::TooShort,
        ErrorKind::BadLength,
        ErrorKind::Oversize,
        ErrorKind::BadSop,
        ErrorKind::BadEop,
        ErrorKind::Overlong,
        ErrorKind::UnsizedFeature,
        ErrorKind::ReservedBits,
        ErrorKind::Garbage,
        ErrorKind::Truncated,
    ];

    /// snake_case name for logs and JSON (`bad_checksum`).
    pub fn name(self) -> &'static str {
        match self {
            ErrorKind::BadChecksum => "bad_checksum",
            ErrorKind::BadEscape => "bad_escape",
            ErrorKind::SopInsidePacket => "sop_inside_packet",
            ErrorKind::TooShort => "too_short",
            ErrorKind::BadLength => "bad_length",
            ErrorKind::Oversize => "oversize",
            ErrorKind::BadSop => "bad_sop",
            ErrorKind::BadEop => "bad_eop",
            ErrorKind::Overlong => "overlong",
            ErrorKind::UnsizedFeature => "unsized_feature",
            ErrorKind::ReservedBits => "reserved_bits",
            ErrorKind::Garbage => "garbage",
            ErrorKind::Truncated => "truncated",
        }
    }

    fn index(self) -> usize {
        self as usize
    }
}

impl fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A decode error with where it happened in the stream. `P` is what the family can keep of
/// the damaged packet (a v2 or v1 packet whose checksum failed, what an RSRCP frame held
/// before it became unreadable).
#[derive(Debug, Clone, PartialEq)]
pub struct DecodeError<P> {
    pub kind: ErrorKind,
    /// Stream offset (bytes since the decoder was created) of the packet's start, or of the
    /// first garbage byte; 0 for a single notification decoded on its own.
    pub offset: u64,
    /// For people: the checksum values, byte counts, the feature.
    pub detail: String,
    /// What was read of the damaged packet, when anything was.
    pub packet: Option<Box<P>>,
}

impl<P> DecodeError<P> {
    pub fn new(kind: ErrorKind, offset: u64, detail: String) -> Self {
        DecodeError {
            kind,
            offset,
            detail,
            packet: None,
        }
    }

    /// The same error, with what was read of the packet in another form (a family's packet
    /// wrapped into the seam's).
    pub fn map_packet<Q>(self, f: impl FnOnce(P) -> Option<Q>) -> DecodeError<Q> {
        DecodeError {
            kind: self.kind,
            offset: self.offset,
            detail: self.detail,
            packet: self.packet.and_then(|p| f(*p)).map(Box::new),
        }
    }
}

impl<P> fmt::Display for DecodeError<P> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} at offset {}", self.kind.name(), self.offset)?;
        if !self.detail.is_empty() {
            write!(f, ": {}", self.detail)?;
        }
        Ok(())
    }
}

impl<P: fmt::Debug> std::error::Error for DecodeError<P> {}

/// A decode error as JSON: `{"error": kind, "offset", "detail"}`, as `packet decode --json`
/// and the traces print it.
#[derive(serde::Serialize)]
pub struct ErrorJson<'a> {
    pub error: &'static str,
    pub offset: u64,
    pub detail: &'a str,
}

impl<P> DecodeError<P> {
    pub fn json(&self) -> ErrorJson<'_> {
        ErrorJson {
            error: self.kind.name(),
            offset: self.offset,
            detail: &self.detail,
        }
    }
}

/// Counters of everything a decoder has seen.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DecodeStats {
    /// Packets decoded, of any kind.
    pub packets: u64,
    /// Bytes fed.
    pub bytes: u64,
    /// Bytes in no packet: garbage, and the bytes of packets abandoned after an error.
    pub skipped_bytes: u64,
    errors: [u64; ErrorKind::COUNT],
}

impl DecodeStats {
    pub fn errors(&self, kind: ErrorKind) -> u64 {
        self.errors[kind.index()]
    }

    pub fn total_errors(&self) -> u64 {
        self.errors.iter().sum()
    }

    /// Count one error of `kind`.
    pub fn count_error(&mut self, kind: ErrorKind) {
        self.errors[kind.index()] += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_are_indexed_in_table_order_with_unique_names() {
        let mut names = std::collections::HashSet::new();
        for (i, k) in ErrorKind::ALL.into_iter().enumerate() {
            assert_eq!(k.index(), i);
            assert!(names.insert(k.name()));
        }
    }

    #[test]
    fn errors_count_per_kind_and_show_where() {
        let mut s = DecodeStats::default();
        s.count_error(ErrorKind::Garbage);
        s.count_error(ErrorKind::Garbage);
        s.count_error(ErrorKind::BadEop);
        assert_eq!(s.errors(ErrorKind::Garbage), 2);
        assert_eq!(s.total_errors(), 3);
        let e: DecodeError<u8> = DecodeError::new(ErrorKind::BadEop, 12, "7E found".into());
        assert_eq!(e.to_string(), "bad_eop at offset 12: 7E found");
        let e = DecodeError {
            packet: Some(Box::new(3u8)),
            ..e
        };
        assert_eq!(
            e.map_packet(|p| Some(p as u32 * 2)).packet,
            Some(Box::new(6))
        );
    }
}
