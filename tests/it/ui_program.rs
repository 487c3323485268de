//! Snapshots of the Sphero Edu program beside the app (issue 38 point 10), at 80×24 and
//! 120×40: the status bar's program segment while it rolls (name, the line it waits on, input
//! "program" and its speed in the gauges), the banner of its error naming the line, and a
//! fleet's banner with a line per droid. The states are built as the app builds them: the
//! gauges through `program_status::shown`, as the control loop does.
//!
//! Update after an intended change: `INSTA_UPDATE=always cargo test --features test-hooks
//! --test it ui_program::`, then read every changed `.snap`.

use droidctl::app::program_status::{ProgramView, shown};
use droidctl::app::state::{AppState, ControlView, DroidState};
use droidctl::edu::progress::{Call, Commanded, ProgramState, ProgramStatus};
use droidctl::model::Model;
use droidctl::session::LinkState;
use ratatui::Terminal;
use ratatui::backend::TestBackend;
use std::time::Duration;

fn status(name: &str, state: ProgramState) -> ProgramStatus {
    ProgramStatus {
        name: name.into(),
        state,
        waiting_on: None,
        listening: Vec::new(),
        drive: None,
    }
}

/// A droid as the app shows it with `program` beside it: the gauges from its drive.
fn droid(model: Model, name: &str, program: ProgramStatus) -> DroidState {
    let mut d = DroidState::new(model, name.into());
    d.link = LinkState::Connected;
    d.telemetry.battery_v = Some(3.95);
    d.telemetry.velocity_cm_s = Some([0.0, 63.0]);
    d.telemetry.x_cm = Some(0.0);
    d.telemetry.y_cm = Some(80.0);
    d.rate_in = 10.0;
    d.rate_out = 4.0;
    let view = ProgramView {
        status: program,
        acknowledged: false,
    };
    d.control = shown(&ControlView::default(), Some(&view));
    d.program = Some(view);
    d
}

fn rolling() -> ProgramStatus {
    ProgramStatus {
        waiting_on: Some(Call {
            line: 3,
            text: "delay(3)".into(),
        }),
        drive: Some(Commanded {
            speed: 100,
            heading: 0,
            ..Commanded::default()
        }),
        ..status("/home/class/square.js", ProgramState::Running)
    }
}

fn failed() -> ProgramStatus {
    ProgramStatus {
        drive: Some(Commanded::default()),
        ..status(
            "/home/class/square.js",
            ProgramState::Failed {
                line: Some(6),
                message: "ReferenceError: rol is not defined".into(),
            },
        )
    }
}

fn one(program: ProgramStatus) -> AppState {
    let mut s = AppState::for_droids(vec![droid(Model::Bolt, "SB-1A2B", program)]);
    s.now = Duration::from_secs(12);
    s
}

fn fleet() -> AppState {
    let mut s = AppState::for_droids(vec![
        droid(Model::Bolt, "SB-0001", failed()),
        droid(
            Model::Bolt,
            "SB-0002",
            status("/home/class/square.js", ProgramState::Ended),
        ),
        droid(
            Model::Bolt,
            "SB-0003",
            status("/home/class/square.js", ProgramState::Stopped),
        ),
        droid(Model::Bolt, "SB-0004", rolling()),
    ]);
    s.now = Duration::from_secs(12);
    s
}

fn render(state: &AppState, w: u16, h: u16) -> Terminal<TestBackend> {
    let mut term = Terminal::new(TestBackend::new(w, h)).expect("test backend");
    term.draw(|f| droidctl::ui::draw(f, state)).expect("draw");
    term
}

fn text(state: &AppState, w: u16, h: u16) -> String {
    let term = render(state, w, h);
    let buf = term.backend().buffer();
    buf.content
        .chunks(usize::from(w))
        .map(|row| row.iter().map(|c| c.symbol()).collect::<String>())
        .collect::<Vec<_>>()
        .join("\n")
}

macro_rules! snap {
    ($name:ident, $state:expr, $w:expr, $h:expr) => {
        #[test]
        fn $name() {
            let term = render(&$state, $w, $h);
            insta::assert_snapshot!(stringify!($name), term.backend());
        }
    };
}

snap!(program_rolling_80x24, one(rolling()), 80, 24);
snap!(program_rolling_120x40, one(rolling()), 120, 40);
snap!(program_failed_80x24, one(failed()), 80, 24);
snap!(program_failed_120x40, one(failed()), 120, 40);
snap!(program_fleet_80x24, fleet(), 80, 24);
snap!(program_fleet_120x40, fleet(), 120, 40);

/// What the snapshots show, said: the program's name, line and drive while it rolls, no
/// "deadman" and no speed 0, at both sizes.
#[test]
fn a_rolling_program_is_named_with_its_line_and_its_speed() {
    for (w, h) in [(80, 24), (120, 40)] {
        let screen = text(&one(rolling()), w, h);
        for want in ["square.js", "line 3 delay(3)", "program", "speed 100/255"] {
            assert!(screen.contains(want), "{want:?} at {w}×{h}:\n{screen}");
        }
        assert!(!screen.contains("deadman"), "{w}×{h}:\n{screen}");
        assert!(!screen.contains("program failed"), "{w}×{h}:\n{screen}");
    }
}

/// The error's banner names the file, the line and the message; once a key was pressed it is
/// gone and the status bar still says where it failed.
#[test]
fn the_error_banner_names_the_line_until_seen() {
    for (w, h) in [(80, 24), (120, 40)] {
        let mut s = one(failed());
        let screen = text(&s, w, h);
        for want in [
            "program failed",
            "square.js:6: ReferenceError: rol is not defined",
            "failed at line 6",
        ] {
            assert!(screen.contains(want), "{want:?} at {w}×{h}:\n{screen}");
        }
        if let Some(p) = &mut s.droid_mut().program {
            p.acknowledged = true;
        }
        let screen = text(&s, w, h);
        assert!(!screen.contains("program failed"), "{w}×{h}:\n{screen}");
        assert!(screen.contains("failed at line 6"), "{w}×{h}:\n{screen}");
    }
}

/// A fleet's banner has every droid whose program is over, by name; the running one is not
/// in it.
#[test]
fn a_fleets_banner_names_each_droid() {
    let screen = text(&fleet(), 120, 40);
    for want in [
        "SB-0001: square.js:6: ReferenceError",
        "SB-0002: square.js ended",
        "SB-0003: square.js: ended by the emergency stop",
    ] {
        assert!(screen.contains(want), "{want:?}:\n{screen}");
    }
    assert!(!screen.contains("SB-0004: "), "{screen}");
}

/// Hostile programs' texts (control characters, very long lines) stay inside the screen at
/// every size and never panic the drawing.
#[test]
fn hostile_program_texts_are_drawn_bounded() {
    let nasty = "\u{1b}[2J\u{7}x".repeat(500);
    let mut p = failed();
    p.name = nasty.clone();
    p.state = ProgramState::Failed {
        line: Some(u32::MAX),
        message: nasty.clone(),
    };
    let mut r = rolling();
    r.waiting_on = Some(Call {
        line: u32::MAX,
        text: nasty,
    });
    for state in [one(p), one(r)] {
        for (w, h) in [(1, 1), (20, 6), (40, 12), (80, 24), (120, 40)] {
            let screen = text(&state, w, h);
            assert!(!screen.contains('\u{1b}'), "{w}×{h}:\n{screen}");
        }
    }
}
