//! `droidctl --program PROGRAM.js`: a Sphero Edu program runs with the app's screen live,
//! and the emergency stop ends both the program and the motion (issue 29 point 1).

// Unix pseudo-terminals.
#![cfg(unix)]

use serde_json::Value;
use std::time::{Duration, Instant};

use crate::common::pty;

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

/// A scratch directory and the files of an app run with a program.
struct AppRun {
    dir: std::path::PathBuf,
    samples: std::path::PathBuf,
    log: std::path::PathBuf,
    tui: pty::Tui,
}

impl AppRun {
    fn start(name: &str, program: &str) -> AppRun {
        let dir =
            std::env::temp_dir().join(format!("droidctl-edu-app-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(format!("{name}.js"));
        std::fs::write(&path, program).unwrap();
        let samples = dir.join("samples.jsonl");
        let log = dir.join("droidctl.log");
        let tui = pty::Tui::start(
            &[
                "--sim",
                "bolt",
                "--program",
                path.to_str().unwrap(),
                "--jsonl",
                samples.to_str().unwrap(),
            ],
            &[
                ("DROIDCTL_LOG_FILE", log.to_str().unwrap()),
                ("DROIDCTL_CONFIG", "/dev/null"),
            ],
        );
        AppRun {
            dir,
            samples,
            log,
            tui,
        }
    }

    fn logged(&self) -> String {
        std::fs::read_to_string(&self.log).unwrap_or_default()
    }

    fn wait_logged(&self, what: &str, limit: Duration) {
        let start = Instant::now();
        while !self.logged().contains(what) {
            assert!(
                start.elapsed() < limit,
                "{what:?} never logged; screen:\n{}",
                self.tui.text()
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for AppRun {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// Issue 37: the program's engine dies of a stack overflow while the droid rolls. Before the
/// engine had its own process that aborted droidctl, leaving the terminal in the alternate
/// screen and the droid rolling; now the droid stops, the app goes on, and on quit the
/// terminal is given back and the crash said.
#[test]
fn a_crashed_engine_stops_the_droid_and_the_app_goes_on() {
    let mut run = AppRun::start(
        "crash",
        "async function startProgram() {\n  setSpeed(100);\n  await delay(1.5);\n  eval(\"(\".repeat(1000000) + \"1\" + \")\".repeat(1000000));\n}\n",
    );
    let start = Instant::now();
    while !speeds(&run.samples).iter().any(|(_, v)| *v > 30.0) {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "the program never moved the droid; screen:\n{}",
            run.tui.text()
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    run.wait_logged("engine crashed", Duration::from_secs(60));
    let crashed = speeds(&run.samples).last().map_or(0.0, |s| s.0);
    std::thread::sleep(Duration::from_millis(2000));
    let after: Vec<_> = speeds(&run.samples)
        .into_iter()
        .filter(|(t, _)| *t > crashed + 1.0)
        .collect();
    assert!(
        !after.is_empty(),
        "samples after the crash: the app goes on"
    );
    assert!(
        after.iter().all(|(_, v)| *v < 5.0),
        "the droid stopped: {after:?}"
    );
    assert!(run.tui.try_wait().is_none(), "the app is still running");
    run.tui.send(b"q");
    let status = run.tui.wait_exit(Duration::from_secs(15));
    // The program failed (its engine crashed): exit status 1 (issue 38 point 10).
    assert_eq!(status.exit_code(), 1, "{status:?}");
    std::thread::sleep(Duration::from_millis(200));
    assert!(!run.tui.alternate_screen(), "the terminal is given back");
    let screen = run.tui.text();
    assert!(
        screen.contains("engine crashed") && screen.contains("too deeply nested"),
        "{screen}"
    );
}

#[cfg(target_os = "linux")]
/// The CPU time a process has used, in clock ticks (`/proc/PID/stat`: utime + stime).
fn cpu_ticks(pid: u32) -> u64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    let after = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<u64> = after
        .split_whitespace()
        .map(|v| v.parse().unwrap_or(0))
        .collect();
    f.get(11).copied().unwrap_or(0) + f.get(12).copied().unwrap_or(0)
}

#[cfg(target_os = "linux")]
/// Its children's process ids, every thread's.
fn children(pid: u32) -> Vec<String> {
    let mut out = Vec::new();
    for t in std::fs::read_dir(format!("/proc/{pid}/task"))
        .into_iter()
        .flatten()
        .flatten()
    {
        let c = std::fs::read_to_string(t.path().join("children")).unwrap_or_default();
        out.extend(c.split_whitespace().map(String::from));
    }
    out
}

/// Issue 37 item 10: a program that computes without waiting through a helper (Boa counts
/// loop turns per call frame, so its loop limit never came) is ended after 5 s, and its
/// engine with it: no process left, no core kept busy until quit.
#[cfg(target_os = "linux")]
#[test]
fn an_ended_program_keeps_no_core_busy() {
    let mut run = AppRun::start(
        "busy",
        "function helper() { return 1; }\nasync function startProgram() {\n  setSpeed(50);\n  while (true) { helper(); }\n}\n",
    );
    run.wait_logged("without waiting", Duration::from_secs(60));
    let pid = run.tui.pid().expect("the app's pid");
    std::thread::sleep(Duration::from_millis(500));
    assert_eq!(children(pid), Vec::<String>::new(), "no engine left");
    let before = cpu_ticks(pid);
    std::thread::sleep(Duration::from_secs(2));
    let used = cpu_ticks(pid) - before;
    // 100 ticks a second: a core kept busy is about 200.
    assert!(
        used < 100,
        "{used} ticks of CPU in 2 s after the program ended"
    );
    run.tui.send(b"q");
    // The program was ended for computing without waiting: it failed, exit status 1.
    assert_eq!(run.tui.wait_exit(Duration::from_secs(15)).exit_code(), 1);
}

/// Issue 37 item 10: a program calling in a tight loop fills neither the log (a burst, then a
/// few lines a second, and how many were left out) nor the disk.
#[test]
fn a_program_cannot_flood_the_log() {
    let mut run = AppRun::start(
        "flood",
        "async function startProgram() {\n  while (true) {\n    for (let i = 0; i < 900; i++) setMainLed({ r: i % 256, g: 0, b: 0 });\n    await delay(0);\n  }\n}\n",
    );
    run.wait_logged("lines not logged", Duration::from_secs(60));
    std::thread::sleep(Duration::from_secs(3));
    let size = std::fs::metadata(&run.log).map(|m| m.len()).unwrap_or(0);
    assert!(size < 1 << 20, "the log is {size} bytes");
    run.tui.send(b"q");
    assert!(run.tui.wait_exit(Duration::from_secs(15)).success());
}

/// A program that fails makes the app's exit status 1 (issue 38 point 10), as `droidctl run
/// PROGRAM.js` does; its error is said after the screen is restored.
#[test]
fn a_program_that_failed_makes_the_apps_exit_status_1() {
    let dir = std::env::temp_dir().join(format!("droidctl-edu-app-f-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let program = dir.join("fails.js");
    std::fs::write(
        &program,
        "async function startProgram() {\n  await delay(0.2);\n  throw new Error(\"boom\");\n}\n",
    )
    .unwrap();
    let log = dir.join("droidctl.log");
    let mut tui = pty::Tui::start(
        &["--sim", "bolt", "--program", program.to_str().unwrap()],
        &[
            ("DROIDCTL_LOG_FILE", log.to_str().unwrap()),
            ("DROIDCTL_CONFIG", "/dev/null"),
        ],
    );
    let start = Instant::now();
    while !std::fs::read_to_string(&log)
        .unwrap_or_default()
        .contains("program ended")
    {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "the program never ended; screen:\n{}",
            tui.text()
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    tui.send(b"q");
    let status = tui.wait_exit(Duration::from_secs(15));
    assert_eq!(status.exit_code(), 1, "{status:?}");
    assert!(
        tui.text().contains("fails.js:3: Error: boom"),
        "{}",
        tui.text()
    );
    let _ = std::fs::remove_dir_all(&dir);
}
