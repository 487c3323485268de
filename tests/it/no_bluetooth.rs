//! On a machine without Bluetooth (no D-Bus system bus: forced here by pointing
//! DBUS_SYSTEM_BUS_ADDRESS at nothing), the app, `drive`, `run` and `scan` exit with status 1 within seconds and
//! one line naming what is missing and mentioning `--sim` — never a panic or a hang.

// "No Bluetooth" here is Linux's: no D-Bus system bus.
#![cfg(target_os = "linux")]

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn check(args: &[&str]) {
    let dir = std::env::temp_dir().join(format!("droidctl-nobt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let script = dir.join("m.txt");
    std::fs::write(&script, "wake\ndrive 50 0 for 1s\n").unwrap();
    let args: Vec<String> = args
        .iter()
        .map(|a| a.replace("SCRIPT", script.to_str().unwrap()))
        .collect();
    let start = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(&args)
        .env("DROIDCTL_LOG_FILE", dir.join("log"))
        .env("DROIDCTL_CONFIG", "/dev/null")
        .env(
            "DBUS_SYSTEM_BUS_ADDRESS",
            "unix:path=/nonexistent/droidctl-test-bus",
        )
        .env("RUST_BACKTRACE", "1")
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let took = start.elapsed();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
    assert!(took < Duration::from_secs(10), "{args:?} took {took:?}");
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "{args:?}: one line: {stderr}"
    );
    assert!(stderr.contains("--sim"), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    assert!(
        out.stdout.is_empty() || !String::from_utf8_lossy(&out.stdout).contains("\x1b[?1049h"),
        "no TUI started"
    );
}

#[test]
fn the_app_without_bluetooth() {
    check(&[]);
}

#[test]
fn drive_without_bluetooth() {
    check(&["drive", "--scan-timeout", "2"]);
}

#[test]
fn run_without_bluetooth() {
    check(&["run", "SCRIPT"]);
}

#[test]
fn scan_without_bluetooth() {
    check(&["scan", "--timeout", "1"]);
}
