//! What a virtual droid receives and sends, decoded: the trace of `droidctl sim --bluez
//! --trace`.
//!
//! One [`PacketTracer`] per droid reassembles the GATT traffic into packets per direction
//! (a packet may span several 20-byte writes or notifications) and explains each one:
//! - `in`: API packets the host writes (v2 packets, v1 commands) and, as `gatt-write`, the
//!   writes that are not packets (the v2 unlock, the v1 wake sequence, Robi's start
//!   confirmation and its one-byte remote-control inputs);
//! - `out`: the droid's packets (v2 responses and notifications, v1 responses and async
//!   messages, Robi's frames) and what the host reads (Robi's handshake; other reads as
//!   `gatt-read`).
//!
//! Each record carries the JSON object `droidctl packet decode --json` prints for the packet
//! (the family's reader writes both, so the two cannot drift apart) and a one-line text.

use crate::family::{self, Found, Reader, Side};
use crate::gatt::{GattUuid, HandshakeStep};
use crate::hex;
use crate::model::Model;
use serde::Serialize;

/// Which way a record went, seen from the droid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TraceDir {
    /// Host to droid (writes).
    In,
    /// Droid to host (notifications, read values).
    Out,
}

impl TraceDir {
    pub fn name(self) -> &'static str {
        match self {
            TraceDir::In => "in",
            TraceDir::Out => "out",
        }
    }
}

/// One traced packet (or non-packet GATT operation).
#[derive(Debug, Clone, PartialEq)]
pub struct TraceRecord {
    pub dir: TraceDir,
    /// What `droidctl packet decode --json` prints for it, as JSON text; `{"kind":
    /// "gatt-write", "uuid", "hex"}` (or `gatt-read`) for GATT operations that carry no
    /// packet.
    pub packet: String,
    /// One line for people: `command drive-with-heading seq 3: speed=60 …`.
    pub text: String,
}

impl TraceRecord {
    /// The JSON line `sim --bluez --trace --json` prints: `{"t_ms", "device", "dir",
    /// "packet"}`.
    pub fn json_line(&self, t_ms: u64, device: &str) -> String {
        let device = serde_json::to_string(device).unwrap_or_else(|_| "\"\"".into());
        format!(
            "{{\"t_ms\":{t_ms},\"device\":{device},\"dir\":\"{}\",\"packet\":{}}}",
            self.dir.name(),
            self.packet
        )
    }

    /// The packet's JSON as a value, for tools and tests that look inside.
    pub fn packet_value(&self) -> serde_json::Value {
        serde_json::from_str(&self.packet).unwrap_or(serde_json::Value::Null)
    }

    /// What the droid shows now (`matrix: character 'A' in #ff0000`): `{"kind": "state",
    /// "shows": …}`.
    pub fn state(text: &str) -> TraceRecord {
        TraceRecord {
            dir: TraceDir::Out,
            packet: serde_json::json!({"kind": "state", "shows": text}).to_string(),
            text: text.to_string(),
        }
    }

    fn of(dir: TraceDir, f: &dyn Found) -> TraceRecord {
        let mut json = Vec::new();
        f.write_json(false, &mut json);
        TraceRecord {
            dir,
            packet: String::from_utf8(json).unwrap_or_default(),
            text: f.line(),
        }
    }
}

/// Decodes one droid's GATT traffic into [`TraceRecord`]s.
pub struct PacketTracer {
    model: Model,
    /// The characteristic API packets are written to (none for Robi: its inputs are bytes).
    api: Option<GattUuid>,
    /// The characteristics the droid's packets are notified on.
    notify: Vec<GattUuid>,
    /// The characteristics the host reads as part of the handshake (Robi's version and
    /// interval): decoded as the droid's packets.
    reads: Vec<GattUuid>,
    inbound: Box<dyn Reader>,
    outbound: Box<dyn Reader>,
}

impl PacketTracer {
    pub fn new(model: Model) -> PacketTracer {
        let profile = crate::family::gatt_profile(model);
        let f = family::for_model(model);
        PacketTracer {
            model,
            api: profile
                .inputs
                .is_empty()
                .then_some(profile.write.characteristic),
            notify: profile.notify.iter().map(|c| c.characteristic).collect(),
            reads: profile
                .handshake
                .iter()
                .filter_map(|s| match s {
                    HandshakeStep::Read { ch, .. } => Some(ch.characteristic),
                    HandshakeStep::Write { .. } => None,
                })
                .collect(),
            inbound: f.side_reader(Side::Host, false),
            outbound: f.side_reader(Side::Droid, true),
        }
    }

    /// A new connection: the byte streams start afresh (a half packet of the last one is
    /// dropped, as the droid drops it).
    pub fn reset(&mut self) {
        *self = PacketTracer::new(self.model);
    }

    /// The host wrote `bytes` to `ch`.
    pub fn write(&mut self, ch: GattUuid, bytes: &[u8]) -> Vec<TraceRecord> {
        if Some(ch) != self.api {
            return vec![gatt_op("gatt-write", TraceDir::In, ch, bytes)];
        }
        records(&mut *self.inbound, TraceDir::In, bytes)
    }

    /// The droid notified `bytes` on `ch`.
    pub fn notify(&mut self, ch: GattUuid, bytes: &[u8]) -> Vec<TraceRecord> {
        if !self.notify.contains(&ch) {
            return vec![gatt_op("gatt-notify", TraceDir::Out, ch, bytes)];
        }
        records(&mut *self.outbound, TraceDir::Out, bytes)
    }

    /// The host read `bytes` from `ch`.
    pub fn read(&mut self, ch: GattUuid, bytes: &[u8]) -> Vec<TraceRecord> {
        if self.reads.contains(&ch) && !bytes.is_empty() {
            return records(&mut *self.outbound, TraceDir::Out, bytes);
        }
        vec![gatt_op("gatt-read", TraceDir::Out, ch, bytes)]
    }
}

/// What `reader` finds in `bytes`, as records going `dir`.
fn records(reader: &mut dyn Reader, dir: TraceDir, bytes: &[u8]) -> Vec<TraceRecord> {
    let mut out = Vec::new();
    // Records are collected in memory: nothing here can fail.
    let _ = reader.feed(
        bytes,
        Some(&mut |f| {
            out.push(TraceRecord::of(dir, f));
            Ok(())
        }),
    );
    out
}

/// A GATT operation that carries no packet, as JSON.
#[derive(Serialize)]
struct GattOp<'a> {
    kind: &'a str,
    uuid: String,
    hex: String,
}

fn gatt_op(kind: &str, dir: TraceDir, ch: GattUuid, bytes: &[u8]) -> TraceRecord {
    let verb = kind.strip_prefix("gatt-").unwrap_or(kind);
    let op = GattOp {
        kind,
        uuid: ch.to_string(),
        hex: hex::compact(bytes),
    };
    TraceRecord {
        dir,
        packet: serde_json::to_string(&op).unwrap_or_default(),
        text: format!("{verb} {ch}: {}", shown_hex(bytes)),
    }
}

fn shown_hex(bytes: &[u8]) -> String {
    if bytes.is_empty() {
        "(empty)".into()
    } else {
        hex::spaced(bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::family::v1::gatt::{V1_ANTI_DOS, V1_COMMANDS, V1_RESPONSES};
    use crate::family::v2::gatt::{V2_ANTI_DOS, V2_API};
    use crate::protocol::v2::wire::DriveFlags;
    use crate::protocol::{v1, v2};
    use crate::units::Heading;

    #[test]
    fn v2_packets_are_reassembled_and_explained() {
        let mut t = PacketTracer::new(Model::R2D2);
        let unlock = t.write(V2_ANTI_DOS, b"usetheforce...band");
        assert_eq!(unlock.len(), 1);
        assert_eq!(unlock[0].packet_value()["kind"], "gatt-write");
        assert_eq!(unlock[0].packet_value()["uuid"], V2_ANTI_DOS.to_string());
        assert_eq!(
            unlock[0].packet_value()["hex"],
            hex::compact(b"usetheforce...band")
        );
        let wire = v2::cmd::drive_with_heading(60, Heading::default(), DriveFlags::empty())
            .to_packet(7)
            .encode();
        let (a, b) = wire.split_at(4);
        assert!(t.write(V2_API, a).is_empty(), "half a packet");
        let r = t.write(V2_API, b);
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].dir, TraceDir::In);
        assert_eq!(r[0].packet_value()["command"], "drive-with-heading");
        assert_eq!(r[0].packet_value()["fields"]["speed"], 60);
        assert!(
            r[0].text
                .starts_with("command drive-with-heading seq 7: speed=60"),
            "{}",
            r[0].text
        );
        let note = v2::Packet::notification(0x13, 0x19, vec![]).encode();
        let r = t.notify(V2_API, &note);
        assert_eq!(r[0].dir, TraceDir::Out);
        assert_eq!(r[0].packet_value()["command"], "will-sleep");
        assert_eq!(
            t.write(V2_API, &[0x8D, 0x01, 0xD8]).len(),
            1,
            "a decode error"
        );
    }

    #[test]
    fn v1_commands_in_responses_out() {
        let mut t = PacketTracer::new(Model::BB8);
        assert_eq!(
            t.write(V1_ANTI_DOS, b"011i3")[0].packet_value()["kind"],
            "gatt-write"
        );
        let ping = v1::Packet::Command(v1::cmd::ping().to_packet(3))
            .encode()
            .unwrap();
        let r = t.write(V1_COMMANDS, &ping);
        assert_eq!(r[0].packet_value()["kind"], "command");
        assert_eq!(r[0].packet_value()["command"], "ping");
        let pre_sleep = v1::Packet::Async(v1::AsyncPacket::new(0x05, vec![]))
            .encode()
            .unwrap();
        let r = t.notify(V1_RESPONSES, &pre_sleep);
        assert_eq!(r[0].packet_value()["kind"], "async");
        assert_eq!(r[0].dir, TraceDir::Out);
    }
}
