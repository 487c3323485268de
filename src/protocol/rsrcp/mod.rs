//! The Robi State Report Communication Protocol (RSRCP 1.0.0) of the Robi 42 school robot.
//! Sans-IO: bytes in, typed values out, and back. No clocks, no async.
//!
//! Sources: `robi-rsrcp.md` (the spec) and `droid-facts.md` §5, which wins where they differ
//! and fills in what the spec leaves out (bit values, sizes, endianness, the firmware's
//! behaviour). Where the spec is silent, the item's docs say which fact was used.
//!
//! - [`decode_handshake`] / [`decode_frame`]: one BLE value. Over BLE every notification of
//!   the frames characteristic is exactly one frame and the handshake characteristic holds
//!   the 5-byte handshake, so no framing is needed there.
//! - [`Framer`]: byte streams (captures, a TCP relay), where frames must be found by the length
//!   their EFS implies.
//! - [`frame_gap`]: lost frames from consecutive 24-bit frame ids.
//! - [`velocity_byte`], [`steering_byte`], [`wheel_speeds`]: the remote-control service.
//! - [`to_json`], `summary()`, `fields()`: describing what was decoded.
//!
//! The GATT UUIDs (RSRC service 0x2579 with frames 0x8765, handshake 0x4744 and start
//! confirmation 0x4234; remote-control service 0xBA73 with velocity 0x6B2F and steering
//! 0x3F4A) and the connection sequence (read the handshake, write `01` to start) are the Robi
//! family's GATT profile (`crate::family::robi::gatt`): this module is the wire format only.

pub mod control;
pub mod describe;
pub mod efs;
pub mod error;
pub mod frame;
pub mod frame_id;
pub mod framer;

pub use control::{
    STEERING_STRAIGHT, STEPPER_MAX_HZ, STEPPER_MIN_HZ, steering_byte, stepper_hz, velocity_byte,
    wheel_speeds,
};
pub use describe::{JSON_KEYS, json, to_json};
pub use efs::{Efs, Feature};
pub use error::{Damage, DecodeStats, ERROR_KINDS, ErrorKind, FrameError};
pub use frame::{
    Buttons, EOP, FRAME_ID_MASK, Frame, HANDSHAKE_LEN, HEADER_LEN, Handshake, Leds, MAX_FRAME_LEN,
    MIN_FRAME_LEN, Motors, Piezo, SOP, VERSION_1_0_0, decode_frame, decode_handshake,
};
pub use frame_id::{FRAME_ID_MODULUS, frame_delta, frame_gap};
pub use framer::{Feed, Framer};

/// What the robot sends: the handshake once at connection, then frames.
#[derive(Debug, Clone, PartialEq)]
pub enum Item {
    Handshake(Handshake),
    Frame(Frame),
}

impl Item {
    pub fn kind(&self) -> &'static str {
        match self {
            Item::Handshake(_) => "handshake",
            Item::Frame(_) => "frame",
        }
    }
}
