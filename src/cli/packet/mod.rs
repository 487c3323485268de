//! `droidctl packet`: decode bytes into explained packets, encode packets, list the
//! catalogues, for every protocol family.
//!
//! This file holds the arguments, the choice of family (given with `--protocol` or detected
//! from the first start-of-packet byte) and how the options become the family's reading
//! options; [`print`] is the one decode-and-print loop every family's packets go through,
//! [`file`] reads files of any size and [`btsnoop`] phone logs. The families themselves
//! (framing, descriptions, encoding, catalogues) live behind [`crate::family`].

mod btsnoop;
mod file;
mod print;

pub use btsnoop::decode_reader as decode_btsnoop_reader;
pub use file::{BLOCK, FileSummary, decode_reader};

use super::CliError;
use crate::family::{self, Family, ReadOption, ReadOptions, Side};
use crate::hex;
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
        #[arg(add = clap_complete::ArgValueCompleter::new(crate::cli::complete::encode_names))]
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

pub fn run(cmd: PacketCmd, out: &mut dyn Write) -> Result<i32, CliError> {
    // One buffer in front of the terminal or pipe: a packet per line would otherwise be a
    // write per line.
    let mut out = std::io::BufWriter::with_capacity(64 * 1024, out);
    let result = run_buffered(cmd, &mut out);
    out.flush().map_err(io_err)?;
    result
}

fn run_buffered(cmd: PacketCmd, out: &mut dyn Write) -> Result<i32, CliError> {
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
            print::decode(&bytes, opts, stream, json, out)
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

/// A family by its `--protocol` name.
fn family_named(text: &str) -> Result<&'static dyn Family, CliError> {
    family::by_name(text).ok_or_else(|| {
        CliError::usage(format!(
            "unknown protocol {text:?}; use {}",
            family::names()
        ))
    })
}

/// The family to decode `bytes` as: `--protocol`, or the first SOP byte's (v2 without one),
/// with the reason for messages.
fn choose_family(
    args: &DecodeArgs,
    bytes: &[u8],
) -> Result<(&'static dyn Family, String), CliError> {
    Ok(match &args.protocol {
        Some(p) => (family_named(p)?, String::new()),
        None => match family::detect(bytes) {
            Some((f, at)) => (
                f,
                format!(
                    " (detected from the SOP byte {:02X} at offset {at}; --protocol overrides)",
                    f.sop()
                ),
            ),
            None => (family::all()[0], String::new()),
        },
    })
}

/// The options as the family's reading options, checked against the family (`why` says how
/// it was chosen). `follow`: take the masks from the stream's own commands when none are
/// given.
fn read_options(
    args: DecodeArgs,
    family: &dyn Family,
    why: &str,
    follow: bool,
) -> Result<ReadOptions, CliError> {
    let mask = |flag: &str, text: Option<String>| -> Result<Option<u32>, CliError> {
        text.map(|t| {
            parse_uint(&t, u32::MAX as u64)
                .map(|v| v as u32)
                .map_err(|e| CliError::usage(format!("{flag}: {e}")))
        })
        .transpose()
    };
    // v2 and RSRCP packets say what they are: only v1 reads the side.
    let side = match args.from.as_deref() {
        None => None,
        Some(_) if !family.read_options().contains(&ReadOption::Side) => None,
        Some(t) if t.eq_ignore_ascii_case("host") => Some(Side::Host),
        Some(t) if t.eq_ignore_ascii_case("droid") => Some(Side::Droid),
        Some(t) => {
            return Err(CliError::usage(format!(
                "--from: unknown side {t:?}; use host or droid"
            )));
        }
    };
    let frames = match args.frames.as_deref() {
        None => None,
        Some(t) => match uint_opt("frames", t, u16::MAX as u64)? {
            0 => return Err(CliError::usage("--frames: a packet holds at least 1 frame")),
            m => Some(m as u16),
        },
    };
    let opts = ReadOptions {
        side,
        sensor_mask: mask("--sensor-mask", args.sensor_mask)?,
        ext_mask: mask("--ext-mask", args.ext_mask)?,
        mask2: mask("--mask2", args.mask2)?,
        frames,
        request: args.request,
        follow,
        whole_values: false,
    };
    // An option another family reads is refused rather than ignored: a mask given for the
    // wrong family would silently change nothing.
    for option in ReadOption::given(&opts) {
        if !family.read_options().contains(&option) {
            let readers: Vec<&str> = family::all()
                .into_iter()
                .filter(|f| f.read_options().contains(&option))
                .map(|f| f.name())
                .collect();
            return Err(CliError::usage(format!(
                "{} applies to {} packets, but the input is decoded as {}{why}",
                option.flag(),
                readers.join(" and "),
                family.name()
            )));
        }
    }
    Ok(opts)
}

/// The reader for `bytes` as the options say.
fn reader_for(
    args: DecodeArgs,
    bytes: &[u8],
    follow: bool,
) -> Result<(&'static dyn Family, Box<dyn family::Reader>), CliError> {
    let (family, why) = choose_family(&args, bytes)?;
    let opts = read_options(args, family, &why, follow)?;
    let reader = family
        .reader(&opts)
        .map_err(|e| CliError::usage(e.to_string()))?;
    Ok((family, reader))
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
    let family = match given.as_deref() {
        Some(p) => family_named(p)?,
        None => family::all()[0],
    };
    let wire = family
        .encode_named(name, params)
        .map_err(|e| CliError::usage(e.to_string()))?;
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
        None => vec![family::all()[0]],
        Some(p) if p.eq_ignore_ascii_case("all") => family::all().to_vec(),
        Some(p) => vec![family::by_name(p).ok_or_else(|| {
            CliError::usage(format!(
                "unknown protocol {p:?}; use {}, or all",
                family::names()
            ))
        })?],
    };
    let mut listed = 0;
    for family in &families {
        let mut section = Vec::new();
        let n = family.list(filter, &mut section).map_err(io_err)?;
        if n == 0 {
            continue;
        }
        if families.len() > 1 {
            if listed > 0 {
                writeln!(out).map_err(io_err)?;
            }
            writeln!(out, "== {} ==", family.name()).map_err(io_err)?;
        }
        out.write_all(&section).map_err(io_err)?;
        listed += n;
    }
    if listed == 0 {
        let names: Vec<&str> = families.iter().map(|f| f.name()).collect();
        let wider = if families.len() == 1 {
            "; `--protocol all` searches every family"
        } else {
            ""
        };
        return Err(CliError::usage(format!(
            "nothing in the {} catalogue matches {:?}: `droidctl packet list` lists it all{wider}",
            names.join(", "),
            filter.unwrap_or_default()
        )));
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_of_another_family_are_refused_with_who_reads_them() {
        let args = DecodeArgs {
            ext_mask: Some("1".into()),
            sensor_mask: Some("1".into()),
            ..DecodeArgs::default()
        };
        let v1 = family::by_name("v1").unwrap();
        let e = read_options(args, v1, " (detected)", false).unwrap_err();
        assert_eq!(
            e.message,
            "--ext-mask applies to v2 packets, but the input is decoded as v1 (detected)"
        );
        let args = DecodeArgs {
            sensor_mask: Some("1".into()),
            ..DecodeArgs::default()
        };
        let rsrcp = family::by_name("rsrcp").unwrap();
        let e = read_options(args, rsrcp, "", false).unwrap_err();
        assert!(
            e.message
                .starts_with("--sensor-mask applies to v2 and v1 packets")
        );
    }
}
