//! Errors that point the right way: a capture or a btsnoop log given to `packet decode --file`
//! is recognised and sent to what reads it; `plot` says what it reads whatever is wrong with
//! its input; a mission's unknown command lists every command there is; `packet list` with a
//! filter that matches nothing is an error, and never prints a heading without entries.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("droidctl-errors-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn droidctl_in(dir: &Path, args: &[&str], stdin: &[u8]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(args)
        .current_dir(dir)
        .env("DROIDCTL_CONFIG", "/dev/null")
        .env("DROIDCTL_LOG_FILE", dir.join("droidctl.log"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The child may stop reading early: a refused input is not read to its end.
    let _ = child.stdin.take().unwrap().write_all(stdin);
    child.wait_with_output().unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

const MISSION: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/missions/square.txt");
const BTSNOOP: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/r2d2.btsnoop");

#[test]
fn decode_file_recognises_captures_and_btsnoop_logs() {
    let dir = scratch("decode");
    let o = droidctl_in(
        &dir,
        &["run", MISSION, "--sim", "--record", "m.capture"],
        b"",
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let capture = std::fs::read(dir.join("m.capture")).unwrap();
    for (args, stdin) in [
        (&["packet", "decode", "--file", "m.capture"][..], &b""[..]),
        (&["packet", "decode", "--file", "-"], &capture[..]),
    ] {
        let o = droidctl_in(&dir, args, stdin);
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("droidctl capture"), "{args:?}: {err}");
        assert!(err.contains("droidctl replay"), "{args:?}: {err}");
        assert!(!err.contains("malformed hex"), "{args:?}: {err}");
        assert!(o.stdout.is_empty(), "{args:?}: nothing decoded");
    }
    let o = droidctl_in(&dir, &["packet", "decode", "--file", BTSNOOP], b"");
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("btsnoop log") && err.contains("--btsnoop"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn plot_says_what_it_reads_whatever_is_wrong() {
    let dir = scratch("plot");
    for (name, body) in [
        ("garbage", &b"garbage\n"[..]),
        ("binary", b"\x00\x01\x02\xff"),
        ("half.jsonl", b"{\"t_ms\": 1\n"),
        ("other.jsonl", b"{\"a\": 1}\n"),
    ] {
        std::fs::write(dir.join(name), body).unwrap();
        let o = droidctl_in(&dir, &["plot", name], b"");
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains("run --json"), "{name}: {err}");
        assert!(
            err.contains("replay --json") && err.contains("capture"),
            "{name}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_unknown_mission_command_lists_every_command() {
    let dir = scratch("mission");
    std::fs::write(dir.join("m.txt"), "wake\nfly 1 2\n").unwrap();
    let o = droidctl_in(&dir, &["run", "m.txt", "--sim"], b"");
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("m.txt:2: unknown command \"fly\""), "{err}");
    for c in droidctl::script::COMMANDS {
        assert!(err.contains(c), "{c}: {err}");
    }
    for c in ["matrix", "tank", "calibrate"] {
        assert!(err.contains(c), "{c}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every heading (a line not indented, not `== family ==`) has entries under it.
fn no_empty_heading(listing: &str) -> bool {
    let lines: Vec<&str> = listing.lines().filter(|l| !l.is_empty()).collect();
    lines.iter().enumerate().all(|(i, l)| {
        l.starts_with("  ")
            || l.starts_with("== ")
            || lines.get(i + 1).is_some_and(|n| n.starts_with("  "))
    })
}

#[test]
fn packet_list_prints_no_empty_heading_and_refuses_a_filter_matching_nothing() {
    let dir = scratch("list");
    for args in [
        &["packet", "list", "nonsense"][..],
        &["packet", "list", "nonsense", "--protocol", "all"],
        &["packet", "list", "nonsense", "--protocol", "rsrcp"],
    ] {
        let o = droidctl_in(&dir, args, b"");
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(o.stdout.is_empty(), "{args:?}: {}", text(&o.stdout));
        assert!(
            err.contains("\"nonsense\"") && err.contains("packet list"),
            "{args:?}: {err}"
        );
    }
    for args in [
        &["packet", "list", "drive"][..],
        &["packet", "list", "drive", "--protocol", "all"],
        &["packet", "list", "roll", "--protocol", "v1"],
        &["packet", "list", "sensor"],
        &["packet", "list", "bolt"],
        &["packet", "list", "poti", "--protocol", "rsrcp"],
        &["packet", "list"],
        &["packet", "list", "--protocol", "all"],
    ] {
        let o = droidctl_in(&dir, args, b"");
        let out = text(&o.stdout);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {}", text(&o.stderr));
        assert!(out.lines().any(|l| l.starts_with("  ")), "{args:?}: {out}");
        assert!(
            no_empty_heading(&out),
            "{args:?} prints a heading without entries:\n{out}"
        );
    }
    // `drive` names commands only: no notification heading.
    let out = text(&droidctl_in(&dir, &["packet", "list", "drive"], b"").stdout);
    assert!(!out.contains("Notifications"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Scripts, programs and the configuration are read whole, so they are read bounded: an
/// endless file (`/dev/zero`) is one line and exit 2 at once, never unbounded memory.
#[cfg(unix)]
#[test]
fn an_endless_script_program_or_configuration_is_one_line_not_unbounded_memory() {
    let dir = scratch("endless");
    let program = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/edu/beacon.js");
    for args in [
        vec!["run", "/dev/zero", "--sim", "bolt"],
        vec!["run", program, "/dev/zero", "--sim", "bolt,bolt"],
        vec!["--sim", "bolt", "--program", "/dev/zero"],
    ] {
        let out = droidctl_in(&dir, &args, b"");
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("larger than 4096 KiB"), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    }
    let out = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["config", "check"])
        .env("DROIDCTL_CONFIG", "/dev/zero")
        .env("DROIDCTL_LOG_FILE", dir.join("droidctl.log"))
        .output()
        .unwrap();
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("larger than 1024 KiB"), "{err}");
}
