//! `droidctl packet` for Sphero API v2: decode, encode, list.

use super::{
    CliError, Output, byte_opt, data_opt, expect_one, io_err, pairs, params_text, unknown_command,
};
use crate::hex;
use crate::protocol::v2::catalog;
use crate::protocol::v2::{
    DecodeError, DecodeErrorKind, Decoder, Described, Device, Flags, Kind, Packet, StreamingConfig,
    describe, value,
};
use serde_json::json;
use std::io::Write;

/// One item of decoded output.
enum Item {
    Packet { packet: Packet, checksum_ok: bool },
    Error(DecodeError),
}

/// Decode `bytes`: one packet, or a stream with `output.stream`. The masks name sensor
/// values (`ext_mask` needs `mask`).
pub(super) fn decode(
    bytes: &[u8],
    output: Output,
    mask: Option<u32>,
    ext_mask: Option<u32>,
    out: &mut dyn Write,
) -> Result<i32, CliError> {
    let Output { stream, json } = output;
    let streaming = mask.map(|mask| StreamingConfig {
        mask,
        ext_mask: ext_mask.unwrap_or(0),
        interval_ms: 1,
    });
    let streaming = streaming.as_ref();
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
pub(super) fn packet_text(p: &Packet, received: Option<&[u8]>, d: &Described) -> String {
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

/// Build the wire bytes for `packet encode NAME ARGS...` (v2).
pub fn encode(name: &str, args: &[String]) -> Result<Vec<u8>, CliError> {
    encode_pairs(name, pairs(args)?)
}

/// Build the wire bytes from `--key value` pairs already split.
pub(super) fn encode_pairs(name: &str, given: Vec<(String, String)>) -> Result<Vec<u8>, CliError> {
    let mut header = Header::default();
    let mut params = Vec::new();
    let mut raw = (None, None, Vec::new());
    for (k, v) in given {
        match k.as_str() {
            // 0xFF marks notifications: never a request's SEQ.
            "seq" => header.seq = byte_opt(&k, &v, 254)?,
            "tid" => header.tid = Some(byte_opt(&k, &v, 255)?),
            "sid" => header.sid = Some(byte_opt(&k, &v, 255)?),
            "no-response" => header.no_response = true,
            "did" if name == "raw" => raw.0 = Some(byte_opt(&k, &v, 255)?),
            "cid" if name == "raw" => raw.1 = Some(byte_opt(&k, &v, 255)?),
            "data" if name == "raw" => raw.2 = data_opt(&v)?,
            "no-reset-timeout" => {
                return Err(CliError::usage(
                    "--no-reset-timeout is an API v1 option (--protocol v1); v2 has no such bit",
                ));
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
            CliError::usage(unknown_command(name, catalog::suggestions(name), ""))
        })?;
        let data = def.encode_params(&params).map_err(CliError::usage)?;
        check_led_values(def.name.as_str(), &data)?;
        (def.did, def.cid, data)
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
    let Some(mask_bytes) = data.get(..width) else {
        return Ok(());
    };
    let mask = mask_bytes.iter().fold(0u32, |a, &b| (a << 8) | b as u32);
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

pub(super) fn list(filter: Option<&str>, out: &mut dyn Write) -> std::io::Result<()> {
    let keep = |n: &str| filter.is_none_or(|f| n.contains(f));
    writeln!(out, "Commands (DID/CID  name  parameters):")?;
    for c in catalog::commands().iter().filter(|c| keep(&c.name)) {
        writeln!(
            out,
            "  {:02X}/{:02X}  {:<44} {}",
            c.did,
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
