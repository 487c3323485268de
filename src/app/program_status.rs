//! The Sphero Edu program running beside the app (`droidctl --program P.js`), as the screen
//! shows it (issue 38 point 10): its name, state and the line it waits on in the status bar,
//! its drive in the gauges (input "program" instead of "deadman"), and its end or error in a
//! banner that stays until a key.
//!
//! The runtime publishes each droid's program through a `watch` ([`crate::edu::progress`]);
//! [`forward`] turns every droid's into one bounded channel the event loop reads, so one task
//! owns the state, as for every other input.

use super::core::App;
use super::state::ControlView;
use crate::edu::progress::{ProgramState, ProgramStatus};
use tokio::sync::{mpsc, watch};

/// What the app shows of a droid's program.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProgramView {
    pub status: ProgramStatus,
    /// Its end was seen (a key was pressed since): the banner is gone.
    pub acknowledged: bool,
}

impl ProgramView {
    /// Whether its end's banner is up.
    pub fn banner(&self) -> bool {
        self.status.state.over() && !self.acknowledged
    }
}

/// Each droid's program status, by fleet index (droids without a program have none).
pub type ProgramFeeds = Vec<(usize, watch::Receiver<ProgramStatus>)>;

/// Statuses waiting for the loop at most: each is a droid's latest, so a full channel only
/// delays a forwarder, which then sends the newest.
const CAPACITY: usize = 32;

/// Every droid's program status into one channel, tagged with its index; and the tasks.
pub(super) fn forward(
    feeds: ProgramFeeds,
) -> (
    mpsc::Receiver<(usize, ProgramStatus)>,
    Vec<tokio::task::JoinHandle<()>>,
) {
    let (tx, rx) = mpsc::channel(CAPACITY);
    let tasks = feeds
        .into_iter()
        .map(|(i, mut feed)| {
            let tx = tx.clone();
            tokio::spawn(async move {
                // The status as it is now, then every change until the runtime is gone.
                loop {
                    let s = feed.borrow_and_update().clone();
                    if tx.send((i, s)).await.is_err() || feed.changed().await.is_err() {
                        return;
                    }
                }
            })
        })
        .collect();
    (rx, tasks)
}

/// The drive panel's view: the operator's controller's, or while a program drives and the
/// operator does not (no drive input, no emergency stop), what the program commands.
pub fn shown(operator: &ControlView, program: Option<&ProgramView>) -> ControlView {
    let driving = program.filter(|p| !p.status.state.over());
    let Some(d) = driving.and_then(|p| p.status.drive) else {
        return operator.clone();
    };
    if !operator.deadman || operator.estop {
        return operator.clone();
    }
    ControlView {
        speed: d.speed,
        heading: crate::units::Heading::wrapped(f64::from(d.heading)),
        reverse: d.reverse,
        tank: d.tank,
        // The program holds the drive: the deadman does not.
        deadman: d.speed == 0 && d.tank.is_none_or(|t| t == (0, 0)),
        source: "program",
        ..operator.clone()
    }
}

/// The words of a program's state for the status bar: `line 4 delay(1)`, `waits for
/// collision`, `ended`, `failed at line 3`, `stopped`.
pub fn state_words(s: &ProgramStatus) -> String {
    match &s.state {
        ProgramState::Starting => "starting".into(),
        ProgramState::Running => match (&s.waiting_on, s.listening.is_empty()) {
            (Some(c), _) => format!("line {} {}", c.line, c.text),
            (None, false) => format!("waits for {}", s.listening.join(", ")),
            (None, true) => "running".into(),
        },
        ProgramState::Ended => "ended".into(),
        ProgramState::Stopped => "stopped by the emergency stop".into(),
        ProgramState::Failed { line: Some(l), .. } => format!("failed at line {l}"),
        ProgramState::Failed { line: None, .. } => "failed".into(),
    }
}

/// The program's file name without its folders (`/home/class/square.js` is `square.js`):
/// the screen has little room, and the folder is the operator's own.
pub fn file_name(s: &ProgramStatus) -> &str {
    std::path::Path::new(&s.name)
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or(&s.name)
}

/// The banner's line for a program that is over: `square.js ended`, `fails.js:3: Error: boom`.
pub fn end_words(s: &ProgramStatus) -> String {
    let name = file_name(s);
    match &s.state {
        ProgramState::Failed {
            line: Some(l),
            message,
        } => format!("{name}:{l}: {message}"),
        ProgramState::Failed {
            line: None,
            message,
        } => format!("{name}: {message}"),
        ProgramState::Stopped => format!("{name}: ended by the emergency stop"),
        _ => format!("{name} ended"),
    }
}

impl App {
    /// Droid `i`'s program changed: the status bar, the gauges and, at its end, the banner.
    pub(super) fn on_program(&mut self, i: usize, status: ProgramStatus) {
        let Some(mut d) = self.droid(i) else {
            return;
        };
        let view = ProgramView {
            status,
            acknowledged: false,
        };
        if d.view.program.as_ref() == Some(&view) {
            return;
        }
        d.view.program = Some(view);
        *d.dirty = true;
        // The gauges follow the program's drive now, not at the next control tick.
        d.apply(Vec::new());
    }

    /// A key was pressed: every end banner is seen. The key still does what it does (the
    /// emergency stop is never taken by a banner).
    pub(super) fn acknowledge_programs(&mut self) {
        for d in &mut self.state.droids {
            if let Some(p) = &mut d.program
                && p.banner()
            {
                p.acknowledged = true;
                self.dirty = true;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::edu::progress::{Call, Commanded};

    fn running(speed: u8) -> ProgramView {
        let mut status = ProgramStatus::new("p.js");
        status.state = ProgramState::Running;
        status.drive = Some(Commanded {
            speed,
            heading: 90,
            ..Commanded::default()
        });
        ProgramView {
            status,
            acknowledged: false,
        }
    }

    #[test]
    fn the_gauges_show_the_programs_drive_while_the_operator_does_not_drive() {
        let idle = ControlView::default();
        let c = shown(&idle, Some(&running(100)));
        assert_eq!(
            (c.speed, c.heading.degrees(), c.source),
            (100, 90, "program")
        );
        assert!(!c.deadman);
        // The operator drives, or stopped everything: theirs is shown.
        let driving = ControlView {
            deadman: false,
            speed: 40,
            source: "keyboard",
            ..ControlView::default()
        };
        assert_eq!(shown(&driving, Some(&running(100))), driving);
        let stopped = ControlView {
            estop: true,
            ..ControlView::default()
        };
        assert_eq!(shown(&stopped, Some(&running(100))), stopped);
        // A program that is over drives nothing.
        let mut over = running(100);
        over.status.state = ProgramState::Ended;
        assert_eq!(shown(&idle, Some(&over)), idle);
        assert_eq!(shown(&idle, None), idle);
    }

    #[test]
    fn the_state_names_the_line_waited_on() {
        let mut s = running(0).status;
        s.waiting_on = Some(Call {
            line: 4,
            text: "delay(1)".into(),
        });
        assert_eq!(state_words(&s), "line 4 delay(1)");
        s.waiting_on = None;
        s.listening = vec!["collision"];
        assert_eq!(state_words(&s), "waits for collision");
        s.state = ProgramState::Failed {
            line: Some(3),
            message: "Error: boom".into(),
        };
        assert_eq!(state_words(&s), "failed at line 3");
        assert_eq!(end_words(&s), "p.js:3: Error: boom");
        s.name = "/home/class/p.js".into();
        assert_eq!(end_words(&s), "p.js:3: Error: boom");
    }
}
