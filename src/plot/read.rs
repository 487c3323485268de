//! `plot`'s inputs, streamed into [`Tracks`]: a `run --json` / `replay --json` output (one
//! droid, or a fleet's lines naming their droid), a droidctl capture of one droid or of
//! several, a btsnoop log. Nothing holds the whole input: JSON is read line by line, a
//! droidctl capture is read twice (once to find the mission's start and end, once to sample
//! it); only a btsnoop log is loaded whole (its records are sorted by time).
//!
//! Every input is hostile: lines are bounded ([`MAX_LINE`]), errors name the line, nothing
//! panics. A file that is not such an input is [`ReadError::Bad`] (exit 2); one that cannot
//! be read is [`ReadError::Io`] (exit 1).

use super::track::Tracks;
use crate::capture::fleet::{FleetLine, FleetReader};
use crate::capture::replay::{PlanBuilder, Sampler};
use crate::capture::{Line, TextReader};
use crate::mission::Sample;
use crate::model::Model;
use std::io::{BufRead, Read};
use std::time::Duration;

/// What `droidctl plot` reads, for every message about an input it cannot read.
pub const READS: &str = "plot reads the output of `droidctl run --json` or `replay --json`, or \
                         a capture (`--record`, a btsnoop log)";

/// The longest line read (a sample's JSON is under 1 KiB; a capture's line under 2.1 KiB).
pub const MAX_LINE: usize = 64 * 1024;

/// Why an input could not be plotted.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ReadError {
    /// Not a run's output or a capture (bad input).
    Bad(String),
    /// Reading failed.
    Io(String),
}

/// What the capture readers need to know.
#[derive(Debug, Clone, Copy)]
pub struct Options {
    pub interval: Duration,
    /// `--model`, for a capture that does not name its droid.
    pub model: Option<Model>,
}

/// Lines of a reader, at most [`MAX_LINE`] bytes each: a longer one is cut there and
/// flagged (the rest of it is skipped).
pub struct Lines<R> {
    reader: R,
    buf: Vec<u8>,
    pub number: usize,
}

impl<R: BufRead> Lines<R> {
    pub fn new(reader: R) -> Self {
        Lines {
            reader,
            buf: Vec::new(),
            number: 0,
        }
    }

    /// The next line (without its end): its number, its text, and whether it was too long;
    /// `None` at the end.
    pub fn next_line(&mut self) -> std::io::Result<Option<(usize, &str, bool)>> {
        self.buf.clear();
        let n = (&mut self.reader)
            .take(MAX_LINE as u64 + 1)
            .read_until(b'\n', &mut self.buf)?;
        if n == 0 {
            return Ok(None);
        }
        self.number += 1;
        let mut long = false;
        if self.buf.last() != Some(&b'\n') && self.buf.len() > MAX_LINE {
            long = true;
            // Skip the rest of the line.
            loop {
                let chunk = self.reader.fill_buf()?;
                if chunk.is_empty() {
                    break;
                }
                match chunk.iter().position(|b| *b == b'\n') {
                    Some(i) => {
                        self.reader.consume(i + 1);
                        break;
                    }
                    None => {
                        let len = chunk.len();
                        self.reader.consume(len);
                    }
                }
            }
            self.buf.truncate(MAX_LINE);
        }
        while matches!(self.buf.last(), Some(b'\n' | b'\r')) {
            self.buf.pop();
        }
        let text = match std::str::from_utf8(&self.buf) {
            Ok(t) => t,
            Err(e) => std::str::from_utf8(&self.buf[..e.valid_up_to()]).unwrap_or_default(),
        };
        Ok(Some((self.number, text, long)))
    }
}

/// The kind of an input, from its first bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Json,
    Capture,
    Fleet,
    Btsnoop,
}

/// What `head` (the input's first bytes) is; `None`: nothing a plot reads.
pub fn kind(head: &[u8]) -> Option<Kind> {
    if crate::capture::fleet::sniff(head) {
        return Some(Kind::Fleet);
    }
    if TextReader::sniff(head) {
        return Some(Kind::Capture);
    }
    if crate::capture::btsnoop::sniff(head) {
        return Some(Kind::Btsnoop);
    }
    match head.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'{') => Some(Kind::Json),
        _ => None,
    }
}

/// The first line of a `run --json` sample naming its droid, and the summary's mark.
#[derive(serde::Deserialize)]
struct Tag {
    droid: Option<String>,
    done: Option<serde_json::Value>,
}

/// A `run --json` output into `tracks`: every object but the summaries (`"done"`), each
/// named by its `droid` when a fleet's. `name` names the input in messages.
pub fn json(reader: impl BufRead, name: &str, tracks: &mut Tracks) -> Result<(), ReadError> {
    let mut lines = Lines::new(reader);
    while let Some((n, line, long)) = lines.next_line().map_err(|e| io(name, e))? {
        if long {
            return Err(ReadError::Bad(format!(
                "{name}:{n}: a line longer than {} KiB; {READS}",
                MAX_LINE / 1024
            )));
        }
        let line = line.trim().trim_start_matches('\u{feff}');
        if line.is_empty() {
            continue;
        }
        let tag: Tag = serde_json::from_str(line)
            .map_err(|e| ReadError::Bad(format!("{name}:{n}: not a JSON object ({e}); {READS}")))?;
        if tag.done.is_some() {
            continue;
        }
        let s: Sample = serde_json::from_str(line).map_err(|e| {
            ReadError::Bad(format!("{name}:{n}: not a telemetry sample ({e}); {READS}"))
        })?;
        tracks
            .push(tag.droid.as_deref(), &s)
            .map_err(|e| ReadError::Bad(format!("{name}:{n}: {e}")))?;
    }
    Ok(())
}

fn io(name: &str, e: std::io::Error) -> ReadError {
    ReadError::Io(format!("cannot read {name}: {e}"))
}

/// The model to sample a droid's capture with: its own, `--model` when of its family, else
/// its family's representative.
fn model_of(
    header: &crate::capture::Header,
    family: Option<crate::model::Protocol>,
    given: Option<Model>,
) -> Option<Model> {
    let family = header
        .family
        .or(header.model.map(Model::protocol))
        .or(family);
    header
        .model
        .or(given.filter(|m| family.is_none_or(|f| m.protocol() == f)))
        .or_else(|| family.map(|f| crate::family::for_protocol(f).representative()))
}

/// Warnings said on stderr as they come, at most a few, then counted.
struct Said {
    name: String,
    warnings: crate::capture::Warnings,
}

impl Said {
    fn done(self) {
        use std::io::Write;
        for w in self.warnings.into_lines() {
            let _ = writeln!(std::io::stderr(), "droidctl: {}: {w}", self.name);
        }
    }
}

/// A droidctl capture of one droid into `tracks`, from `open` (called once per pass).
pub fn capture<R: BufRead>(
    open: &mut dyn FnMut() -> std::io::Result<R>,
    name: &str,
    opts: Options,
    tracks: &mut Tracks,
) -> Result<(), ReadError> {
    // Pass 1: the header, the mission's start and end, the family.
    let mut reader = TextReader::new();
    let mut plan = PlanBuilder::default();
    let mut family = None;
    let mut said = Said {
        name: name.to_string(),
        warnings: Default::default(),
    };
    let mut lines = Lines::new(open().map_err(|e| io(name, e))?);
    let mut events = 0u64;
    while let Some((n, line, long)) = lines.next_line().map_err(|e| io(name, e))? {
        if long {
            said.warnings.push(format!(
                "line {n}: longer than {} KiB: skipped",
                MAX_LINE / 1024
            ));
            continue;
        }
        match reader.line(line) {
            Ok(Line::Event(t)) => {
                events += 1;
                if family.is_none() {
                    family = t.event.family();
                }
                plan.event(&t);
            }
            Ok(Line::Nothing) => {}
            Ok(Line::Unknown(kind)) => said.warnings.push(crate::capture::unknown_kind(n, &kind)),
            Err(e) if e.line == 1 => return Err(ReadError::Bad(format!("{name}: {e}"))),
            Err(e) => said.warnings.push(e.to_string()),
        }
    }
    said.done();
    if lines.number == 0 {
        return Ok(());
    }
    plan.check("droidctl capture")
        .map_err(|e| ReadError::Bad(format!("{name}: {e}")))?;
    if events == 0 {
        return Ok(());
    }
    let model = model_of(&reader.header, family, opts.model)
        .ok_or_else(|| ReadError::Bad(format!("{name}: no droid traffic found")))?;
    // Pass 2: the samples.
    let mut sampler = Sampler::new(plan.plan(), model, opts.interval);
    let mut reader = TextReader::new();
    let mut lines = Lines::new(open().map_err(|e| io(name, e))?);
    let mut bad = None;
    let mut emit = |s: &Sample| {
        if let Err(e) = tracks.push(None, s) {
            bad = Some(e);
        }
        Ok(())
    };
    while let Some((_, line, long)) = lines.next_line().map_err(|e| io(name, e))? {
        if long {
            continue;
        }
        if let Ok(Line::Event(t)) = reader.line(line) {
            sampler
                .event(&t, &mut emit, &mut |_, _| {})
                .map_err(|e| io(name, e))?;
        }
    }
    sampler
        .finish(&mut emit, &mut |_, _| {})
        .map_err(|e| io(name, e))?;
    match bad {
        Some(e) => Err(ReadError::Bad(format!("{name}: {e}"))),
        None => Ok(()),
    }
}

/// A droidctl capture of several droids into `tracks`, each droid its own track named as
/// its header names it, from `open` (called once per pass).
pub fn fleet<R: BufRead>(
    open: &mut dyn FnMut() -> std::io::Result<R>,
    name: &str,
    opts: Options,
    tracks: &mut Tracks,
) -> Result<(), ReadError> {
    let bad = |e: String| ReadError::Bad(format!("{name}: {e}"));
    // Pass 1.
    let mut reader = FleetReader::new();
    let mut plans: Vec<PlanBuilder> = Vec::new();
    let mut families = Vec::new();
    let mut shared = Vec::new();
    let mut said = Said {
        name: name.to_string(),
        warnings: Default::default(),
    };
    let mut lines = Lines::new(open().map_err(|e| io(name, e))?);
    while let Some((n, line, long)) = lines.next_line().map_err(|e| io(name, e))? {
        if long {
            said.warnings.push(format!(
                "line {n}: longer than {} KiB: skipped",
                MAX_LINE / 1024
            ));
            continue;
        }
        match reader.line(line).map_err(bad)? {
            FleetLine::Event(i, t) => {
                plans.resize_with(reader.droids(), PlanBuilder::default);
                families.resize(reader.droids(), None);
                if families[i].is_none() {
                    families[i] = t.event.family();
                }
                plans[i].event(&t);
            }
            FleetLine::Shared(t) => shared.push(t),
            FleetLine::Nothing => {}
            FleetLine::DroidWarning(_, w) | FleetLine::Warning(w) => said.warnings.push(w),
        }
    }
    said.done();
    reader.finish().map_err(bad)?;
    let n = reader.droids();
    plans.resize_with(n, PlanBuilder::default);
    families.resize(n, None);
    // The lines about every droid (the recorder's `end`) close each droid's events where
    // they are in time order (as [`crate::capture::fleet::read`] gives them).
    let closing: Vec<Vec<crate::capture::Timed>> = plans
        .iter_mut()
        .map(|p| {
            let mine: Vec<_> = shared
                .iter()
                .filter(|t: &&crate::capture::Timed| p.last().is_none_or(|l| l <= t.at))
                .cloned()
                .collect();
            for t in &mine {
                p.event(t);
            }
            mine
        })
        .collect();
    let mut samplers = Vec::with_capacity(n);
    let mut names = Vec::with_capacity(n);
    for (k, plan) in plans.iter().enumerate() {
        plan.check("droidctl capture")
            .map_err(|e| bad(format!("droid {}: {e}", k + 1)))?;
        let header = reader.header(k);
        let model = model_of(&header, families[k], opts.model);
        names.push(header.droid.clone().unwrap_or_else(|| {
            let m = model.map_or("droid", Model::display_name);
            format!("{m} {}", k + 1)
        }));
        // A droid without a single event has nothing to draw.
        samplers.push(
            model
                .filter(|_| plan.events() > 0)
                .map(|m| Sampler::new(plan.plan(), m, opts.interval)),
        );
    }
    // Pass 2: each droid's events to its sampler, each sample to its track.
    let mut failed = None;
    let mut reader = FleetReader::new();
    let mut lines = Lines::new(open().map_err(|e| io(name, e))?);
    while let Some((_, line, long)) = lines.next_line().map_err(|e| io(name, e))? {
        if long {
            continue;
        }
        if let Ok(FleetLine::Event(i, t)) = reader.line(line)
            && let Some(Some(s)) = samplers.get_mut(i)
        {
            let droid = names[i].as_str();
            s.event(
                &t,
                &mut |x| {
                    if let Err(e) = tracks.push(Some(droid), x) {
                        failed = Some(e);
                    }
                    Ok(())
                },
                &mut |_, _| {},
            )
            .map_err(|e| io(name, e))?;
        }
    }
    for ((s, droid), closing) in samplers.into_iter().zip(&names).zip(&closing) {
        let Some(mut s) = s else { continue };
        for t in closing {
            s.event(
                t,
                &mut |x| {
                    if let Err(e) = tracks.push(Some(droid), x) {
                        failed = Some(e);
                    }
                    Ok(())
                },
                &mut |_, _| {},
            )
            .map_err(|e| io(name, e))?;
        }
        s.finish(
            &mut |x| {
                if let Err(e) = tracks.push(Some(droid), x) {
                    failed = Some(e);
                }
                Ok(())
            },
            &mut |_, _| {},
        )
        .map_err(|e| io(name, e))?;
    }
    match failed {
        Some(e) => Err(bad(e)),
        None => Ok(()),
    }
}
