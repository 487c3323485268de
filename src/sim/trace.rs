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
//! (with the packet CLI's own builders, so the two cannot drift apart) and a one-line text.

use crate::hex;
use crate::link::gatt::{GattProfile, GattUuid, ROBI_HANDSHAKE};
use crate::model::{Model, Protocol};
use crate::protocol::{rsrcp, v1, v2, value};
use serde_json::{Value, json};

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
    /// What `droidctl packet decode --json` prints for it; `{"kind": "gatt-write", "uuid",
    /// "hex"}` (or `gatt-read`) for GATT operations that carry no packet.
    pub packet: Value,
    /// One line for people: `command drive-with-heading seq 3: speed=60 …`.
    pub text: String,
}

impl TraceRecord {
    /// The JSON line `sim --bluez --trace --json` prints: `{"t_ms", "device", "dir",
    /// "packet"}`.
    pub fn json_line(&self, t_ms: u64, device: &str) -> Value {
        json!({
            "t_ms": t_ms,
            "device": device,
            "dir": self.dir.name(),
            "packet": self.packet,
        })
    }
}

/// The per-direction stream decoders of one family.
enum Streams {
    V2 {
        inbound: v2::Decoder,
        outbound: v2::Decoder,
    },
    V1 {
        inbound: v1::Decoder,
        outbound: v1::Decoder,
    },
    Rsrcp,
}

impl Streams {
    fn new(protocol: Protocol) -> Streams {
        match protocol {
            Protocol::SpheroV2 => Streams::V2 {
                inbound: v2::Decoder::new(),
                outbound: v2::Decoder::new(),
            },
            Protocol::SpheroV1 => Streams::V1 {
                inbound: v1::Decoder::new(v1::Source::Host),
                outbound: v1::Decoder::new(v1::Source::Droid),
            },
            Protocol::Rsrcp => Streams::Rsrcp,
        }
    }
}

/// Decodes one droid's GATT traffic into [`TraceRecord`]s.
pub struct PacketTracer {
    protocol: Protocol,
    /// The characteristic API packets are written to (none for Robi: its inputs are bytes).
    api: Option<GattUuid>,
    /// The characteristics the droid's packets are notified on.
    notify: Vec<GattUuid>,
    streams: Streams,
}

impl PacketTracer {
    pub fn new(model: Model) -> PacketTracer {
        let profile = GattProfile::for_model(model);
        let protocol = model.protocol();
        PacketTracer {
            protocol,
            api: (protocol != Protocol::Rsrcp).then_some(profile.write.characteristic),
            notify: profile.notify.iter().map(|c| c.characteristic).collect(),
            streams: Streams::new(protocol),
        }
    }

    /// A new connection: the byte streams start afresh (a half packet of the last one is
    /// dropped, as the droid drops it).
    pub fn reset(&mut self) {
        self.streams = Streams::new(self.protocol);
    }

    /// The host wrote `bytes` to `ch`.
    pub fn write(&mut self, ch: GattUuid, bytes: &[u8]) -> Vec<TraceRecord> {
        if Some(ch) != self.api {
            return vec![gatt_op("gatt-write", TraceDir::In, ch, bytes)];
        }
        let mut out = Vec::new();
        match &mut self.streams {
            Streams::V2 { inbound, .. } => {
                for r in inbound.feed(bytes) {
                    out.push(v2_record(TraceDir::In, r));
                }
            }
            Streams::V1 { inbound, .. } => {
                for r in inbound.feed(bytes) {
                    out.push(v1_record(TraceDir::In, r));
                }
            }
            Streams::Rsrcp => out.push(gatt_op("gatt-write", TraceDir::In, ch, bytes)),
        }
        out
    }

    /// The droid notified `bytes` on `ch`.
    pub fn notify(&mut self, ch: GattUuid, bytes: &[u8]) -> Vec<TraceRecord> {
        if !self.notify.contains(&ch) {
            return vec![gatt_op("gatt-notify", TraceDir::Out, ch, bytes)];
        }
        let mut out = Vec::new();
        match &mut self.streams {
            Streams::V2 { outbound, .. } => {
                for r in outbound.feed(bytes) {
                    out.push(v2_record(TraceDir::Out, r));
                }
            }
            Streams::V1 { outbound, .. } => {
                for r in outbound.feed(bytes) {
                    out.push(v1_record(TraceDir::Out, r));
                }
            }
            // One frame per notification, read as `packet decode --protocol rsrcp` reads one.
            Streams::Rsrcp => out.push(rsrcp_record(
                rsrcp::decode_frame(bytes).map(rsrcp::Item::Frame),
            )),
        }
        out
    }

    /// The host read `bytes` from `ch`.
    pub fn read(&mut self, ch: GattUuid, bytes: &[u8]) -> Vec<TraceRecord> {
        if self.protocol == Protocol::Rsrcp && ch == ROBI_HANDSHAKE && !bytes.is_empty() {
            return vec![rsrcp_record(
                rsrcp::decode_handshake(bytes).map(rsrcp::Item::Handshake),
            )];
        }
        vec![gatt_op("gatt-read", TraceDir::Out, ch, bytes)]
    }
}

fn gatt_op(kind: &str, dir: TraceDir, ch: GattUuid, bytes: &[u8]) -> TraceRecord {
    let verb = kind.strip_prefix("gatt-").unwrap_or(kind);
    TraceRecord {
        dir,
        packet: json!({"kind": kind, "uuid": ch.to_string(), "hex": hex::compact(bytes)}),
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

/// `: fields` or `: problem`, or nothing.
fn tail(fields: &Option<value::Fields>, problem: &Option<String>) -> String {
    match (fields, problem) {
        (Some(f), _) if !f.is_empty() => format!(": {}", value::fields_line(f)),
        (None, Some(p)) => format!(": {p}"),
        _ => String::new(),
    }
}

fn error_json(kind: &str, offset: u64, detail: &str) -> Value {
    json!({"error": kind, "offset": offset, "detail": detail})
}

fn v2_record(dir: TraceDir, r: Result<v2::Packet, v2::DecodeError>) -> TraceRecord {
    match r {
        Ok(p) => {
            let d = v2::describe(&p, None);
            let label = d
                .name
                .clone()
                .unwrap_or_else(|| format!("{}/0x{:02X}", v2::Device::describe(p.did), p.cid));
            let err = p
                .err
                .filter(|e| !e.is_success())
                .map(|e| format!(" error {}", e.name()))
                .unwrap_or_default();
            TraceRecord {
                dir,
                packet: crate::cli::packet::packet_json(&p, true, &d),
                text: format!(
                    "{} {label} seq {}{err}{} [{}]",
                    d.kind.name(),
                    p.seq,
                    tail(&d.fields, &d.problem),
                    hex::spaced(&p.encode())
                ),
            }
        }
        Err(e) => TraceRecord {
            dir,
            packet: error_json(e.kind.name(), e.offset, &e.detail),
            text: format!("decode error: {} ({})", e.kind.name(), e.detail),
        },
    }
}

fn v1_record(dir: TraceDir, r: Result<v1::Packet, v1::DecodeError>) -> TraceRecord {
    match r {
        Ok(p) => {
            let d = v1::describe(&p, None, None);
            let head = match &p {
                v1::Packet::Command(c) => format!("seq {}", c.seq),
                v1::Packet::Response(r) => format!("seq {} {}", r.seq, r.mrsp),
                v1::Packet::Async(_) => String::new(),
            };
            let wire = p.encode().map(|w| hex::spaced(&w)).unwrap_or_default();
            TraceRecord {
                dir,
                packet: crate::cli::packet::v1_packet_json(&p, &d, true),
                text: format!(
                    "{} {}{}{} [{wire}]",
                    d.kind.name(),
                    d.label(&p),
                    if head.is_empty() {
                        String::new()
                    } else {
                        format!(" {head}")
                    },
                    tail(&d.fields, &d.problem),
                ),
            }
        }
        Err(e) => TraceRecord {
            dir,
            packet: error_json(e.kind.name(), e.offset, &e.detail),
            text: format!("decode error: {} ({})", e.kind.name(), e.detail),
        },
    }
}

fn rsrcp_record(r: Result<rsrcp::Item, rsrcp::FrameError>) -> TraceRecord {
    let text = match &r {
        Ok(item) => item.summary(),
        Err(e) => format!("decode error: {}", e.summary()),
    };
    TraceRecord {
        dir: TraceDir::Out,
        packet: rsrcp::to_json(&r),
        text,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::gatt::{V1_ANTI_DOS, V1_COMMANDS, V1_RESPONSES, V2_ANTI_DOS, V2_API};
    use crate::protocol::v2::wire::DriveFlags;
    use crate::units::Heading;

    #[test]
    fn v2_packets_are_reassembled_and_explained() {
        let mut t = PacketTracer::new(Model::R2D2);
        let unlock = t.write(V2_ANTI_DOS, b"usetheforce...band");
        assert_eq!(unlock.len(), 1);
        assert_eq!(unlock[0].packet["kind"], "gatt-write");
        assert_eq!(unlock[0].packet["uuid"], V2_ANTI_DOS.to_string());
        assert_eq!(unlock[0].packet["hex"], hex::compact(b"usetheforce...band"));
        let wire = v2::cmd::drive_with_heading(60, Heading::default(), DriveFlags::empty())
            .to_packet(7)
            .encode();
        let (a, b) = wire.split_at(4);
        assert!(t.write(V2_API, a).is_empty(), "half a packet");
        let r = t.write(V2_API, b);
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].dir, TraceDir::In);
        assert_eq!(r[0].packet["command"], "drive-with-heading");
        assert_eq!(r[0].packet["fields"]["speed"], 60);
        assert!(
            r[0].text
                .starts_with("command drive-with-heading seq 7: speed=60"),
            "{}",
            r[0].text
        );
        let note = v2::Packet::notification(0x13, 0x19, vec![]).encode();
        let r = t.notify(V2_API, &note);
        assert_eq!(r[0].dir, TraceDir::Out);
        assert_eq!(r[0].packet["command"], "will-sleep");
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
            t.write(V1_ANTI_DOS, b"011i3")[0].packet["kind"],
            "gatt-write"
        );
        let ping = v1::Packet::Command(v1::cmd::ping().to_packet(3))
            .encode()
            .unwrap();
        let r = t.write(V1_COMMANDS, &ping);
        assert_eq!(r[0].packet["kind"], "command");
        assert_eq!(r[0].packet["command"], "ping");
        let pre_sleep = v1::Packet::Async(v1::AsyncPacket::new(0x05, vec![]))
            .encode()
            .unwrap();
        let r = t.notify(V1_RESPONSES, &pre_sleep);
        assert_eq!(r[0].packet["kind"], "async");
        assert_eq!(r[0].dir, TraceDir::Out);
    }

    /// What `droidctl packet decode --json --protocol P [--from SIDE] HEX` prints.
    fn decoded(protocol: &str, from: Option<&str>, wire: &[u8]) -> Value {
        let cmd = crate::cli::packet::PacketCmd::Decode {
            hex: vec![hex::spaced(wire)],
            file: None,
            btsnoop: None,
            handle: Vec::new(),
            summary: false,
            protocol: Some(protocol.into()),
            from: from.map(String::from),
            stream: false,
            json: true,
            sensor_mask: None,
            ext_mask: None,
            mask2: None,
            frames: None,
            request: None,
        };
        let mut out = Vec::new();
        crate::cli::packet::run(cmd, &mut out).unwrap();
        serde_json::from_slice(&out).unwrap()
    }

    /// The trace's `packet` is exactly the object `packet decode --json` prints, for every
    /// family and both directions.
    #[test]
    fn packets_are_what_packet_decode_json_prints() {
        use crate::protocol::rsrcp::{Frame, Handshake};
        let mut t = PacketTracer::new(Model::R2D2);
        let cmd =
            v2::cmd::drive_with_heading(60, Heading::default(), DriveFlags::empty()).to_packet(3);
        let resp = v2::Packet::response_to(&cmd, v2::ErrorCode::Success, vec![]);
        let note = v2::Packet::notification(0x13, 0x19, vec![]);
        for (dir, wire) in [
            (TraceDir::In, cmd.encode()),
            (TraceDir::Out, resp.encode()),
            (TraceDir::Out, note.encode()),
        ] {
            let r = match dir {
                TraceDir::In => t.write(V2_API, &wire),
                TraceDir::Out => t.notify(V2_API, &wire),
            };
            assert_eq!(r[0].packet, decoded("v2", None, &wire));
        }
        let mut t = PacketTracer::new(Model::BB8);
        let c = v1::cmd::ping().to_packet(9);
        let wire_in = v1::Packet::Command(c.clone()).encode().unwrap();
        let wire_out = v1::Packet::Response(v1::Response::to(&c, v1::Mrsp::Ok, vec![]))
            .encode()
            .unwrap();
        let wire_async = v1::Packet::Async(v1::AsyncPacket::new(0x05, vec![]))
            .encode()
            .unwrap();
        assert_eq!(
            t.write(V1_COMMANDS, &wire_in)[0].packet,
            decoded("v1", Some("host"), &wire_in)
        );
        assert_eq!(
            t.notify(V1_RESPONSES, &wire_out)[0].packet,
            decoded("v1", Some("droid"), &wire_out)
        );
        assert_eq!(
            t.notify(V1_RESPONSES, &wire_async)[0].packet,
            decoded("v1", Some("droid"), &wire_async)
        );
        let mut t = PacketTracer::new(Model::Robi42);
        let hs = Handshake {
            version: 1,
            msdt_ms: 10,
        }
        .encode()
        .to_vec();
        assert_eq!(
            t.read(ROBI_HANDSHAKE, &hs)[0].packet,
            decoded("rsrcp", None, &hs)
        );
        let frame = Frame::default().encode();
        assert_eq!(
            t.notify(crate::link::gatt::ROBI_FRAMES, &frame)[0].packet,
            decoded("rsrcp", None, &frame)
        );
        let w = t.write(crate::link::gatt::ROBI_VELOCITY, &[200]);
        assert_eq!(w[0].packet["kind"], "gatt-write");
        assert_eq!(w[0].packet["hex"], "c8");
    }
}
