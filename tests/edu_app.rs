//! `droidctl --program PROGRAM.js`: a Sphero Edu program runs with the app's screen live,
//! and the emergency stop ends both the program and the motion (issue 29 point 1).

// Unix pseudo-terminals.
#![cfg(unix)]

use serde_json::Value;
use std::time::{Duration, Instant};

#[path = "common/pty.rs"]
mod pty;

/// The samples the app wrote so far: (seconds, speed).
fn speeds(path: &std::path::Path) -> Vec<(f64, f64)> {
    std::fs::read_to_string(path)
        .unwrap_or_default()
        .lines()
        .filter_map(|l| serde_json::from_str::<Value>(l).ok())
        .filter_map(|v| Some((v["t_ms"].as_f64()? / 1000.0, v["speed"].as_f64()?)))
        .collect()
}

#[test]
fn the_emergency_stop_ends_the_program_and_the_motion() {
    let dir = std::env::temp_dir().join(format!("droidctl-edu-app-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let program = dir.join("keep-rolling.js");
    // It asks for speed again and again: only its end keeps the droid still.
    std::fs::write(
        &program,
        "async function startProgram() {\n  while (true) {\n    setSpeed(100);\n    await delay(0.3);\n  }\n}\n",
    )
    .unwrap();
    let samples = dir.join("samples.jsonl");
    let log = dir.join("droidctl.log");
    let (p, s, l) = (
        program.to_str().unwrap(),
        samples.to_str().unwrap(),
        log.to_str().unwrap(),
    );
    let mut tui = pty::Tui::start(
        &["--sim", "bolt", "--program", p, "--jsonl", s],
        &[("DROIDCTL_LOG_FILE", l), ("DROIDCTL_CONFIG", "/dev/null")],
    );
    // The program drives: the droid rolls.
    let start = Instant::now();
    while !speeds(&samples).iter().any(|(_, v)| *v > 30.0) {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "the program never moved the droid; screen:\n{}",
            tui.text()
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    // The emergency stop (space).
    tui.send(b" ");
    let pressed = speeds(&samples).last().map_or(0.0, |s| s.0);
    std::thread::sleep(Duration::from_millis(2500));
    let after: Vec<_> = speeds(&samples)
        .into_iter()
        .filter(|(t, _)| *t > pressed + 1.0)
        .collect();
    assert!(!after.is_empty(), "samples after the stop");
    assert!(
        after.iter().all(|(_, v)| *v < 5.0),
        "the droid stays stopped after the emergency stop: {after:?}"
    );
    let logged = std::fs::read_to_string(&log).unwrap_or_default();
    assert!(
        logged.contains("emergency stop"),
        "the program ended: {logged}"
    );
    tui.send(b"q");
    let status = tui.wait_exit(Duration::from_secs(15));
    assert!(status.success(), "{status:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The Matrix panel shows what a program put on BOLT's matrix (the panel follows the matrix
/// commands that go out, whoever sends them): here the program's animations.
#[test]
fn the_matrix_panel_shows_what_the_program_draws() {
    let dir = std::env::temp_dir().join(format!("droidctl-edu-app-m-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("droidctl.log");
    let program = format!(
        "{}/tests/fixtures/edu/animation.js",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut tui = pty::Tui::start(
        &["--sim", "bolt", "--program", &program],
        &[
            ("DROIDCTL_LOG_FILE", log.to_str().unwrap()),
            ("DROIDCTL_CONFIG", "/dev/null"),
        ],
    );
    let start = Instant::now();
    for want in ["animation 0", "animation 1"] {
        while !tui.text().contains(want) {
            assert!(
                start.elapsed() < Duration::from_secs(30),
                "no {want:?} on the screen:\n{}",
                tui.text()
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
    tui.send(b"q");
    let status = tui.wait_exit(Duration::from_secs(15));
    assert!(status.success(), "{status:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
