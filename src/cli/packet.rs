//! `droidctl packet`: decode bytes into explained packets, encode catalogue commands.

use super::CliError;
use crate::hex;
use crate::protocol::v2::catalog::{self, FieldDef};
use crate::protocol::v2::wire::parse_uint;
use crate::protocol::v2::{
    DecodeError, Decoder, Described, Device, Flags, Kind, Packet, StreamingConfig, describe, value,
};
use clap::Subcommand;
use serde_json::json;
use std::io::Write;

#[derive(Debug, Subcommand)]
pub enum PacketCmd {
    /// Decode hex bytes (spaces, colons and 0x prefixes are fine).
    Decode {
        /// The bytes, as one or more hex words.
        #[arg(required = true, num_args = 1..)]
        hex: Vec<String>,
        /// Treat the input as a byte stream holding many packets and garbage.
        #[arg(long)]
        stream: bool,
        /// One JSON object per line.
        #[arg(long)]
        json: bool,
        /// Standard sensor-streaming mask in effect, to name sensor values (e.g. 0x0007E078).
        #[arg(long, value_name = "MASK")]
        sensor_mask: Option<String>,
        /// Extended sensor-streaming mask in effect (e.g. 0x07800000).
        #[arg(long, value_name = "MASK", requires = "sensor_mask")]
        ext_mask: Option<String>,
    },
    /// Encode a catalogue command as wire bytes: `encode NAME [--param value ...]
    /// [--seq N] [--tid N] [--sid N] [--no-response]`, or `encode raw --did N --cid N [--data HEX]`.
    #[command(disable_help_flag = false)]
    Encode {
        /// Command name (see `droidctl packet list`), or `raw`.
        name: String,
        /// Parameters as `--name value`, plus --seq, --tid, --sid, --no-response.
        #[arg(
            trailing_var_arg = true,
            allow_hyphen_values = true,
            value_name = "ARGS"
        )]
        args: Vec<String>,
    },
    /// List every catalogue command and notification with its parameters.
    List {
        /// Only names containing this text.
        filter: Option<String>,
    },
}

pub fn run(cmd: PacketCmd, out: &mut dyn Write) -> Result<i32, CliError> {
    match cmd {
        PacketCmd::Decode {
            hex,
            stream,
            json,
            sensor_mask,
            ext_mask,
        } => {
            let bytes = hex::parse(&hex.join(" ")).map_err(CliError::usage)?;
            let streaming = match sensor_mask {
                Some(m) => {
                    let mask = parse_uint(&m, u32::MAX as u64)
                        .map_err(|e| CliError::usage(format!("--sensor-mask: {e}")))?;
                    let ext = match ext_mask {
                        Some(e) => parse_uint(&e, u32::MAX as u64)
                            .map_err(|e| CliError::usage(format!("--ext-mask: {e}")))?,
                        None => 0,
                    };
                    Some(StreamingConfig {
                        mask: mask as u32,
                        ext_mask: ext as u32,
                        interval_ms: 1,
                    })
                }
                None => None,
            };
            decode(&bytes, stream, json, streaming.as_ref(), out)
        }
        PacketCmd::Encode { name, args } => {
            let wire = encode(&name, &args)?;
            writeln!(out, "{}", hex::spaced(&wire)).map_err(io_err)?;
            Ok(0)
        }
        PacketCmd::List { filter } => {
            list(filter.as_deref(), out).map_err(io_err)?;
            Ok(0)
        }
    }
}

fn io_err(e: std::io::Error) -> CliError {
    CliError::output(e)
}

/// One item of decoded output.
enum Item {
    Packet { packet: Packet, checksum_ok: bool },
    Error(DecodeError),
}

fn decode(
    bytes: &[u8],
    stream: bool,
    json: bool,
    streaming: Option<&StreamingConfig>,
    out: &mut dyn Write,
) -> Result<i32, CliError> {
    let mut decoder = Decoder::new();
    let mut items: Vec<Item> = decoder
        .feed(bytes)
        .map(|r| match r {
            Ok(packet) => Item::Packet {
                packet,
                checksum_ok: true,
            },
            Err(e) => Item::Error(e),
        })
        .collect();
    items.extend(decoder.finish().into_iter().map(Item::Error));

    if !stream {
        // One packet expected. A bad checksum still shows the packet, with the verdict.
        let packets = items
            .iter()
            .filter(|i| matches!(i, Item::Packet { .. }))
            .count();
        if packets > 1 || items.len() > 1 {
            return Err(CliError::usage(format!(
                "the input holds {} packets or errors, not one packet; use --stream to decode a byte stream",
                items.len()
            )));
        }
        match items.pop() {
            None => return Err(CliError::usage("no bytes to decode")),
            Some(Item::Error(DecodeError {
                packet: Some(packet),
                kind: crate::protocol::v2::DecodeErrorKind::BadChecksum,
                ..
            })) => {
                items.push(Item::Packet {
                    packet: *packet,
                    checksum_ok: false,
                });
            }
            Some(other) => items.push(other),
        }
    }

    let mut status = 0;
    for (i, item) in items.iter().enumerate() {
        match item {
            Item::Packet {
                packet,
                checksum_ok,
            } => {
                if !checksum_ok {
                    status = 1;
                }
                let d = describe(packet, streaming);
                if json {
                    writeln!(out, "{}", packet_json(packet, *checksum_ok, &d)).map_err(io_err)?;
                } else {
                    if i > 0 {
                        writeln!(out).map_err(io_err)?;
                    }
                    // A packet with a bad checksum only comes out of a single-packet decode,
                    // where the input is exactly its wire bytes: show those, not a re-encoding
                    // (which would carry the corrected checksum).
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
                    if i > 0 {
                        writeln!(out).map_err(io_err)?;
                    }
                    writeln!(out, "decode error: {e}").map_err(io_err)?;
                }
            }
        }
    }
    // A stream with garbage is still a successful decode of what was there.
    Ok(if stream { 0 } else { status })
}

/// The JSON object for one packet (field names documented in README).
pub fn packet_json(p: &Packet, checksum_ok: bool, d: &Described) -> serde_json::Value {
    json!({
        "kind": d.kind.name(),
        "did": p.did,
        "cid": p.cid,
        "seq": p.seq,
        "flags": p.flags.bits(),
        "flag_names": p.flags.names(),
        "ext_flags": p.ext_flags,
        "tid": p.tid,
        "sid": p.sid,
        "err": p.err.map(|e| e.to_byte()),
        "err_name": p.err.map(|e| e.name()),
        "data": hex::compact(&p.data),
        "checksum_ok": checksum_ok,
        "command": d.name,
        "fields": d.fields.as_ref().map(value::fields_json),
        "problem": d.problem,
    })
}

/// `received` is the wire as it arrived when the checksum failed (`None` when it was fine).
fn packet_text(p: &Packet, received: Option<&[u8]>, d: &Described) -> String {
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
        format!(
            "{} (0x{:02X})",
            d.name.as_deref().unwrap_or("unknown"),
            p.cid
        ),
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
    let chk = crate::protocol::v2::packet::checksum(&p.body());
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

/// Header options of `packet encode`.
#[derive(Debug, Default)]
struct Header {
    seq: u8,
    tid: Option<u8>,
    sid: Option<u8>,
    no_response: bool,
}

/// Split `--key value` / `--key=value` pairs; flags without a value are `""`.
fn pairs(args: &[String]) -> Result<Vec<(String, String)>, CliError> {
    let mut out = Vec::new();
    let mut it = args.iter().peekable();
    while let Some(a) = it.next() {
        let Some(key) = a.strip_prefix("--") else {
            return Err(CliError::usage(format!(
                "unexpected argument {a:?}: parameters are given as --name value"
            )));
        };
        if let Some((k, v)) = key.split_once('=') {
            out.push((k.to_string(), v.to_string()));
        } else if key == "no-response" {
            out.push((key.to_string(), String::new()));
        } else {
            let v = it
                .next()
                .ok_or_else(|| CliError::usage(format!("--{key} needs a value")))?;
            out.push((key.to_string(), v.clone()));
        }
    }
    Ok(out)
}

fn byte_opt(key: &str, v: &str, max: u64) -> Result<u8, CliError> {
    parse_uint(v, max)
        .map(|n| n as u8)
        .map_err(|e| CliError::usage(format!("--{key}: {e}")))
}

/// Build the wire bytes for `packet encode`.
pub fn encode(name: &str, args: &[String]) -> Result<Vec<u8>, CliError> {
    let mut header = Header::default();
    let mut params = Vec::new();
    let mut raw = (None, None, Vec::new());
    for (k, v) in pairs(args)? {
        match k.as_str() {
            // 0xFF marks notifications: never a request's SEQ.
            "seq" => header.seq = byte_opt(&k, &v, 254)?,
            "tid" => header.tid = Some(byte_opt(&k, &v, 255)?),
            "sid" => header.sid = Some(byte_opt(&k, &v, 255)?),
            "no-response" => header.no_response = true,
            "did" if name == "raw" => raw.0 = Some(byte_opt(&k, &v, 255)?),
            "cid" if name == "raw" => raw.1 = Some(byte_opt(&k, &v, 255)?),
            "data" if name == "raw" => {
                raw.2 = hex::parse(&v).map_err(|e| CliError::usage(format!("--data: {e}")))?
            }
            _ => params.push((k, v)),
        }
    }
    let (did, cid, data) = if name == "raw" {
        if let Some((k, _)) = params.first() {
            return Err(CliError::usage(format!(
                "raw takes --did, --cid and --data, not --{k}"
            )));
        }
        let did = raw.0.ok_or_else(|| CliError::usage("raw needs --did"))?;
        let cid = raw.1.ok_or_else(|| CliError::usage("raw needs --cid"))?;
        (did, cid, raw.2)
    } else {
        let def = catalog::by_name(name).ok_or_else(|| {
            let hint = catalog::suggestions(name);
            let hint = if hint.is_empty() {
                "see `droidctl packet list`".to_string()
            } else {
                format!("did you mean {}?", hint.join(", "))
            };
            CliError::usage(format!("unknown command {name:?}; {hint}"))
        })?;
        let data = def.encode_params(&params).map_err(CliError::usage)?;
        check_led_values(def.name.as_str(), &data)?;
        (def.did(), def.cid, data)
    };
    let mut p = Packet::command(did, cid, header.seq, data);
    if header.no_response {
        p.flags.remove(Flags::REQUESTS_RESPONSE);
    }
    p.tid = header.tid;
    p.sid = header.sid;
    Ok(p.normalized().encode())
}

/// The LED mask commands carry one value per set mask bit; catch a mismatch before the droid
/// answers bad_data_length.
fn check_led_values(name: &str, data: &[u8]) -> Result<(), CliError> {
    let width = match name {
        "set-all-leds-with-8-bit-mask" => 1,
        "set-all-leds-with-16-bit-mask" => 2,
        "set-all-leds-with-32-bit-mask" => 4,
        _ => return Ok(()),
    };
    let mask = data[..width].iter().fold(0u32, |a, &b| (a << 8) | b as u32);
    let values = data.len() - width;
    if values != mask.count_ones() as usize {
        return Err(CliError::usage(format!(
            "--values: mask 0x{mask:0w$X} has {} bit(s) set, so it needs {} value byte(s), got {values}",
            mask.count_ones(),
            mask.count_ones(),
            w = width * 2
        )));
    }
    Ok(())
}

fn params_text(params: &[FieldDef]) -> String {
    params
        .iter()
        .map(|p| format!("--{} <{}>", p.option(), p.description))
        .collect::<Vec<_>>()
        .join(" ")
}

fn list(filter: Option<&str>, out: &mut dyn Write) -> std::io::Result<()> {
    let keep = |n: &str| filter.is_none_or(|f| n.contains(f));
    writeln!(out, "Commands (DID/CID  name  parameters):")?;
    for c in catalog::commands().iter().filter(|c| keep(&c.name)) {
        writeln!(
            out,
            "  {:02X}/{:02X}  {:<44} {}",
            c.did(),
            c.cid,
            c.name,
            params_text(c.params)
        )?;
    }
    writeln!(out, "Notifications (DID/CID  name  fields):")?;
    for n in catalog::notifications().iter().filter(|n| keep(&n.name)) {
        let fields: Vec<_> = n.fields.iter().map(|f| f.name).collect();
        writeln!(
            out,
            "  {:02X}/{:02X}  {:<44} {}",
            n.device.id(),
            n.cid,
            n.name,
            fields.join(" ")
        )?;
    }
    Ok(())
}
