//! Sphero API v2: framing, the command catalogue, typed notifications and sensor streaming.
//! Sans-IO: bytes in, typed values out, and back. No clocks, no async.

pub mod catalog;
pub mod decoder;
pub mod device;
pub mod error;
pub mod flags;
pub mod notify;
pub mod packet;
pub mod sensor;
/// Re-exported from the shared core, where v1 uses them too.
pub use super::{value, wire};

pub use catalog::{Command, CommandDef, cmd};
pub use decoder::{DecodeError, DecodeErrorKind, Decoded, Decoder, DecoderStats};
pub use device::Device;
pub use error::ErrorCode;
pub use flags::Flags;
pub use notify::{Collision, Notification};
pub use packet::{Packet, PacketRef};
pub use sensor::{SensorSample, StreamingConfig};
pub use value::{Fields, Value};

/// What kind of packet this is, by its flags and SEQ.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Command,
    Response,
    Notification,
}

impl Kind {
    pub fn of(p: &Packet) -> Kind {
        if p.is_response() {
            Kind::Response
        } else if p.is_notification() {
            Kind::Notification
        } else {
            Kind::Command
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Kind::Command => "command",
            Kind::Response => "response",
            Kind::Notification => "notification",
        }
    }
}

/// A packet explained with the catalogue: its name and decoded payload.
#[derive(Debug, Clone, PartialEq)]
pub struct Described {
    pub kind: Kind,
    /// Catalogue name, `None` for an unknown DID/CID.
    pub name: Option<String>,
    /// Decoded payload; `None` when the payload did not fit the schema, the response carried
    /// an error, or the command is unknown.
    pub fields: Option<Fields>,
    /// Why `fields` is `None`, when that is a problem worth showing.
    pub problem: Option<String>,
}

/// Explain a packet. `streaming` gives the masks in effect for sensor data; without it the
/// sensor values are shown as a plain list.
pub fn describe(p: &Packet, streaming: Option<&StreamingConfig>) -> Described {
    let kind = Kind::of(p);
    let (name, schema) = match kind {
        Kind::Command | Kind::Response => match catalog::lookup(p.did, p.cid) {
            Some(def) => (
                Some(def.name.clone()),
                Some(if kind == Kind::Command {
                    def.params
                } else {
                    def.response
                }),
            ),
            None => (None, None),
        },
        Kind::Notification => match catalog::notification(p.did, p.cid) {
            Some(def) => (Some(def.name.clone()), Some(def.fields)),
            None => (None, None),
        },
    };
    let mut d = Described {
        kind,
        name,
        fields: None,
        problem: None,
    };
    if let Some(err) = p.err.filter(|e| !e.is_success()) {
        d.problem = Some(err.to_string());
        return d;
    }
    if kind == Kind::Notification
        && (p.did, p.cid) == (0x18, 0x02)
        && let Some(cfg) = streaming
    {
        match sensor::decode_sample(cfg, &p.data) {
            Ok(s) => d.fields = Some(s.fields()),
            Err(e) => d.problem = Some(e.to_string()),
        }
        return d;
    }
    match schema {
        Some(schema) => match catalog::decode_fields(schema, &p.data) {
            Ok(f) => d.fields = Some(f),
            Err(e) => d.problem = Some(e.to_string()),
        },
        None => {
            d.problem = Some(format!(
                "unknown {} {}/0x{:02X}",
                kind.name(),
                Device::describe(p.did),
                p.cid
            ))
        }
    }
    d
}

impl Described {
    /// A short label: the name, or `did/cid` in hex.
    pub fn label(&self, p: &Packet) -> String {
        match &self.name {
            Some(n) => n.clone(),
            None => format!("{}/0x{:02X}", Device::describe(p.did), p.cid),
        }
    }
}
