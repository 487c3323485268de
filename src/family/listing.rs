//! `packet list`'s output for every family: a heading is printed above its first entry only,
//! so a filter that keeps nothing of a section prints no empty heading, and the caller knows
//! how many entries matched (none is an error there, not an empty list).

use std::fmt::Display;
use std::io::Write;

pub struct Listing<'a> {
    out: &'a mut dyn Write,
    heading: Option<String>,
    entries: usize,
}

impl<'a> Listing<'a> {
    pub fn new(out: &'a mut dyn Write) -> Listing<'a> {
        Listing {
            out,
            heading: None,
            entries: 0,
        }
    }

    /// The heading of the entries that follow; printed with the first of them.
    pub fn heading(&mut self, text: impl Display) {
        self.heading = Some(text.to_string());
    }

    /// One entry, under the current heading.
    pub fn entry(&mut self, line: impl Display) -> std::io::Result<()> {
        if let Some(h) = self.heading.take() {
            writeln!(self.out, "{h}")?;
        }
        self.entries += 1;
        writeln!(self.out, "{line}")
    }

    /// How many entries were listed.
    pub fn entries(&self) -> usize {
        self.entries
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_heading_without_entries_is_not_printed() {
        let mut out = Vec::new();
        let mut l = Listing::new(&mut out);
        l.heading("Empty:");
        l.heading("Full:");
        l.entry("  one").unwrap();
        l.entry("  two").unwrap();
        l.heading("Empty too:");
        assert_eq!(l.entries(), 2);
        assert_eq!(String::from_utf8(out).unwrap(), "Full:\n  one\n  two\n");
    }
}
