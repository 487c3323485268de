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
pub mod device;
pub mod notify;
pub mod packet;
pub mod sensor;
pub mod types;

pub use super::value::{self, Fields, Value};
pub use catalog::{AsyncDef, Command, CommandDef, cmd};
pub use decoder::{DecodeError, DecodeErrorKind, Decoder, DecoderStats, Source};
pub use device::Device;
pub use notify::{
    Collision, Notification, NotificationError, decode_async, decode_collision, encode_async,
    encode_collision,
};
pub use packet::{AsyncPacket, CommandPacket, FrameError, Kind, Mrsp, Packet, Response};
pub use sensor::{SensorSample, StreamingConfig, decode_samples, encode_samples};
pub use types::{ApiVersion, I16List, MotorMode, OptionalMask, RollState};

/// A packet explained with the catalogue: its name and decoded payload.
#[derive(Debug, Clone, PartialEq)]
pub struct Described {
    pub kind: Kind,
    /// Catalogue name (of the command, of the command a response answers, or of the async
    /// message); `None` when unknown.
    pub name: Option<String>,
    /// Decoded payload; `None` when the payload did not fit its schema, the response carried
    /// an error, or nothing tells how to read it (an unknown command, a response whose
    /// request is not known: its bytes are still in the packet's `data`).
    pub fields: Option<Fields>,
    /// Why `fields` is `None`, when that is a problem worth showing.
    pub problem: Option<String>,
}

impl Described {
    /// A short label: the name, or the ids in hex.
    pub fn label(&self, p: &Packet) -> String {
        if let Some(n) = &self.name {
            return n.clone();
        }
        match p {
            Packet::Command(c) => format!("{}/0x{:02X}", Device::describe(c.did), c.cid),
            Packet::Response(r) => format!("response seq {}", r.seq),
            Packet::Async(a) => catalog::async_name(a.id_code),
        }
    }
}

/// Explain a packet. `streaming` gives the Set Data Streaming configuration in effect for
/// sensor data (without it the values are shown as a raw i16 list); `request` is the command
/// a response answers, when the caller has matched it by SEQ (without it the response's
/// payload stays raw).
pub fn describe(
    p: &Packet,
    streaming: Option<&StreamingConfig>,
    request: Option<&Command>,
) -> Described {
    let mut d = Described {
        kind: p.kind(),
        name: None,
        fields: None,
        problem: None,
    };
    let decode =
        |d: &mut Described, schema: catalog::Schema, data: &[u8]| match catalog::decode_fields(
            schema, data,
        ) {
            Ok(f) => d.fields = Some(f),
            Err(e) => d.problem = Some(e.to_string()),
        };
    match p {
        Packet::Command(c) => match catalog::lookup(c.did, c.cid) {
            Some(def) => {
                d.name = Some(def.name.clone());
                decode(&mut d, def.params, &c.data);
            }
            None => {
                d.problem = Some(format!(
                    "unknown command {}/0x{:02X}",
                    Device::describe(c.did),
                    c.cid
                ))
            }
        },
        Packet::Response(r) => {
            let def = request.and_then(Command::def);
            d.name = def.map(|def| def.name.clone());
            if !r.mrsp.is_success() {
                d.problem = Some(r.mrsp.to_string());
            } else if let Some(def) = def {
                decode(&mut d, def.response, &r.data);
            }
        }
        Packet::Async(a) => {
            let def = catalog::async_message(a.id_code);
            d.name = def.map(|def| def.name.to_string());
            match (a.id_code, streaming, def) {
                (catalog::id::SENSOR_DATA, Some(cfg), _) => match decode_samples(cfg, &a.data) {
                    Ok(frames) => d.fields = Some(frames_fields(&frames)),
                    Err(e) => d.problem = Some(e.to_string()),
                },
                (_, _, Some(def)) => decode(&mut d, def.fields, &a.data),
                (_, _, None) => {
                    d.fields = Some(vec![("data", Value::Bytes(a.data.clone()))]);
                }
            }
        }
    }
    d
}

/// Sensor frames as fields: one frame gives one value per name; several frames give one list
/// per name, frame by frame, so each name appears once.
fn frames_fields(frames: &[SensorSample]) -> Fields {
    match frames {
        [one] => one.fields(),
        _ => {
            let Some(first) = frames.first() else {
                return Fields::new();
            };
            first
                .values
                .iter()
                .enumerate()
                .map(|(i, (name, _))| {
                    let list = frames
                        .iter()
                        .map(|f| {
                            f.values
                                .get(i)
                                .map_or(Value::Float(f64::NAN), |(_, v)| Value::Float(*v as f64))
                        })
                        .collect();
                    (*name, Value::List(list))
                })
                .collect()
        }
    }
}

/// The JSON object for one packet. Every key is always present; keys that do not apply to
/// the packet's kind are null: `kind` ("command" | "response" | "async"), `sop2`, `did`,
/// `cid`, `seq`, `mrsp`, `mrsp_name`, `id_code`, `data` (lowercase hex), `checksum_ok`,
/// `command` (catalogue name or null), `fields` (object, null when undecoded), `problem`.
pub fn to_json(p: &Packet, d: &Described, checksum_ok: bool) -> serde_json::Value {
    let (sop2, did, cid, seq, mrsp, id_code) = match p {
        Packet::Command(c) => (
            Some(c.sop2),
            Some(c.did),
            Some(c.cid),
            Some(c.seq),
            None,
            None,
        ),
        Packet::Response(r) => (None, None, None, Some(r.seq), Some(r.mrsp), None),
        Packet::Async(a) => (None, None, None, None, None, Some(a.id_code)),
    };
    serde_json::json!({
        "kind": p.kind().name(),
        "sop2": sop2,
        "did": did,
        "cid": cid,
        "seq": seq,
        "mrsp": mrsp.map(Mrsp::to_byte),
        "mrsp_name": mrsp.map(Mrsp::name),
        "id_code": id_code,
        "data": crate::hex::compact(p.data()),
        "checksum_ok": checksum_ok,
        "command": d.name,
        "fields": d.fields.as_ref().map(value::fields_json),
        "problem": d.problem,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn response_fields_need_the_request() {
        let resp = Packet::Response(Response {
            mrsp: Mrsp::Ok,
            seq: 4,
            data: vec![10, 20, 30],
        });
        let d = describe(&resp, None, None);
        assert_eq!((d.name, d.fields, d.problem), (None, None, None));
        let d = describe(&resp, None, Some(&cmd::get_rgb_led()));
        assert_eq!(d.name.as_deref(), Some("get-rgb-led"));
        assert_eq!(
            d.fields,
            Some(vec![
                ("red", Value::Int(10)),
                ("green", Value::Int(20)),
                ("blue", Value::Int(30))
            ])
        );
    }

    #[test]
    fn error_response_has_a_problem() {
        let resp = Packet::Response(Response {
            mrsp: Mrsp::from_byte(0x04),
            seq: 4,
            data: vec![],
        });
        let d = describe(&resp, None, Some(&cmd::ping()));
        assert!(d.problem.unwrap().starts_with("unknown_command"));
    }

    #[test]
    fn json_keys_are_all_present() {
        let p = Packet::Async(AsyncPacket::new(0x05, vec![]));
        let d = describe(&p, None, None);
        let j = to_json(&p, &d, true);
        assert_eq!(j["kind"], "async");
        assert_eq!(j["id_code"], 5);
        assert!(j["did"].is_null() && j["mrsp"].is_null());
        assert_eq!(j["command"], "pre-sleep-warning");
        assert_eq!(j["fields"], serde_json::json!({}));
    }
}
