//! `droidctl packet decode --file FILE`: a byte stream of any size, binary or hex text, read
//! from a file or standard input in fixed-size blocks and decoded as it comes: memory stays
//! flat whatever the input's size. The output ends with a summary: packets per kind and
//! decode errors per kind.
//!
//! Every family goes through its [`Reader`](crate::family::Reader) and the same
//! [`Printer`](super::print::Printer); with `--summary` a reader only counts (v2 then
//! allocates nothing per packet).

use super::print::Printer;
use super::{CliError, DecodeArgs, io_err};
use crate::family::{Family, Reader};
use serde_json::{Value, json};
use std::io::{Read, Write};

/// How much is read at a time; also how much the hex-or-binary and family sniffing look at.
pub const BLOCK: usize = 64 * 1024;

/// What a file decode found.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FileSummary {
    pub protocol: &'static str,
    /// Whether the input was hex text.
    pub hex: bool,
    /// Bytes decoded (after hex conversion).
    pub bytes: u64,
    pub packets: u64,
    /// Packets per kind (`command`, `response`, `notification`; RSRCP `handshake`, `frame`).
    pub kinds: Vec<(&'static str, u64)>,
    /// Errors per kind, every kind of the family (zeros included).
    pub errors: Vec<(&'static str, u64)>,
}

impl FileSummary {
    pub fn error_total(&self) -> u64 {
        self.errors.iter().map(|(_, n)| n).sum()
    }

    fn json(&self) -> Value {
        let map = |v: &[(&'static str, u64)]| {
            Value::Object(v.iter().map(|(k, n)| (k.to_string(), json!(n))).collect())
        };
        json!({"summary": {
            "protocol": self.protocol,
            "input": if self.hex { "hex" } else { "binary" },
            "bytes": self.bytes,
            "packets": self.packets,
            "kinds": map(&self.kinds),
            "errors": map(&self.errors),
            "error_total": self.error_total(),
        }})
    }

    fn text(&self) -> String {
        let kinds: Vec<String> = self
            .kinds
            .iter()
            .filter(|(_, n)| *n > 0)
            .map(|(k, n)| format!("{k} {n}"))
            .collect();
        let errors: Vec<String> = self
            .errors
            .iter()
            .filter(|(_, n)| *n > 0)
            .map(|(k, n)| format!("{k} {n}"))
            .collect();
        format!(
            "summary: {} {}, {} bytes, {} packets{}, {}",
            self.protocol,
            if self.hex { "hex text" } else { "binary" },
            self.bytes,
            self.packets,
            if kinds.is_empty() {
                String::new()
            } else {
                format!(" ({})", kinds.join(", "))
            },
            if errors.is_empty() {
                "no errors".to_string()
            } else {
                format!("{} errors: {}", self.error_total(), errors.join(", "))
            }
        )
    }
}

/// `--file PATH` (`-`: standard input).
pub(super) fn decode_path(
    path: &str,
    args: DecodeArgs,
    json: bool,
    summary_only: bool,
    out: &mut dyn Write,
) -> Result<i32, CliError> {
    let mut input: Box<dyn Read> = if path == "-" {
        Box::new(std::io::stdin().lock())
    } else {
        let mut file = std::fs::File::open(path)
            .map_err(|e| CliError::usage(format!("cannot read {path}: {e}")))?;
        let mut head = [0u8; 32];
        let n = read_block(&mut file, &mut head, 0)?;
        if let Some(what) = another_format(&head[..n]) {
            return Err(CliError::usage(
                format!("{path} is {what}").replace("FILE", path),
            ));
        }
        Box::new(std::io::Read::chain(
            std::io::Cursor::new(head[..n].to_vec()),
            file,
        ))
    };
    decode_reader(&mut input, args, json, summary_only, out).map(|_| 0)
}

/// What a file `--file` should not read as bytes is, and what reads it (`FILE` stands for
/// its name): captures and btsnoop logs have their own readers.
fn another_format(head: &[u8]) -> Option<&'static str> {
    if head.starts_with(b"droidctl-capture ") {
        Some(
            "a droidctl capture (`--record`), not a byte stream: `droidctl replay FILE` shows \
             its packets in the app, `droidctl replay FILE --json` prints its telemetry",
        )
    } else if head.starts_with(&crate::capture::btsnoop::MAGIC[..]) {
        Some("a btsnoop log: decode it with `droidctl packet decode --btsnoop FILE`")
    } else {
        None
    }
}

/// Decode everything `input` holds, printing each packet and error (unless `summary_only`)
/// and the summary. Bytes that cannot be read or hex that is malformed end the decode with an
/// error naming the offset, after the summary of what came before.
pub fn decode_reader(
    input: &mut dyn Read,
    args: DecodeArgs,
    json: bool,
    summary_only: bool,
    out: &mut dyn Write,
) -> Result<FileSummary, CliError> {
    let mut block = vec![0u8; BLOCK];
    let mut bytes = Vec::with_capacity(BLOCK);
    // The first block decides hex or binary, and the family.
    let first = read_block(input, &mut block, 0)?;
    if first == 0 {
        return Err(CliError::usage("the input is empty: no bytes to decode"));
    }
    if let Some(what) = another_format(&block[..first]) {
        return Err(CliError::usage(format!("the input is {what}")));
    }
    let is_hex = looks_like_hex(&block[..first]);
    let mut hex = HexText::default();
    let mut failure = None;
    // Hex text is converted into `bytes`; binary input is decoded from the block it was read
    // into, not copied first.
    if is_hex && let Err(e) = hex.convert(&block[..first], &mut bytes) {
        failure = Some(e);
    }
    let (family, mut reader) =
        super::reader_for(args, if is_hex { &bytes } else { &block[..first] }, true)?;
    let mut printer = Printer::new(out, json, true, summary_only);
    let mut read = first as u64;
    let mut n = first;
    loop {
        let chunk = if is_hex { &bytes[..] } else { &block[..n] };
        feed(&mut *reader, chunk, &mut printer).map_err(io_err)?;
        bytes.clear();
        if failure.is_some() {
            break;
        }
        n = match read_block(input, &mut block, read) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) => {
                failure = Some(e.message);
                break;
            }
        };
        read += n as u64;
        if is_hex && let Err(e) = hex.convert(&block[..n], &mut bytes) {
            failure = Some(e);
        }
    }
    if is_hex
        && failure.is_none()
        && let Err(e) = hex.finish(&mut bytes)
    {
        failure = Some(e);
    }
    feed(&mut *reader, &bytes, &mut printer).map_err(io_err)?;
    let summary = finish(family, &mut *reader, &mut printer, is_hex).map_err(io_err)?;
    match failure {
        Some(message) => Err(CliError::failure(message)),
        None => Ok(summary),
    }
}

/// Fill `block` as far as the input goes (a pipe returns short reads).
fn read_block(input: &mut dyn Read, block: &mut [u8], at: u64) -> Result<usize, CliError> {
    let mut filled = 0;
    while filled < block.len() {
        match input.read(&mut block[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => {
                return Err(CliError::failure(format!(
                    "cannot read the input at offset {}: {e}",
                    at + filled as u64
                )));
            }
        }
    }
    Ok(filled)
}

/// Text (printable ASCII and whitespace) with hex digits in it is read as hex; anything else
/// as binary. Every packet family starts with a byte above 0x7E (8D, FF, 7E is `~` but its
/// frames carry binary fields), so a binary capture is never all printable. A stray non-hex
/// character in hex text is then reported with its offset rather than read as binary.
fn looks_like_hex(bytes: &[u8]) -> bool {
    bytes
        .iter()
        .all(|b| matches!(b, 0x20..=0x7E | b'\t' | b'\n' | b'\r'))
        && bytes.iter().any(u8::is_ascii_hexdigit)
}

/// Hex text to bytes, a block at a time, with the rules of [`crate::hex::parse`]: separators
/// (whitespace, `:`, `,`, `-`) and `0x` prefixes at the start of a token are skipped.
#[derive(Debug, Default)]
struct HexText {
    /// The high nibble of a byte whose low nibble has not come yet.
    high: Option<u8>,
    /// A `0` at the start of a token, which is a digit unless an `x` follows.
    zero: bool,
    /// The previous character was a separator (or there was none).
    after_sep: bool,
    started: bool,
    /// Characters consumed.
    pos: u64,
}

impl HexText {
    fn is_sep(c: u8) -> bool {
        matches!(c, b' ' | b'\t' | b'\n' | b'\r' | b':' | b',' | b'-')
    }

    fn digit(&mut self, d: u8, out: &mut Vec<u8>) {
        match self.high.take() {
            Some(h) => out.push((h << 4) | d),
            None => self.high = Some(d),
        }
    }

    fn convert(&mut self, text: &[u8], out: &mut Vec<u8>) -> Result<(), String> {
        for &c in text {
            let at = self.pos;
            self.pos += 1;
            let token_start = self.high.is_none() && (!self.started || self.after_sep);
            self.started = true;
            if self.zero {
                self.zero = false;
                if c == b'x' || c == b'X' {
                    self.after_sep = false;
                    continue;
                }
                self.digit(0, out);
            } else if c == b'0' && token_start {
                self.zero = true;
                self.after_sep = false;
                continue;
            }
            if Self::is_sep(c) {
                self.after_sep = true;
                continue;
            }
            self.after_sep = false;
            match (c as char).to_digit(16) {
                Some(d) => self.digit(d as u8, out),
                None => {
                    return Err(format!(
                        "malformed hex at offset {at}: {:?} is not a hex digit (the bytes before it were decoded)",
                        c as char
                    ));
                }
            }
        }
        Ok(())
    }

    fn finish(&mut self, out: &mut Vec<u8>) -> Result<(), String> {
        if std::mem::take(&mut self.zero) {
            self.digit(0, out);
        }
        match self.high {
            Some(_) => Err(format!(
                "malformed hex: the text ends at offset {} after half a byte",
                self.pos
            )),
            None => Ok(()),
        }
    }
}

/// Decode a block: printed, or only counted with `--summary`.
fn feed(reader: &mut dyn Reader, bytes: &[u8], printer: &mut Printer) -> std::io::Result<()> {
    if bytes.is_empty() {
        return Ok(());
    }
    if printer.summary_only() {
        return reader.feed(bytes, None);
    }
    reader.feed(bytes, Some(&mut |f| printer.show(f)))
}

/// The input ended: what was left half-read, then the summary.
fn finish(
    family: &dyn Family,
    reader: &mut dyn Reader,
    printer: &mut Printer,
    hex: bool,
) -> std::io::Result<FileSummary> {
    reader.finish(Some(&mut |f| printer.show(f)))?;
    let st = reader.stats();
    let summary = FileSummary {
        protocol: family.name(),
        hex,
        bytes: st.bytes,
        packets: st.packets,
        kinds: reader.kinds(),
        errors: family
            .error_kinds()
            .iter()
            .map(|k| (k.name(), st.errors(*k)))
            .collect(),
    };
    if printer.json() {
        writeln!(printer.out(), "{}", summary.json())?;
    } else {
        if printer.printed() {
            writeln!(printer.out())?;
        }
        writeln!(printer.out(), "{}", summary.text())?;
    }
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hex_of(text: &str, cut: usize) -> Result<Vec<u8>, String> {
        let mut h = HexText::default();
        let mut out = Vec::new();
        for c in text.as_bytes().chunks(cut.max(1)) {
            h.convert(c, &mut out)?;
        }
        h.finish(&mut out)?;
        Ok(out)
    }

    #[test]
    fn hex_text_in_any_cut_matches_hex_parse() {
        for text in [
            "8D 0A 13 0D 00 D5 D8",
            "0x8D,0x0A:0x13 0d\n00d5d8",
            "00 0x00 00x",
            "0a0b0c",
            "0x0x",
        ] {
            let want = crate::hex::parse(text);
            for cut in 1..6 {
                assert_eq!(hex_of(text, cut).is_ok(), want.is_ok(), "{text} cut {cut}");
                if let Ok(w) = &want {
                    assert_eq!(&hex_of(text, cut).unwrap(), w, "{text} cut {cut}");
                }
            }
        }
    }

    #[test]
    fn hex_errors_name_the_offset() {
        let e = hex_of("8D 0A 1G", 3).unwrap_err();
        assert!(e.contains("offset 7"), "{e}");
        let e = hex_of("8D 0", 2).unwrap_err();
        assert!(e.contains("half a byte"), "{e}");
    }

    #[test]
    fn sniffing() {
        assert!(looks_like_hex(b"8d 0a\n"));
        assert!(!looks_like_hex(&[0x8D, 0x0A]));
        assert!(!looks_like_hex(b"  \n"));
        assert!(
            looks_like_hex(b"8D 0A 1G"),
            "a typo is reported, not read as binary"
        );
    }
}
