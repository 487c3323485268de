//! `droidctl packet --protocol v1`: Sphero API v1 (BB-8, SPRK+, Ollie): decode, encode, list.

use super::{
    CliError, Output, byte_opt, data_opt, expect_one, io_err, params_text, uint_opt,
    unknown_command,
};
use crate::hex;
use crate::protocol::v1::packet::{SOP2_ANSWER, SOP2_ASYNC, SOP2_RESET_TIMEOUT, SOP2_RESPONSE};
use crate::protocol::v1::{
    Command, CommandPacket, DecodeError, DecodeErrorKind, Decoder, Described, Device, Packet,
    Source, StreamingConfig, catalog, describe, to_json,
};
use serde_json::{Value, json};
use std::io::Write;

/// The keys of a packet's JSON object, in order. [`to_json`] has two more (`sop2`,
/// `problem`) that the `packet decode` format leaves out.
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

/// What `decode` needs beyond the bytes.
#[derive(Debug, Clone)]
pub(super) struct DecodeOpts {
    pub source: Source,
    /// Set Data Streaming's MASK and MASK2 in effect, to name sensor values.
    pub mask: Option<u32>,
    pub mask2: Option<u32>,
    /// Set Data Streaming's M (frames per packet).
    pub frames: Option<u16>,
    /// The command the responses answer.
    pub request: Option<Command>,
}

impl DecodeOpts {
    pub(super) fn streaming(&self) -> Result<Option<StreamingConfig>, CliError> {
        if self.mask.is_none() && self.mask2.is_none() {
            if self.frames.is_some() {
                return Err(CliError::usage(
                    "--frames needs the masks in effect: --sensor-mask and/or --mask2",
                ));
            }
            return Ok(None);
        }
        Ok(Some(StreamingConfig {
            n: 1,
            m: self.frames.unwrap_or(1),
            mask: self.mask.unwrap_or(0),
            pcnt: 0,
            mask2: self.mask2.unwrap_or(0),
        }))
    }
}

/// `--from host|droid`.
pub(super) fn parse_source(text: &str) -> Result<Source, CliError> {
    if text.eq_ignore_ascii_case("host") {
        Ok(Source::Host)
    } else if text.eq_ignore_ascii_case("droid") {
        Ok(Source::Droid)
    } else {
        Err(CliError::usage(format!(
            "--from: unknown side {text:?}; use host or droid"
        )))
    }
}

/// `--frames M`: 1..=65535.
pub(super) fn parse_frames(text: &str) -> Result<u16, CliError> {
    match uint_opt("frames", text, u16::MAX as u64)? {
        0 => Err(CliError::usage("--frames: a packet holds at least 1 frame")),
        m => Ok(m as u16),
    }
}

/// `--request NAME`: a v1 catalogue command.
pub(super) fn parse_request(name: &str) -> Result<Command, CliError> {
    let def = catalog::by_name(name).ok_or_else(|| {
        let msg = unknown_command(name, catalog::suggestions(name), " --protocol v1");
        CliError::usage(format!("--request: {msg}"))
    })?;
    Ok(Command {
        did: def.did,
        cid: def.cid,
        data: Vec::new(),
    })
}

/// One item of decoded output.
enum Item {
    Packet { packet: Packet, checksum_ok: bool },
    Error(DecodeError),
}

impl From<Result<Packet, DecodeError>> for Item {
    fn from(r: Result<Packet, DecodeError>) -> Self {
        match r {
            Ok(packet) => Item::Packet {
                packet,
                checksum_ok: true,
            },
            Err(e) => Item::Error(e),
        }
    }
}

pub(super) fn decode(
    bytes: &[u8],
    output: Output,
    opts: &DecodeOpts,
    out: &mut dyn Write,
) -> Result<i32, CliError> {
    let Output { stream, json } = output;
    let streaming = opts.streaming()?;
    let mut decoder = Decoder::new(opts.source);
    let mut items: Vec<Item> = decoder.feed(bytes).map(Item::from).collect();
    items.extend(decoder.finish().into_iter().map(Item::from));

    if !stream {
        // One packet expected. A bad checksum still shows the packet, with the verdict.
        let item = match expect_one(items, "packets or errors")? {
            Item::Error(DecodeError {
                packet: Some(packet),
                kind: DecodeErrorKind::BadChecksum,
                ..
            }) => Item::Packet {
                packet: *packet,
                checksum_ok: false,
            },
            other => other,
        };
        items = vec![item];
    }

    let mut status = 0;
    for (i, item) in items.iter().enumerate() {
        if i > 0 && !json {
            writeln!(out).map_err(io_err)?;
        }
        match item {
            Item::Packet {
                packet,
                checksum_ok,
            } => {
                if !checksum_ok {
                    status = 1;
                }
                let d = describe(packet, streaming.as_ref(), opts.request.as_ref());
                if json {
                    writeln!(out, "{}", packet_json(packet, &d, *checksum_ok)).map_err(io_err)?;
                } else {
                    // A bad checksum only comes out of a single-packet decode, where the input
                    // is exactly the packet: show it as received, not re-encoded.
                    let received = (!checksum_ok).then_some(bytes);
                    write!(out, "{}", packet_text(packet, received, &d)).map_err(io_err)?;
                }
            }
            Item::Error(e) => {
                status = 1;
                if json {
                    let v = json!({"error": e.kind.name(), "offset": e.offset, "detail": e.detail});
                    writeln!(out, "{v}").map_err(io_err)?;
                } else {
                    writeln!(out, "decode error: {e}").map_err(io_err)?;
                    if !stream {
                        writeln!(out, "hint: {}", side_hint(opts.source)).map_err(io_err)?;
                    }
                }
            }
        }
    }
    // A stream with garbage is still a successful decode of what was there.
    Ok(if stream { 0 } else { status })
}

/// The same bytes read from the other side may make sense.
fn side_hint(source: Source) -> &'static str {
    match source {
        Source::Host => {
            "read as sent by the host (commands); responses and async messages need --from droid"
        }
        Source::Droid => {
            "read as sent by the droid (responses, async messages); commands need --from host"
        }
    }
}

/// The JSON object for one packet: exactly [`JSON_KEYS`], null where a key does not apply.
pub fn packet_json(p: &Packet, d: &Described, checksum_ok: bool) -> Value {
    let full = to_json(p, d, checksum_ok);
    Value::Object(
        JSON_KEYS
            .iter()
            .map(|k| {
                (
                    (*k).to_string(),
                    full.get(*k).cloned().unwrap_or(Value::Null),
                )
            })
            .collect(),
    )
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

/// `received` is the wire as it arrived when the checksum failed (`None` when it was fine).
pub(super) fn packet_text(p: &Packet, received: Option<&[u8]>, d: &Described) -> String {
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
                format!(
                    "{} (0x{:02X})",
                    d.name.as_deref().unwrap_or("unknown"),
                    c.cid
                ),
            );
            line("seq", c.seq.to_string());
        }
        Packet::Response(r) => {
            line("sop2", format!("0x{SOP2_RESPONSE:02X} response"));
            line(
                "response",
                match &d.name {
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

/// Build the wire bytes of a v1 command: a catalogue name with its parameters, or `raw`.
/// Header options: `--seq N` (0..=255), `--no-response` (clears SOP2's answer bit),
/// `--no-reset-timeout` (clears its reset-timeout bit).
pub(super) fn encode(name: &str, given: Vec<(String, String)>) -> Result<Vec<u8>, CliError> {
    let is_raw = name == "raw";
    let (mut seq, mut answer, mut reset_timeout) = (0, true, true);
    let mut params = Vec::new();
    let (mut did, mut cid, mut data) = (None, None, Vec::new());
    for (k, v) in given {
        match k.as_str() {
            "seq" => seq = byte_opt(&k, &v, 255)?,
            "no-response" => answer = false,
            "no-reset-timeout" => reset_timeout = false,
            "tid" | "sid" => {
                return Err(CliError::usage(format!(
                    "--{k}: API v1 packets have no target or source id"
                )));
            }
            "did" if is_raw => did = Some(byte_opt(&k, &v, 255)?),
            "cid" if is_raw => cid = Some(byte_opt(&k, &v, 255)?),
            "data" if is_raw => data = data_opt(&v)?,
            _ => params.push((k, v)),
        }
    }
    let (did, cid, data) = if is_raw {
        if let Some((k, _)) = params.first() {
            return Err(CliError::usage(format!(
                "raw takes --did, --cid and --data, not --{k}"
            )));
        }
        let did = did.ok_or_else(|| CliError::usage("raw needs --did"))?;
        let cid = cid.ok_or_else(|| CliError::usage("raw needs --cid"))?;
        (did, cid, data)
    } else {
        let def = catalog::by_name(name).ok_or_else(|| {
            CliError::usage(unknown_command(
                name,
                catalog::suggestions(name),
                " --protocol v1",
            ))
        })?;
        let data = def.encode_params(&params).map_err(CliError::usage)?;
        (def.did, def.cid, data)
    };
    let packet = CommandPacket::new(did, cid, seq, data).with_options(answer, reset_timeout);
    Packet::Command(packet)
        .encode()
        .map_err(|e| CliError::usage(e.to_string()))
}

pub(super) fn list(filter: Option<&str>, out: &mut dyn Write) -> std::io::Result<()> {
    let keep = |n: &str| filter.is_none_or(|f| n.contains(f));
    writeln!(out, "Commands (DID/CID  name  parameters):")?;
    for c in catalog::commands().iter().filter(|c| keep(&c.name)) {
        let line = format!(
            "  {:02X}/{:02X}  {:<30} {}",
            c.did,
            c.cid,
            c.name,
            params_text(c.params)
        );
        writeln!(out, "{}", line.trim_end())?;
    }
    writeln!(out, "Async messages (ID  name  fields):")?;
    for a in catalog::async_messages().iter().filter(|a| keep(a.name)) {
        let fields: Vec<_> = a.fields.iter().map(|f| f.name).collect();
        let line = format!(
            "  {:02X}     {:<30} {}",
            a.id_code,
            a.name,
            fields.join(" ")
        );
        writeln!(out, "{}", line.trim_end())?;
    }
    Ok(())
}
