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
    let mut plan = PlanBuilder::default();
    for t in &c.events {
        plan.event(t);
    }
    plan.check(c.kind)
}

/// The script line of a mission's `step LINE TEXT` mark. A Sphero Edu program's run marks
/// its calls the same way (`step 3 roll(90, 100, 2)`, `step 4 setMainLed(255, 0, 0)`, and
/// what a robot without a speaker says: `step 5 Sphero BOLT plays sound "Animal.Cat"`):
/// those are not script lines, and are neither read as one nor refused. A mission line
/// starts with one of the script's commands; nothing else is read as one.
fn step_text(mark: &str) -> Option<&str> {
    let rest = mark.strip_prefix("step ")?;
    let (_, text) = rest.split_once(' ')?;
    let first = text.split_whitespace().next().unwrap_or("");
    crate::script::COMMANDS
        .iter()
        .any(|c| c.eq_ignore_ascii_case(first))
        .then_some(text)
}

/// What sampling a capture needs to know before its first event: where the mission starts
/// and ends, and whether it marks its steps. One pass over the events finds it
/// ([`PlanBuilder`]), so a capture can be sampled from a file read twice, never held whole.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Plan {
    start: Duration,
    end: Duration,
    /// Events from this index on are after the mission (its `mission-end` mark on).
    end_idx: usize,
    /// The index of the `mission-start` mark.
    start_idx: Option<usize>,
    steps: bool,
}

/// A [`Plan`] taken from the events one by one.
#[derive(Debug, Clone, Default)]
pub struct PlanBuilder {
    n: usize,
    mission_start: Option<(usize, Duration)>,
    first_connect: Option<Duration>,
    first: Option<Duration>,
    last: Option<Duration>,
    mission_end: Option<(usize, Duration)>,
    steps: bool,
    /// The first mission step mark whose script line cannot be read.
    bad_mark: Option<String>,
}

impl PlanBuilder {
    /// What replay refuses (see [`validate`]), once every event is in; `kind` names the
    /// capture in the message.
    pub fn check(&self, kind: &str) -> Result<(), String> {
        let span = self.span();
        if span > MAX_SPAN {
            return Err(format!(
                "the {kind} spans {:.0} days from its first event to its last; a recording holds at \
                 most {} days (is a time stamp damaged?)",
                span.as_secs_f64() / 86_400.0,
                MAX_SPAN.as_secs() / 86_400
            ));
        }
        match &self.bad_mark {
            Some(m) => Err(m.clone()),
            None => Ok(()),
        }
    }

    pub fn event(&mut self, t: &super::Timed) {
        if self.bad_mark.is_none()
            && let Event::Mark(m) = &t.event
            && let Some(text) = step_text(m)
            && let Err(errors) = crate::script::parse(text)
        {
            let why: Vec<String> = errors.iter().map(|e| e.message.clone()).collect();
            self.bad_mark = Some(format!(
                "the mark at {} ms (`{}`): {}",
                super::format_time(t.at),
                super::shown(m),
                why.join("; ")
            ));
        }
        let i = self.n;
        self.n += 1;
        self.first.get_or_insert(t.at);
        self.last = Some(t.at);
        match &t.event {
            Event::Connect if self.first_connect.is_none() => self.first_connect = Some(t.at),
            Event::Mark(m) if m == "mission-start" && self.mission_start.is_none() => {
                self.mission_start = Some((i, t.at))
            }
            Event::Mark(m) if m == "mission-end" && self.mission_end.is_none() => {
                self.mission_end = Some((i, t.at))
            }
            Event::Mark(m) if m.starts_with("step ") => self.steps = true,
            _ => {}
        }
    }

    /// The time of the last event seen.
    pub fn last(&self) -> Option<Duration> {
        self.last
    }

    /// Events seen.
    pub fn events(&self) -> usize {
        self.n
    }

    /// The events' span from first to last.
    pub fn span(&self) -> Duration {
        match (self.first, self.last) {
            (Some(a), Some(b)) => b.saturating_sub(a),
            _ => Duration::ZERO,
        }
    }

    pub fn plan(&self) -> Plan {
        let start = self
            .mission_start
            .map(|(_, at)| at)
            .or(self.first_connect)
            .or(self.first)
            .unwrap_or_default();
        // The mission ends at its mark: what follows (the final stop, the close) is not its.
        let (end_idx, end) = match self.mission_end {
            Some((i, at)) => (i, at),
            None => (self.n, self.last.unwrap_or_default()),
        };
        Plan {
            start,
            end: end.max(start),
            end_idx,
            start_idx: self.mission_start.map(|(i, _)| i),
            steps: self.steps,
        }
    }
}

/// Telemetry samples made as a capture's events come, one by one, as [`samples`] makes them
/// (memory flat whatever the capture's length).
pub struct Sampler {
    plan: Plan,
    interval: Duration,
    mirror: Mirror,
    telemetry: Telemetry,
    next_sample: Duration,
    idx: usize,
    out: Vec<Output>,
}

impl Sampler {
    pub fn new(plan: Plan, model: Model, interval: Duration) -> Sampler {
        Sampler {
            plan,
            interval: interval.max(Duration::from_millis(1)),
            mirror: Mirror::new(model),
            telemetry: Telemetry::default(),
            next_sample: plan.start,
            idx: 0,
            out: Vec::new(),
        }
    }

    fn sample(&self, at: Duration) -> Sample {
        crate::mission::sample_of(
            &self.telemetry,
            at.saturating_sub(self.plan.start).as_millis() as u64,
        )
    }

    fn apply(&mut self, e: &super::Timed) {
        self.out.clear();
        self.mirror.event(e, &mut self.out);
        if e.at >= self.plan.start {
            for o in &self.out {
                fold(
                    &mut self.telemetry,
                    o,
                    e.at.saturating_sub(self.plan.start),
                    self.plan.steps,
                );
            }
        }
    }

    /// The samples due before `quiet_until` (the next event's time, or the end) are emitted
    /// as they come; a silence longer than [`MAX_GAP`] is jumped over.
    fn jump_gap(&mut self, quiet_until: Duration, gap: &mut dyn FnMut(Duration, Duration)) {
        if quiet_until.saturating_sub(self.next_sample) > MAX_GAP {
            let steps =
                (quiet_until - self.next_sample).as_nanos() / self.interval.as_nanos().max(1);
            let resume = self.next_sample + self.interval * steps.min(u32::MAX as u128) as u32;
            let start = self.plan.start;
            gap(
                self.next_sample.saturating_sub(start),
                resume.saturating_sub(start),
            );
            self.next_sample = resume;
        }
    }

    /// The next event of the capture (in order, every one).
    pub fn event(
        &mut self,
        e: &super::Timed,
        emit: &mut dyn FnMut(&Sample) -> std::io::Result<()>,
        gap: &mut dyn FnMut(Duration, Duration),
    ) -> std::io::Result<()> {
        let idx = self.idx;
        self.idx += 1;
        if idx >= self.plan.end_idx {
            return Ok(());
        }
        // The first sample holds what came up to the mission's start: the events before its
        // mark, or at its time without one (the connect greeting); later ones what came
        // before them.
        while self.next_sample < self.plan.end {
            let first = self.next_sample == self.plan.start;
            let before = e.at < self.next_sample
                || (first
                    && self
                        .plan
                        .start_idx
                        .map_or(e.at == self.plan.start, |s| idx < s));
            if before {
                break;
            }
            emit(&self.sample(self.next_sample))?;
            self.next_sample += self.interval;
            // Nothing happens until this event (or the end): jump a long silence.
            self.jump_gap(e.at.min(self.plan.end), gap);
        }
        self.apply(e);
        Ok(())
    }

    /// After the last event: the samples up to the end, the final one, and the summary.
    pub fn finish(
        mut self,
        emit: &mut dyn FnMut(&Sample) -> std::io::Result<()>,
        gap: &mut dyn FnMut(Duration, Duration),
    ) -> std::io::Result<ReplaySummary> {
        while self.next_sample < self.plan.end {
            emit(&self.sample(self.next_sample))?;
            self.next_sample += self.interval;
            self.jump_gap(self.plan.end, gap);
        }
        emit(&self.sample(self.plan.end))?;
        Ok(self.summary())
    }

    fn summary(&self) -> ReplaySummary {
        let (end, start, telemetry, mirror) = (
            self.plan.end,
            self.plan.start,
            &self.telemetry,
            &self.mirror,
        );
        // Counters up to the end, as the mission counted them.
        let st = mirror.stats();
        ReplaySummary {
            done: true,
            t_ms: end.saturating_sub(start).as_millis() as u64,
            sent: st.sent,
            received: st.received,
            errors: st.errors,
            unanswered: mirror.pending() as u64,
            collisions: telemetry.collisions,
            x_cm: telemetry.x_cm,
            y_cm: telemetry.y_cm,
        }
    }
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
    let mut plan = PlanBuilder::default();
    for t in &capture.events {
        plan.event(t);
    }
    let mut sampler = Sampler::new(plan.plan(), model, interval);
    for t in &capture.events {
        sampler.event(t, emit, gap)?;
    }
    sampler.finish(emit, gap)
}
