//! Record → replay: a recorded `--sim` mission replays to the telemetry it printed (each
//! family); the app replays a capture to the same screen every time, says REPLAY and sends
//! nothing; a killed recording leaves a readable capture; damaged captures replay what they
//! hold.

use droidctl::app::input::{KeyKind, TermEvent};
use droidctl::app::run::{AppInputs, AppOptions, Source, run as run_source};
use droidctl::capture::replay::Replay;
use droidctl::capture::{Capture, Event};
use droidctl::config::Config;
use droidctl::config::{Key, KeyCode};
use droidctl::model::Model;
use droidctl::teleop::held::ReleaseMode;
use ratatui::{Terminal, backend::TestBackend, buffer::Buffer};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Duration;
use tokio::sync::mpsc;

fn droidctl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(args)
        .env("RUST_BACKTRACE", "1")
        .env_remove("RUST_LOG")
        .env(
            "DROIDCTL_LOG_FILE",
            std::env::temp_dir().join("droidctl-capture-replay.log"),
        )
        .output()
        .expect("run droidctl")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("droidctl-replay-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("tmp dir");
    d
}

fn lines(o: &Output) -> Vec<Value> {
    assert_eq!(
        o.status.code(),
        Some(0),
        "stderr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect()
}

const V2_MISSION: &str = "wake\nstance tripod\nled front 0 0 255\ndrive 80 0 for 2s\ndrive 80 90 for 2s\nstop\nhead 90\nwait 1s\nanimation 10\nwait 1s\n";
const V1_MISSION: &str =
    "wake\nled front 0 255 0\ndrive 100 180 for 2s\ndrive 100 90 for 3s\nwait 1s\n";
const ROBI_MISSION: &str = "drive 100 0 for 2s\ndrive 150 30 for 3s\nstop\nwait 1s\n";

/// Record a `--sim` mission; its printed samples and the capture's path.
fn record(dir: &Path, model: &str, script: &str) -> (Vec<Value>, PathBuf) {
    let script_path = dir.join(format!("{model}.txt"));
    std::fs::write(&script_path, script).unwrap();
    let capture = dir.join(format!("{model}.capture"));
    let live = lines(&droidctl(&[
        "run",
        script_path.to_str().unwrap(),
        "--sim",
        model,
        "--json",
        "--record",
        capture.to_str().unwrap(),
    ]));
    (live, capture)
}

#[test]
fn a_recorded_sim_mission_replays_to_the_telemetry_it_printed() {
    let dir = tmp("roundtrip");
    for (model, script) in [
        ("r2d2", V2_MISSION),
        ("bb8", V1_MISSION),
        // Ollie streams its locator turned (issue 32): the replay reads it back as live.
        ("ollie", V1_MISSION),
        ("robi", ROBI_MISSION),
    ] {
        let (live, capture) = record(&dir, model, script);
        let replayed = lines(&droidctl(&["replay", capture.to_str().unwrap(), "--json"]));
        assert!(live.len() > 40, "{model}: {} lines", live.len());
        assert_eq!(live.len(), replayed.len(), "{model}");
        // Every sample, the final one included, is the same.
        for (l, r) in live.iter().zip(&replayed).take(live.len() - 1) {
            assert_eq!(l, r, "{model}");
        }
        let (l, r) = (live.last().unwrap(), replayed.last().unwrap());
        for k in [
            "done",
            "t_ms",
            "sent",
            "received",
            "errors",
            "collisions",
            "x_cm",
            "y_cm",
        ] {
            assert_eq!(l[k], r[k], "{model}: summary {k}");
        }
        // Another interval samples the same capture at its own pace.
        let every_250 = lines(&droidctl(&[
            "replay",
            capture.to_str().unwrap(),
            "--json",
            "--interval",
            "250",
        ]));
        assert_eq!(every_250[1]["t_ms"], 250);
    }
}

fn key(code: KeyCode) -> TermEvent {
    TermEvent::Key {
        key: Key { code, ctrl: false },
        kind: KeyKind::Press,
    }
}

/// Replay `capture` in the app under paused time, pressing `keys` at their times; the screen
/// at the end.
async fn replay_screen(capture: &Capture, keys: &[(u64, TermEvent)]) -> (Buffer, Vec<u8>) {
    let (buffer, exit) = replay_with(capture, keys, Config::defaults()).await;
    let telemetry = format!("{:?}", exit.state.droid().telemetry).into_bytes();
    (buffer, telemetry)
}

/// The same with `config`'s bindings; the screen and how the app ended.
async fn replay_with(
    capture: &Capture,
    keys: &[(u64, TermEvent)],
    config: Config,
) -> (Buffer, droidctl::app::run::Exit) {
    let (term_tx, term_rx) = mpsc::channel(64);
    let (_pad_tx, pad_rx) = mpsc::channel(1);
    let (_quit_tx, quit_rx) = mpsc::channel(1);
    let opts = AppOptions {
        config,
        model: Model::R2D2,
        droid_name: "R2-D2 (replay)".into(),
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
    let replay = Replay::new(capture.clone(), Model::R2D2);
    let mut terminal = Terminal::new(TestBackend::new(120, 40)).unwrap();
    let keys = keys.to_vec();
    let driver = async move {
        let start = tokio::time::Instant::now();
        for (at, k) in keys {
            tokio::time::sleep_until(start + Duration::from_millis(at)).await;
            term_tx.send(k).await.unwrap();
        }
        tokio::time::sleep(Duration::from_millis(200)).await;
        term_tx.send(key(KeyCode::Char('q'))).await.unwrap();
    };
    let source = Source::Replay(Box::new(replay), "test.capture".into());
    let (exit, ()) = tokio::join!(
        run_source(&mut terminal, source, opts, inputs, droidctl::ui::draw),
        driver
    );
    (terminal.backend().buffer().clone(), exit.unwrap())
}

#[tokio::test(start_paused = true)]
async fn replay_keys_come_from_the_key_map() {
    let dir = tmp("rebound");
    let (_, path) = record(&dir, "r2d2", V2_MISSION);
    let capture = Capture::load(&path).unwrap();
    let config =
        Config::parse_merged(None, "[keys.replay]\npause = [\"k\"]\nfaster = [\"F\"]\n").unwrap();
    // Space no longer pauses; `F` doubles the speed and `k` pauses.
    let keys = [
        (500, key(KeyCode::Space)),
        (600, key(KeyCode::Char('F'))),
        (700, key(KeyCode::Char('k'))),
    ];
    let (screen, exit) = replay_with(&capture, &keys, config).await;
    let view = exit.state.droid().replay.clone().expect("a replay view");
    assert!(view.paused, "k paused");
    assert_eq!(view.speed, 2.0, "F went faster");
    // Played 0.6 s at 1x (Space did not pause), then 0.1 s at 2x, then paused.
    assert_eq!(view.position, Duration::from_millis(800), "{view:?}");
    let help = exit
        .state
        .help
        .iter()
        .find(|s| s.title == "Replay")
        .unwrap();
    assert!(
        help.lines
            .iter()
            .any(|l| l.keys == "k" && l.action.starts_with("pause")),
        "{help:?}"
    );
    assert!(text(&screen).contains("REPLAY"));
}

fn text(b: &Buffer) -> String {
    let mut s = String::new();
    for y in 0..b.area.height {
        for x in 0..b.area.width {
            s.push_str(b[(x, y)].symbol());
        }
        s.push('\n');
    }
    s
}

#[tokio::test(start_paused = true)]
async fn the_app_replays_a_capture_to_the_same_screen_every_time() {
    let dir = tmp("screen");
    let (_, path) = record(&dir, "r2d2", V2_MISSION);
    let capture = Capture::load(&path).unwrap();
    let keys = [
        (1500, key(KeyCode::Char('+'))),
        (2500, key(KeyCode::Right)),
        (2600, key(KeyCode::Space)),
        (2700, key(KeyCode::Char('.'))),
        (2800, key(KeyCode::Char('.'))),
        (3000, key(KeyCode::Space)),
        (3500, key(KeyCode::Left)),
        (4000, key(KeyCode::Space)),
    ];
    let (a, ta) = replay_screen(&capture, &keys).await;
    let (b, tb) = replay_screen(&capture, &keys).await;
    let shown = text(&a);
    assert_eq!(shown, text(&b), "the same capture, the same screen");
    assert_eq!(ta, tb, "the same telemetry");
    assert!(shown.contains("REPLAY"), "{shown}");
    assert!(shown.contains("capture test.capture"), "{shown}");
    assert!(shown.contains("sensor-streaming-data"), "{shown}");

    // Played to its end, the app shows where the mission ended.
    let (end, _) = replay_screen(&capture, &[(100, key(KeyCode::End))]).await;
    let shown = text(&end);
    let last = capture.duration().as_millis() / 100;
    let clock = format!("{}:{:02}.{}", last / 600, last / 10 % 60, last % 10);
    assert!(
        shown.contains(&format!("{clock}/{clock}")),
        "{clock}\n{shown}"
    );
}

#[test]
fn replay_refuses_what_is_not_a_capture_and_reads_a_damaged_one() {
    let dir = tmp("damaged");
    let junk = dir.join("junk");
    std::fs::write(&junk, "hello\n").unwrap();
    let o = droidctl(&["replay", junk.to_str().unwrap(), "--json"]);
    // Not a capture: bad input (docs/exit-status.md).
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("neither a droidctl capture"));

    // Cut in the middle of a line, as a crash leaves it after a flush.
    let (_, path) = record(&dir, "r2d2", V2_MISSION);
    let full = std::fs::read_to_string(&path).unwrap();
    let cut = dir.join("cut.capture");
    std::fs::write(&cut, &full[..full.len() * 2 / 3]).unwrap();
    let o = droidctl(&["replay", cut.to_str().unwrap(), "--json"]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(err.contains("no `end` line"), "{err}");
    let samples = lines(&o);
    assert!(samples.len() > 20);

    let o = droidctl(&["replay", path.to_str().unwrap(), "--json", "--model", "bb8"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("speaks v1"));
}

#[test]
fn record_refuses_to_overwrite_without_force() {
    let dir = tmp("force");
    let script = dir.join("m.txt");
    std::fs::write(&script, "wait 1s\n").unwrap();
    let capture = dir.join("keep.capture");
    std::fs::write(&capture, "precious").unwrap();
    let args = [
        "run",
        script.to_str().unwrap(),
        "--sim",
        "--record",
        capture.to_str().unwrap(),
    ];
    let o = droidctl(&args);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--force"));
    assert_eq!(std::fs::read_to_string(&capture).unwrap(), "precious");
    let mut forced = args.to_vec();
    forced.push("--force");
    let o = droidctl(&forced);
    assert_eq!(o.status.code(), Some(0));
    let c = Capture::load(&capture).unwrap();
    assert_eq!(c.events.last().map(|t| &t.event), Some(&Event::End));
}

/// The app with `--record` in a pseudo-terminal, killed without warning: the capture holds
/// what was flushed (at most a second old) and reads without the `end` line.
#[cfg(unix)]
#[test]
fn a_killed_recording_is_readable_up_to_the_last_flush() {
    use portable_pty::{CommandBuilder, PtySize, native_pty_system};
    use std::io::Read as _;
    let dir = tmp("killed");
    let capture = dir.join("killed.capture");
    let pty = native_pty_system()
        .openpty(PtySize {
            rows: 40,
            cols: 120,
            pixel_width: 0,
            pixel_height: 0,
        })
        .expect("pty");
    let mut cmd = CommandBuilder::new(env!("CARGO_BIN_EXE_droidctl"));
    cmd.args(["drive", "--sim", "--record", capture.to_str().unwrap()]);
    cmd.env("DROIDCTL_LOG_FILE", dir.join("log"));
    cmd.env("DROIDCTL_CONFIG", "/dev/null");
    cmd.env("TERM", "xterm-256color");
    let mut child = pty.slave.spawn_command(cmd).expect("spawn");
    // Keep the terminal's output flowing.
    let mut reader = pty.master.try_clone_reader().expect("reader");
    std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        while matches!(reader.read(&mut buf), Ok(n) if n > 0) {}
    });
    std::thread::sleep(Duration::from_millis(3500));
    // SIGKILL: no exit path runs.
    let pid = child.process_id().expect("pid");
    let _ = Command::new("kill").args(["-9", &pid.to_string()]).status();
    let _ = child.wait();
    let c = Capture::load(&capture).expect("a readable capture");
    assert!(
        c.warnings.iter().any(|w| w.contains("no `end` line")),
        "{:?}",
        c.warnings
    );
    assert_eq!(c.header.model, Some(Model::R2D2));
    let ins = c
        .events
        .iter()
        .filter(|t| matches!(t.event, Event::In(_)))
        .count();
    assert!(ins > 5, "{ins} chunks in after 3.5 s of streaming");
    // At most about a second is lost.
    assert!(
        c.duration() >= Duration::from_millis(1500),
        "{:?}",
        c.duration()
    );
}

/// Hardening (issue 21, points 1 and 2): what a damaged or hostile capture does to
/// `replay --json`.
mod hostile {
    use super::*;
    use droidctl::capture::btsnoop::Datalink;
    use droidctl::capture::hci::build::Log;

    fn stderr(o: &Output) -> String {
        String::from_utf8_lossy(&o.stderr).into_owned()
    }

    #[test]
    fn a_long_silence_is_jumped_not_sampled_every_interval() {
        // 63 bytes: a connect and an end 100,000 s later. Sampling every 100 ms made a
        // million samples (162 MB); the silence is now jumped and said.
        let dir = tmp("silence");
        let path = dir.join("silence.capture");
        std::fs::write(
            &path,
            "droidctl-capture 1\n# model: r2d2\n0.000 connect\n100000000.000 end\n",
        )
        .unwrap();
        let o = droidctl(&["replay", path.to_str().unwrap(), "--json"]);
        let samples = lines(&o);
        assert!(samples.len() <= 4, "{} lines", samples.len());
        assert_eq!(samples.last().unwrap()["done"], true);
        assert!(stderr(&o).contains("no traffic from"), "{}", stderr(&o));
    }

    #[test]
    fn a_span_no_recording_holds_is_refused_with_one_line() {
        let dir = tmp("span");
        let path = dir.join("span.capture");
        std::fs::write(
            &path,
            "droidctl-capture 1\n# model: r2d2\n0.000 connect\n9000000000000000.000 end\n",
        )
        .unwrap();
        let o = droidctl(&["replay", path.to_str().unwrap(), "--json"]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert_eq!(stderr(&o).trim().lines().count(), 1, "{}", stderr(&o));
        assert!(stderr(&o).contains("at most 7 days"), "{}", stderr(&o));

        // The same from a phone's log: a droid's two notifications 9e15 µs apart.
        let mut log = Log::new(Datalink::H4);
        log.le_connected(0x40);
        log.declare(0x40, &[(0x0E, droidctl::family::v2::gatt::V2_API)]);
        let wake = droidctl::protocol::v2::cmd::wake().to_packet(0).encode();
        log.notify(0x40, 0x0E, &wake);
        log.advance(9_000_000_000_000);
        log.notify(0x40, 0x0E, &wake);
        let snoop = dir.join("far.btsnoop");
        std::fs::write(&snoop, &log.bytes).unwrap();
        let o = droidctl(&["replay", snoop.to_str().unwrap(), "--json"]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert_eq!(stderr(&o).trim().lines().count(), 1, "{}", stderr(&o));
        assert!(stderr(&o).contains("at most 7 days"), "{}", stderr(&o));
    }

    #[test]
    fn a_mission_step_too_long_to_wait_is_named_not_a_panic() {
        let dir = tmp("step");
        let path = dir.join("step.capture");
        std::fs::write(
            &path,
            "droidctl-capture 1\n# model: r2d2\n0.000 connect\n0.000 mark mission-start\n\
             1.000 mark step 1 wait 1e20s\n2.000 mark mission-end\n3.000 end\n",
        )
        .unwrap();
        let o = droidctl(&["replay", path.to_str().unwrap(), "--json"]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        let e = stderr(&o);
        assert_eq!(e.trim().lines().count(), 1, "{e}");
        assert!(e.contains("1.000 ms") && e.contains("86400s"), "{e}");
    }
}
