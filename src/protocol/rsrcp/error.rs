//! Why bytes could not be framed or decoded: the shared [`DecodeError`] with what RSRCP can
//! say about a damaged frame ([`Damage`]).

use super::efs::Feature;
use super::frame::Frame;
pub use crate::protocol::decode::{DecodeStats, ErrorKind};

/// The kinds of error RSRCP decoding reports, in the order summaries list them.
pub const ERROR_KINDS: [ErrorKind; 7] = [
    ErrorKind::Garbage,
    ErrorKind::BadSop,
    ErrorKind::BadEop,
    ErrorKind::Truncated,
    ErrorKind::Overlong,
    ErrorKind::UnsizedFeature,
    ErrorKind::ReservedBits,
];

/// What is known of a frame that could not be read whole.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Damage {
    /// Index within the frame where the problem was found: the byte that should have been
    /// EOP, the start of the unsized feature's payload, the number of bytes present when
    /// truncated. 0 for garbage.
    pub at: usize,
    /// The feature that stopped decoding ([`ErrorKind::UnsizedFeature`]).
    pub feature: Option<Feature>,
    /// For [`ErrorKind::UnsizedFeature`] and [`ErrorKind::ReservedBits`]: the frame decoded up
    /// to where it became unreadable (its `efs` is the full EFS).
    pub partial: Option<Frame>,
}

/// A framing or decoding error. `offset` is a stream offset for the
/// [`Framer`](super::Framer) (bytes since it was created), 0 for a single notification.
pub type FrameError = crate::protocol::decode::DecodeError<Damage>;

/// A frame error found at index `at` of the frame.
pub(crate) fn frame_error(kind: ErrorKind, at: usize, detail: String) -> FrameError {
    FrameError {
        kind,
        offset: 0,
        detail,
        packet: Some(Box::new(Damage {
            at,
            ..Damage::default()
        })),
    }
}

impl FrameError {
    /// Where in the frame the problem was found (see [`Damage::at`]).
    pub fn at(&self) -> usize {
        self.packet.as_ref().map_or(0, |d| d.at)
    }

    /// The feature whose undefined size stopped decoding.
    pub fn feature(&self) -> Option<Feature> {
        self.packet.as_ref().and_then(|d| d.feature)
    }

    /// The frame as far as it could be read.
    pub fn partial(&self) -> Option<&Frame> {
        self.packet.as_ref().and_then(|d| d.partial.as_ref())
    }

    fn damage(&mut self) -> &mut Damage {
        self.packet.get_or_insert_with(Box::default)
    }

    pub(crate) fn with_feature(mut self, f: Feature) -> Self {
        self.damage().feature = Some(f);
        self
    }

    pub(crate) fn with_partial(mut self, frame: Frame) -> Self {
        self.damage().partial = Some(frame);
        self
    }
}
