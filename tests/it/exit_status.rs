//! One contract for every subcommand (docs/exit-status.md): bad input 2, a failure at run
//! time 1, a reader that went away 0, Ctrl+c during `run` 130 once the droid is stopped. Each
//! subcommand is run through each case that applies to it, and the page's table is checked
//! against `EXIT_STATUSES`.

// A closed pipe, /dev/full and SIGINT are Unix's.
#![cfg(unix)]

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

const MISSION: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/missions/square.txt");
const SQUARE_JS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/edu/square.js");

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("droidctl-exit-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Where a case's standard output goes.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Out {
    /// A pipe read to its end.
    Read,
    /// A pipe whose reader is gone before the command writes anything.
    Closed,
    /// /dev/full: every write fails with "no space left".
    Full,
}

/// `droidctl args` in `dir` (the default configuration unless `config` names one, the log
/// and state directory inside `dir`, no Bluetooth), `stdin` written then closed: its status
/// and standard error.
fn status(dir: &Path, args: &[&str], out: Out, config: Option<&Path>) -> (Option<i32>, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_droidctl"));
    cmd.args(args)
        .current_dir(dir)
        .env("DROIDCTL_CONFIG", config.unwrap_or(Path::new("/dev/null")))
        .env("DROIDCTL_LOG_FILE", dir.join("droidctl.log"))
        .env("DROIDCTL_STATE_DIR", dir.join("state"))
        .env(
            "DBUS_SYSTEM_BUS_ADDRESS",
            "unix:path=/nonexistent/droidctl-test-bus",
        )
        .env("RUST_BACKTRACE", "1")
        .stdin(Stdio::piped())
        .stderr(Stdio::piped());
    match out {
        Out::Read | Out::Closed => cmd.stdout(Stdio::piped()),
        Out::Full => cmd.stdout(
            std::fs::OpenOptions::new()
                .write(true)
                .open("/dev/full")
                .unwrap(),
        ),
    };
    let mut child = cmd.spawn().unwrap();
    if out == Out::Closed {
        drop(child.stdout.take());
    }
    // A bridge over stdio is told to stop its droid; everything else reads nothing.
    let stdin = if args.contains(&"--stdio") {
        &b"{\"v\":1,\"cmd\":\"stop\"}\n"[..]
    } else {
        &b""[..]
    };
    let _ = child.stdin.take().unwrap().write_all(stdin);
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    (o.status.code(), err)
}

/// A capture of a short simulated run, a run's JSON output, and files that are not inputs.
fn inputs(dir: &Path) {
    let (code, err) = status(
        dir,
        &["run", MISSION, "--sim", "r2d2", "--record", "cap.drc"],
        Out::Read,
        None,
    );
    assert_eq!(code, Some(0), "{err}");
    let o = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["run", MISSION, "--sim", "r2d2", "--json"])
        .current_dir(dir)
        .env("DROIDCTL_CONFIG", "/dev/null")
        .env("DROIDCTL_LOG_FILE", dir.join("droidctl.log"))
        .output()
        .unwrap();
    std::fs::write(dir.join("run.json"), &o.stdout).unwrap();
    std::fs::write(dir.join("notcap.txt"), "hello\n").unwrap();
    std::fs::write(dir.join("empty.json"), "").unwrap();
    std::fs::write(dir.join("bad.toml"), "[control]\ncruise_speed = \"fast\"\n").unwrap();
    std::fs::write(dir.join("exists.toml"), "").unwrap();
    // A picture written to a full disk (plot names its format by the file's ending).
    std::os::unix::fs::symlink("/dev/full", dir.join("full.png")).unwrap();
}

#[test]
fn every_subcommand_keeps_the_contract() {
    let dir = scratch("contract");
    inputs(&dir);
    let bad = dir.join("bad.toml");
    let exists = dir.join("exists.toml");
    // (args, stdout, DROIDCTL_CONFIG, the status the contract gives)
    let cases: &[(&[&str], Out, Option<&Path>, i32)] = &[
        // Bad input: 2.
        (&["--sim", "nosuch"], Out::Read, None, 2),
        (&["packet", "decode", "zz"], Out::Read, None, 2),
        (&["run", "missing.txt", "--sim", "r2d2"], Out::Read, None, 2),
        (&["replay", "missing.drc", "--json"], Out::Read, None, 2),
        (&["replay", "notcap.txt", "--json"], Out::Read, None, 2),
        (&["replay", "notcap.txt"], Out::Read, None, 2),
        (&["plot", "empty.json", "-o", "p.png"], Out::Read, None, 2),
        (&["plot", "missing.json", "-o", "p.png"], Out::Read, None, 2),
        (&["scan", "--timeout", "0"], Out::Read, None, 2),
        (&["scan", "--scan-timeout", "0"], Out::Read, None, 2),
        (&["sim", "--bluez", "nosuch"], Out::Read, None, 2),
        (&["serve", "--sim", "nosuch"], Out::Read, None, 2),
        (
            &["bridge", "--stdio", "--sim", "nosuch"],
            Out::Read,
            None,
            2,
        ),
        (&["config", "init"], Out::Read, Some(&exists), 2),
        (&["config", "check"], Out::Read, Some(&bad), 2),
        (&["config", "show"], Out::Read, Some(&bad), 2),
        (&["completions", "nosuch"], Out::Read, None, 2),
        (&["man", "nosuch"], Out::Read, None, 2),
        (&["examples", "nosuch"], Out::Read, None, 2),
        (&["examples", "square"], Out::Read, None, 2),
        // A failure at run time: 1 (no Bluetooth here; a full disk).
        (&["scan"], Out::Read, None, 1),
        (&["packet", "list"], Out::Full, None, 1),
        (
            &["run", MISSION, "--sim", "r2d2", "--json"],
            Out::Full,
            None,
            1,
        ),
        (&["replay", "cap.drc", "--json"], Out::Full, None, 1),
        (&["plot", "run.json", "-o", "full.png"], Out::Read, None, 1),
        (&["bridge", "--stdio", "--sim", "r2d2"], Out::Full, None, 1),
        (&["config", "path"], Out::Full, None, 1),
        (&["config", "show"], Out::Full, None, 1),
        (&["completions", "bash"], Out::Full, None, 1),
        (&["man"], Out::Full, None, 1),
        (&["examples"], Out::Full, None, 1),
        (&["examples", "tour.txt"], Out::Full, None, 1),
        (&["sim", "--serial", "rvr"], Out::Full, None, 1),
        (&["sim", "--bluez", "r2d2"], Out::Full, None, 1),
        (
            &["run", "--each", SQUARE_JS, SQUARE_JS, "--sim", "mini"],
            Out::Full,
            None,
            1,
        ),
        // The reader went away: 0.
        (&["packet", "list"], Out::Closed, None, 0),
        (
            &["run", MISSION, "--sim", "r2d2", "--json"],
            Out::Closed,
            None,
            0,
        ),
        (&["replay", "cap.drc", "--json"], Out::Closed, None, 0),
        (
            &["bridge", "--stdio", "--sim", "r2d2"],
            Out::Closed,
            None,
            0,
        ),
        (&["config", "path"], Out::Closed, None, 0),
        (&["config", "show"], Out::Closed, None, 0),
        (&["completions", "bash"], Out::Closed, None, 0),
        (&["man"], Out::Closed, None, 0),
        (&["examples"], Out::Closed, None, 0),
        (&["examples", "square.js"], Out::Closed, None, 0),
        (
            &["run", "--each", SQUARE_JS, SQUARE_JS, "--sim", "mini"],
            Out::Closed,
            None,
            0,
        ),
    ];
    let mut wrong = Vec::new();
    for (args, out, config, want) in cases {
        let (code, err) = status(&dir, args, *out, *config);
        if code != Some(*want) {
            wrong.push(format!(
                "{args:?} ({out:?}): {code:?}, not {want}: {}",
                err.trim()
            ));
        } else if *want != 0 {
            // A refusal or a failure is said on standard error.
            let said = err
                .lines()
                .any(|l| l.starts_with("droidctl: error: ") || l.starts_with("error: "));
            if !said {
                wrong.push(format!("{args:?} ({out:?}): no error line: {err}"));
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Ctrl+c during `run`: the droid is stopped, then the status is 130 (128 + SIGINT).
#[test]
fn ctrl_c_during_run_is_130_after_the_stop() {
    let dir = scratch("sigint");
    std::fs::write(dir.join("long.txt"), "wake\ndrive 50 90\nwait 3000s\n").unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["run", "long.txt", "--sim", "r2d2"])
        .current_dir(&dir)
        .env("DROIDCTL_CONFIG", "/dev/null")
        .env("DROIDCTL_LOG_FILE", dir.join("droidctl.log"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The mission's `drive` line is printed once it is under way (signals are watched by then).
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let started = lines
        .by_ref()
        .map_while(Result::ok)
        .any(|l| l.contains("drive 50 90"));
    assert!(started, "the mission never drove");
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("SIGINT"), "{err}");
    assert!(err.contains("the droid was stopped"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// docs/exit-status.md's table is `EXIT_STATUSES`, row for row.
#[test]
fn the_documented_table_is_the_one_droidctl_uses() {
    let page = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/exit-status.md"))
        .unwrap();
    let start = page.find("| status | meaning |").expect("the table");
    let rows: Vec<&str> = page[start..]
        .lines()
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .collect();
    let want: Vec<String> = droidctl::cli::EXIT_STATUSES
        .iter()
        .map(|(s, what)| format!("| {s} | {} |", what.replace('|', "\\|")))
        .collect();
    assert_eq!(rows, want);
}
