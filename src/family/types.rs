//! The family-independent values that cross the seam: commands, packets, decode errors,
//! the droid's error answers and explained packets for the log.

use crate::model::Protocol;
use crate::protocol::notify::{Notification, NotificationError};
use crate::protocol::value::Fields;
use crate::protocol::{rsrcp, v1, v2};
use std::fmt;

/// A command to a droid, in its family's terms.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Command {
    V2(v2::Command),
    V1(v1::Command),
    Robi(RobiControl),
}

/// Robi 42's remote control: both inputs at once, as the robot's firmware reads them
/// (`droid-facts.md` §5): velocity 0..=255 = 0..1 forward only, steering 0 full left,
/// 128 ≈ straight, 255 full right.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RobiControl {
    pub velocity: u8,
    pub steering: u8,
}

impl RobiControl {
    pub const STOP: RobiControl = RobiControl {
        velocity: 0,
        steering: rsrcp::STEERING_STRAIGHT,
    };
}

impl From<v2::Command> for Command {
    fn from(c: v2::Command) -> Self {
        Command::V2(c)
    }
}

impl From<v1::Command> for Command {
    fn from(c: v1::Command) -> Self {
        Command::V1(c)
    }
}

impl Command {
    pub fn protocol(&self) -> Protocol {
        match self {
            Command::V2(_) => Protocol::SpheroV2,
            Command::V1(_) => Protocol::SpheroV1,
            Command::Robi(_) => Protocol::Rsrcp,
        }
    }

    /// A drive command (speed and heading, or Robi's remote control), in any family.
    pub fn is_drive(&self) -> bool {
        match self {
            Command::V2(c) => (c.did, c.cid) == (0x16, 0x07),
            Command::V1(c) => (c.did, c.cid) == (0x02, 0x30),
            Command::Robi(_) => true,
        }
    }

    /// A drive command at speed 0 (a stop), in any family: the session writes those first.
    pub fn is_stop(&self) -> bool {
        match self {
            Command::V2(c) => match (c.did, c.cid) {
                (0x16, 0x07) => c.data.first() == Some(&0),
                // Raw motors with both speeds 0 (RVR's tracks).
                (0x16, 0x01) => c.data.get(1) == Some(&0) && c.data.get(3) == Some(&0),
                _ => false,
            },
            Command::V1(c) => match (c.did, c.cid) {
                (0x02, 0x30) => c.data.first() == Some(&0),
                // Set Raw Motors with both powers 0.
                (0x02, 0x33) => c.data.get(1) == Some(&0) && c.data.get(3) == Some(&0),
                _ => false,
            },
            Command::Robi(c) => c.velocity == 0,
        }
    }

    /// The catalogue name (`drive-with-heading`, `roll`), or `did/cid` in hex.
    pub fn name(&self) -> String {
        match self {
            Command::V2(c) => c
                .def()
                .map(|d| d.name.clone())
                .unwrap_or_else(|| format!("0x{:02X}/0x{:02X}", c.did, c.cid)),
            Command::V1(c) => c
                .def()
                .map(|d| d.name.clone())
                .unwrap_or_else(|| format!("0x{:02X}/0x{:02X}", c.did, c.cid)),
            Command::Robi(_) => "remote-control".into(),
        }
    }

    /// The device id (0 for Robi, which has none).
    pub fn did(&self) -> u8 {
        match self {
            Command::V2(c) => c.did,
            Command::V1(c) => c.did,
            Command::Robi(_) => 0,
        }
    }

    /// The command id (0 for Robi, which has none).
    pub fn cid(&self) -> u8 {
        match self {
            Command::V2(c) => c.cid,
            Command::V1(c) => c.cid,
            Command::Robi(_) => 0,
        }
    }

    /// The payload (Robi: the velocity and steering bytes).
    pub fn data(&self) -> std::borrow::Cow<'_, [u8]> {
        match self {
            Command::V2(c) => (&c.data[..]).into(),
            Command::V1(c) => (&c.data[..]).into(),
            Command::Robi(c) => vec![c.velocity, c.steering].into(),
        }
    }

    pub fn as_v2(&self) -> Option<&v2::Command> {
        match self {
            Command::V2(c) => Some(c),
            _ => None,
        }
    }

    pub fn as_v1(&self) -> Option<&v1::Command> {
        match self {
            Command::V1(c) => Some(c),
            _ => None,
        }
    }
}

/// A decoded packet of any family, as sent or received.
#[derive(Debug, Clone, PartialEq)]
pub enum Packet {
    V2(v2::Packet),
    V1(v1::Packet),
    /// What went to or came from a Robi 42.
    Robi(RobiPacket),
}

/// Robi 42 traffic: remote-control writes out, handshake and frames in.
#[derive(Debug, Clone, PartialEq)]
pub enum RobiPacket {
    Control(RobiControl),
    Item(rsrcp::Item),
}

impl From<v2::Packet> for Packet {
    fn from(p: v2::Packet) -> Self {
        Packet::V2(p)
    }
}

impl From<v1::Packet> for Packet {
    fn from(p: v1::Packet) -> Self {
        Packet::V1(p)
    }
}

impl Packet {
    /// The family the packet belongs to.
    pub fn protocol(&self) -> Protocol {
        match self {
            Packet::V2(_) => Protocol::SpheroV2,
            Packet::V1(_) => Protocol::SpheroV1,
            Packet::Robi(_) => Protocol::Rsrcp,
        }
    }

    /// A packet the host sent, as the command it carries, with its SEQ and whether it asked
    /// for an answer; `None` for what only a droid sends.
    pub fn as_command(&self) -> Option<(Command, u8, bool)> {
        match self {
            Packet::V2(p) if !p.is_response() && !p.is_notification() => Some((
                Command::V2(v2::Command {
                    did: p.did,
                    cid: p.cid,
                    data: p.data.clone(),
                    target: p.tid,
                }),
                p.seq,
                p.flags.contains(v2::Flags::REQUESTS_RESPONSE),
            )),
            Packet::V1(v1::Packet::Command(c)) => Some((
                Command::V1(v1::Command {
                    did: c.did,
                    cid: c.cid,
                    data: c.data.clone(),
                }),
                c.seq,
                c.sop2 & v1::packet::SOP2_ANSWER != 0,
            )),
            // Robi never answers.
            Packet::Robi(RobiPacket::Control(c)) => Some((Command::Robi(*c), 0, false)),
            _ => None,
        }
    }

    /// The wire bytes.
    pub fn encode(&self) -> Vec<u8> {
        match self {
            Packet::V2(p) => p.encode(),
            // A decoded or catalogue-built v1 packet always fits its DLEN.
            Packet::V1(p) => p.encode().unwrap_or_default(),
            Packet::Robi(RobiPacket::Control(c)) => vec![c.velocity, c.steering],
            Packet::Robi(RobiPacket::Item(rsrcp::Item::Handshake(h))) => h.encode().to_vec(),
            Packet::Robi(RobiPacket::Item(rsrcp::Item::Frame(f))) => f.encode(),
        }
    }

    pub fn as_v2(&self) -> Option<&v2::Packet> {
        match self {
            Packet::V2(p) => Some(p),
            _ => None,
        }
    }

    pub fn as_v1(&self) -> Option<&v1::Packet> {
        match self {
            Packet::V1(p) => Some(p),
            _ => None,
        }
    }

    /// The payload.
    pub fn data(&self) -> &[u8] {
        match self {
            Packet::V2(p) => &p.data,
            Packet::V1(p) => p.data(),
            Packet::Robi(_) => &[],
        }
    }
}

/// A stream decode error of any family; it keeps what was read of the damaged packet.
pub type DecodeError = crate::protocol::decode::DecodeError<Packet>;

/// A droid's error answer to a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DroidError {
    V2(v2::ErrorCode),
    V1(v1::Mrsp),
}

impl DroidError {
    /// The code's snake_case name.
    pub fn name(&self) -> String {
        match self {
            DroidError::V2(e) => e.name(),
            DroidError::V1(e) => e.name(),
        }
    }

    /// A sentence for people.
    pub fn message(&self) -> String {
        match self {
            DroidError::V2(e) => e.message(),
            DroidError::V1(e) => e.message(),
        }
    }

    /// The byte on the wire.
    pub fn code(&self) -> u8 {
        match self {
            DroidError::V2(e) => e.to_byte(),
            DroidError::V1(e) => e.to_byte(),
        }
    }

    /// The droid is asleep and must be woken before it obeys.
    pub fn is_target_unavailable(&self) -> bool {
        matches!(self, DroidError::V2(v2::ErrorCode::TargetUnavailable))
    }
}

impl fmt::Display for DroidError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DroidError::V2(e) => e.fmt(f),
            DroidError::V1(e) => write!(f, "{}", e.name()),
        }
    }
}

/// What a packet is, across families (v1 calls notifications "async messages").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PacketKind {
    Command,
    Response,
    Notification,
}

impl PacketKind {
    /// snake_case name for JSON.
    pub fn name(self) -> &'static str {
        match self {
            PacketKind::Command => "command",
            PacketKind::Response => "response",
            PacketKind::Notification => "notification",
        }
    }
}

/// A packet explained with its family's catalogue, for the packet log.
#[derive(Debug, Clone, PartialEq)]
pub struct Explained {
    pub kind: PacketKind,
    /// Catalogue name, or a `device/0xNN` label for unknown ids.
    pub label: String,
    /// Whether the catalogue knows it.
    pub known: bool,
    /// Decoded payload; `None` when it did not fit, the answer was an error, or unknown.
    pub fields: Option<Fields>,
    /// Why `fields` is `None`, when that is worth showing.
    pub problem: Option<String>,
    /// An error answer.
    pub error: Option<DroidError>,
    /// The device id, for the log filter (`dev:drive`).
    pub did: Option<u8>,
    pub seq: Option<u8>,
}

/// The response key: what a response carries to find its request. v2 echoes DID, CID and
/// SEQ; v1 only the SEQ (its DID and CID are 0 here).
pub type Key = (u8, u8, u8);

/// What the codec found in the droid's bytes.
#[derive(Debug, Clone, PartialEq)]
pub enum Incoming {
    /// An answer to a request.
    Response {
        key: Key,
        error: Option<DroidError>,
        packet: Packet,
    },
    /// An unsolicited message, decoded into zero or more notifications (a v1 sensor packet
    /// carries several frames).
    Async {
        notifications: Vec<Result<Notification, NotificationError>>,
        packet: Packet,
    },
    /// A packet that should not come from a droid (a command); logged, otherwise ignored.
    Stray(Packet),
    Error(DecodeError),
}
