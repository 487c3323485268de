//! One overwrite rule for every file droidctl writes when asked (`--record`, `--csv`,
//! `--jsonl`, `plot -o`): an existing file is kept and the command refuses at once (status 2,
//! naming the file and `--force`); `--force` replaces it. Devices are written as they are.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("droidctl-outputs-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn droidctl(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(args)
        .current_dir(dir)
        .env("DROIDCTL_CONFIG", "/dev/null")
        .env("DROIDCTL_LOG_FILE", dir.join("droidctl.log"))
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

fn mission() -> String {
    concat!(env!("CARGO_MANIFEST_DIR"), "/assets/missions/square.txt").to_string()
}

/// `args` writes `target` (in the scratch directory): refused while it exists, replaced with
/// `--force`.
fn check(name: &str, target: &str, args: &[&str], setup: &[&[&str]]) {
    let dir = scratch(name);
    for s in setup {
        let out = droidctl(&dir, s);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{s:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let path = dir.join(target);
    std::fs::write(&path, "keep me").unwrap();
    let out = droidctl(&dir, args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(
        err.contains(&format!("{target} exists")) && err.contains("--force"),
        "{args:?}: {err}"
    );
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        "keep me",
        "{args:?} kept it"
    );

    let mut forced = args.to_vec();
    forced.push("--force");
    let out = droidctl(&dir, &forced);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{forced:?}: {err}");
    let written = std::fs::read(&path).unwrap();
    assert!(
        written.len() > 100 && !written.starts_with(b"keep me"),
        "{forced:?} replaced it"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_record_is_kept_without_force() {
    check(
        "record",
        "m.capture",
        &["run", &mission(), "--sim", "--record", "m.capture"],
        &[],
    );
}

#[test]
fn run_csv_is_kept_without_force() {
    check(
        "csv",
        "m.csv",
        &["run", &mission(), "--sim", "--csv", "m.csv"],
        &[],
    );
}

#[test]
fn a_fleet_run_csv_is_kept_without_force() {
    let patrol = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/patrol.txt");
    check(
        "fleet-csv",
        "f.csv",
        &["run", patrol, "--sim", "r2d2,bb8", "--csv", "f.csv"],
        &[],
    );
}

#[test]
fn replay_csv_is_kept_without_force() {
    let rec: &[&str] = &["run", &mission(), "--sim", "--record", "m.capture"];
    check(
        "replay-csv",
        "r.csv",
        &["replay", "m.capture", "--csv", "r.csv"],
        &[rec],
    );
}

#[test]
fn plot_outputs_are_kept_without_force() {
    let rec: &[&str] = &["run", &mission(), "--sim", "--record", "m.capture"];
    check("plot-png", "m.png", &["plot", "m.capture"], &[rec]);
    check(
        "plot-svg",
        "p.svg",
        &["plot", "m.capture", "-o", "p.png", "-o", "p.svg"],
        &[rec],
    );
}

#[test]
fn the_app_refuses_before_it_starts() {
    // Refused before anything connects or the terminal is taken (stdin is no terminal here).
    for (flag, file) in [
        ("--csv", "a.csv"),
        ("--jsonl", "a.jsonl"),
        ("--record", "a.capture"),
    ] {
        let dir = scratch(&format!("app{flag}"));
        std::fs::write(dir.join(file), "keep me").unwrap();
        let out = droidctl(&dir, &["--sim", flag, file]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{flag}: {err}");
        assert!(err.contains(&format!("{file} exists")), "{flag}: {err}");
        assert_eq!(std::fs::read_to_string(dir.join(file)).unwrap(), "keep me");
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[cfg(unix)]
#[test]
fn devices_are_written_as_they_are() {
    let dir = scratch("devices");
    let out = droidctl(
        &dir,
        &[
            "run",
            &mission(),
            "--sim",
            "--csv",
            "/dev/null",
            "--record",
            "/dev/null",
        ],
    );
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
