//! `droidctl bridge --stdio` as a program drives it through a pipe (issue 20 point 2): the
//! hello, telemetry from a simulated droid while it rolls, one error line per bad line and
//! nothing else, and every droid stopped and the process gone when its stdin ends. Also the
//! refusals of the command line: no droid, both transports, a broker beyond loopback.

use crate::common::cli;

use serde_json::Value;
use std::io::{BufRead, BufReader, Write};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// The bridge's stdout lines, parsed, as they come.
fn lines(out: std::process::ChildStdout) -> mpsc::Receiver<Value> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for l in BufReader::new(out).lines() {
            let Ok(l) = l else { return };
            let v: Value = serde_json::from_str(&l).unwrap_or_else(|e| panic!("{l}: {e}"));
            if tx.send(v).is_err() {
                return;
            }
        }
    });
    rx
}

/// The next object for which `f` holds, within `secs`.
fn wait(rx: &mpsc::Receiver<Value>, secs: u64, what: &str, f: impl Fn(&Value) -> bool) -> Value {
    let end = Instant::now() + Duration::from_secs(secs);
    while let Some(left) = end.checked_duration_since(Instant::now()) {
        match rx.recv_timeout(left) {
            Ok(v) if f(&v) => return v,
            Ok(_) => {}
            Err(_) => break,
        }
    }
    panic!("no {what} within {secs} s");
}

#[test]
fn a_program_drives_a_simulated_droid_through_a_pipe() {
    let dir = std::env::temp_dir().join(format!("droidctl-bridge-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["bridge", "--stdio", "--sim", "r2d2", "--rate", "20"])
        .env("DROIDCTL_CONFIG", "/dev/null")
        .env("RUST_BACKTRACE", "1")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run droidctl bridge");
    let mut stdin = child.stdin.take().unwrap();
    let rx = lines(child.stdout.take().unwrap());
    let hello = wait(&rx, 10, "hello", |v| v["type"] == "hello");
    assert_eq!(hello["v"], 1);
    assert_eq!(hello["droids"][0]["droid"], "D2-0001");
    assert_eq!(hello["command_timeout_ms"], 600);
    wait(&rx, 10, "the link up", |v| {
        v["type"] == "link" && v["state"] == "connected"
    });
    // The connect setup done (R2 in tripod, streaming): the samples have values.
    wait(&rx, 10, "a sample with a position", |v| {
        v["type"] == "telemetry" && v["x_cm"].is_number()
    });
    // Bad lines: one error each, with the id when it could be read.
    stdin
        .write_all(
            b"hello there\n{\"v\":1,\"cmd\":\"drive\",\"speed\":999,\"heading\":0,\"id\":\"d1\"}\n",
        )
        .unwrap();
    let e = wait(&rx, 5, "an error", |v| v["type"] == "error");
    assert_eq!(e["code"], "bad_json");
    let e = wait(&rx, 5, "an error", |v| v["type"] == "error");
    assert_eq!(
        (e["code"].as_str(), e["id"].as_str()),
        (Some("bad_field"), Some("d1"))
    );
    // Drive for two seconds, a command every 0.3 s: it rolls.
    for _ in 0..7 {
        stdin
            .write_all(b"{\"v\":1,\"cmd\":\"drive\",\"speed\":150,\"heading\":90}\n")
            .unwrap();
        stdin.flush().unwrap();
        std::thread::sleep(Duration::from_millis(300));
    }
    let t = wait(&rx, 5, "a sample while rolling", |v| {
        v["type"] == "telemetry" && v["speed"].as_f64().is_some_and(|s| s > 20.0)
    });
    assert_eq!(t["droid"], "D2-0001");
    assert!(t["x_cm"].is_number(), "{t}");
    // Then silence: the command timeout stops it.
    let s = wait(&rx, 5, "the timeout's stop", |v| v["type"] == "stopped");
    assert_eq!(s["reason"], "timeout");
    // Rolling again, then stdin ends: stopped, and the process exits.
    stdin
        .write_all(b"{\"v\":1,\"cmd\":\"drive\",\"speed\":150,\"heading\":90}\n")
        .unwrap();
    stdin.flush().unwrap();
    std::thread::sleep(Duration::from_millis(200));
    drop(stdin);
    let s = wait(&rx, 5, "the stop at the end of input", |v| {
        v["type"] == "stopped"
    });
    assert_eq!(s["reason"], "input_closed");
    let status = crate::common::cli::exit_within(
        &mut child,
        Duration::from_secs(10),
        "the bridge, after its input ended,",
    );
    assert_eq!(status.code(), Some(0));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 41: a BOLT+ behind the bridge: its capabilities say `matrix` and `screen`, and a
/// matrix command (drawn on its screen) and a drive are done on the simulated BOLT+.
#[test]
fn a_boltplus_draws_on_its_screen_through_the_bridge() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["bridge", "--stdio", "--sim", "boltplus"])
        .env("DROIDCTL_CONFIG", "/dev/null")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("run droidctl bridge");
    let mut stdin = child.stdin.take().unwrap();
    let rx = lines(child.stdout.take().unwrap());
    let hello = wait(&rx, 10, "hello", |v| v["type"] == "hello");
    let droid = &hello["droids"][0];
    assert!(
        droid["droid"].as_str().unwrap().starts_with("BP-"),
        "{hello}"
    );
    assert_eq!(droid["model"], "boltplus", "{hello}");
    let caps = droid["capabilities"].to_string();
    assert!(
        caps.contains("\"matrix\"") && caps.contains("\"screen\""),
        "{hello}"
    );
    wait(&rx, 10, "ready", |v| {
        v["type"] == "link" && v["ready"] == true
    });
    stdin
        .write_all(b"{\"v\":1,\"cmd\":\"matrix\",\"op\":\"char\",\"char\":\"A\",\"id\":\"m1\"}\n")
        .unwrap();
    stdin.flush().unwrap();
    let r = wait(&rx, 5, "the matrix reply", |v| {
        v["type"] == "reply" || v["type"] == "error"
    });
    assert_eq!(
        (r["type"].as_str(), r["id"].as_str()),
        (Some("reply"), Some("m1")),
        "{r}"
    );
    assert_eq!(r["ok"], true, "{r}");
    drop(stdin);
    let status = crate::common::cli::exit_within(
        &mut child,
        Duration::from_secs(10),
        "the bridge, after its input ended,",
    );
    assert_eq!(status.code(), Some(0));
}

#[test]
fn the_command_line_refuses_what_it_cannot_do() {
    let e = cli::usage_error(&["bridge", "--stdio"]);
    assert!(e.contains("--sim"), "{e}");
    let o = cli::droidctl(&["bridge", "--sim", "r2d2"]);
    assert_eq!(o.status.code(), Some(2), "a transport is needed");
    let o = cli::droidctl(&[
        "bridge",
        "--stdio",
        "--mqtt",
        "mqtt://localhost",
        "--sim",
        "r2d2",
    ]);
    assert_eq!(o.status.code(), Some(2), "one transport at a time");
    // A broker beyond loopback, without --allow-remote: refused before anything connects.
    let e = cli::usage_error(&["bridge", "--mqtt", "mqtt://192.0.2.7:1883", "--sim", "r2d2"]);
    assert!(e.contains("--allow-remote"), "{e}");
    let e = cli::usage_error(&["bridge", "--stdio", "--sim", "r2d2", "--qos", "1"]);
    assert!(e.contains("--qos is for MQTT"), "{e}");
    for (args, what) in [
        (
            &["bridge", "--mqtt", "http://localhost", "--sim", "r2d2"][..],
            "broker URL",
        ),
        (
            &[
                "bridge",
                "--stdio",
                "--sim",
                "r2d2",
                "--command-timeout",
                "50",
            ][..],
            "command-timeout",
        ),
    ] {
        let o = cli::droidctl(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(
            cli::stderr(&o).contains(what),
            "{args:?}: {}",
            cli::stderr(&o)
        );
    }
}

/// Issue 27 point 5 (and 8): a client that writes everything at once and reads slowly
/// (`| (sleep 1; cat)`) gets every reply and every error, and the `input_closed` notice;
/// a byte-order mark on the first line and `"v":1.0` are taken. Issue 40 point 11: the
/// answers are the same every run, all replies, as no command is read before the droid is
/// ready.
#[test]
fn a_slow_reader_gets_every_answer_through_the_pipe() {
    let dir = std::env::temp_dir().join(format!("droidctl-bridge-slow-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut input = b"\xEF\xBB\xBF{\"v\":1.0,\"cmd\":\"stop\",\"id\":\"bom\"}\n".to_vec();
    input.extend_from_slice(b"{\"v\":1,\"cmd\":\"drive\",\"speed\":60,\"heading\":0}\n");
    for n in 0..10_000 {
        input.extend_from_slice(format!("{{\"v\":1,\"cmd\":\"stop\",\"id\":{n}}}\n").as_bytes());
    }
    input.extend_from_slice(&b"garbage\n".repeat(20_000));
    input.extend_from_slice(b"{\"v\":1,\"cmd\":\"drive\",\"speed\":60,\"heading\":0}\n");
    let file = dir.join("input.jsonl");
    std::fs::write(&file, &input).unwrap();
    // The wait for `ready` is bounded by the scan timeout (5 s by default): a loaded machine
    // can take longer to set a droid up, so the bound here is far from the test's path.
    let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["bridge", "--stdio", "--sim", "r2d2", "--scan-timeout", "60"])
        .env("DROIDCTL_CONFIG", "/dev/null")
        .stdin(std::fs::File::open(&file).unwrap())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("run droidctl bridge");
    let out = child.stdout.take().unwrap();
    std::thread::sleep(Duration::from_secs(1));
    let lines: Vec<Value> = BufReader::new(out)
        .lines()
        .map(|l| serde_json::from_str(&l.unwrap()).unwrap())
        .collect();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(0));
    // Every id is answered once, by a reply: the first command waits for the droid's
    // first `ready` (issue 40 point 11), so none races the connection.
    let answers: Vec<&Value> = lines
        .iter()
        .filter(|v| (v["type"] == "reply" || v["type"] == "error") && !v["id"].is_null())
        .collect();
    let ids: std::collections::HashSet<String> =
        answers.iter().map(|v| v["id"].to_string()).collect();
    assert_eq!(ids.len(), 10_001, "every id answered once");
    assert_eq!(answers.len(), 10_001, "an answer per id");
    let errors: Vec<&&Value> = answers.iter().filter(|v| v["type"] != "reply").collect();
    assert!(
        errors.is_empty(),
        "answered before the droid was ready: {errors:?}"
    );
    let ready = lines
        .iter()
        .position(|v| v["type"] == "link" && v["ready"] == true)
        .expect("the droid became ready");
    let first = lines
        .iter()
        .position(|v| v["type"] == "reply")
        .expect("replies");
    assert!(
        ready < first,
        "the first reply comes after the droid is ready"
    );
    assert_eq!(
        lines
            .iter()
            .filter(|v| v["type"] == "error" && v["id"].is_null())
            .count(),
        20_000,
        "an error per bad line"
    );
    assert!(
        ids.contains("\"bom\""),
        "the first line, after its byte-order mark"
    );
    assert!(
        lines
            .iter()
            .any(|v| v["type"] == "stopped" && v["reason"] == "input_closed"),
        "the input_closed notice"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 27 point 8: a `$` topic prefix is the broker's and a password file is read with a
/// cap: both refused at once with a usage error, before any broker is asked.
#[test]
fn broker_reserved_prefixes_and_endless_password_files_are_refused() {
    for prefix in ["$SYS", "$share/room", "$"] {
        let e = cli::usage_error(&[
            "bridge",
            "--mqtt",
            "mqtt://127.0.0.1:1",
            "--sim",
            "r2d2",
            "--topic-prefix",
            prefix,
        ]);
        assert!(e.contains("the broker's own"), "{prefix}: {e}");
    }
    let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args([
            "bridge",
            "--mqtt",
            "mqtt://127.0.0.1:1",
            "--sim",
            "r2d2",
            "--username",
            "u",
            "--password-file",
            "/dev/zero",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let end = Instant::now() + Duration::from_secs(20);
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if Instant::now() > end {
            let _ = child.kill();
            panic!("--password-file /dev/zero is read without end");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    assert_eq!(status.code(), Some(2), "{err}");
    assert!(err.contains("not a password file"), "{err}");
}
