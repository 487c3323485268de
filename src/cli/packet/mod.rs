//! `droidctl packet`: decode bytes into explained packets, encode packets, list the catalogues,
//! for the three protocol families: Sphero API v2 ([`v2`]), Sphero API v1 ([`v1`]) and the
//! Robi 42's RSRCP ([`rsrcp`]).
//!
//! This file holds the arguments, the choice of family (given with `--protocol` or detected
//! from the first start-of-packet byte) and the helpers the families share. Each family's
//! decoding, encoding and listing lives in its own file.

mod btsnoop;
mod file;
mod rsrcp;
mod v1;
mod v2;

pub use file::{FileSummary, decode_reader};
// `DecodeArgs` is public for `decode_reader`.

pub use v1::packet_json as v1_packet_json;
pub use v2::{encode, packet_json};

use super::CliError;
use crate::hex;
use crate::protocol::schema::FieldDef;
use crate::protocol::wire::parse_uint;
use clap::Subcommand;
use std::io::Write;

#[derive(Debug, Subcommand)]
pub enum PacketCmd {
    /// Decode hex bytes, a file or a Bluetooth snoop log into explained packets (v2, v1 or
    /// RSRCP).
    ///
    /// Spaces, colons and 0x prefixes are fine. Without --protocol the family is the one of
    /// the first start-of-packet byte in the input: 8D v2, FF v1, 7E RSRCP (v2 when there is
    /// none). v1 bytes are read as sent by the host unless --from droid says otherwise.
    /// --file reads a byte stream of any size (binary or hex text) in constant memory;
    /// --btsnoop reads an HCI snoop log and decodes the droid's traffic in it.
    Decode {
        /// The bytes, as one or more hex words.
        #[arg(required_unless_present_any = ["file", "btsnoop"], num_args = 1..)]
        hex: Vec<String>,
        /// Decode the byte stream in FILE (`-` for standard input): binary, or hex text
        /// (detected from the first 64 KiB). Implies --stream; ends with a summary.
        #[arg(long, value_name = "FILE", conflicts_with_all = ["hex", "btsnoop"])]
        file: Option<String>,
        /// Decode the droid traffic in an HCI snoop log (btsnoop format: Android's
        /// btsnoop_hci.log, `btmon -w`): ATT writes and notifications, by the characteristic
        /// handles found in the log's GATT discovery (or --handle).
        #[arg(long, value_name = "FILE", conflicts_with = "hex")]
        btsnoop: Option<String>,
        /// With --btsnoop: the ATT handle(s) of the droid's characteristics, for a log that
        /// starts after the GATT discovery (decimal or 0x hex; repeat for several).
        #[arg(long, value_name = "N", requires = "btsnoop")]
        handle: Vec<String>,
        /// With --file or --btsnoop: print only the summary (counts per kind and error kind).
        #[arg(long)]
        summary: bool,
        /// Protocol family: v2 (R2-D2, R2-Q5, BB-9E), v1 (BB-8, SPRK+, Ollie) or rsrcp
        /// (Robi 42). Default: detected from the first SOP byte (8D, FF or 7E).
        #[arg(long, value_name = "v2|v1|rsrcp")]
        protocol: Option<String>,
        /// Who sent v1 bytes: host (commands; the default) or droid (responses and async
        /// messages). A v1 command and a response both start FF FF, so this picks the
        /// reading. v2 and RSRCP packets say what they are: they ignore it.
        #[arg(long, value_name = "host|droid")]
        from: Option<String>,
        /// Treat the input as a byte stream holding many packets and garbage.
        #[arg(long)]
        stream: bool,
        /// One JSON object per line.
        #[arg(long)]
        json: bool,
        /// Sensor-streaming mask in effect, to name sensor values: v2's standard mask
        /// (e.g. 0x0007E078) or v1's MASK of Set Data Streaming (e.g. 0x00077C00).
        #[arg(long, value_name = "MASK")]
        sensor_mask: Option<String>,
        /// v2: extended sensor-streaming mask in effect (e.g. 0x07800000).
        #[arg(long, value_name = "MASK", requires = "sensor_mask")]
        ext_mask: Option<String>,
        /// v1: MASK2 of Set Data Streaming in effect (e.g. 0x0D800000); MASK is 0 without
        /// --sensor-mask.
        #[arg(long, value_name = "MASK")]
        mask2: Option<String>,
        /// v1: frames per sensor-data packet (Set Data Streaming's M; default 1). Needs
        /// --sensor-mask or --mask2.
        #[arg(long, value_name = "M")]
        frames: Option<String>,
        /// v1: the command the responses answer (a v1 response does not name it), to name
        /// and decode their payload, e.g. get-rgb-led.
        #[arg(long, value_name = "NAME")]
        request: Option<String>,
    },
    /// Encode a packet as wire bytes (v2 unless --protocol says otherwise).
    ///
    /// v2: `encode NAME [--param value ...] [--seq N] [--tid N]
    /// [--sid N] [--no-response]`, or `encode raw --did N --cid N [--data HEX]`. v1
    /// (`--protocol v1`): `encode NAME [--param value ...] [--seq N] [--no-response]
    /// [--no-reset-timeout]`, or `raw`. RSRCP (`--protocol rsrcp`): `encode frame
    /// [--frame-id N] [--motors L,R] [--poti N] [--buttons NAMES] [--leds NAMES]
    /// [--piezo HZ|off]` or `encode handshake [--version N] [--msdt MS]`, test input as the
    /// robot would send it.
    #[command(disable_help_flag = false)]
    Encode {
        /// Protocol family: v2 (the default), v1 or rsrcp. May also follow NAME.
        #[arg(long, value_name = "v2|v1|rsrcp")]
        protocol: Option<String>,
        /// Command name (see `droidctl packet list`), or `raw`.
        name: String,
        /// Parameters as `--name value`, plus the header options above.
        #[arg(
            trailing_var_arg = true,
            allow_hyphen_values = true,
            value_name = "ARGS"
        )]
        args: Vec<String>,
    },
    /// List every catalogue command and notification with its parameters (v2 unless
    /// --protocol says otherwise).
    ///
    /// v1 lists commands and async messages; rsrcp the characteristics, the EFS features
    /// with their bits and payload sizes, and the remote-control bytes; all lists the three.
    List {
        /// Only names containing this text.
        filter: Option<String>,
        /// v2 (the default), v1, rsrcp or all.
        #[arg(long, value_name = "v2|v1|rsrcp|all")]
        protocol: Option<String>,
    },
}

/// A protocol family.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Protocol {
    V2,
    V1,
    Rsrcp,
}

impl Protocol {
    pub const ALL: [Protocol; 3] = [Protocol::V2, Protocol::V1, Protocol::Rsrcp];

    pub fn name(self) -> &'static str {
        match self {
            Protocol::V2 => "v2",
            Protocol::V1 => "v1",
            Protocol::Rsrcp => "rsrcp",
        }
    }

    /// The first byte of every packet of this family.
    pub fn sop(self) -> u8 {
        match self {
            Protocol::V2 => 0x8D,
            Protocol::V1 => 0xFF,
            Protocol::Rsrcp => 0x7E,
        }
    }

    fn parse(text: &str) -> Result<Protocol, CliError> {
        Protocol::ALL
            .into_iter()
            .find(|p| p.name().eq_ignore_ascii_case(text))
            .ok_or_else(|| {
                CliError::usage(format!("unknown protocol {text:?}; use v2, v1 or rsrcp"))
            })
    }

    /// The family of the first start-of-packet byte in `bytes` (8D v2, FF v1, 7E RSRCP) and
    /// its offset; `None` when there is none.
    pub fn detect(bytes: &[u8]) -> Option<(Protocol, usize)> {
        bytes.iter().enumerate().find_map(|(i, &b)| {
            Protocol::ALL
                .into_iter()
                .find(|p| p.sop() == b)
                .map(|p| (p, i))
        })
    }
}

/// How `decode` prints.
#[derive(Debug, Clone, Copy)]
struct Output {
    stream: bool,
    json: bool,
}

pub fn run(cmd: PacketCmd, out: &mut dyn Write) -> Result<i32, CliError> {
    match cmd {
        PacketCmd::Decode {
            hex,
            protocol,
            from,
            stream,
            json,
            sensor_mask,
            ext_mask,
            mask2,
            frames,
            request,
            file,
            btsnoop,
            handle,
            summary,
        } => {
            let opts = DecodeArgs {
                protocol,
                from,
                sensor_mask,
                ext_mask,
                mask2,
                frames,
                request,
            };
            if let Some(path) = btsnoop {
                let handles = handle
                    .iter()
                    .map(|h| uint_opt("handle", h, u16::MAX as u64).map(|v| v as u16))
                    .collect::<Result<Vec<_>, _>>()?;
                return btsnoop::decode(&path, opts, &handles, json, summary, out);
            }
            if let Some(path) = file {
                return file::decode_path(&path, opts, json, summary, out);
            }
            if summary {
                return Err(CliError::usage("--summary applies to --file and --btsnoop"));
            }
            let bytes = hex::parse(&hex.join(" ")).map_err(CliError::usage)?;
            decode(&bytes, opts, Output { stream, json }, out)
        }
        PacketCmd::Encode {
            protocol,
            name,
            args,
        } => encode_cmd(protocol, &name, &args, out),
        PacketCmd::List { filter, protocol } => list(filter.as_deref(), protocol.as_deref(), out),
    }
}

/// `decode`'s options other than the bytes and the output form, as given.
#[derive(Debug, Clone, Default)]
pub struct DecodeArgs {
    pub protocol: Option<String>,
    pub from: Option<String>,
    pub sensor_mask: Option<String>,
    pub ext_mask: Option<String>,
    pub mask2: Option<String>,
    pub frames: Option<String>,
    pub request: Option<String>,
}

/// The family to decode `bytes` as: `--protocol`, or the first SOP byte's (v2 without one),
/// with the reason for messages.
fn choose_family(args: &DecodeArgs, bytes: &[u8]) -> Result<(Protocol, String), CliError> {
    Ok(match &args.protocol {
        Some(p) => (Protocol::parse(p)?, String::new()),
        None => match Protocol::detect(bytes) {
            Some((p, at)) => (
                p,
                format!(
                    " (detected from the SOP byte {:02X} at offset {at}; --protocol overrides)",
                    p.sop()
                ),
            ),
            None => (Protocol::V2, String::new()),
        },
    })
}

/// The per-family decoding options, checked against the family.
enum FamilyOpts {
    V2 {
        mask: Option<u32>,
        ext_mask: Option<u32>,
    },
    V1(v1::DecodeOpts),
    Rsrcp,
}

fn decode(
    bytes: &[u8],
    args: DecodeArgs,
    output: Output,
    out: &mut dyn Write,
) -> Result<i32, CliError> {
    let (family, why) = choose_family(&args, bytes)?;
    match family_opts(args, family, &why)? {
        FamilyOpts::V2 { mask, ext_mask } => v2::decode(bytes, output, mask, ext_mask, out),
        FamilyOpts::V1(opts) => v1::decode(bytes, output, &opts, out),
        FamilyOpts::Rsrcp => rsrcp::decode(bytes, output, out),
    }
}

/// Check the options against `family` (`why` says how it was chosen) and parse them.
fn family_opts(args: DecodeArgs, family: Protocol, why: &str) -> Result<FamilyOpts, CliError> {
    // An option another family reads is refused rather than ignored: a mask given for the
    // wrong family would silently change nothing.
    let only = |flag: &str, given: bool, fams: &[Protocol]| -> Result<(), CliError> {
        if given && !fams.contains(&family) {
            let names: Vec<&str> = fams.iter().map(|f| f.name()).collect();
            return Err(CliError::usage(format!(
                "{flag} applies to {} packets, but the input is decoded as {}{why}",
                names.join(" and "),
                family.name()
            )));
        }
        Ok(())
    };
    only("--ext-mask", args.ext_mask.is_some(), &[Protocol::V2])?;
    only("--mask2", args.mask2.is_some(), &[Protocol::V1])?;
    only("--frames", args.frames.is_some(), &[Protocol::V1])?;
    only("--request", args.request.is_some(), &[Protocol::V1])?;
    let sensor_mask = args.sensor_mask.is_some();
    only("--sensor-mask", sensor_mask, &[Protocol::V2, Protocol::V1])?;
    let from = args.from.as_deref().map(v1::parse_source).transpose()?;
    let mask = |flag: &str, text: Option<String>| -> Result<Option<u32>, CliError> {
        text.map(|t| {
            parse_uint(&t, u32::MAX as u64)
                .map(|v| v as u32)
                .map_err(|e| CliError::usage(format!("{flag}: {e}")))
        })
        .transpose()
    };
    let sensor_mask = mask("--sensor-mask", args.sensor_mask)?;
    Ok(match family {
        Protocol::V2 => FamilyOpts::V2 {
            mask: sensor_mask,
            ext_mask: mask("--ext-mask", args.ext_mask)?,
        },
        Protocol::V1 => FamilyOpts::V1(v1::DecodeOpts {
            source: from.unwrap_or(crate::protocol::v1::Source::Host),
            mask: sensor_mask,
            mask2: mask("--mask2", args.mask2)?,
            frames: args.frames.as_deref().map(v1::parse_frames).transpose()?,
            request: args.request.as_deref().map(v1::parse_request).transpose()?,
        }),
        Protocol::Rsrcp => FamilyOpts::Rsrcp,
    })
}

/// `encode`: `--protocol` may come before NAME or among its parameters.
fn encode_cmd(
    protocol: Option<String>,
    name: &str,
    args: &[String],
    out: &mut dyn Write,
) -> Result<i32, CliError> {
    let mut given = protocol;
    let mut params = Vec::new();
    for (k, v) in pairs(args)? {
        if k == "protocol" {
            if given.as_ref().is_some_and(|g| !g.eq_ignore_ascii_case(&v)) {
                return Err(CliError::usage("--protocol given twice"));
            }
            given = Some(v);
        } else {
            params.push((k, v));
        }
    }
    let family = given
        .as_deref()
        .map(Protocol::parse)
        .transpose()?
        .unwrap_or(Protocol::V2);
    let wire = match family {
        Protocol::V2 => v2::encode_pairs(name, params)?,
        Protocol::V1 => v1::encode(name, params)?,
        Protocol::Rsrcp => rsrcp::encode(name, params)?,
    };
    writeln!(out, "{}", hex::spaced(&wire)).map_err(io_err)?;
    Ok(0)
}

/// `list`: v2 by default, one family, or all of them under a heading each.
fn list(
    filter: Option<&str>,
    protocol: Option<&str>,
    out: &mut dyn Write,
) -> Result<i32, CliError> {
    let families = match protocol {
        None => vec![Protocol::V2],
        Some(p) if p.eq_ignore_ascii_case("all") => Protocol::ALL.to_vec(),
        Some(p) => vec![Protocol::parse(p).map_err(|_| {
            CliError::usage(format!("unknown protocol {p:?}; use v2, v1, rsrcp or all"))
        })?],
    };
    for (i, family) in families.iter().enumerate() {
        if families.len() > 1 {
            if i > 0 {
                writeln!(out).map_err(io_err)?;
            }
            writeln!(out, "== {} ==", family.name()).map_err(io_err)?;
        }
        match family {
            Protocol::V2 => v2::list(filter, out),
            Protocol::V1 => v1::list(filter, out),
            Protocol::Rsrcp => rsrcp::list(filter, out),
        }
        .map_err(io_err)?;
    }
    Ok(0)
}

fn io_err(e: std::io::Error) -> CliError {
    CliError::output(e)
}

/// Options of `packet encode` that take no value.
const FLAGS: [&str; 2] = ["no-response", "no-reset-timeout"];

/// Split `--key value` / `--key=value` pairs; flags without a value ([`FLAGS`]) are `""`.
fn pairs(args: &[String]) -> Result<Vec<(String, String)>, CliError> {
    let mut out = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let Some(key) = a.strip_prefix("--") else {
            return Err(CliError::usage(format!(
                "unexpected argument {a:?}: parameters are given as --name value"
            )));
        };
        if let Some((k, v)) = key.split_once('=') {
            out.push((k.to_string(), v.to_string()));
        } else if FLAGS.contains(&key) {
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

/// A number in `0..=max` for option `--key` (decimal or `0x` hex).
fn uint_opt(key: &str, v: &str, max: u64) -> Result<u64, CliError> {
    parse_uint(v, max).map_err(|e| CliError::usage(format!("--{key}: {e}")))
}

fn byte_opt(key: &str, v: &str, max: u64) -> Result<u8, CliError> {
    uint_opt(key, v, max.min(255)).map(|n| n as u8)
}

/// Hex data of `--data`.
fn data_opt(v: &str) -> Result<Vec<u8>, CliError> {
    hex::parse(v).map_err(|e| CliError::usage(format!("--data: {e}")))
}

/// "unknown command X; did you mean …?" from a catalogue's suggestions; `list` is what
/// follows `droidctl packet list` to see that catalogue.
fn unknown_command(name: &str, hint: Vec<&str>, list: &str) -> String {
    let hint = if hint.is_empty() {
        format!("see `droidctl packet list{list}`")
    } else {
        format!("did you mean {}?", hint.join(", "))
    };
    format!("unknown command {name:?}; {hint}")
}

/// A command's parameters as `--name <description> ...`, for `packet list`.
fn params_text(params: &[FieldDef]) -> String {
    params
        .iter()
        .map(|p| format!("--{} <{}>", p.option(), p.description))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Single-packet mode: the decoder's items must be exactly one, else the input needs
/// `--stream`.
fn expect_one<T>(mut items: Vec<T>, what: &str) -> Result<T, CliError> {
    if items.len() > 1 {
        return Err(CliError::usage(format!(
            "the input holds {} {what}, not one packet; use --stream to decode a byte stream",
            items.len()
        )));
    }
    items
        .pop()
        .ok_or_else(|| CliError::usage("no bytes to decode"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detect_takes_the_first_sop() {
        assert_eq!(Protocol::detect(&[]), None);
        assert_eq!(Protocol::detect(&[1, 2, 3]), None);
        assert_eq!(
            Protocol::detect(&[1, 0x7E, 0x8D, 0xFF]),
            Some((Protocol::Rsrcp, 1))
        );
        assert_eq!(Protocol::detect(&[0xFF, 0x8D]), Some((Protocol::V1, 0)));
        assert_eq!(Protocol::detect(&[0, 0, 0x8D]), Some((Protocol::V2, 2)));
    }

    #[test]
    fn protocol_names() {
        for p in Protocol::ALL {
            assert_eq!(Protocol::parse(p.name()).ok(), Some(p));
        }
        assert_eq!(Protocol::parse("V1").ok(), Some(Protocol::V1));
        assert!(Protocol::parse("v3").is_err());
    }
}
