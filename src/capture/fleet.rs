//! A capture of several droids in one file, each droid's traffic kept apart.
//!
//! It is the droidctl capture format with a droid on every line: the magic line says version
//! 2 (an older droidctl refuses it with its version rather than misreading it), the header
//! lists the droids, and each event line starts with `@K` (K from 1, in the header's order)
//! followed by the version-1 event line of that droid:
//!
//! ```text
//! droidctl-capture 2
//! # droidctl: 0.1.0
//! # started: 2025-06-01T10:00:00.123Z
//! # droids: 2
//! # droid-1: r2d2 v2 D2-0001
//! # droid-2: bb8 v1 BB-0002
//! @1 0.000 connect
//! @2 0.004 connect
//! @1 0.120 out api 8d0a130d00d5d8
//! …
//! ```
//!
//! Reading splits it into one [`Capture`] per droid, each read by the version-1 reader, so
//! everything that replays or decodes one droid's capture does so for each droid of a fleet.

use super::{Capture, Header, Line, MAGIC, TextReader, Timed, Warnings};
use crate::model::Model;
use std::fmt::Write;

/// The format version of a capture of several droids.
pub const FLEET_VERSION: u32 = 2;

/// Most droids a capture may list (a bound on what a file can make us allocate).
pub const MAX_DROIDS: usize = 64;

/// The header of a capture of several droids.
pub fn header_text(droids: &[Header]) -> String {
    let mut s = format!("{MAGIC} {FLEET_VERSION}\n");
    let first = droids.first();
    if let Some(v) = first.and_then(|h| h.droidctl.as_deref()) {
        let _ = writeln!(s, "# droidctl: {v}");
    }
    if let Some(v) = first.and_then(|h| h.started.as_deref()) {
        let _ = writeln!(s, "# started: {v}");
    }
    let _ = writeln!(s, "# droids: {}", droids.len());
    for (i, h) in droids.iter().enumerate() {
        let model = h.model.map(Model::id).unwrap_or("-");
        let family = h
            .family
            .map(|p| crate::family::for_protocol(p).name())
            .unwrap_or("-");
        let name = h.droid.as_deref().unwrap_or("-").replace(['\n', '\r'], " ");
        let _ = writeln!(s, "# droid-{}: {model} {family} {name}", i + 1);
    }
    s
}

/// Whether `bytes` start like a capture of several droids.
pub fn sniff(bytes: &[u8]) -> bool {
    let head = format!("{MAGIC} {FLEET_VERSION}");
    bytes.starts_with(head.as_bytes())
        && matches!(bytes.get(head.len()), None | Some(b'\n' | b'\r' | b' '))
}

/// What one line of a capture of several droids held.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FleetLine {
    Nothing,
    /// An event of droid `.0` (0-based, in the header's order).
    Event(usize, Timed),
    /// A line of droid `.0` that could not be read (its message names the file's line).
    DroidWarning(usize, String),
    /// A line about every droid (no `@K`: the recorder's `end`), at most [`MAX_SHARED`].
    Shared(Timed),
    /// A line about no droid of the capture (an unknown `@K`, a shared line past
    /// [`MAX_SHARED`], a damaged one): skipped.
    Warning(String),
}

/// Most lines without `@K` a capture may hold: each is every droid's (the recorder writes
/// one, its `end`); past that they are warnings, so a file of them cannot make each droid
/// copy them (issue 27 point 3: 10 MB of them copied to 64 droids took 679 MB).
pub const MAX_SHARED: usize = 8;

/// A capture of several droids read line by line, each droid's lines through its own
/// version-1 reader (so each droid is read as its own capture is). Nothing is copied per
/// droid: a line goes to the one droid it names, a line naming none is a warning; time and
/// memory are linear in the file (issue 27 point 3: 64 droids and 1 MB of lines about a droid
/// not listed printed 327 MB of warnings).
#[derive(Debug, Default)]
pub struct FleetReader {
    line: usize,
    /// `# droidctl:` and `# started:` as written, for every droid.
    common: Vec<String>,
    /// Each listed droid's header lines, until the first event.
    listed: Vec<String>,
    /// Each droid's reader, from the first event on.
    readers: Vec<TextReader>,
    /// Header warnings of each droid (a model it does not know), with the file's line.
    header_warnings: Vec<Vec<String>>,
    /// The reader of lines without `@K`, and how many it has read.
    shared: Option<TextReader>,
    shared_lines: usize,
}

impl FleetReader {
    pub fn new() -> FleetReader {
        FleetReader::default()
    }

    /// How many droids the header lists.
    pub fn droids(&self) -> usize {
        self.listed.len()
    }

    /// Droid `k`'s header (after the first event; else what it lists so far).
    pub fn header(&mut self, k: usize) -> Header {
        self.start();
        self.readers
            .get(k)
            .map(|r| r.header.clone())
            .unwrap_or_default()
    }

    /// The header's problems with droid `k`.
    pub fn header_warnings(&self, k: usize) -> &[String] {
        self.header_warnings.get(k).map_or(&[], Vec::as_slice)
    }

    /// The readers of each droid, fed their headers (once).
    fn start(&mut self) {
        if !self.readers.is_empty() || self.listed.is_empty() {
            return;
        }
        for (k, h) in self.listed.iter().enumerate() {
            let mut r = TextReader::new();
            let mut warnings = Vec::new();
            let _ = r.line(&format!("{MAGIC} {}", super::VERSION));
            for l in self.common.iter().map(String::as_str).chain(h.lines()) {
                if let Err(e) = r.line(l) {
                    warnings.push(format!("droid-{}: {}", k + 1, e.message));
                }
            }
            self.readers.push(r);
            self.header_warnings.push(warnings);
        }
    }

    /// Read the next line. An error is fatal (not a capture of several droids, a header out
    /// of order, an event before the droids are listed).
    pub fn line(&mut self, text: &str) -> Result<FleetLine, String> {
        self.line += 1;
        let n = self.line;
        if n == 1 {
            if !sniff(text.as_bytes()) {
                return Err(format!(
                    "line 1: not a capture of several droids (it does not start with \"{MAGIC} {FLEET_VERSION}\")"
                ));
            }
            return Ok(FleetLine::Nothing);
        }
        if let Some(c) = text.strip_prefix('#') {
            if !self.readers.is_empty() {
                return Ok(FleetLine::Nothing);
            }
            let Some((k, v)) = c.split_once(':') else {
                return Ok(FleetLine::Nothing);
            };
            let (k, v) = (k.trim(), v.trim());
            match k {
                "droidctl" | "started" => self.common.push(format!("# {k}: {v}")),
                _ => {
                    if let Some(idx) = k.strip_prefix("droid-") {
                        let idx: usize = idx.parse().map_err(|_| {
                            format!("line {n}: {:?} is not droid-N", super::shown(k))
                        })?;
                        if idx != self.listed.len() + 1 || idx > MAX_DROIDS {
                            return Err(format!(
                                "line {n}: droid-{idx} out of order (expected droid-{}, at most {MAX_DROIDS})",
                                self.listed.len() + 1
                            ));
                        }
                        self.listed.push(droid_header(v));
                    }
                }
            }
            return Ok(FleetLine::Nothing);
        }
        if text.trim().is_empty() {
            return Ok(FleetLine::Nothing);
        }
        if self.listed.is_empty() {
            return Err(format!("line {n}: an event before the droids are listed"));
        }
        self.start();
        let Some((k, rest)) = text.strip_prefix('@').and_then(|r| r.split_once(' ')) else {
            return Ok(self.shared_line(n, text));
        };
        let Some((i, reader)) = k
            .parse::<usize>()
            .ok()
            .and_then(|k| k.checked_sub(1))
            .and_then(|i| self.readers.get_mut(i).map(|r| (i, r)))
        else {
            return Ok(FleetLine::Warning(format!(
                "line {n}: no droid {:?} in this capture: skipped",
                super::shown(k)
            )));
        };
        Ok(match reader.line_at(n, rest) {
            Ok(Line::Event(t)) => FleetLine::Event(i, t),
            Ok(Line::Nothing) => FleetLine::Nothing,
            Ok(Line::Unknown(kind)) => FleetLine::DroidWarning(i, super::unknown_kind(n, &kind)),
            Err(e) => FleetLine::DroidWarning(i, e.to_string()),
        })
    }

    /// A line without `@K`: every droid's, the first [`MAX_SHARED`] of them.
    fn shared_line(&mut self, n: usize, text: &str) -> FleetLine {
        if self.shared_lines >= MAX_SHARED {
            return FleetLine::Warning(format!(
                "line {n}: no `@K` naming its droid (more than {MAX_SHARED} such lines): skipped"
            ));
        }
        self.shared_lines += 1;
        let r = self.shared.get_or_insert_with(|| {
            let mut r = TextReader::new();
            let _ = r.line(&format!("{MAGIC} {}", super::VERSION));
            r
        });
        match r.line_at(n, text) {
            Ok(Line::Event(t)) => FleetLine::Shared(t),
            Ok(Line::Nothing) => FleetLine::Nothing,
            Ok(Line::Unknown(kind)) => FleetLine::Warning(super::unknown_kind(n, &kind)),
            Err(e) => FleetLine::Warning(e.to_string()),
        }
    }

    /// The end of the file: an error when it listed no droid.
    pub fn finish(&mut self) -> Result<(), String> {
        if self.listed.is_empty() {
            return Err("the capture lists no droids (no `# droid-1:` line)".into());
        }
        self.start();
        Ok(())
    }
}

/// A capture of several droids, read: each droid's capture, and the file's own warnings
/// (lines about no droid of it), summarised.
#[derive(Debug, Clone, Default)]
pub struct Split {
    pub droids: Vec<Capture>,
    pub warnings: Vec<String>,
}

/// Read a capture of several droids into one capture per droid (in the header's order). Bad
/// lines of a droid are that droid's warnings; lines about no droid are the file's. Both are
/// summarised ([`super::Warnings`]).
pub fn read(text: &str) -> Result<Split, String> {
    let mut r = FleetReader::new();
    let mut events: Vec<Vec<Timed>> = Vec::new();
    let mut droid_warnings: Vec<Warnings> = Vec::new();
    let mut warnings = Warnings::default();
    let mut shared = Vec::new();
    for line in text.split_inclusive('\n') {
        match r.line(line.trim_end_matches(['\r', '\n']))? {
            FleetLine::Nothing => {}
            FleetLine::Event(i, t) => {
                events.resize_with(r.droids(), Vec::new);
                events[i].push(t);
            }
            FleetLine::DroidWarning(i, w) => {
                droid_warnings.resize_with(r.droids(), Warnings::default);
                droid_warnings[i].push(w);
            }
            FleetLine::Shared(t) => shared.push(t),
            FleetLine::Warning(w) => warnings.push(w),
        }
    }
    r.finish()?;
    events.resize_with(r.droids(), Vec::new);
    droid_warnings.resize_with(r.droids(), Warnings::default);
    // The lines about every droid (the recorder's `end`) close each droid's events, where
    // they are in time order.
    for e in &mut events {
        for t in &shared {
            if e.last().is_none_or(|l| l.at <= t.at) {
                e.push(t.clone());
            }
        }
    }
    let mut droids = Vec::with_capacity(r.droids());
    for (k, (events, mut w)) in events.into_iter().zip(droid_warnings).enumerate() {
        let mut c = Capture {
            header: r.header(k),
            events,
            warnings: r.header_warnings(k).to_vec(),
            kind: "droidctl capture",
        };
        c.warnings.append(&mut std::mem::take(&mut w).into_lines());
        c.finish(Warnings::default());
        droids.push(c);
    }
    Ok(Split {
        droids,
        warnings: warnings.into_lines(),
    })
}

/// [`read`], the file's own warnings given to the first droid (said once, not per droid).
pub fn split(text: &str) -> Result<Vec<Capture>, String> {
    let mut s = read(text)?;
    if let Some(first) = s.droids.first_mut() {
        first.warnings.append(&mut s.warnings);
    }
    Ok(s.droids)
}

/// `MODEL FAMILY NAME` as header lines of one droid's capture.
fn droid_header(v: &str) -> String {
    let mut words = v.splitn(3, ' ');
    let model = words.next().unwrap_or("-");
    let family = words.next().unwrap_or("-");
    let name = words.next().unwrap_or("").trim();
    let mut s = String::new();
    if model != "-" {
        let _ = writeln!(s, "# model: {model}");
    }
    if family != "-" {
        let _ = writeln!(s, "# family: {family}");
    }
    if !name.is_empty() && name != "-" {
        let _ = writeln!(s, "# droid: {name}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::capture::{Event, Timed, event_line};
    use std::time::Duration;

    fn header(model: Model, name: &str) -> Header {
        Header {
            droidctl: Some("0.1.0".into()),
            model: Some(model),
            family: Some(model.protocol()),
            droid: Some(name.into()),
            started: Some("2025-06-01T10:00:00.123Z".into()),
        }
    }

    #[test]
    fn droids_are_kept_apart_and_read_back_as_one_capture_each() {
        let mut text = header_text(&[
            header(Model::R2D2, "D2-0001"),
            header(Model::BB8, "BB-0002"),
        ]);
        let ev = |ms: u64, e: Event| {
            event_line(&Timed {
                at: Duration::from_millis(ms),
                event: e,
            })
        };
        text += &format!("@1 {}", ev(0, Event::Connect));
        text += &format!("@2 {}", ev(4, Event::Connect));
        text += &format!("@2 {}", ev(5, Event::In(vec![0xff, 0xff, 0, 1, 1, 0xfd])));
        text += &format!("@1 {}", ev(9, Event::Close));
        text += &format!("@3 {}", ev(10, Event::Close));
        text += "@1 not a time\n";
        assert!(sniff(text.as_bytes()));
        let split = split(&text).unwrap();
        assert_eq!(split.len(), 2);
        assert_eq!(split[0].header.model, Some(Model::R2D2));
        assert_eq!(split[0].header.droid.as_deref(), Some("D2-0001"));
        assert_eq!(split[0].events.len(), 2);
        assert_eq!(split[1].header.model, Some(Model::BB8));
        assert_eq!(split[1].events.len(), 2);
        assert_eq!(
            split[1].events[1].event,
            Event::In(vec![0xff, 0xff, 0, 1, 1, 0xfd])
        );
        assert!(
            split[0]
                .warnings
                .iter()
                .any(|w| w.contains("no droid \"3\""))
        );
        assert!(split[0].warnings.iter().any(|w| w.contains("not a time")));
        // One droid's reader refuses the fleet's version with what to do.
        let e = Capture::from_text(&text).unwrap_err();
        assert!(e.contains("several droids"), "{e}");
    }

    #[test]
    fn malformed_headers_are_errors() {
        assert!(split("droidctl-capture 1\n").is_err());
        assert!(split("droidctl-capture 2\n@1 0.000 connect\n").is_err());
        assert!(split("droidctl-capture 2\n# droid-2: r2d2 v2 X\n").is_err());
        assert!(split("droidctl-capture 2\n# droids: 0\n").is_err());
        assert!(!sniff(b"droidctl-capture 20\n"));
    }
}
