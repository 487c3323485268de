//! The one decode-and-print loop of `packet decode`: whatever family the bytes are, its
//! reader hands each packet and error to a [`Printer`], which writes the family's JSON object
//! or text. Hex on the command line (one packet, or `--stream`) comes through [`decode`];
//! files of any size through [`super::file`].

use super::{CliError, DecodeArgs, io_err};
use crate::family::Found;
use std::io::{self, Write};

/// How found packets are printed.
pub(super) struct Printer<'a> {
    out: &'a mut dyn Write,
    json: bool,
    /// Each packet's stream offset too (`--file`).
    with_offset: bool,
    summary_only: bool,
    /// Whether the last block printed had several lines: blocks of several lines are kept
    /// apart by a blank line, one-line items (RSRCP's summaries) are not.
    last_multi: Option<bool>,
    /// The JSON line being made, reused.
    line: Vec<u8>,
}

impl<'a> Printer<'a> {
    pub fn new(out: &'a mut dyn Write, json: bool, with_offset: bool, summary_only: bool) -> Self {
        Printer {
            out,
            json,
            with_offset,
            summary_only,
            last_multi: None,
            line: Vec::with_capacity(1024),
        }
    }

    pub fn json(&self) -> bool {
        self.json
    }

    pub fn summary_only(&self) -> bool {
        self.summary_only
    }

    pub fn out(&mut self) -> &mut dyn Write {
        self.out
    }

    /// Whether anything was printed.
    pub fn printed(&self) -> bool {
        self.last_multi.is_some()
    }

    pub fn show(&mut self, f: &dyn Found) -> io::Result<()> {
        if self.summary_only {
            return Ok(());
        }
        if self.json {
            self.line.clear();
            f.write_json(self.with_offset, &mut self.line);
            self.line.push(b'\n');
            self.last_multi = Some(false);
            return self.out.write_all(&self.line);
        }
        let text = f.text();
        let offset_line = self.with_offset && f.error_kind().is_none();
        let multi = offset_line || text.trim_end().contains('\n');
        if let Some(last) = self.last_multi
            && (multi || last)
        {
            writeln!(self.out)?;
        }
        if offset_line {
            writeln!(self.out, "{:<9} {}", "offset", f.offset())?;
        }
        self.last_multi = Some(multi);
        self.out.write_all(text.as_bytes())
    }
}

/// Decode hex given on the command line: exactly one packet (the status says whether it was
/// good), or with `stream` a byte stream holding many packets and garbage.
pub(super) fn decode(
    bytes: &[u8],
    args: DecodeArgs,
    stream: bool,
    json: bool,
    out: &mut dyn Write,
) -> Result<i32, CliError> {
    let (_, mut reader) = super::reader_for(args, bytes, false)?;
    let mut printer = Printer::new(out, json, false, false);
    if !stream {
        let found = reader
            .one(bytes)
            .map_err(|e| CliError::usage(e.to_string()))?;
        printer.show(&*found).map_err(io_err)?;
        if found.error_kind().is_some()
            && !json
            && let Some(hint) = reader.hint()
        {
            writeln!(printer.out(), "hint: {hint}").map_err(io_err)?;
        }
        return Ok(if found.is_bad() { 1 } else { 0 });
    }
    let mut show = |f: &dyn Found| printer.show(f);
    reader.feed(bytes, Some(&mut show)).map_err(io_err)?;
    reader.finish(Some(&mut show)).map_err(io_err)?;
    // A stream with garbage is still a successful decode of what was there.
    Ok(0)
}
