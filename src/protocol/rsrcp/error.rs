//! Why bytes could not be framed or decoded.

use super::efs::Feature;
use super::frame::Frame;
use std::fmt;

/// What went wrong, without the details.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FrameErrorKind {
    /// Bytes outside any frame or handshake (stream framer only).
    Garbage,
    /// A notification that does not start with SOP `7E`.
    BadSop,
    /// The byte where the EFS puts the end of the frame (or the handshake's fifth byte) is
    /// not EOP `7F`.
    BadEop,
    /// Fewer bytes than the header or the EFS needs (for the framer: the stream ended).
    Truncated,
    /// A notification longer than its EFS implies. BLE delivers exactly one frame per
    /// notification (`droid-facts.md` §5), so extra bytes mean the EFS and the payload
    /// disagree.
    Overlong,
    /// The EFS enables a feature the spec has not sized yet; the frame is decoded up to it and
    /// no further (see [`FrameError::partial`]).
    UnsizedFeature,
    /// The EFS sets a reserved bit (0x001F); every defined feature is decoded, but where the
    /// frame ends is unknown.
    ReservedBits,
}

impl FrameErrorKind {
    pub const ALL: [FrameErrorKind; 7] = [
        FrameErrorKind::Garbage,
        FrameErrorKind::BadSop,
        FrameErrorKind::BadEop,
        FrameErrorKind::Truncated,
        FrameErrorKind::Overlong,
        FrameErrorKind::UnsizedFeature,
        FrameErrorKind::ReservedBits,
    ];

    /// Snake-case name for logs and JSON.
    pub fn name(self) -> &'static str {
        match self {
            FrameErrorKind::Garbage => "garbage",
            FrameErrorKind::BadSop => "bad_sop",
            FrameErrorKind::BadEop => "bad_eop",
            FrameErrorKind::Truncated => "truncated",
            FrameErrorKind::Overlong => "overlong",
            FrameErrorKind::UnsizedFeature => "unsized_feature",
            FrameErrorKind::ReservedBits => "reserved_bits",
        }
    }

    pub(crate) fn index(self) -> usize {
        self as usize
    }
}

impl fmt::Display for FrameErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A framing or decoding error.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameError {
    pub kind: FrameErrorKind,
    /// Where the rejected frame (its SOP) or the garbage run starts: a stream offset for the
    /// [`Framer`](super::Framer) (bytes since it was created), 0 for a single notification.
    pub offset: u64,
    /// Index within the frame where the problem was found: the byte that should have been
    /// EOP, the start of the unsized feature's payload, the number of bytes present when
    /// truncated. 0 for garbage.
    pub at: usize,
    /// For people: byte counts, the EFS, the feature.
    pub detail: String,
    /// The feature that stopped decoding ([`FrameErrorKind::UnsizedFeature`]).
    pub feature: Option<Feature>,
    /// For [`FrameErrorKind::UnsizedFeature`] and [`FrameErrorKind::ReservedBits`]: the frame
    /// decoded up to where it became unreadable (its `efs` is the full EFS).
    pub partial: Option<Box<Frame>>,
}

impl FrameError {
    pub(crate) fn new(kind: FrameErrorKind, at: usize, detail: String) -> Self {
        FrameError {
            kind,
            offset: 0,
            at,
            detail,
            feature: None,
            partial: None,
        }
    }
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} at offset {}", self.kind.name(), self.offset)?;
        if !self.detail.is_empty() {
            write!(f, ": {}", self.detail)?;
        }
        Ok(())
    }
}

impl std::error::Error for FrameError {}
