//! A v1 packet explained for people and tools: its catalogue name and decoded payload
//! ([`describe`]), the JSON object `packet decode --json` and the traces print ([`json`]),
//! the multi-line text of `packet decode` ([`text`]) and a trace's one line ([`line`]).

use super::Command;
use super::catalog;
use super::device::Device;
use super::packet::{
    Kind, Mrsp, Packet, SOP2_ANSWER, SOP2_ASYNC, SOP2_RESET_TIMEOUT, SOP2_RESPONSE,
};
use super::sensor::{SensorSample, StreamingConfig, decode_samples};
use crate::hex;
use crate::protocol::value::{Fields, FieldsJson, HexJson, Value};
use serde::Serialize;

/// A packet explained with the catalogue: its name and decoded payload.
#[derive(Debug, Clone, PartialEq)]
pub struct Described {
    pub kind: Kind,
    /// Catalogue name (of the command, of the command a response answers, or of the async
    /// message); `None` when unknown.
    pub name: Option<&'static str>,
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
        if let Some(n) = self.name {
            return n.to_string();
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
                d.name = Some(def.name.as_str());
                // A payload of a real client's own (spherov2's Roll with its reverse byte)
                // reads as the fields it carries (fix, issue 32: the virtual BlueZ's trace
                // and `packet decode` showed spherov2's every Roll without fields).
                match catalog::client_variant(c.did, c.cid, &c.data) {
                    Some(f) => d.fields = Some(f),
                    None => decode(&mut d, def.params, &c.data),
                }
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
            d.name = def.map(|def| def.name.as_str());
            if !r.mrsp.is_success() {
                d.problem = Some(r.mrsp.to_string());
            } else if let Some(def) = def {
                decode(&mut d, def.response, &r.data);
            }
        }
        Packet::Async(a) => {
            let def = catalog::async_message(a.id_code);
            d.name = def.map(|def| def.name);
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

/// The keys of a packet's JSON object, in order.
pub const JSON_KEYS: [&str; 11] = [
    "kind",
    "did",
    "cid",
    "seq",
    "mrsp",
    "mrsp_name",
    "id_code",
    "data",
    "checksum_ok",
    "command",
    "fields",
];

/// The JSON object for one packet: exactly [`JSON_KEYS`], null where a key does not apply to
/// the packet's kind: `kind` ("command" | "response" | "async"), `did`, `cid`, `seq`, `mrsp`,
/// `mrsp_name`, `id_code`, `data` (lowercase hex), `checksum_ok`, `command` (catalogue name
/// or null), `fields` (object, null when undecoded). Written straight to the output with
/// `serde_json::to_writer`.
#[derive(Serialize)]
pub struct Json<'a> {
    /// The packet's stream offset, first, when the caller gives it (`packet decode --file`).
    #[serde(skip_serializing_if = "Option::is_none")]
    offset: Option<u64>,
    kind: &'static str,
    did: Option<u8>,
    cid: Option<u8>,
    seq: Option<u8>,
    mrsp: Option<u8>,
    mrsp_name: Option<String>,
    id_code: Option<u8>,
    data: HexJson<'a>,
    checksum_ok: bool,
    command: Option<&'static str>,
    fields: Option<FieldsJson<'a>>,
}

impl Json<'_> {
    /// The same object with the packet's stream offset as its first key.
    pub fn at(mut self, offset: u64) -> Self {
        self.offset = Some(offset);
        self
    }
}

/// The JSON form of `p`, explained as `d`.
pub fn json<'a>(p: &'a Packet, d: &'a Described, checksum_ok: bool) -> Json<'a> {
    let (did, cid, seq, mrsp, id_code) = match p {
        Packet::Command(c) => (Some(c.did), Some(c.cid), Some(c.seq), None, None),
        Packet::Response(r) => (None, None, Some(r.seq), Some(r.mrsp), None),
        Packet::Async(a) => (None, None, None, None, Some(a.id_code)),
    };
    Json {
        offset: None,
        kind: p.kind().name(),
        did,
        cid,
        seq,
        mrsp: mrsp.map(Mrsp::to_byte),
        mrsp_name: mrsp.map(Mrsp::name),
        id_code,
        data: HexJson(p.data()),
        checksum_ok,
        command: d.name,
        fields: d.fields.as_deref().map(FieldsJson),
    }
}

/// The JSON object as a value, for tests and tools that look inside (output goes through
/// [`json`]).
pub fn to_json(p: &Packet, d: &Described, checksum_ok: bool) -> serde_json::Value {
    serde_json::to_value(json(p, d, checksum_ok)).unwrap_or(serde_json::Value::Null)
}

/// SOP2 option bits of a command, by name.
fn sop2_names(sop2: u8) -> String {
    let names: Vec<&str> = [
        (SOP2_ANSWER, "answer"),
        (SOP2_RESET_TIMEOUT, "reset_timeout"),
    ]
    .into_iter()
    .filter(|(bit, _)| sop2 & bit != 0)
    .map(|(_, n)| n)
    .collect();
    if names.is_empty() {
        "(none)".into()
    } else {
        names.join(" | ")
    }
}

/// `packet decode`'s text: one `key value` line per header field, then the payload's fields.
/// `received` is the wire as it arrived when the checksum failed (`None` when it was fine).
pub fn text(p: &Packet, received: Option<&[u8]>, d: &Described) -> String {
    let encoded = p.encode().ok();
    let mut s = String::new();
    let mut line = |k: &str, v: String| s.push_str(&format!("{k:<9} {v}\n"));
    let wire = received.or(encoded.as_deref());
    line(
        "wire",
        wire.map_or_else(|| "(cannot be framed)".into(), hex::spaced),
    );
    match p {
        Packet::Command(c) => {
            line("sop2", format!("0x{:02X} {}", c.sop2, sop2_names(c.sop2)));
            line(
                "device",
                format!("{} (0x{:02X})", Device::describe(c.did), c.did),
            );
            line(
                "command",
                format!("{} (0x{:02X})", d.name.unwrap_or("unknown"), c.cid),
            );
            line("seq", c.seq.to_string());
        }
        Packet::Response(r) => {
            line("sop2", format!("0x{SOP2_RESPONSE:02X} response"));
            line(
                "response",
                match d.name {
                    Some(n) => format!("{n} (named by --request)"),
                    None => {
                        "unknown command (a v1 response does not name it; see --request)".into()
                    }
                },
            );
            line("seq", r.seq.to_string());
            line("mrsp", format!("0x{:02X} {}", r.mrsp.to_byte(), r.mrsp));
        }
        Packet::Async(a) => {
            line("sop2", format!("0x{SOP2_ASYNC:02X} async"));
            line(
                "async",
                format!(
                    "{} (id 0x{:02X})",
                    catalog::async_name(a.id_code),
                    a.id_code
                ),
            );
        }
    }
    let data = p.data();
    line(
        "data",
        if data.is_empty() {
            "(none)".into()
        } else {
            hex::spaced(data)
        },
    );
    if let Some(fields) = &d.fields {
        for (name, v) in fields {
            line(&format!("  {name}"), v.to_string());
        }
    }
    if let Some(problem) = &d.problem {
        line("note", problem.clone());
    }
    let chk = encoded
        .as_ref()
        .and_then(|w| w.last().copied())
        .unwrap_or(0);
    line(
        "checksum",
        if received.is_none() {
            format!("0x{chk:02X} ok")
        } else {
            format!("BAD (the packet's checksum does not match; 0x{chk:02X} expected)")
        },
    );
    s
}

/// One line for a trace: `command roll seq 3: speed=128 … [FF FF …]`.
pub fn line(p: &Packet, d: &Described) -> String {
    let head = match p {
        Packet::Command(c) => format!(" seq {}", c.seq),
        Packet::Response(r) => format!(" seq {} {}", r.seq, r.mrsp),
        Packet::Async(_) => String::new(),
    };
    let wire = p.encode().map(|w| hex::spaced(&w)).unwrap_or_default();
    format!(
        "{} {}{head}{} [{wire}]",
        d.kind.name(),
        d.label(p),
        crate::protocol::v2::describe::tail(&d.fields, &d.problem),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::v1::{AsyncPacket, Response, cmd};

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
        assert_eq!(d.name, Some("get-rgb-led"));
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
        let j = serde_json::to_value(json(&p, &d, true)).unwrap();
        assert_eq!(j["kind"], "async");
        assert_eq!(j["id_code"], 5);
        assert!(j["did"].is_null() && j["mrsp"].is_null());
        let keys: Vec<&str> = j.as_object().unwrap().keys().map(String::as_str).collect();
        assert_eq!(keys, JSON_KEYS);
        assert_eq!(j["command"], "pre-sleep-warning");
        assert_eq!(j["fields"], serde_json::json!({}));
    }
}
