//! Replay: a capture played back through a [`Mirror`], by capture time. The app drives a
//! [`Replay`] with its own clock (pause, speed, seek, step) and applies what comes out to the
//! same telemetry and packet log as live; [`samples`] folds a whole capture into the
//! telemetry samples `droidctl run --json` prints.
//!
//! Sans-IO: positions are capture times; nothing here sleeps.

use super::mirror::{Mirror, Output};
use super::{Capture, Event};
use crate::mission::Sample;
use crate::model::Model;
use crate::telemetry::{Stance, Telemetry};
use std::time::Duration;

/// The playback speeds, slowest first.
pub const SPEEDS: [f64; 7] = [0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0];

/// A capture being played.
pub struct Replay {
    capture: Capture,
    model: Model,
    mirror: Mirror,
    /// The next event to apply.
    next: usize,
    /// Capture time reached.
    position: Duration,
}

impl Replay {
    pub fn new(capture: Capture, model: Model) -> Replay {
        Replay {
            mirror: Mirror::new(model),
            capture,
            model,
            next: 0,
            position: Duration::ZERO,
        }
    }

    pub fn capture(&self) -> &Capture {
        &self.capture
    }

    pub fn model(&self) -> Model {
        self.model
    }

    pub fn duration(&self) -> Duration {
        self.capture.duration()
    }

    pub fn position(&self) -> Duration {
        self.position
    }

    pub fn mirror(&self) -> &Mirror {
        &self.mirror
    }

    /// Events applied so far, and in all.
    pub fn progress(&self) -> (usize, usize) {
        (self.next, self.capture.events.len())
    }

    /// When the next event happens, if any is left.
    pub fn next_at(&self) -> Option<Duration> {
        self.capture.events.get(self.next).map(|t| t.at)
    }

    pub fn at_end(&self) -> bool {
        self.next >= self.capture.events.len()
    }

    /// Apply every event up to and including `t`, appending what they produced with their
    /// times; the position becomes `t` (at most the end).
    pub fn advance_to(&mut self, t: Duration, out: &mut Vec<(Duration, Output)>) {
        let mut produced = Vec::new();
        while let Some(e) = self.capture.events.get(self.next) {
            if e.at > t {
                break;
            }
            produced.clear();
            self.mirror.event(e, &mut produced);
            out.extend(produced.drain(..).map(|o| (e.at, o)));
            self.next += 1;
        }
        self.position = t.min(self.duration()).max(self.position);
    }

    /// Apply the next event, and the others at the same time; the position becomes theirs.
    /// `false` at the end.
    pub fn step(&mut self, out: &mut Vec<(Duration, Output)>) -> bool {
        match self.next_at() {
            Some(t) => {
                self.advance_to(t, out);
                true
            }
            None => false,
        }
    }

    /// Back to the start, nothing applied.
    pub fn rewind(&mut self) {
        self.mirror = Mirror::new(self.model);
        self.next = 0;
        self.position = Duration::ZERO;
    }
}

/// The time of the first mark named `name`.
fn mark(c: &Capture, name: &str) -> Option<Duration> {
    c.events.iter().find_map(|t| match &t.event {
        Event::Mark(m) if m == name => Some(t.at),
        _ => None,
    })
}

/// The action of a mission's `step LINE TEXT` mark.
fn step_action(mark: &str) -> Option<crate::script::Action> {
    crate::script::parse(step_text(mark)?)
        .ok()?
        .pop()
        .map(|s| s.action)
}

/// Telemetry as a mission folds it, from the mirror's outputs. A mission asks for a stance
/// change when its step starts, before the command is written: with `steps` (the capture
/// marks the mission's steps) the step marks say when, else the writes do.
pub fn fold(t: &mut Telemetry, o: &Output, at: Duration, steps: bool) {
    match o {
        Output::Notification(n) => t.apply(n, at),
        Output::Battery(v) => t.battery_v = Some(*v),
        Output::StanceRequested(a) if !steps => t.stance_requested(*a),
        Output::Mark(m) if steps => {
            if let Some(crate::script::Action::Stance(a)) = step_action(m) {
                t.stance_requested(a);
            }
        }
        Output::StanceRead(s) if t.stance == Stance::Unknown => {
            t.stance = Stance::from_state(*s);
        }
        _ => {}
    }
}

/// What a replayed capture ends with (`--json` prints it with `"done": true`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ReplaySummary {
    pub done: bool,
    pub t_ms: u64,
    pub sent: u64,
    pub received: u64,
    pub errors: u64,
    /// Requests whose answer is not in the capture.
    pub unanswered: u64,
    pub collisions: u32,
    pub x_cm: Option<f32>,
    pub y_cm: Option<f32>,
}

/// The longest capture replay reads, from its first event to its last: a week of recording.
/// Anything longer is a damaged time stamp, not a session.
pub const MAX_SPAN: Duration = Duration::from_secs(7 * 24 * 3600);

/// A stretch of a capture without a single event this long (the link down, the recorder
/// idle) is not sampled every interval: `replay --json` jumps over it and says so.
pub const MAX_GAP: Duration = Duration::from_secs(600);

/// What replay refuses to read: a capture spanning more than [`MAX_SPAN`], or a mission step
/// mark whose script line cannot be read (a `wait 1e20s`). One line saying where and why.
pub fn validate(c: &Capture) -> Result<(), String> {
    if let (Some(first), Some(last)) = (c.events.first(), c.events.last()) {
        let span = last.at.saturating_sub(first.at);
        if span > MAX_SPAN {
            return Err(format!(
                "the {} spans {:.0} days from its first event to its last; a recording holds at \
                 most {} days (is a time stamp damaged?)",
                c.kind,
                span.as_secs_f64() / 86_400.0,
                MAX_SPAN.as_secs() / 86_400
            ));
        }
    }
    for t in &c.events {
        if let Event::Mark(m) = &t.event
            && let Some(text) = step_text(m)
            && let Err(errors) = crate::script::parse(text)
        {
            let why: Vec<String> = errors.iter().map(|e| e.message.clone()).collect();
            return Err(format!(
                "the mark at {} ms (`{m}`): {}",
                super::format_time(t.at),
                why.join("; ")
            ));
        }
    }
    Ok(())
}

/// The script line of a mission's `step LINE TEXT` mark.
fn step_text(mark: &str) -> Option<&str> {
    let rest = mark.strip_prefix("step ")?;
    rest.split_once(' ').map(|(_, text)| text)
}

/// The telemetry samples of a whole capture, every `interval` from the mission's start (its
/// `mission-start` mark, else the first connect, else the first event) to its end
/// (`mission-end`, else the last event), then one at the end: what `droidctl run --json`
/// printed when the capture was recorded from it. A sample at `T` holds what arrived before
/// `T` (the live sampler reads the telemetry as the tick fires, before that instant's
/// notifications are through the session).
///
/// Each sample goes to `emit` as it is made (memory stays flat whatever the capture's span);
/// a stretch of more than [`MAX_GAP`] without events is jumped over and reported to `gap`
/// (from, to).
pub fn samples(
    capture: &Capture,
    model: Model,
    interval: Duration,
    emit: &mut dyn FnMut(&Sample) -> std::io::Result<()>,
    gap: &mut dyn FnMut(Duration, Duration),
) -> std::io::Result<ReplaySummary> {
    let interval = interval.max(Duration::from_millis(1));
    let start = mark(capture, "mission-start")
        .or_else(|| {
            capture
                .events
                .iter()
                .find(|t| t.event == Event::Connect)
                .map(|t| t.at)
        })
        .or(capture.events.first().map(|t| t.at))
        .unwrap_or_default();
    // The mission ends at its mark: what follows (the final stop, the close) is not its.
    let end_idx = capture
        .events
        .iter()
        .position(|t| matches!(&t.event, Event::Mark(m) if m == "mission-end"))
        .unwrap_or(capture.events.len());
    let end = capture
        .events
        .get(end_idx)
        .map(|t| t.at)
        .unwrap_or(capture.duration())
        .max(start);
    let steps = capture
        .events
        .iter()
        .any(|t| matches!(&t.event, Event::Mark(m) if m.starts_with("step ")));
    let mut mirror = Mirror::new(model);
    let mut telemetry = Telemetry::default();
    let mut out = Vec::new();
    let mut next_sample = start;
    let mut events = capture.events[..end_idx].iter().peekable();
    let sample = |t: &Telemetry, at: Duration| {
        crate::mission::sample_of(t, at.saturating_sub(start).as_millis() as u64)
    };
    let mut apply = |e: &super::Timed, telemetry: &mut Telemetry| {
        out.clear();
        mirror.event(e, &mut out);
        if e.at >= start {
            for o in &out {
                fold(telemetry, o, e.at.saturating_sub(start), steps);
            }
        }
    };
    // The first sample holds what came up to the mission's start: the events before its mark,
    // or at its time without one (the connect greeting); later ones what came before them.
    let start_idx = capture
        .events
        .iter()
        .position(|t| matches!(&t.event, Event::Mark(m) if m == "mission-start"));
    let mut idx = 0;
    while next_sample < end {
        let first = next_sample == start;
        while let Some(e) = events.next_if(|e| {
            e.at < next_sample || (first && start_idx.map_or(e.at == start, |s| idx < s))
        }) {
            apply(e, &mut telemetry);
            idx += 1;
        }
        emit(&sample(&telemetry, next_sample))?;
        next_sample += interval;
        // Nothing happens until the next event (or the end): jump a long silence.
        let quiet_until = events.peek().map_or(end, |e| e.at.min(end));
        if quiet_until.saturating_sub(next_sample) > MAX_GAP {
            let steps = (quiet_until - next_sample).as_nanos() / interval.as_nanos().max(1);
            let resume = next_sample + interval * steps.min(u32::MAX as u128) as u32;
            gap(
                next_sample.saturating_sub(start),
                resume.saturating_sub(start),
            );
            next_sample = resume;
        }
    }
    // The rest up to the end, then the final sample.
    for e in events {
        apply(e, &mut telemetry);
    }
    emit(&sample(&telemetry, end))?;
    // Counters up to the end, as the mission counted them.
    let st = mirror.stats();
    let summary = ReplaySummary {
        done: true,
        t_ms: end.saturating_sub(start).as_millis() as u64,
        sent: st.sent,
        received: st.received,
        errors: st.errors,
        unanswered: mirror.pending() as u64,
        collisions: telemetry.collisions,
        x_cm: telemetry.x_cm,
        y_cm: telemetry.y_cm,
    };
    Ok(summary)
}
