//! Sphero API v1 (BB-8, SPRK+, Ollie): framing, the command catalogue, async messages and
//! sensor streaming. Sans-IO: bytes in, typed values out, and back. No clocks, no async.
//!
//! Shaped like [`super::v2`] so the two families read alike: a catalogue with typed
//! constructors ([`cmd`]), a streaming [`Decoder`], [`describe`] for people and [`to_json`]
//! for tools. Differences forced by the wire format: the decoder is told which side it reads
//! ([`Source`]), packets are one of three shapes ([`Packet`]), encoding can fail (DLEN is one
//! byte), and a response does not name its command, so [`describe`] is given the request.

pub mod catalog;
pub mod decoder;
pub mod describe;
pub mod device;
pub mod notify;
pub mod packet;
pub mod sensor;
pub mod types;

pub use super::value::{self, Fields, Value};
pub use catalog::{AsyncDef, Command, CommandDef, cmd};
pub use decoder::{DecodeError, DecodeStats, Decoder, ERROR_KINDS, ErrorKind, Source};
pub use describe::{Described, JSON_KEYS, describe, to_json};
pub use device::Device;
pub use notify::{
    Collision, Notification, NotificationError, decode_async, decode_collision, encode_async,
    encode_collision,
};
pub use packet::{AsyncPacket, CommandPacket, FrameError, Kind, Mrsp, Packet, Response};
pub use sensor::{SensorSample, StreamingConfig, decode_samples, encode_samples};
pub use types::{ApiVersion, I16List, MotorMode, OptionalMask, RollState};
