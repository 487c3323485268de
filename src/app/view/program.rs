//! What the screen shows of the Sphero Edu program running beside the app (`--program`,
//! issue 38 point 10), below everything that changes it ([`super::super::program_status`]
//! feeds it): the program's view, the gauges while it drives, and the words the status bar and
//! the end banner use.

use crate::edu::progress::{ProgramState, ProgramStatus};
use crate::teleop::control::ControlView;

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
