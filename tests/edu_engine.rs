//! Issue 37: a Sphero Edu program can never crash, starve or outlive the stop. The engine
//! runs in a child process (src/edu/child.rs); whatever happens to it (a stack overflow, no
//! memory left, a kill), droidctl stops the droid at once, keeps the capture whole and says
//! what happened in one line.

use droidctl::capture::{Capture, Event};
use droidctl::protocol::v2::decoder::Decoder;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[path = "it/common/scratch.rs"]
mod scratch;
use scratch::{Scratch, path, stderr};

/// Run droidctl with `args` in `dir`, failing (and killing it) past `limit`.
fn run_bounded(dir: &Scratch, args: &[&str], limit: Duration) -> std::process::Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(args)
        .current_dir(&dir.0)
        .env("DROIDCTL_LOG_FILE", dir.log())
        .env("DROIDCTL_CONFIG", "/dev/null")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            panic!(
                "droidctl did not end in {limit:?}: {}",
                stderr(&child.wait_with_output().unwrap())
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// The drive commands in a capture: (time, speed).
fn drives(cap: &Path) -> (Vec<(Duration, u8)>, Capture) {
    let c = Capture::load(cap).unwrap_or_else(|e| panic!("{}: {e}", cap.display()));
    let mut out = Vec::new();
    for t in &c.events {
        if let Event::Out(_, bytes) = &t.event {
            for p in Decoder::new().decode_all(bytes).into_iter().flatten() {
                // Driving, drive with heading: speed first.
                if p.did == 0x16 && p.cid == 0x07 {
                    out.push((t.at, p.data.first().copied().unwrap_or(0)));
                }
            }
        }
    }
    (out, c)
}

/// The program's failure as said: one line, naming the crash and the stop.
fn one_line(err: &str) -> &str {
    let lines: Vec<&str> = err.lines().filter(|l| l.contains("engine")).collect();
    assert_eq!(lines.len(), 1, "one line about the engine: {err}");
    lines[0]
}

/// A program drives, prepares (`prep`, its own turns), then at `at` seconds nests too deep
/// for any stack: the child dies of a stack overflow, the droid is stopped at that instant
/// (the crash comes mid-turn, which takes no simulated time), the capture ends with its `end`
/// line, exit 1, one line.
fn crashes_while_driving(name: &str, prep: &str, at: f64, deep: &str) {
    let dir = Scratch::new("edu-engine", name);
    let p = dir.file(
        &format!("{name}.js"),
        &format!(
            "async function startProgram() {{\n  setSpeed(100);\n  {prep}\n  await delay(1);\n  {deep}\n}}\n"
        ),
    );
    let cap = dir.0.join("run.cap");
    let out = run_bounded(
        &dir,
        &["run", path(&p), "--sim", "bolt", "--record", path(&cap)],
        Duration::from_secs(120),
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    let line = one_line(&err);
    assert!(
        line.contains("engine crashed") && line.contains("too deeply nested"),
        "{line}"
    );
    assert!(line.contains("droid stopped"), "{line}");
    #[cfg(unix)]
    assert!(line.contains("SIGABRT"), "{line}");
    let (drives, c) = drives(&cap);
    assert!(
        matches!(c.events.last().map(|t| &t.event), Some(Event::End)),
        "the capture is complete: {:?}",
        c.events.last()
    );
    // The program starts once the droid is set up and its first sample is in (issue 38 point
    // 1), with its first drive: its clock counts from there.
    let started = drives
        .iter()
        .find(|d| d.1 > 0)
        .map(|d| d.0)
        .unwrap_or_else(|| panic!("it drove: {drives:?}"));
    let crash = started + Duration::from_secs_f64(at);
    let stop = drives
        .iter()
        .find(|(t, speed)| *speed == 0 && *t >= crash - Duration::from_millis(100))
        .unwrap_or_else(|| panic!("a stop after the crash: {drives:?}"));
    assert!(
        stop.0 < crash + Duration::from_millis(50),
        "the stop within 50 ms of the crash at {crash:?}: {stop:?}"
    );
}

#[test]
fn eval_of_a_million_parentheses_crashes_only_the_engine() {
    crashes_while_driving(
        "eval",
        "",
        1.0,
        "eval(\"(\".repeat(1000000) + \"1\" + \")\".repeat(1000000));",
    );
}

#[test]
fn a_function_of_arrays_nested_a_million_deep_crashes_only_the_engine() {
    crashes_while_driving(
        "function",
        "",
        1.0,
        "new Function(\"return \" + \"[\".repeat(1000000) + \"]\".repeat(1000000));",
    );
}

/// Deep but legal: each of these overflowed the engine's old 16 MiB thread and aborted
/// droidctl; with the child's stack they run.
#[test]
fn deep_but_legal_programs_run() {
    let dir = Scratch::new("edu-engine", "legal");
    let p = dir.file(
        "deep.js",
        "async function startProgram() {\n  let a = [];\n  for (let i = 0; i < 10000; i++) a = [a];\n  await delay(0.1);\n  String(a);\n  await delay(0.1);\n  let o = {};\n  for (let i = 0; i < 2000; i++) o = { o };\n  await delay(0.1);\n  JSON.stringify(o);\n  await delay(0.1);\n  eval(\"(\".repeat(1000) + \"1\" + \")\".repeat(1000));\n}\n",
    );
    let out = run_bounded(
        &dir,
        &["run", path(&p), "--sim", "bolt"],
        Duration::from_secs(120),
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
}

/// What a check of `text` said: exit status and stderr.
fn check(dir: &Scratch, name: &str, text: &str) -> (Option<i32>, String) {
    let p = dir.file(name, text);
    let out = run_bounded(
        dir,
        &["run", path(&p), "--sim", "bolt", "--timeout", "1"],
        Duration::from_secs(120),
    );
    (out.status.code(), stderr(&out))
}

#[test]
fn deep_nesting_at_the_syntax_check_is_exit_2_and_deep_legal_programs_run() {
    let dir = Scratch::new("edu-engine", "check");
    let start = "async function startProgram() { await delay(0.1); }\n";
    // Too deep for any stack: exit 2, said, nothing sent.
    for (name, deep) in [
        (
            "parens.js",
            format!(
                "let x = {}1{};\n",
                "(".repeat(1_000_000),
                ")".repeat(1_000_000)
            ),
        ),
        (
            "arrays.js",
            format!(
                "let x = {}{};\n",
                "[".repeat(1_000_000),
                "]".repeat(1_000_000)
            ),
        ),
    ] {
        let (code, err) = check(&dir, name, &format!("{start}{deep}"));
        assert_eq!(code, Some(2), "{name}: {err}");
        assert!(err.contains("too deeply nested"), "{name}: {err}");
        assert!(err.contains("nothing was sent"), "{name}: {err}");
    }
    // Deep but legal (each overflowed droidctl's main thread before the child): they run.
    for (name, deep) in [
        (
            "parens300.js",
            format!("let x = {}1{};\n", "(".repeat(300), ")".repeat(300)),
        ),
        (
            "arrows250.js",
            format!("let f = {}1;\n", "() => ".repeat(250)),
        ),
        (
            "arrays400.js",
            format!("let x = {}{};\n", "[".repeat(400), "]".repeat(400)),
        ),
        ("plus.js", format!("let x = 0{};\n", "+1".repeat(50_000))),
    ] {
        let (code, err) = check(&dir, name, &format!("{start}{deep}"));
        assert_eq!(code, Some(0), "{name}: {err}");
    }
}

#[cfg(target_os = "linux")]
#[test]
fn a_program_that_keeps_what_it_allocates_ends_at_its_memory_limit() {
    let dir = Scratch::new("edu-engine", "memory");
    let p = dir.file(
        "hog.js",
        "async function startProgram() {\n  setSpeed(100);\n  const kept = [];\n  for (let i = 0; ; i++) {\n    kept.push(\"x\".repeat(4000000) + i);\n    await delay(0.01);\n  }\n}\n",
    );
    let started = Instant::now();
    let out = run_bounded(
        &dir,
        &[
            "run",
            path(&p),
            "--sim",
            "bolt",
            "--program-memory",
            "64",
            "--timeout",
            "600",
        ],
        Duration::from_secs(120),
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    let line = one_line(&err);
    assert!(line.contains("more than its 64 MiB"), "{line}");
    assert!(line.contains("droid stopped"), "{line}");
    assert!(
        started.elapsed() < Duration::from_secs(60),
        "{:?}",
        started.elapsed()
    );
}

#[test]
fn recursion_after_an_await_says_so_with_its_line() {
    let dir = Scratch::new("edu-engine", "recursion");
    let p = dir.file(
        "deep.js",
        "async function startProgram() {\n  setSpeed(50);\n  await delay(0.5);\n  down(0);\n}\nfunction down(n) { return down(n + 1) + 1; }\n",
    );
    let out = run_bounded(
        &dir,
        &["run", path(&p), "--sim", "bolt"],
        Duration::from_secs(60),
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("too much recursion"), "{err}");
    assert!(
        err.contains("deep.js:3:"),
        "the line it went on from: {err}"
    );
    // Before any await: the engine's error, with the line.
    let p = dir.file(
        "sync.js",
        "async function startProgram() {\n  down(0);\n}\nfunction down(n) { return down(n + 1) + 1; }\n",
    );
    let out = run_bounded(
        &dir,
        &["run", path(&p), "--sim", "bolt"],
        Duration::from_secs(60),
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("too much recursion"), "{err}");
}

#[test]
fn a_tiny_timeout_ends_the_program_at_its_timeout() {
    let dir = Scratch::new("edu-engine", "timeout");
    let sq = format!("{}/examples/edu/square.js", env!("CARGO_MANIFEST_DIR"));
    let out = run_bounded(
        &dir,
        &["run", &sq, "--sim", "bolt", "--timeout", "0.001"],
        Duration::from_secs(60),
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("--timeout: the program ran 0.001 s"), "{err}");
    assert!(!err.contains("computed for"), "{err}");
}

/// The engine children of this process (`droidctl __droidctl-edu-engine …`).
#[cfg(target_os = "linux")]
fn engine_children() -> Vec<u32> {
    let mut pids = Vec::new();
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return pids;
    };
    for t in tasks.flatten() {
        let children = std::fs::read_to_string(t.path().join("children")).unwrap_or_default();
        for pid in children
            .split_whitespace()
            .filter_map(|p| p.parse::<u32>().ok())
        {
            let cmd = std::fs::read(format!("/proc/{pid}/cmdline")).unwrap_or_default();
            if String::from_utf8_lossy(&cmd).contains(droidctl::edu::child::ENGINE_ARG) {
                pids.push(pid);
            }
        }
    }
    pids
}

/// One run on droidctl's real clock: a program drives, its engine child is killed (SIGKILL)
/// from outside; returns how long after the kill the stop went out (from the capture) and
/// what the run said.
#[cfg(target_os = "linux")]
async fn killed_while_driving(dir: &Scratch, k: usize) -> (Duration, String) {
    use droidctl::capture::record::Recorder;
    use droidctl::edu::{EngineOptions, Program, ProgramOptions};
    use droidctl::mission::MissionOptions;
    use droidctl::model::Model;
    use droidctl::sim::{Faults, SimConfig, SimLink};
    let model = Model::Bolt;
    let cap = dir.0.join(format!("killed-{k}.cap"));
    let rec = Recorder::create(&cap, true).unwrap();
    rec.start(&Recorder::header_for(model, "BOLT (simulated)"));
    let rec_start = tokio::time::Instant::now();
    let link = rec.wrap(Box::new(SimLink::new(
        model,
        SimConfig::for_model(model),
        Faults::none(),
    )));
    let (cfg, mission) = droidctl::cli::run::mission_session(model, MissionOptions::default());
    let session = droidctl::session::start(link, cfg);
    let engine = EngineOptions {
        exe: Some(env!("CARGO_BIN_EXE_droidctl").into()),
        ..EngineOptions::default()
    };
    let program = Program::new_with(
        "async function startProgram() {\n  setSpeed(120);\n  while (true) { await delay(0.2); }\n}\n"
            .into(),
        "drive.js".into(),
        &engine,
    )
    .unwrap();
    let opts = ProgramOptions {
        mission,
        ..ProgramOptions::default()
    };
    let run = {
        let session = session.clone();
        tokio::spawn(async move {
            let emit: droidctl::mission::Emit = std::sync::Arc::new(|_| {});
            let start = tokio::time::Instant::now();
            droidctl::edu::run(&session, model, &program, opts, emit, start).await
        })
    };
    // Driving, on the real clock (the program starts once the droid is set up and streams:
    // issue 38 point 1).
    tokio::time::sleep(Duration::from_millis(2000)).await;
    let pids = engine_children();
    assert_eq!(pids.len(), 1, "one engine child: {pids:?}");
    let pid = libc::pid_t::try_from(pids[0]).unwrap();
    let before_kill = tokio::time::Instant::now();
    // SAFETY: kill(2) with a pid this test read from its own children.
    let killed = unsafe { libc::kill(pid, libc::SIGKILL) };
    assert_eq!(killed, 0, "the engine child was killed");
    let r = tokio::time::timeout(Duration::from_secs(10), run)
        .await
        .expect("the run ends when its engine is killed")
        .unwrap();
    session.shutdown(Vec::new()).await;
    rec.finish().unwrap();
    let said = r.err().map(|e| e.to_string()).unwrap_or_default();
    let killed_at = before_kill - rec_start;
    let (drives, _) = drives(&cap);
    assert!(
        drives.iter().any(|d| d.1 > 0 && d.0 < killed_at),
        "it drove: {drives:?}"
    );
    let stop = drives
        .iter()
        .find(|(at, speed)| *speed == 0 && *at >= killed_at)
        .unwrap_or_else(|| panic!("a stop after the kill at {killed_at:?}: {drives:?}"));
    (stop.0 - killed_at, said)
}

#[cfg(target_os = "linux")]
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_killed_engine_stops_the_droid_within_50_ms() {
    let dir = Scratch::new("edu-engine", "sigkill");
    let (took, said) = killed_while_driving(&dir, 0).await;
    assert!(
        said.contains("engine was killed (signal 9, SIGKILL)") && said.contains("droid stopped"),
        "{said}"
    );
    assert!(
        took < Duration::from_millis(50),
        "the stop {took:?} after the kill"
    );
    assert!(engine_children().is_empty(), "no engine child left");
}

/// docs/reliability.md's figure: `cargo test --release --test edu_engine -- --ignored
/// --nocapture crash_to_stop` (20 kills, p50 and max).
#[cfg(target_os = "linux")]
#[ignore]
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn crash_to_stop_latency() {
    let dir = Scratch::new("edu-engine", "latency");
    let mut took = Vec::new();
    for k in 0..20 {
        took.push(killed_while_driving(&dir, k).await.0);
    }
    took.sort();
    println!(
        "engine killed → stop on the droid, 20 runs: p50 {:?}, max {:?}",
        took[took.len() / 2],
        took[took.len() - 1]
    );
}
