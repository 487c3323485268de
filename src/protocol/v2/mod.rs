//! Sphero API v2: framing, the command catalogue, typed notifications and sensor streaming.
//! Sans-IO: bytes in, typed values out, and back. No clocks, no async.

pub mod catalog;
pub mod decoder;
pub mod describe;
pub mod device;
pub mod error;
pub mod flags;
pub mod frame;
pub mod notify;
pub mod packet;
pub mod sensor;
pub mod stream;
pub mod types;
/// Re-exported from the shared core, where v1 uses them too.
pub use super::{value, wire};

pub use catalog::{Command, CommandDef, cmd};
pub use decoder::{DecodeError, DecodeStats, Decoded, Decoder, ERROR_KINDS, ErrorKind};
pub use describe::{Described, Kind, describe};
pub use device::Device;
pub use error::ErrorCode;
pub use flags::Flags;
pub use notify::{Collision, Notification};
pub use packet::{Packet, PacketRef};
pub use sensor::{SensorSample, StreamingConfig};
pub use value::{Fields, Value};
