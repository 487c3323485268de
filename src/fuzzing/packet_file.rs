//! Hex and binary file input (`packet decode --file FILE`): any bytes, read in the short
//! pieces a pipe gives, decode to packets and a summary, or end with one error naming the
//! offset, never a panic. The summary counts every byte (binary) or every byte the hex text
//! holds (the same bytes `hex::parse` makes of it), and a hex file decodes exactly as the
//! binary file of its bytes does; with `--json` every line is a JSON object.
//!
//! Input layout: the first byte picks `--protocol`, `--from`, `--json` and `--summary`; the
//! second the size of the reads; the rest is the file.

use super::{Bytes, Target};
use crate::cli::packet::{DecodeArgs, FileSummary, decode_reader};
use std::io::Read;

pub const TARGET: Target = Target {
    name: "packet_file",
    run: run_input,
    dictionary: &[
        b"8D 0A 13 0D 00 D5 D8\n",
        b"0x",
        b"8d",
        b"ff ff",
        b"7e",
        b", ",
        b":",
        b"-",
        &[0x8D],
        &[0xFF, 0xFF],
        &[0x7E],
        &[0xD8],
    ],
};

/// A reader that hands out at most `step` bytes per read, as a pipe may.
struct Trickle<'a> {
    data: &'a [u8],
    step: usize,
}

impl Read for Trickle<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.step.min(buf.len()).min(self.data.len());
        buf[..n].copy_from_slice(&self.data[..n]);
        self.data = &self.data[n..];
        Ok(n)
    }
}

fn args(opts: u8) -> DecodeArgs {
    DecodeArgs {
        protocol: match opts % 4 {
            0 => None,
            1 => Some("v2".into()),
            2 => Some("v1".into()),
            _ => Some("rsrcp".into()),
        },
        from: match (opts >> 2) % 3 {
            0 => None,
            1 => Some("droid".into()),
            _ => Some("host".into()),
        },
        ..DecodeArgs::default()
    }
}

fn decode(
    file: &[u8],
    opts: u8,
    step: usize,
    json: bool,
    summary: bool,
) -> (Result<FileSummary, String>, String) {
    let mut out = Vec::new();
    let mut input = Trickle { data: file, step };
    let r = decode_reader(&mut input, args(opts), json, summary, &mut out).map_err(|e| e.message);
    let text = String::from_utf8(out).expect("the output is UTF-8");
    (r, text)
}

/// Printable text with hex digits: what the reader takes for hex.
fn is_hex_text(b: &[u8]) -> bool {
    b.iter()
        .all(|c| matches!(c, 0x20..=0x7E | b'\t' | b'\n' | b'\r'))
        && b.iter().any(u8::is_ascii_hexdigit)
}

pub fn run_input(data: &[u8]) {
    let mut b = Bytes::new(data);
    let opts = b.u8();
    let step = 1 + b.u8() as usize * 97;
    let file = b.rest();
    let json = opts & 0x40 != 0;
    let summary_only = opts & 0x80 != 0;
    let (result, text) = decode(file, opts, step, json, summary_only);
    if json {
        for line in text.lines() {
            serde_json::from_str::<serde_json::Value>(line)
                .unwrap_or_else(|e| panic!("not a JSON line ({e}): {line}"));
        }
    }
    let summary = match result {
        Ok(s) => s,
        Err(message) => {
            assert!(!message.is_empty());
            // Only what cannot be read: nothing, or hex text that is malformed (the first
            // block decides hex).
            let first = &file[..file.len().min(crate::cli::packet::BLOCK)];
            assert!(file.is_empty() || is_hex_text(first), "{message}");
            return;
        }
    };
    assert!(summary.packets <= summary.bytes);
    let kinds: u64 = summary.kinds.iter().map(|(_, n)| n).sum();
    assert_eq!(kinds, summary.packets, "{summary:?}");
    if !summary.hex {
        assert_eq!(summary.bytes, file.len() as u64);
        return;
    }
    // Hex: the bytes are those `hex::parse` makes of the text, and decode as that binary
    // file does (unless those bytes read as hex text themselves).
    let text_in = String::from_utf8_lossy(file);
    let bytes = crate::hex::parse(&text_in).expect("hex the reader accepted parses");
    assert_eq!(summary.bytes, bytes.len() as u64);
    if !bytes.is_empty() && !is_hex_text(&bytes) {
        let (binary, _) = decode(&bytes, opts, step, json, summary_only);
        let binary = binary.expect("the same bytes as binary decode");
        assert_eq!(
            (&binary.kinds, &binary.errors, binary.packets),
            (&summary.kinds, &summary.errors, summary.packets)
        );
    }
}
