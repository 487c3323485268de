//! A v2 packet explained for people and tools: its catalogue name and decoded payload
//! ([`describe`]), the JSON object `packet decode --json` and the traces print ([`json`]), the
//! multi-line text of `packet decode` ([`text`]) and the one line of a trace ([`line`]).

use super::catalog;
use super::device::Device;
use super::packet::{Packet, checksum};
use super::sensor::{self, StreamingConfig};
use crate::hex;
use crate::protocol::value::{Fields, FieldsJson, HexJson, fields_line};
use serde::Serialize;

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
    pub name: Option<&'static str>,
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
                Some(def.name.as_str()),
                Some(if kind == Kind::Command {
                    def.params
                } else {
                    def.response
                }),
            ),
            None => (None, None),
        },
        Kind::Notification => match catalog::notification(p.did, p.cid) {
            Some(def) => (Some(def.name.as_str()), Some(def.fields)),
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
        match self.name {
            Some(n) => n.to_string(),
            None => format!("{}/0x{:02X}", Device::describe(p.did), p.cid),
        }
    }
}

/// The JSON object for one packet (field names documented in README): written straight to
/// the output with `serde_json::to_writer`, no `Value` tree in between.
#[derive(Serialize)]
pub struct Json<'a> {
    /// The packet's stream offset, first, when the caller gives it (`packet decode --file`).
    #[serde(skip_serializing_if = "Option::is_none")]
    offset: Option<u64>,
    kind: &'static str,
    did: u8,
    cid: u8,
    seq: u8,
    flags: u8,
    flag_names: FlagNames,
    ext_flags: Option<u8>,
    tid: Option<u8>,
    sid: Option<u8>,
    err: Option<u8>,
    err_name: Option<std::borrow::Cow<'static, str>>,
    data: HexJson<'a>,
    checksum_ok: bool,
    command: Option<&'static str>,
    fields: Option<FieldsJson<'a>>,
    problem: Option<&'a str>,
}

/// The flags' names as a JSON array, written without collecting them.
struct FlagNames(super::Flags);

impl Serialize for FlagNames {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.0.name_iter())
    }
}

impl Json<'_> {
    /// The same object with the packet's stream offset as its first key.
    pub fn at(mut self, offset: u64) -> Self {
        self.offset = Some(offset);
        self
    }
}

/// The JSON form of `p`, explained as `d`.
pub fn json<'a>(p: &'a Packet, checksum_ok: bool, d: &'a Described) -> Json<'a> {
    Json {
        offset: None,
        kind: d.kind.name(),
        did: p.did,
        cid: p.cid,
        seq: p.seq,
        flags: p.flags.bits(),
        flag_names: FlagNames(p.flags),
        ext_flags: p.ext_flags,
        tid: p.tid,
        sid: p.sid,
        err: p.err.map(|e| e.to_byte()),
        err_name: p.err.map(|e| e.name_cow()),
        data: HexJson(&p.data),
        checksum_ok,
        command: d.name,
        fields: d.fields.as_deref().map(FieldsJson),
        problem: d.problem.as_deref(),
    }
}

/// `packet decode`'s text: one `key value` line per header field, then the payload's fields.
/// `received` is the wire as it arrived when the checksum failed (`None` when it was fine):
/// shown as received, not re-encoded with a corrected checksum.
pub fn text(p: &Packet, received: Option<&[u8]>, d: &Described) -> String {
    let checksum_ok = received.is_none();
    let mut s = String::new();
    let mut line = |k: &str, v: String| s.push_str(&format!("{k:<9} {v}\n"));
    line(
        "wire",
        hex::spaced(&received.map_or_else(|| p.encode(), <[u8]>::to_vec)),
    );
    let names = p.flags.names();
    line(
        "flags",
        format!(
            "0x{:02X} {}",
            p.flags.bits(),
            if names.is_empty() {
                "(none)".into()
            } else {
                names.join(" | ")
            }
        ),
    );
    if let Some(x) = p.ext_flags {
        line("ext flags", format!("0x{x:02X}"));
    }
    if let Some(t) = p.tid {
        line(
            "target",
            format!("0x{t:02X} (port {}, node {})", t >> 4, t & 0xF),
        );
    }
    if let Some(t) = p.sid {
        line(
            "source",
            format!("0x{t:02X} (port {}, node {})", t >> 4, t & 0xF),
        );
    }
    line(
        "device",
        format!("{} (0x{:02X})", Device::describe(p.did), p.did),
    );
    line(
        d.kind.name(),
        format!("{} (0x{:02X})", d.name.unwrap_or("unknown"), p.cid),
    );
    line(
        "seq",
        if d.kind == Kind::Notification {
            format!("{} (notification)", p.seq)
        } else {
            p.seq.to_string()
        },
    );
    if let Some(e) = p.err {
        line("error", format!("0x{:02X} {e}", e.to_byte()));
    }
    line(
        "data",
        if p.data.is_empty() {
            "(none)".into()
        } else {
            hex::spaced(&p.data)
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
    let chk = checksum(&p.body());
    line(
        "checksum",
        if checksum_ok {
            format!("0x{chk:02X} ok")
        } else {
            format!("BAD (the packet's checksum does not match; 0x{chk:02X} expected)")
        },
    );
    s
}

/// One line for a trace: `command drive-with-heading seq 3: speed=60 … [8D …]`.
pub fn line(p: &Packet, d: &Described) -> String {
    let err = p
        .err
        .filter(|e| !e.is_success())
        .map(|e| format!(" error {}", e.name()))
        .unwrap_or_default();
    format!(
        "{} {} seq {}{err}{} [{}]",
        d.kind.name(),
        d.label(p),
        p.seq,
        tail(&d.fields, &d.problem),
        hex::spaced(&p.encode())
    )
}

/// `: fields` or `: problem`, or nothing: the end of a one-line description.
pub fn tail(fields: &Option<Fields>, problem: &Option<String>) -> String {
    match (fields, problem) {
        (Some(f), _) if !f.is_empty() => format!(": {}", fields_line(f)),
        (None, Some(p)) => format!(": {p}"),
        _ => String::new(),
    }
}
