//! Issue 38 point 10: the app shows the Sphero Edu program running beside it (`droidctl
//! --program P.js`): its name and the line it waits on in the status bar, what it commands in
//! the gauges while the droid rolls (input "program", not "deadman" and speed 0), and its error
//! in a banner naming the line, until a key. The app loop runs under paused time on a
//! simulated BOLT, the program in its engine's child as `droidctl` runs it, and every frame is
//! drawn by the real UI into a test backend.

use crate::common::edu_run::engine;
use droidctl::app::input::{KeyKind, TermEvent};
use droidctl::app::run::{self, AppInputs, AppOptions};
use droidctl::app::state::AppState;
use droidctl::config::{Config, Key, KeyCode};
use droidctl::edu::progress::ProgramState;
use droidctl::edu::{Program, ProgramOptions};
use droidctl::mission::{Emit, MissionOptions};
use droidctl::model::Model;
use droidctl::sim::{Faults, SimConfig, SimLink};
use droidctl::teleop::held::ReleaseMode;
use ratatui::backend::TestBackend;
use ratatui::{Frame, Terminal};
use std::cell::RefCell;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::mpsc;
use tokio::time::{Instant, sleep};

thread_local! {
    /// The last frame drawn: the state and the screen's rows (the app runs on this test's
    /// thread: a current-thread runtime).
    static FRAME: RefCell<Option<(AppState, String)>> = const { RefCell::new(None) };
}

/// The real UI, and what it drew kept for the test.
fn draw(f: &mut Frame, s: &AppState) {
    droidctl::ui::draw(f, s);
    let buf = f.buffer_mut();
    let w = usize::from(buf.area.width.max(1));
    let text = buf
        .content
        .chunks(w)
        .map(|row| row.iter().map(|c| c.symbol()).collect::<String>())
        .collect::<Vec<_>>()
        .join("\n");
    FRAME.with(|f| *f.borrow_mut() = Some((s.clone(), text)));
}

fn frame() -> (AppState, String) {
    FRAME
        .with(|f| f.borrow().clone())
        .expect("the app drew a frame")
}

/// Wait (on the paused clock, up to `limit` of it) until the last frame satisfies `ok`.
async fn until(limit: Duration, what: &str, ok: impl Fn(&AppState, &str) -> bool) {
    let start = Instant::now();
    loop {
        if let Some((s, text)) = FRAME.with(|f| f.borrow().clone())
            && ok(&s, &text)
        {
            return;
        }
        assert!(
            start.elapsed() < limit,
            "never {what}; last frame:\n{}",
            FRAME
                .with(|f| f.borrow().clone())
                .map(|f| f.1)
                .unwrap_or_default()
        );
        sleep(Duration::from_millis(50)).await;
    }
}

const PROGRAM: &str = "async function startProgram() {
  setSpeed(100);
  await delay(3);
  stopRoll();
  await delay(0.5);
  throw new Error(\"boom\");
}
";

#[tokio::test(start_paused = true)]
async fn the_app_shows_the_program_its_line_its_drive_and_its_error() {
    let model = Model::Bolt;
    let link = SimLink::new(model, SimConfig::for_model(model), Faults::none());
    let probe = link.probe();
    let (cfg, mission) = droidctl::cli::run::mission_session(model, MissionOptions::default());
    let session = droidctl::session::start(Box::new(link), cfg);
    let program =
        Program::new_with(PROGRAM.into(), "/class/rolls.js".into(), &engine()).expect("checks");
    let (progress, feed) = droidctl::edu::progress::channel(&program.path);
    let opts = ProgramOptions {
        mission,
        progress: Some(progress),
        ..ProgramOptions::default()
    };
    let (term, term_rx) = mpsc::channel(16);
    let (_pad, pad_rx) = mpsc::channel(16);
    let (quit, quit_rx) = mpsc::channel(4);
    let app = {
        let session = session.clone();
        tokio::spawn(async move {
            let mut terminal = Terminal::new(TestBackend::new(80, 24)).expect("backend");
            let opts = AppOptions {
                config: Config::defaults(),
                model,
                droid_name: "BOLT (simulated)".into(),
                log_path: None,
                release: ReleaseMode::Reported,
                tripod_on_connect: false,
                samples: None,
                remember: None,
            };
            let inputs = AppInputs {
                term: term_rx,
                pad: pad_rx,
                quit: quit_rx,
            };
            run::run_with_programs(&mut terminal, session, opts, inputs, vec![(0, feed)], draw)
                .await
                .expect("the app runs")
        })
    };
    let ran = {
        let session = session.clone();
        tokio::spawn(async move {
            let emit: Emit = Arc::new(|_| {});
            let start = Instant::now();
            droidctl::edu::run(&session, model, &program, opts, emit, start).await
        })
    };

    // Rolling: the program's name and the line it waits on; its speed in the gauges.
    until(Duration::from_secs(30), "rolling on line 3", |s, _| {
        s.droid()
            .program
            .as_ref()
            .is_some_and(|p| p.status.waiting_on.as_ref().is_some_and(|c| c.line == 3))
            && s.droid().telemetry.speed_cm_s().is_some_and(|v| v > 20.0)
    })
    .await;
    let (s, screen) = frame();
    let c = &s.droid().control;
    assert_eq!((c.speed, c.source), (100, "program"), "{c:?}");
    assert!(probe.state().velocity_cm_s > 20.0, "the droid rolls");
    for shown in ["rolls.js", "line 3 delay(3)", "program", "speed 100/255"] {
        assert!(screen.contains(shown), "{shown:?} not on screen:\n{screen}");
    }
    assert!(!screen.contains("deadman"), "{screen}");

    // Stopped, then waiting on line 5: the gauges say what it commands now.
    until(Duration::from_secs(10), "on line 5", |s, _| {
        s.droid()
            .program
            .as_ref()
            .is_some_and(|p| p.status.waiting_on.as_ref().is_some_and(|c| c.line == 5))
    })
    .await;
    let (s, screen) = frame();
    assert_eq!(s.droid().control.speed, 0);
    assert!(screen.contains("line 5 delay(0.5)"), "{screen}");

    // Its error: a banner naming the file, the line and the message.
    until(Duration::from_secs(10), "failed", |s, _| {
        s.droid()
            .program
            .as_ref()
            .is_some_and(|p| matches!(p.status.state, ProgramState::Failed { .. }))
    })
    .await;
    let (s, screen) = frame();
    assert_eq!(
        s.droid().program.as_ref().map(|p| p.status.state.clone()),
        Some(ProgramState::Failed {
            line: Some(6),
            message: "Error: boom".into()
        })
    );
    for shown in [
        "program failed",
        "rolls.js:6: Error: boom",
        "failed at line 6",
    ] {
        assert!(screen.contains(shown), "{shown:?} not on screen:\n{screen}");
    }
    let result = ran.await.expect("the program's task");
    assert!(result.is_err(), "the program failed: {result:?}");

    // A key closes the banner; the status bar still says how it ended.
    term.send(TermEvent::Key {
        key: Key::plain(KeyCode::F(12)),
        kind: KeyKind::Press,
    })
    .await
    .expect("the app reads keys");
    until(Duration::from_secs(2), "the banner closed", |_, text| {
        !text.contains("program failed")
    })
    .await;
    let (_, screen) = frame();
    assert!(screen.contains("failed at line 6"), "{screen}");
    quit.send("test".into()).await.expect("the app runs");
    let exit = app.await.expect("the app's task");
    assert!(exit.state.droid().program.is_some());
    session.shutdown(Vec::new()).await;
}
