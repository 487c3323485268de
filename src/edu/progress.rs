//! What a running program is doing, for a screen to show (issue 38 point 10: the app showed
//! nothing of it): its state, the line it waits on, what it commands the droid, and how it
//! ended. The runtime ([`super::run`]) publishes it through a `watch`: a watch holds the
//! latest value only, so however fast a program calls, what waits for a reader is bounded,
//! and a slow reader never holds the program up.

use std::collections::VecDeque;
use std::sync::Arc;
use tokio::sync::watch;

/// The longest call text kept (a call's arguments can be a long string: `scrollMatrixText`).
pub const MAX_CALL_CHARS: usize = 80;
/// The longest error message kept (the whole one is in the log and said at exit).
pub const MAX_MESSAGE_CHARS: usize = 400;
/// Calls waited on kept at once (un-awaited timed calls pile up in a loop).
const MAX_PENDING: usize = 64;

/// Where a program stands.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ProgramState {
    /// Waiting for the droid to be set up and its first sample (every reading is a number
    /// from the program's first line).
    Starting,
    /// Between its turns: waiting on a call ([`ProgramStatus::waiting_on`]) or for an event.
    Running,
    /// `startProgram` returned with no handler left, or `exitProgram()`.
    Ended,
    /// The operator's emergency stop ended it: the operator's choice, not a failure.
    Stopped,
    /// Its own error (or its engine's, or its time limit) ended it; the line when known.
    Failed { line: Option<u32>, message: String },
}

impl ProgramState {
    /// Whether the program is over.
    pub fn over(&self) -> bool {
        matches!(
            self,
            ProgramState::Ended | ProgramState::Stopped | ProgramState::Failed { .. }
        )
    }
}

/// A call the program waits on: its line and the call as written (`delay(1)`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Call {
    pub line: u32,
    pub text: String,
}

/// What the program last commanded the droid's drive (the app's gauges show it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Commanded {
    /// 0..=255.
    pub speed: u8,
    /// Degrees, 0..360.
    pub heading: u16,
    pub reverse: bool,
    /// `rawMotor(left, right)`: the motors, −255..=255 each, instead of a speed.
    pub tank: Option<(i16, i16)>,
}

/// A program's status as a screen shows it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProgramStatus {
    /// The program as given (`square.js`).
    pub name: String,
    pub state: ProgramState,
    /// The call it waits on now (the latest of those pending), if any.
    pub waiting_on: Option<Call>,
    /// The events its handlers listen for (`collision`, …).
    pub listening: Vec<&'static str>,
    /// Its drive as last commanded (`None` before its first).
    pub drive: Option<Commanded>,
}

impl ProgramStatus {
    pub fn new(name: impl Into<String>) -> ProgramStatus {
        ProgramStatus {
            name: name.into(),
            state: ProgramState::Starting,
            waiting_on: None,
            listening: Vec::new(),
            drive: None,
        }
    }
}

/// Where a runtime publishes its program's status (`ProgramOptions::progress`): the app
/// holds the receiving end.
pub type Progress = Arc<watch::Sender<ProgramStatus>>;

/// A new channel for the program named `name`: the sender for the runtime, the receiver for
/// a screen.
pub fn channel(name: &str) -> (Progress, watch::Receiver<ProgramStatus>) {
    let (tx, rx) = watch::channel(ProgramStatus::new(name));
    (Arc::new(tx), rx)
}

/// `text` cut to `max` characters (an ellipsis says it was).
pub fn cut(text: &str, max: usize) -> String {
    if text.chars().count() <= max {
        return text.to_string();
    }
    let mut s: String = text.chars().take(max.saturating_sub(1)).collect();
    s.push('…');
    s
}

/// The runtime's side: the calls pending (by promise), and where to publish.
#[derive(Debug, Default)]
pub(super) struct Reporter {
    to: Option<Progress>,
    /// Calls whose promise is not yet resolved, oldest first.
    pending: VecDeque<(u64, Call)>,
}

impl Reporter {
    pub fn new(to: Option<Progress>) -> Reporter {
        Reporter {
            to,
            pending: VecDeque::new(),
        }
    }

    fn update(&self, f: impl FnOnce(&mut ProgramStatus) -> bool) {
        if let Some(tx) = &self.to {
            tx.send_if_modified(f);
        }
    }

    /// A call that returns a promise resolved later: the program may wait on it.
    pub fn called(&mut self, promise: u64, line: u32, text: &str) {
        if self.to.is_none() {
            return;
        }
        if self.pending.len() >= MAX_PENDING {
            self.pending.pop_front();
        }
        self.pending.push_back((
            promise,
            Call {
                line,
                text: cut(text, MAX_CALL_CHARS),
            },
        ));
    }

    /// Promises resolved: their calls are no longer waited on.
    pub fn resolved(&mut self, promises: &[u64]) {
        if !promises.is_empty() {
            self.pending.retain(|(id, _)| !promises.contains(id));
        }
    }

    /// A turn is over and the program waits: on its latest pending call, or for events.
    pub fn waiting(&self, listening: &[&'static str]) {
        let on = self.pending.back().map(|(_, c)| c.clone());
        self.update(|s| {
            let next = (ProgramState::Running, on, listening);
            if (&s.state, &s.waiting_on, s.listening.as_slice()) == (&next.0, &next.1, next.2) {
                return false;
            }
            s.state = next.0;
            s.waiting_on = next.1;
            s.listening = listening.to_vec();
            true
        });
    }

    /// The program's drive as commanded now.
    pub fn drove(&self, c: Commanded) {
        self.update(|s| {
            let changed = s.drive != Some(c);
            s.drive = Some(c);
            changed
        });
    }

    /// `setSpeed`, `roll`, `setHeading`, `stopRoll`…: the drive as the droid is told it.
    pub fn drove_at(&self, speed: u8, heading: u16, reverse: bool) {
        self.drove(Commanded {
            speed,
            heading,
            reverse,
            tank: None,
        });
    }

    /// `rawMotor(left, right)`: the motors, no speed or heading.
    pub fn raw(&self, left: i16, right: i16) {
        let heading = self
            .to
            .as_ref()
            .map_or(0, |tx| tx.borrow().drive.map_or(0, |d| d.heading));
        self.drove(Commanded {
            speed: left.unsigned_abs().max(right.unsigned_abs()).min(255) as u8,
            heading,
            reverse: false,
            tank: Some((left, right)),
        });
    }

    /// The program's play ended with `r`; `estop` is the message of an end by the
    /// operator's emergency stop.
    pub fn ended(&mut self, r: &Result<(), super::engine::Failure>, estop: &str) {
        self.over(match r {
            Ok(()) => ProgramState::Ended,
            Err(f) if f.line.is_none() && f.message == estop => ProgramState::Stopped,
            Err(f) => ProgramState::Failed {
                line: f.line,
                message: f.message.clone(),
            },
        });
    }

    /// The program is over: how (the drive is stopped by then).
    fn over(&mut self, state: ProgramState) {
        self.pending.clear();
        let state = match state {
            ProgramState::Failed { line, message } => ProgramState::Failed {
                line,
                message: cut(&message, MAX_MESSAGE_CHARS),
            },
            s => s,
        };
        self.update(|s| {
            s.state = state;
            s.waiting_on = None;
            s.listening.clear();
            if let Some(d) = &mut s.drive {
                d.speed = 0;
                d.tank = d.tank.map(|_| (0, 0));
            }
            true
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_latest_pending_call_is_the_one_waited_on() {
        let (tx, rx) = channel("p.js");
        let mut r = Reporter::new(Some(tx));
        r.called(1, 3, "roll(0, 50, 2)");
        r.called(2, 4, "delay(1)");
        r.waiting(&[]);
        assert_eq!(rx.borrow().waiting_on.as_ref().map(|c| c.line), Some(4));
        r.resolved(&[2]);
        r.waiting(&["collision"]);
        assert_eq!(rx.borrow().waiting_on.as_ref().map(|c| c.line), Some(3));
        r.resolved(&[1]);
        r.waiting(&["collision"]);
        let s = rx.borrow().clone();
        assert_eq!((s.waiting_on, s.listening), (None, vec!["collision"]));
    }

    #[test]
    fn what_is_kept_is_bounded() {
        let (tx, rx) = channel("p.js");
        let mut r = Reporter::new(Some(tx));
        for i in 0..10_000 {
            r.called(i, 1, &"x".repeat(10_000));
        }
        assert_eq!(r.pending.len(), MAX_PENDING);
        r.waiting(&[]);
        let shown = rx
            .borrow()
            .waiting_on
            .clone()
            .map(|c| c.text.chars().count());
        assert_eq!(shown, Some(MAX_CALL_CHARS));
        r.over(ProgramState::Failed {
            line: Some(1),
            message: "e".repeat(100_000),
        });
        let ProgramState::Failed { message, .. } = rx.borrow().state.clone() else {
            panic!("failed");
        };
        assert_eq!(message.chars().count(), MAX_MESSAGE_CHARS);
    }

    #[test]
    fn an_ended_program_commands_no_speed() {
        let (tx, rx) = channel("p.js");
        let mut r = Reporter::new(Some(tx));
        r.drove(Commanded {
            speed: 100,
            heading: 90,
            ..Commanded::default()
        });
        assert_eq!(rx.borrow().drive.map(|d| d.speed), Some(100));
        r.over(ProgramState::Ended);
        let s = rx.borrow().clone();
        assert_eq!(s.state, ProgramState::Ended);
        assert_eq!(s.drive.map(|d| (d.speed, d.heading)), Some((0, 90)));
    }
}
