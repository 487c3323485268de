//! `droidctl sim --bluez`: the real BLE path end to end. The simulator serves droids on a
//! private bus as BlueZ does; the real `droidctl` binary reaches it through
//! `DBUS_SYSTEM_BUS_ADDRESS`, btleplug and bluez-async, without `--sim`: scanning, missions of
//! each protocol family (compared with the same mission against `--sim`), the app in a
//! pseudo-terminal, and the fault paths (a dropped link, a refused connection). A few checks
//! talk D-Bus to it directly, as other BlueZ clients do.
//!
//! The bus is `dbus-daemon` where it is installed (`.ci/run` installs it), else busd, the bus
//! in Rust `sim --bluez` runs in-process (issue 28); `DROIDCTL_DBUS_DAEMON=embedded` picks
//! busd where both could run (`.ci/run`'s fresh-machine step, and
//! [`the_embedded_bus_serves_bluez_clients`] here). Nothing is skipped either way.

#![cfg(target_os = "linux")]

use crate::common::lines::{Lines, first_line};
use dbus::arg::{PropMap, RefArg, Variant};
use dbus::blocking::Connection;
use dbus::message::MatchRule;
use droidctl::protocol::v2::{Decoder, Packet};
use std::collections::HashMap;
use std::process::{Child, Command, Output, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

// -------------------------------------------------------------------------------------------
// Harness
// -------------------------------------------------------------------------------------------

/// Whether `dbus-daemon` is installed (then `sim --bluez` runs it, unless told otherwise).
fn dbus_daemon_installed() -> bool {
    Command::new("dbus-daemon")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// A scratch directory removed on drop.
struct TempDir(std::path::PathBuf);

impl TempDir {
    fn new(tag: &str) -> TempDir {
        static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let p = std::env::temp_dir().join(format!(
            "droidctl-simbluez-{tag}-{}-{n}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).unwrap();
        TempDir(p)
    }

    fn file(&self, name: &str, text: &str) -> String {
        let p = self.0.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_string_lossy().into_owned()
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A running `droidctl sim --bluez`, stopped with SIGTERM on drop.
struct Sim {
    child: Child,
    address: String,
    /// Its stderr so far, line by line.
    lines: Lines,
    /// Advertised names, in the order the models were given.
    names: Vec<String>,
    /// What it printed on stdout after the export line (nothing, once it ended).
    stdout_rest: std::sync::mpsc::Receiver<String>,
}

impl Sim {
    fn start(args: &[&str]) -> Sim {
        Sim::start_env(args, &[])
    }

    /// As [`Sim::start`], with environment variables set for it.
    fn start_env(args: &[&str], env: &[(&str, &str)]) -> Sim {
        let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
            .arg("sim")
            .arg("--bluez")
            .args(args)
            .envs(env.iter().copied())
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start droidctl sim --bluez");
        let lines = Lines::collect(child.stderr.take().unwrap());
        // Anything more on stdout would break "only the export line": `stdout_rest` keeps it
        // for the check in `stop`.
        let (first, stdout_rest) =
            first_line(child.stdout.take().unwrap(), Duration::from_secs(10));
        let first = first.expect("droidctl sim printed its address");
        let address = first
            .trim()
            .strip_prefix("DBUS_SYSTEM_BUS_ADDRESS=")
            .unwrap_or_else(|| panic!("export line, got {first:?}"))
            .to_string();
        assert!(address.starts_with("unix:path="), "{address}");
        let mut sim = Sim {
            child,
            address,
            lines,
            names: Vec::new(),
            stdout_rest,
        };
        // One "NAME (MODEL) at ADDRESS" line per droid, before "serving on".
        let serving = sim.wait_line("serving on", Duration::from_secs(5));
        assert!(serving.contains(&sim.address), "{serving}");
        sim.names = sim
            .lines()
            .iter()
            .filter_map(|l| {
                let rest = l.strip_prefix("droidctl sim: ")?;
                let (name, _) = rest.split_once(" (")?;
                rest.contains(") at ").then(|| name.to_string())
            })
            .collect();
        sim
    }

    fn lines(&self) -> Vec<String> {
        self.lines.all()
    }

    fn wait_line(&self, what: &str, limit: Duration) -> String {
        self.lines.wait_for(what, limit)
    }

    /// SIGTERM, and it must end cleanly: exit 0, its directory gone.
    fn stop(self) -> Vec<String> {
        self.stop_with("-TERM")
    }

    /// Stop with a signal (`-TERM`, `-INT` as Ctrl-C sends): exit 0, the private daemon's
    /// directory gone, nothing on stdout but the export line.
    fn stop_with(mut self, signal: &str) -> Vec<String> {
        let dir = self
            .address
            .strip_prefix("unix:path=")
            .and_then(|p| p.strip_suffix("/bus"))
            .map(std::path::PathBuf::from);
        let _ = Command::new("kill")
            .args([signal, &self.child.id().to_string()])
            .status();
        let start = Instant::now();
        let status = loop {
            if let Some(s) = self.child.try_wait().unwrap() {
                break s;
            }
            assert!(start.elapsed() < Duration::from_secs(5), "sim did not stop");
            std::thread::sleep(Duration::from_millis(20));
        };
        // Everything it said read to the end before anyone judges it.
        assert!(
            self.lines.wait_end(Duration::from_secs(5)),
            "its stderr did not end"
        );
        assert!(status.success(), "{status:?}\n{}", self.lines().join("\n"));
        let rest = self
            .stdout_rest
            .recv_timeout(Duration::from_secs(2))
            .unwrap_or_default();
        assert_eq!(rest, "", "nothing on stdout but the export line");
        if let Some(dir) = dir {
            assert!(!dir.exists(), "{} left behind", dir.display());
        }
        self.lines()
    }
}

impl Drop for Sim {
    fn drop(&mut self) {
        if matches!(self.child.try_wait(), Ok(None)) {
            let _ = Command::new("kill")
                .args(["-TERM", &self.child.id().to_string()])
                .status();
            let start = Instant::now();
            while matches!(self.child.try_wait(), Ok(None))
                && start.elapsed() < Duration::from_secs(3)
            {
                std::thread::sleep(Duration::from_millis(20));
            }
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// The real binary against the virtual BlueZ (or `--sim` when `bus` is `None`).
fn droidctl(args: &[&str], bus: Option<&str>, dir: &TempDir) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_droidctl"));
    cmd.args(args)
        .stdin(Stdio::null())
        .env("DROIDCTL_LOG_FILE", dir.0.join("droidctl.log"))
        .env(
            "DROIDCTL_CONFIG",
            config_or_defaults(dir.0.join("config.toml")),
        );
    match bus {
        Some(a) => cmd.env("DBUS_SYSTEM_BUS_ADDRESS", a),
        // No way to a system bus: `--sim` must not need one.
        None => cmd.env(
            "DBUS_SYSTEM_BUS_ADDRESS",
            "unix:path=/nonexistent/droidctl-test/bus",
        ),
    };
    cmd.output().expect("run droidctl")
}

use crate::common::mission_run;
use mission_run::{Run, f, parse_run, text};

/// The same mission through `sim --bluez` and against `--sim`: both complete, and the
/// telemetry agrees within what real time allows.
fn mission_matches(model: &str, mission: &str) -> (Run, Run) {
    let sim = Sim::start(&[model]);
    let name = sim.names[0].clone();
    let dir = TempDir::new(model);
    let script = dir.file("mission.txt", mission);
    let t0 = Instant::now();
    let ble = droidctl(
        &["run", &script, "--name", &name, "--json"],
        Some(&sim.address),
        &dir,
    );
    let took = t0.elapsed();
    assert_eq!(
        ble.status.code(),
        Some(0),
        "stderr: {}\nsim: {}",
        text(&ble.stderr),
        sim.lines().join("\n")
    );
    let reference = droidctl(&["run", &script, "--sim", model, "--json"], None, &dir);
    assert_eq!(
        reference.status.code(),
        Some(0),
        "{}",
        text(&reference.stderr)
    );
    let (ble, reference) = (parse_run(&ble), parse_run(&reference));
    mission_run::assert_matches(&ble, &reference, took);
    // The connection ended with the mission.
    let lines = sim.stop();
    assert!(
        lines
            .iter()
            .any(|l| l.contains(&format!("{name}: connected ("))),
        "{lines:?}"
    );
    assert!(
        lines
            .iter()
            .any(|l| l.contains(&format!("{name}: disconnected by the client"))),
        "{lines:?}"
    );
    (ble, reference)
}

// -------------------------------------------------------------------------------------------
// Missions through btleplug, one per family
// -------------------------------------------------------------------------------------------

/// API v2: the anti-DoS unlock, the setup, a stance change and a drive.
#[test]
fn r2d2_mission_through_bluez_matches_the_simulator() {
    let (ble, _) = mission_matches("r2d2", "stance tripod\ndrive 80 90 for 1.5s\nwait 0.3s\n");
    let last = &ble.samples[ble.samples.len() - 1];
    assert_eq!(last["stance"], "tripod", "{last}");
}

/// API v1: the wake sequence, then driving.
#[test]
fn bb8_mission_through_bluez_matches_the_simulator() {
    mission_matches("bb8", "drive 80 90 for 1.5s\nwait 0.3s\n");
}

/// RSRCP: the handshake read and the start confirmation, frames one per notification, the
/// remote control.
#[test]
fn robi_mission_through_bluez_matches_the_simulator() {
    let (ble, reference) = mission_matches("robi", "drive 200 0 for 2s\nwait 0.3s\n");
    let frames = |r: &Run| f(&r.samples[r.samples.len() - 1]["frames"]);
    assert!(frames(&ble) >= 20.0, "frames flow: {}", frames(&ble));
    assert!((frames(&ble) - frames(&reference)).abs() <= 4.0);
}

/// Issue 19: BOLT, Mini and RVR found by `--name` and driven through btleplug on the virtual
/// BlueZ, as in the simulator (BOLT and Mini unlock like R2-D2; RVR has no unlock and every
/// command addressed; BOLT's matrix line and RVR's tracks on the way).
#[test]
fn bolt_mini_and_rvr_missions_through_bluez_match_the_simulator() {
    mission_matches(
        "bolt",
        "matrix char A 255 0 0\ncalibrate compass\ndrive 80 90 for 1.5s\nwait 0.3s\n",
    );
    mission_matches("mini", "drive 80 90 for 1.5s\nwait 0.3s\n");
    let (ble, _) = mission_matches("rvr", "tank 150 150 for 1.5s\nwait 0.3s\n");
    let last = &ble.samples[ble.samples.len() - 1];
    assert!(f(&last["y_cm"]) > 30.0, "both tracks forward: {last}");
}

#[test]
fn scan_names_bolt_mini_and_rvr() {
    let sim = Sim::start(&["bolt", "mini", "rvr"]);
    let dir = TempDir::new("scan-robots");
    let out = droidctl(
        &["scan", "--timeout", "0.5", "--json"],
        Some(&sim.address),
        &dir,
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let seen: Vec<(String, String)> = text(&out.stdout)
        .lines()
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            (
                v["name"].as_str().unwrap_or("?").to_string(),
                v["model"].as_str().unwrap_or("?").to_string(),
            )
        })
        .collect();
    assert_eq!(seen.len(), 3, "{seen:?}");
    for ((name, model), (prefix, id)) in
        seen.iter()
            .zip([("SB-", "bolt"), ("SM-", "mini"), ("RV-", "rvr")])
    {
        assert!(name.starts_with(prefix), "{seen:?}");
        assert_eq!(model, id);
    }
    sim.stop();
}

// -------------------------------------------------------------------------------------------
// Scanning
// -------------------------------------------------------------------------------------------

#[test]
fn scan_lists_a_droid_of_each_family() {
    let sim = Sim::start(&["r2d2", "bb8", "robi"]);
    assert_eq!(sim.names.len(), 3, "{:?}", sim.lines());
    let dir = TempDir::new("scan");
    let out = droidctl(&["scan", "--timeout", "1"], Some(&sim.address), &dir);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let rows: Vec<&str> = stdout.lines().collect();
    assert_eq!(rows.len(), 4, "{stdout}");
    assert!(rows[0].starts_with("NAME"), "{stdout}");
    // Strongest first: the order they were given.
    for (row, (name, model)) in rows[1..].iter().zip([
        (&sim.names[0], "R2-D2"),
        (&sim.names[1], "BB-8"),
        (&sim.names[2], "Robi 42"),
    ]) {
        assert!(row.starts_with(name.as_str()), "{row}");
        assert!(row.contains(model), "{row}");
        assert!(row.ends_with("dBm"), "{row}");
    }
    assert!(sim.names[0].starts_with("D2-") && sim.names[1].starts_with("BB-"));
    assert_eq!(sim.names[2], "Robi 42");
    let out = droidctl(
        &["scan", "--timeout", "0.5", "--json"],
        Some(&sim.address),
        &dir,
    );
    let models: Vec<String> = text(&out.stdout)
        .lines()
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            v["model"].as_str().unwrap_or("?").to_string()
        })
        .collect();
    assert_eq!(models, ["r2d2", "bb8", "robi"]);
    // Ctrl-C: a clean stop.
    let lines = sim.stop_with("-INT");
    assert!(
        lines.last().is_some_and(|l| l.ends_with("SIGINT: stopped")),
        "{lines:?}"
    );
}

// -------------------------------------------------------------------------------------------
// Faults through btleplug
// -------------------------------------------------------------------------------------------

/// The trace records (`--trace --json`) of device `name` in `lines`, with their line index.
fn trace_of(lines: &[String], name: &str) -> Vec<(usize, serde_json::Value)> {
    lines
        .iter()
        .enumerate()
        .filter(|(_, l)| l.starts_with('{'))
        .filter_map(|(i, l)| {
            let v: serde_json::Value =
                serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}"));
            (v["device"] == name).then_some((i, v))
        })
        .collect()
}

/// The commands `name` received, in order: (line index, the `packet decode --json` object).
fn commands_in(lines: &[String], name: &str) -> Vec<(usize, serde_json::Value)> {
    trace_of(lines, name)
        .into_iter()
        .filter(|(_, v)| v["dir"] == "in" && v["packet"]["kind"] == "command")
        .map(|(i, v)| (i, v["packet"].clone()))
        .collect()
}

/// The speeds of the drive commands among `commands`.
fn drive_speeds(commands: &[(usize, serde_json::Value)]) -> Vec<u64> {
    commands
        .iter()
        .filter(|(_, p)| p["command"] == "drive-with-heading")
        .map(|(_, p)| p["fields"]["speed"].as_u64().unwrap_or(u64::MAX))
        .collect()
}

/// The index of the first line containing `what` at or after `from`.
fn line_at(lines: &[String], from: usize, what: &str) -> usize {
    from + lines[from..]
        .iter()
        .position(|l| l.contains(what))
        .unwrap_or_else(|| panic!("no {what:?} after line {from} in\n{}", lines.join("\n")))
}

/// The droid drops the link while driving: droidctl says so, reconnects, runs the handshake
/// and the setup again, resumes at speed 0, and the mission completes. The trace shows the
/// order: after the reconnect the unlock, the wake, then a stop at the last heading before
/// any other setup command, the fail-safe among the setup.
#[test]
fn a_disconnect_mid_drive_reconnects_and_resumes_at_speed_0() {
    // Connected at 0 s; setup ≈ 1.3 s, stance 2 s: driving from about 3.4 s to 7.4 s.
    let sim = Sim::start(&[
        "r2d2",
        "--fault",
        "disconnect-after=4.5",
        "--trace",
        "--json",
    ]);
    let name = sim.names[0].clone();
    let dir = TempDir::new("dc");
    let script = dir.file(
        "mission.txt",
        "stance tripod\ndrive 60 90\nwait 4s\nstop\nwait 0.3s\n",
    );
    let out = droidctl(&["run", &script, "--name", &name], Some(&sim.address), &dir);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert_eq!(out.status.code(), Some(0), "{stdout}\n{stderr}");
    // The run shows the link going and coming back.
    let lost = stderr
        .find("link lost: the droid disconnected — reconnecting (attempt 1)")
        .unwrap_or_else(|| panic!("{stderr}"));
    let back = stderr
        .find("] reconnected")
        .unwrap_or_else(|| panic!("{stderr}"));
    assert!(back > lost);
    assert!(stdout.contains("done in"), "{stdout}");
    assert!(stdout.contains("failed steps 0"), "{stdout}");
    let lines = sim.stop();
    let dropped = format!("{name}: fault disconnect-after: dropped the connection after 4.50 s");
    let drop_at = line_at(&lines, 0, &dropped);
    let connected = format!("{name}: connected (");
    let connects = lines.iter().filter(|l| l.contains(&connected)).count();
    assert_eq!(connects, 2, "{lines:?}");
    let reconnect = line_at(&lines, drop_at, &connected);
    // Before the drop it was driving at 60, with the fail-safe set.
    let before = commands_in(&lines[..drop_at], &name);
    assert!(drive_speeds(&before).contains(&60), "{before:?}");
    assert!(
        before
            .iter()
            .any(|(_, p)| p["command"] == "set-custom-control-system-timeout"
                && p["fields"]["timeout_ms"] == 2000),
        "the fail-safe: {before:?}"
    );
    // Nothing reaches the droid while it is gone.
    assert!(
        trace_of(&lines[drop_at..reconnect], &name)
            .iter()
            .all(|(_, v)| v["dir"] != "in"),
        "{lines:?}"
    );
    // Then the handshake again: the unlock, as a GATT write that is no API packet.
    let after = trace_of(&lines[reconnect..], &name);
    let first_in = &after
        .iter()
        .find(|(_, v)| v["dir"] == "in")
        .expect("writes after the reconnect")
        .1["packet"];
    assert_eq!(first_in["kind"], "gatt-write", "{first_in}");
    assert_eq!(first_in["uuid"], "00020005-574f-4f20-5370-6865726f2121");
    assert_eq!(
        first_in["hex"],
        droidctl::hex::compact(b"usetheforce...band"),
        "unlock first"
    );
    // The wake, then a stop at the last heading before any other setup command.
    let cmds = commands_in(&lines[reconnect..], &name);
    let names: Vec<&str> = cmds
        .iter()
        .map(|(_, p)| p["command"].as_str().unwrap_or("?"))
        .collect();
    assert_eq!(&names[..2], ["wake", "drive-with-heading"], "{names:?}");
    assert_eq!(cmds[1].1["fields"]["speed"], 0, "stop first: {:?}", cmds[1]);
    assert_eq!(cmds[1].1["fields"]["heading"], 90, "at the last heading");
    assert!(
        names.contains(&"set-custom-control-system-timeout"),
        "the fail-safe again: {names:?}"
    );
    let speeds = drive_speeds(&cmds);
    assert!(speeds.contains(&60), "then drives on: {speeds:?}");
    assert_eq!(speeds.last(), Some(&0), "and stops at the end: {speeds:?}");
}

/// A droid that refuses every connection: droidctl retries, then gives up with the
/// documented one-line error and status 1. (Named to start first: it takes the mission's
/// 20 s connect limit.)
#[test]
fn a_droid_refusing_connections_gives_one_line_and_status_1() {
    let sim = Sim::start(&["r2d2", "--fault", "refuse-connect"]);
    let name = sim.names[0].clone();
    let dir = TempDir::new("refused");
    let script = dir.file("mission.txt", "drive 60 0 for 1s\n");
    let out = droidctl(&["run", &script, "--name", &name], Some(&sim.address), &dir);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(out.stdout.is_empty(), "{}", text(&out.stdout));
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    assert!(
        stderr.starts_with(
            "droidctl: error: no connection within 20 s: the connection was aborted \
             (le-connection-abort-by-local) — wake the droid"
        ),
        "{stderr}"
    );
    let lines = sim.stop();
    let refused = lines
        .iter()
        .filter(|l| l.contains("fault refuse-connect: refusing the connection"))
        .count();
    assert!(refused >= 3, "droidctl retried: {lines:?}");
    assert!(
        !lines.iter().any(|l| l.contains(": connected (")),
        "{lines:?}"
    );
}

// -------------------------------------------------------------------------------------------
// The app in a pseudo-terminal
// -------------------------------------------------------------------------------------------

use crate::common::pty;

/// The droid's y position as the sensors panel shows it ("pos x … y … cm").
fn shown_y(screen: &str) -> Option<f32> {
    let line = screen.lines().find(|l| l.contains("pos x"))?;
    let after = &line[line.find(" y ")? + 3..];
    after.split_whitespace().next()?.parse().ok()
}

/// The app finds the R2-D2 on the virtual BlueZ, connects, shows what it notifies (sensor
/// streaming in the packet log, the position on the sensors panel), drives it with `w`, and
/// quits with `q`, disconnecting.
#[test]
fn the_app_drives_r2d2_through_the_virtual_bluez() {
    let sim = Sim::start(&["r2d2"]);
    let name = sim.names[0].clone();
    let dir = TempDir::new("app");
    let log = dir.0.join("droidctl.log").to_string_lossy().into_owned();
    let config = config_or_defaults(dir.0.join("config.toml"))
        .to_string_lossy()
        .into_owned();
    let mut tui = pty::Tui::start(
        &["--name", &name],
        &[
            ("DBUS_SYSTEM_BUS_ADDRESS", sim.address.as_str()),
            ("DROIDCTL_LOG_FILE", log.as_str()),
            ("DROIDCTL_CONFIG", config.as_str()),
        ],
    );
    let screen = tui.wait_for("connected", Duration::from_secs(20));
    assert!(
        screen.contains(&name),
        "the droid's name on screen:\n{screen}"
    );
    tui.wait_for("stance tripod", Duration::from_secs(10));
    // Notifications arrive: sensor streaming in the log, the position on the panel.
    tui.wait_for("sensor-streaming", Duration::from_secs(5));
    tui.wait_for("pos x", Duration::from_secs(5));
    let before = shown_y(&tui.text()).unwrap_or(0.0);
    tui.hold(b"w", Duration::from_millis(2500));
    std::thread::sleep(Duration::from_millis(800));
    let screen = tui.text();
    let after = shown_y(&screen).expect("position on screen");
    assert!(
        after > before + 30.0,
        "the droid moved forward: {before} → {after}\n{screen}"
    );
    assert!(screen.contains("drive-with-heading"), "{screen}");
    tui.send(b"q");
    let status = tui.wait_exit(Duration::from_secs(10));
    assert!(status.success(), "{status:?}");
    sim.wait_line(
        &format!("{name}: disconnected by the client"),
        Duration::from_secs(5),
    );
    let lines = sim.stop();
    assert!(
        lines
            .iter()
            .any(|l| l.contains(&format!("{name}: connected ("))),
        "{lines:?}"
    );
}

// -------------------------------------------------------------------------------------------
// The D-Bus API as other BlueZ clients see it
// -------------------------------------------------------------------------------------------

type Tree = HashMap<dbus::Path<'static>, HashMap<String, PropMap>>;

fn managed(c: &Connection) -> Tree {
    let p = c.with_proxy("org.bluez", "/", Duration::from_secs(2));
    let (tree,): (Tree,) = p
        .method_call(
            "org.freedesktop.DBus.ObjectManager",
            "GetManagedObjects",
            (),
        )
        .expect("GetManagedObjects");
    tree
}

fn call(c: &Connection, path: &str, iface: &str, member: &str) -> Result<(), dbus::Error> {
    c.with_proxy("org.bluez", path, Duration::from_secs(2))
        .method_call(iface, member, ())
}

fn prop(tree: &Tree, path: &str, iface: &str, name: &str) -> Option<String> {
    let v = tree
        .get(&dbus::Path::from(path.to_string()))?
        .get(iface)?
        .get(name)?;
    Some(format!("{:?}", v.0))
}

fn err_name(r: Result<(), dbus::Error>) -> String {
    r.err()
        .and_then(|e| e.name().map(str::to_string))
        .unwrap_or_default()
}

/// Discovery sessions, connecting, the GATT objects, reads, writes and notifications, the
/// handshake at the D-Bus level, one connection at a time.
#[test]
fn the_dbus_api_as_bluez_clients_see_it() {
    let sim = Sim::start(&["r2d2"]);
    let name = sim.names[0].clone();
    let a = Connection::new_address(&sim.address).unwrap();
    let b = Connection::new_address(&sim.address).unwrap();
    let adapter = "/org/bluez/hci0";
    // Before any discovery only the adapter is there.
    let tree = managed(&a);
    assert!(prop(&tree, adapter, "org.bluez.Adapter1", "Powered").is_some());
    assert!(!tree.keys().any(|p| p.contains("dev_")), "{tree:?}");
    call(&a, adapter, "org.bluez.Adapter1", "StartDiscovery").unwrap();
    assert_eq!(
        err_name(call(&a, adapter, "org.bluez.Adapter1", "StartDiscovery")),
        "org.bluez.Error.InProgress"
    );
    assert_eq!(
        err_name(call(&b, adapter, "org.bluez.Adapter1", "StopDiscovery")),
        "org.bluez.Error.Failed",
        "b has no discovery session"
    );
    let tree = managed(&a);
    let dev = tree
        .keys()
        .find(|p| p.contains("dev_"))
        .expect("the droid is heard")
        .to_string();
    assert_eq!(
        prop(&tree, &dev, "org.bluez.Device1", "Name"),
        Some(format!("{name:?}"))
    );
    assert_eq!(
        prop(&tree, &dev, "org.bluez.Device1", "Connected"),
        Some("false".into())
    );
    // Notifications and property changes arrive as signals: collect them (property, bytes
    // for byte arrays, the value as text).
    type Seen = Arc<Mutex<Vec<(String, Vec<u8>, String)>>>;
    let seen: Seen = Arc::default();
    {
        let seen = seen.clone();
        let rule = MatchRule::new_signal("org.freedesktop.DBus.Properties", "PropertiesChanged")
            .with_namespaced_path(dev.clone());
        a.add_match(rule, move |(): (), _, m| {
            let path = m.path().map(|p| p.to_string()).unwrap_or_default();
            if let Ok((iface, changed)) = m.read2::<&str, PropMap>() {
                for (k, v) in changed {
                    let bytes: Vec<u8> = dbus::arg::cast::<Vec<u8>>(&v.0)
                        .cloned()
                        .unwrap_or_default();
                    let shown = format!("{:?}", v.0);
                    seen.lock()
                        .unwrap()
                        .push((format!("{path} {iface}.{k}"), bytes, shown));
                }
            }
            true
        })
        .unwrap();
    }
    call(&a, &dev, "org.bluez.Device1", "Connect").unwrap();
    // One connection at a time.
    assert_eq!(
        err_name(call(&b, &dev, "org.bluez.Device1", "Connect")),
        "org.bluez.Error.Failed"
    );
    sim.wait_line("refused a connection from", Duration::from_secs(2));
    // Services resolve; the GATT table appears under the device.
    let start = Instant::now();
    let tree = loop {
        let t = managed(&a);
        if prop(&t, &dev, "org.bluez.Device1", "ServicesResolved") == Some("true".into()) {
            break t;
        }
        assert!(start.elapsed() < Duration::from_secs(3), "never resolved");
        std::thread::sleep(Duration::from_millis(20));
    };
    let find_char = |uuid: &str| -> String {
        tree.iter()
            .find(|(_, ifaces)| {
                ifaces
                    .get("org.bluez.GattCharacteristic1")
                    .and_then(|p| p.get("UUID"))
                    .is_some_and(|v| v.0.as_str() == Some(uuid))
            })
            .map(|(p, _)| p.to_string())
            .unwrap_or_else(|| panic!("no characteristic {uuid} in {tree:?}"))
    };
    let api = find_char("00010002-574f-4f20-5370-6865726f2121");
    let anti_dos = find_char("00020005-574f-4f20-5370-6865726f2121");
    assert!(api.starts_with(&format!("{dev}/service")), "{api}");
    let flags = prop(&tree, &api, "org.bluez.GattCharacteristic1", "Flags").unwrap();
    assert!(
        flags.contains("notify") && flags.contains("write"),
        "{flags}"
    );
    let services: Vec<String> = tree
        .values()
        .filter_map(|i| i.get("org.bluez.GattService1"))
        .filter_map(|p| p.get("UUID").and_then(|v| v.0.as_str().map(str::to_string)))
        .collect();
    assert_eq!(services.len(), 2, "{services:?}");
    fn chr<'a>(c: &'a Connection, path: &str) -> dbus::blocking::Proxy<'static, &'a Connection> {
        c.with_proxy("org.bluez", path.to_string(), Duration::from_secs(2))
    }
    // Not readable.
    let r: Result<(Vec<u8>,), _> = chr(&a, &api).method_call(
        "org.bluez.GattCharacteristic1",
        "ReadValue",
        (PropMap::new(),),
    );
    assert_eq!(
        r.err()
            .and_then(|e| e.name().map(str::to_string))
            .as_deref(),
        Some("org.bluez.Error.NotPermitted")
    );
    call(&a, &api, "org.bluez.GattCharacteristic1", "StartNotify").unwrap();
    let write = |path: &str, bytes: &[u8]| {
        let mut opts = PropMap::new();
        opts.insert(
            "type".into(),
            Variant(Box::new("request".to_string()) as Box<dyn RefArg>),
        );
        let r: Result<(), _> = chr(&a, path).method_call(
            "org.bluez.GattCharacteristic1",
            "WriteValue",
            (bytes.to_vec(), opts),
        );
        r.unwrap();
    };
    let ping = [0x8D, 0x0A, 0x13, 0x0D, 0x00, 0xD5, 0xD8];
    let pump = |c: &Connection, for_: Duration| {
        let end = Instant::now() + for_;
        while Instant::now() < end {
            let _ = c.process(Duration::from_millis(20));
        }
    };
    let values = |seen: &Seen| -> Vec<Vec<u8>> {
        seen.lock()
            .unwrap()
            .iter()
            .filter(|(k, _, _)| k.starts_with(&api) && k.ends_with(".Value"))
            .map(|(_, v, _)| v.clone())
            .collect()
    };
    // Locked: a ping goes unanswered.
    write(&api, &ping);
    pump(&a, Duration::from_millis(300));
    assert!(values(&seen).is_empty(), "{:?}", seen.lock().unwrap());
    // Unlocked: the same ping is answered, as a notification on Value.
    write(&anti_dos, b"usetheforce...band");
    write(&api, &ping);
    pump(&a, Duration::from_millis(300));
    let answers: Vec<Packet> = Decoder::new()
        .decode_all(&values(&seen).concat())
        .into_iter()
        .filter_map(Result::ok)
        .collect();
    assert_eq!(answers.len(), 1, "{:?}", seen.lock().unwrap());
    assert!(answers[0].is_response(), "{:?}", answers[0]);
    assert_eq!((answers[0].did, answers[0].cid), (0x13, 0x0D));
    assert!(
        seen.lock()
            .unwrap()
            .iter()
            .any(|(k, _, v)| k.ends_with(".Notifying") && v == "true"),
        "{:?}",
        seen.lock().unwrap()
    );
    // What no client should send gets an error, never a crash.
    let bad: Result<(), _> = chr(&a, &api).method_call(
        "org.bluez.GattCharacteristic1",
        "WriteValue",
        ("not bytes", 7u32),
    );
    assert_eq!(
        bad.err()
            .and_then(|e| e.name().map(str::to_string))
            .as_deref(),
        Some("org.freedesktop.DBus.Error.InvalidArgs")
    );
    let props = chr(&a, &dev);
    let r: Result<(Variant<Box<dyn RefArg>>,), _> = props.method_call(
        "org.freedesktop.DBus.Properties",
        "Get",
        ("org.bluez.Device1", "Nope"),
    );
    assert_eq!(
        r.err()
            .and_then(|e| e.name().map(str::to_string))
            .as_deref(),
        Some("org.freedesktop.DBus.Error.InvalidArgs")
    );
    let r: Result<(), _> = props.method_call(
        "org.freedesktop.DBus.Properties",
        "Set",
        (
            "org.bluez.Device1",
            "Address",
            Variant("00:00:00:00:00:00".to_string()),
        ),
    );
    assert_eq!(
        r.err()
            .and_then(|e| e.name().map(str::to_string))
            .as_deref(),
        Some("org.freedesktop.DBus.Error.PropertyReadOnly")
    );
    let r: Result<(), _> = props.method_call(
        "org.freedesktop.DBus.Properties",
        "Set",
        ("org.bluez.Device1", "Trusted", Variant("yes".to_string())),
    );
    assert!(r.is_err());
    assert_eq!(
        err_name(call(
            &a,
            &format!("{dev}/nothing"),
            "org.bluez.Device1",
            "Connect"
        )),
        "org.freedesktop.DBus.Error.UnknownObject"
    );
    let (xml,): (String,) = props
        .method_call("org.freedesktop.DBus.Introspectable", "Introspect", ())
        .unwrap();
    assert!(
        xml.contains("<interface name=\"org.bluez.Device1\">"),
        "{xml}"
    );
    assert!(xml.contains("<node name=\"service"), "{xml}");
    // Disconnect: the GATT objects go, the device stays.
    call(&a, &dev, "org.bluez.Device1", "Disconnect").unwrap();
    assert_eq!(
        err_name(call(&a, &dev, "org.bluez.Device1", "Disconnect")),
        "org.bluez.Error.NotConnected"
    );
    let tree = managed(&a);
    assert!(tree.contains_key(&dbus::Path::from(dev.clone())));
    assert!(!tree.keys().any(|p| p.contains("/service")), "{tree:?}");
    // Now b may connect.
    call(&b, &dev, "org.bluez.Device1", "Connect").unwrap();
    drop(b);
    // b left the bus: its connection goes with it.
    sim.wait_line("left the bus", Duration::from_secs(2));
    let lines = sim.stop();
    assert!(!lines.iter().any(|l| l.contains("panicked")), "{lines:?}");
}

// -------------------------------------------------------------------------------------------
// The real world (issue 15): remembered devices, the adapter switched off, fail-safes, a
// droid that wants to sleep, leaving cleanly
// -------------------------------------------------------------------------------------------

/// Start the real binary against the bus in the background (a mission that runs while the
/// test does something to the adapter).
fn spawn_droidctl(args: &[&str], bus: &str, dir: &TempDir) -> Child {
    Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .env("DROIDCTL_LOG_FILE", dir.0.join("droidctl.log"))
        .env(
            "DROIDCTL_CONFIG",
            config_or_defaults(dir.0.join("config.toml")),
        )
        .env("DBUS_SYSTEM_BUS_ADDRESS", bus)
        .spawn()
        .expect("start droidctl")
}

/// `bluetoothctl power on|off`, as it does it: a Set of the adapter's Powered.
fn set_powered(c: &Connection, on: bool) {
    let p = c.with_proxy("org.bluez", "/org/bluez/hci0", Duration::from_secs(2));
    let r: Result<(), dbus::Error> = p.method_call(
        "org.freedesktop.DBus.Properties",
        "Set",
        ("org.bluez.Adapter1", "Powered", Variant(on)),
    );
    r.expect("Set Powered");
}

/// Wait until `pred` holds for the simulator's lines.
fn wait_lines(sim: &Sim, limit: Duration, what: &str, pred: impl Fn(&[String]) -> bool) {
    let start = Instant::now();
    while !pred(&sim.lines()) {
        assert!(
            start.elapsed() < limit,
            "no {what}:\n{}",
            sim.lines().join("\n")
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// BlueZ lists devices it remembers even when they are nowhere near: droidctl neither lists
/// nor picks them, `--all` shows them as not heard, and asking for one by name fails after
/// the scan with one line instead of a connection attempt.
#[test]
fn remembered_devices_are_neither_listed_nor_picked() {
    let sim = Sim::start(&["bb8", "--remembered", "r2d2"]);
    let (here, gone) = (sim.names[0].clone(), sim.names[1].clone());
    assert!(gone.starts_with("D2-"), "{:?}", sim.names);
    let dir = TempDir::new("remembered");
    let out = droidctl(&["scan", "--timeout", "1"], Some(&sim.address), &dir);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let rows: Vec<&str> = stdout.lines().collect();
    assert_eq!(rows.len(), 2, "{stdout}");
    assert!(rows[1].starts_with(&here), "{stdout}");
    let out = droidctl(
        &["scan", "--timeout", "1", "--all", "--json"],
        Some(&sim.address),
        &dir,
    );
    let all: Vec<serde_json::Value> = text(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(all.len(), 2, "{all:?}");
    assert_eq!(
        (all[0]["name"].as_str(), &all[0]["heard"]),
        (Some(here.as_str()), &serde_json::json!(true))
    );
    assert_eq!(all[1]["name"], gone.as_str());
    assert_eq!(all[1]["heard"], false);
    assert_eq!(all[1]["rssi"], serde_json::Value::Null);
    // The default pick is the droid that is there.
    let script = dir.file("mission.txt", "wait 0.2s\n");
    let out = droidctl(
        &["run", &script, "--scan-timeout", "1"],
        Some(&sim.address),
        &dir,
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    // By name: one line once the scan is over, no connection attempt.
    let t0 = Instant::now();
    let out = droidctl(
        &["run", &script, "--name", &gone, "--scan-timeout", "1"],
        Some(&sim.address),
        &dir,
    );
    let took = t0.elapsed();
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    assert!(
        stderr.contains(&format!("{gone} ("))
            && stderr.contains("is known to this computer but not in range"),
        "{stderr}"
    );
    assert!(stderr.contains("wake it"), "{stderr}");
    assert!(
        took < Duration::from_secs(4),
        "no connection attempt: {took:?}"
    );
    let lines = sim.stop();
    assert_eq!(
        lines
            .iter()
            .filter(|l| l.contains(&format!("{here}: connected (")))
            .count(),
        1,
        "{lines:?}"
    );
    assert!(
        !lines
            .iter()
            .any(|l| l.contains(&format!("{gone}: connection attempt"))),
        "{lines:?}"
    );
}

/// The adapter switched off mid-drive (`bluetoothctl power off`) and on again: the run says
/// it waits, reconnects by itself once the adapter is on, and the trace shows the droid
/// resuming with a stop at the last heading before anything else. An adapter that is off at
/// the start is one line naming the fix.
#[test]
fn the_adapter_switched_off_mid_drive_is_waited_for() {
    let sim = Sim::start(&["r2d2", "--trace", "--json"]);
    let name = sim.names[0].clone();
    let dir = TempDir::new("power");
    let script = dir.file(
        "mission.txt",
        "stance tripod\ndrive 60 90\nwait 6s\nstop\nwait 0.3s\n",
    );
    let run = spawn_droidctl(&["run", &script, "--name", &name], &sim.address, &dir);
    wait_lines(&sim, Duration::from_secs(20), "drive at 60", |lines| {
        drive_speeds(&commands_in(lines, &name)).contains(&60)
    });
    let bus = Connection::new_address(&sim.address).unwrap();
    set_powered(&bus, false);
    sim.wait_line(
        &format!("{name}: disconnected (adapter off)"),
        Duration::from_secs(2),
    );
    std::thread::sleep(Duration::from_millis(1500));
    set_powered(&bus, true);
    let out = run.wait_with_output().unwrap();
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert_eq!(out.status.code(), Some(0), "{stdout}\n{stderr}");
    assert!(
        stderr.contains("] Bluetooth adapter is off — waiting"),
        "{stderr}"
    );
    assert!(stderr.contains("] reconnected"), "{stderr}");
    assert!(stdout.contains("failed steps 0"), "{stdout}");
    // Off at the start: one line naming the fix, at once.
    set_powered(&bus, false);
    for args in [
        &["scan", "--timeout", "1"][..],
        &["run", &script, "--name", &name],
    ] {
        let t0 = Instant::now();
        let out = droidctl(args, Some(&sim.address), &dir);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.contains("`bluetoothctl power on`"), "{stderr}");
        assert!(t0.elapsed() < Duration::from_secs(3), "{args:?}");
    }
    let lines = sim.stop();
    let on = line_at(&lines, 0, "adapter powered on");
    let reconnect = line_at(&lines, on, &format!("{name}: connected ("));
    let cmds = commands_in(&lines[reconnect..], &name);
    let names: Vec<&str> = cmds
        .iter()
        .map(|(_, p)| p["command"].as_str().unwrap_or("?"))
        .collect();
    assert_eq!(&names[..2], ["wake", "drive-with-heading"], "{names:?}");
    assert_eq!(cmds[1].1["fields"]["speed"], 0, "stop first: {:?}", cmds[1]);
    assert_eq!(cmds[1].1["fields"]["heading"], 90, "at the last heading");
    let speeds = drive_speeds(&cmds);
    assert!(speeds.contains(&60), "then drives on: {speeds:?}");
    assert_eq!(speeds.last(), Some(&0), "{speeds:?}");
}

/// A v1 droid: the wake sequence as GATT writes that are no API packets, then the
/// stop-on-disconnect fail-safe among the setup, and its answers as decoded responses.
#[test]
fn a_v1_droid_is_woken_and_given_its_fail_safe() {
    let sim = Sim::start(&["bb8", "--trace", "--json"]);
    let name = sim.names[0].clone();
    let dir = TempDir::new("v1trace");
    let script = dir.file("mission.txt", "drive 60 0 for 0.5s\nwait 0.2s\n");
    let out = droidctl(&["run", &script, "--name", &name], Some(&sim.address), &dir);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let lines = sim.stop();
    let trace = trace_of(&lines, &name);
    let writes: Vec<(String, String)> = trace
        .iter()
        .filter(|(_, v)| v["packet"]["kind"] == "gatt-write")
        .map(|(_, v)| {
            let p = &v["packet"];
            (
                p["uuid"].as_str().unwrap_or("").to_string(),
                p["hex"].as_str().unwrap_or("").to_string(),
            )
        })
        .collect();
    assert_eq!(
        writes,
        [
            (
                "22bb746f-2bbd-7554-2d6f-726568705327".to_string(),
                droidctl::hex::compact(b"011i3")
            ),
            (
                "22bb746f-2bb2-7554-2d6f-726568705327".to_string(),
                "07".to_string()
            ),
            (
                "22bb746f-2bbf-7554-2d6f-726568705327".to_string(),
                "01".to_string()
            ),
        ]
    );
    let cmds = commands_in(&lines, &name);
    let fail_safe = cmds
        .iter()
        .find(|(_, p)| p["command"] == "set-temporary-option-flags")
        .unwrap_or_else(|| panic!("no fail-safe: {cmds:?}"));
    assert_eq!(
        fail_safe.1["fields"]["flags"].as_u64().map(|f| f & 1),
        Some(1)
    );
    let first_drive = cmds
        .iter()
        .position(|(_, p)| p["command"] == "roll")
        .unwrap_or(usize::MAX);
    assert!(first_drive < cmds.len(), "{cmds:?}");
    assert!(
        trace
            .iter()
            .any(|(_, v)| v["dir"] == "out" && v["packet"]["kind"] == "response"),
        "answers decoded"
    );
}

/// A droid that sleeps after 2 s without a command stays connected through an idle app for
/// three times that (droidctl answers each will-sleep warning with a ping); `q` then stops
/// it and disconnects within 2 s, the last drive command written at speed 0.
#[test]
fn an_idle_app_keeps_the_droid_awake_and_q_leaves_it_stopped() {
    let sim = Sim::start(&["r2d2", "--idle-sleep", "2", "--trace", "--json"]);
    let name = sim.names[0].clone();
    let dir = TempDir::new("idle");
    let log = dir.0.join("droidctl.log").to_string_lossy().into_owned();
    let config = config_or_defaults(dir.0.join("config.toml"))
        .to_string_lossy()
        .into_owned();
    let mut tui = pty::Tui::start(
        &["--name", &name],
        &[
            ("DBUS_SYSTEM_BUS_ADDRESS", sim.address.as_str()),
            ("DROIDCTL_LOG_FILE", log.as_str()),
            ("DROIDCTL_CONFIG", config.as_str()),
        ],
    );
    tui.wait_for("connected", Duration::from_secs(20));
    tui.wait_for("stance tripod", Duration::from_secs(10));
    tui.hold(b"w", Duration::from_millis(1500));
    let idle_from = sim.lines().len();
    std::thread::sleep(Duration::from_secs(7));
    let lines = sim.lines();
    assert!(
        !lines.iter().any(|l| l.contains("fell asleep")),
        "{lines:?}"
    );
    let after = trace_of(&lines[idle_from..], &name);
    let warnings: Vec<usize> = after
        .iter()
        .enumerate()
        .filter(|(_, (_, v))| v["dir"] == "out" && v["packet"]["command"] == "will-sleep")
        .map(|(i, _)| i)
        .collect();
    assert!(
        warnings.len() >= 2,
        "the droid warned while idle: {after:?}"
    );
    for w in &warnings {
        assert!(
            after[*w..]
                .iter()
                .any(|(_, v)| v["dir"] == "in" && v["packet"]["command"] == "ping"),
            "a ping answers each warning: {after:?}"
        );
    }
    assert!(tui.text().contains("connected"), "{}", tui.text());
    let q = Instant::now();
    tui.send(b"q");
    sim.wait_line(
        &format!("{name}: disconnected by the client"),
        Duration::from_secs(2),
    );
    assert!(q.elapsed() <= Duration::from_secs(2), "{:?}", q.elapsed());
    let status = tui.wait_exit(Duration::from_secs(10));
    assert!(status.success(), "{status:?}");
    let lines = sim.stop();
    let speeds = drive_speeds(&commands_in(&lines, &name));
    assert!(speeds.iter().any(|s| *s > 0), "it drove: {speeds:?}");
    assert_eq!(
        speeds.last(),
        Some(&0),
        "the last drive written stops: {speeds:?}"
    );
}

/// The virtual BlueZ as other clients see the real world: a remembered device is there
/// without an RSSI and a Connect to it fails after a few seconds; powering the adapter off
/// ends discovery and says so in PropertiesChanged; an idle droid warns, falls asleep
/// (drops the connection) and cannot be reached any more.
#[test]
fn the_dbus_view_of_power_remembered_devices_and_sleep() {
    let sim = Sim::start(&["r2d2", "--remembered", "bb8", "--idle-sleep", "1"]);
    let (name, old) = (sim.names[0].clone(), sim.names[1].clone());
    let a = Connection::new_address(&sim.address).unwrap();
    let adapter = "/org/bluez/hci0";
    let devices = |tree: &Tree| -> Vec<String> {
        tree.keys()
            .filter(|p| p.rsplit('/').next().is_some_and(|l| l.starts_with("dev_")))
            .map(|p| p.to_string())
            .collect()
    };
    let tree = managed(&a);
    let known = devices(&tree);
    assert_eq!(
        known.len(),
        1,
        "only the remembered one before a discovery: {known:?}"
    );
    let old_dev = known[0].clone();
    assert_eq!(
        prop(&tree, &old_dev, "org.bluez.Device1", "Name"),
        Some(format!("{old:?}"))
    );
    assert_eq!(prop(&tree, &old_dev, "org.bluez.Device1", "RSSI"), None);
    // Changes arrive as signals: (path, property changed or invalidated, value).
    type Seen = Arc<Mutex<Vec<(String, String, String)>>>;
    let seen: Seen = Arc::default();
    {
        let seen = seen.clone();
        let rule = MatchRule::new_signal("org.freedesktop.DBus.Properties", "PropertiesChanged")
            .with_namespaced_path("/org/bluez");
        a.add_match(rule, move |(): (), _, m| {
            let path = m.path().map(|p| p.to_string()).unwrap_or_default();
            if let Ok((_, changed, invalidated)) = m.read3::<&str, PropMap, Vec<String>>() {
                let mut s = seen.lock().unwrap();
                for (k, v) in changed {
                    s.push((path.clone(), k, format!("{:?}", v.0)));
                }
                for k in invalidated {
                    s.push((path.clone(), k, "invalidated".into()));
                }
            }
            true
        })
        .unwrap();
    }
    let pump = |for_: Duration| {
        let end = Instant::now() + for_;
        while Instant::now() < end {
            let _ = a.process(Duration::from_millis(20));
        }
    };
    let saw = |path: &str, key: &str, value: &str| {
        seen.lock()
            .unwrap()
            .iter()
            .any(|(p, k, v)| p == path && k == key && v == value)
    };
    call(&a, adapter, "org.bluez.Adapter1", "StartDiscovery").unwrap();
    let tree = managed(&a);
    let dev = devices(&tree)
        .into_iter()
        .find(|p| *p != old_dev)
        .expect("the droid in range is heard");
    assert_eq!(
        prop(&tree, &dev, "org.bluez.Device1", "Name"),
        Some(format!("{name:?}"))
    );
    assert!(prop(&tree, &dev, "org.bluez.Device1", "RSSI").is_some());
    assert_eq!(
        prop(&tree, &old_dev, "org.bluez.Device1", "RSSI"),
        None,
        "never heard"
    );
    // Nobody answers a connection to the remembered device: it fails as BlueZ's does.
    let t0 = Instant::now();
    let r: Result<(), dbus::Error> = a
        .with_proxy("org.bluez", old_dev.clone(), Duration::from_secs(10))
        .method_call("org.bluez.Device1", "Connect", ());
    let e = r.expect_err("no connection to a device out of range");
    assert_eq!(e.name(), Some("org.bluez.Error.Failed"));
    assert_eq!(e.message(), Some("le-connection-abort-by-local"));
    assert!(
        t0.elapsed() >= Duration::from_millis(2500),
        "{:?}",
        t0.elapsed()
    );
    // `bluetoothctl power off`: discovery stops, the RSSIs go, and the signals say so.
    set_powered(&a, false);
    pump(Duration::from_millis(300));
    assert!(
        saw(adapter, "Powered", "false"),
        "{:?}",
        seen.lock().unwrap()
    );
    assert!(
        saw(adapter, "Discovering", "false"),
        "{:?}",
        seen.lock().unwrap()
    );
    assert!(
        saw(&dev, "RSSI", "invalidated"),
        "{:?}",
        seen.lock().unwrap()
    );
    assert_eq!(
        err_name(call(&a, adapter, "org.bluez.Adapter1", "StartDiscovery")),
        "org.bluez.Error.NotReady"
    );
    assert_eq!(
        err_name(call(&a, &dev, "org.bluez.Device1", "Connect")),
        "org.bluez.Error.NotReady"
    );
    set_powered(&a, true);
    pump(Duration::from_millis(300));
    assert!(
        saw(adapter, "Powered", "true"),
        "{:?}",
        seen.lock().unwrap()
    );
    // A droid left alone after connecting: the warning after 1 s, asleep 5 s later.
    call(&a, &dev, "org.bluez.Device1", "Connect").unwrap();
    let start = Instant::now();
    let api = loop {
        let t = managed(&a);
        let api = t.iter().find_map(|(p, i)| {
            let uuid = i.get("org.bluez.GattCharacteristic1")?.get("UUID")?;
            (uuid.0.as_str() == Some("00010002-574f-4f20-5370-6865726f2121")).then(|| p.to_string())
        });
        if let Some(api) = api {
            break api;
        }
        assert!(start.elapsed() < Duration::from_secs(3), "never resolved");
        std::thread::sleep(Duration::from_millis(20));
    };
    call(&a, &api, "org.bluez.GattCharacteristic1", "StartNotify").unwrap();
    let start = Instant::now();
    while !saw(&dev, "Connected", "false") {
        assert!(
            start.elapsed() < Duration::from_secs(9),
            "{:?}",
            seen.lock().unwrap()
        );
        pump(Duration::from_millis(50));
    }
    let notified: Vec<u8> = seen
        .lock()
        .unwrap()
        .iter()
        .filter(|(p, k, _)| *p == api && k == "Value")
        .flat_map(|(_, _, v)| {
            // `[141, 0, 19, 25, …]`: the bytes as the variant prints them.
            v.trim_matches(|c| c == '[' || c == ']')
                .split(',')
                .filter_map(|b| b.trim().parse::<u8>().ok())
                .collect::<Vec<_>>()
        })
        .collect();
    let warned = Decoder::new()
        .decode_all(&notified)
        .into_iter()
        .filter_map(Result::ok)
        .any(|p| (p.did, p.cid) == (0x13, 0x19));
    assert!(warned, "the will-sleep warning: {notified:?}");
    sim.wait_line(&format!("{name}: fell asleep"), Duration::from_secs(1));
    // Asleep: not heard by a new discovery, and a connection fails.
    call(&a, adapter, "org.bluez.Adapter1", "StartDiscovery").unwrap();
    pump(Duration::from_millis(300));
    assert_eq!(prop(&managed(&a), &dev, "org.bluez.Device1", "RSSI"), None);
    let r: Result<(), dbus::Error> = a
        .with_proxy("org.bluez", dev.clone(), Duration::from_secs(10))
        .method_call("org.bluez.Device1", "Connect", ());
    assert_eq!(
        r.err()
            .and_then(|e| e.name().map(str::to_string))
            .as_deref(),
        Some("org.bluez.Error.Failed")
    );
    let lines = sim.stop();
    assert!(!lines.iter().any(|l| l.contains("panicked")), "{lines:?}");
}

/// The fail-safe through btleplug: droidctl driving a BB-9E dies without a word (SIGKILL),
/// and the droid's control-system timeout stops it; another BB-9E, driven by a client that
/// never set one, keeps rolling after its client disconnects.
#[test]
fn the_fail_safe_stops_a_droid_whose_host_vanished() {
    use droidctl::protocol::v2::cmd;
    use droidctl::protocol::v2::wire::DriveFlags;
    use droidctl::units::Heading;
    let sim = Sim::start(&["bb9e", "bb9e", "--trace", "--json"]);
    let (name, other) = (sim.names[0].clone(), sim.names[1].clone());
    let dir = TempDir::new("failsafe");
    let script = dir.file("mission.txt", "drive 60 0\nwait 20s\n");
    let mut run = spawn_droidctl(&["run", &script, "--name", &name], &sim.address, &dir);
    wait_lines(&sim, Duration::from_secs(20), "drive at 60", |lines| {
        drive_speeds(&commands_in(lines, &name)).contains(&60)
    });
    std::thread::sleep(Duration::from_millis(600));
    run.kill().unwrap();
    let _ = run.wait();
    let stopped = format!("{name}: 3.0 s after the disconnect: stopped");
    sim.wait_line(&stopped, Duration::from_secs(6));
    // Another client drives the other droid: unlock, wake, drive, and leave without the
    // fail-safe.
    let a = Connection::new_address(&sim.address).unwrap();
    let tree = managed(&a);
    let dev = tree
        .keys()
        .find(|p| prop(&tree, p, "org.bluez.Device1", "Name") == Some(format!("{other:?}")))
        .expect("the other droid")
        .to_string();
    call(&a, &dev, "org.bluez.Device1", "Connect").unwrap();
    let start = Instant::now();
    let chars = loop {
        let t = managed(&a);
        let find = |uuid: &str| {
            t.iter().find_map(|(p, i)| {
                let u = i.get("org.bluez.GattCharacteristic1")?.get("UUID")?;
                (u.0.as_str() == Some(uuid)).then(|| p.to_string())
            })
        };
        if let (Some(api), Some(unlock)) = (
            find("00010002-574f-4f20-5370-6865726f2121"),
            find("00020005-574f-4f20-5370-6865726f2121"),
        ) {
            break (api, unlock);
        }
        assert!(start.elapsed() < Duration::from_secs(3), "never resolved");
        std::thread::sleep(Duration::from_millis(20));
    };
    let write = |path: &str, bytes: Vec<u8>| {
        let r: Result<(), dbus::Error> = a
            .with_proxy("org.bluez", path.to_string(), Duration::from_secs(2))
            .method_call(
                "org.bluez.GattCharacteristic1",
                "WriteValue",
                (bytes, PropMap::new()),
            );
        r.unwrap();
    };
    write(&chars.1, b"usetheforce...band".to_vec());
    write(&chars.0, cmd::wake().to_packet(1).encode());
    let drive = cmd::drive_with_heading(40, Heading::new(0).unwrap(), DriveFlags::empty());
    write(&chars.0, drive.to_packet(2).encode());
    std::thread::sleep(Duration::from_millis(500));
    call(&a, &dev, "org.bluez.Device1", "Disconnect").unwrap();
    sim.wait_line(
        &format!("{other}: 3.0 s after the disconnect: still rolling at"),
        Duration::from_secs(6),
    );
    let lines = sim.stop();
    assert!(
        commands_in(&lines, &name)
            .iter()
            .any(|(_, p)| p["command"] == "set-custom-control-system-timeout"),
        "droidctl set the fail-safe"
    );
}

/// Only the bus says who left: a client forging NameOwnerChanged for another client (a
/// unicast signal reaches the virtual BlueZ whatever its match rules) does not tear down the
/// other's connection.
#[test]
fn a_forged_name_owner_changed_does_not_disconnect_another_client() {
    let sim = Sim::start(&["r2d2"]);
    let a = Connection::new_address(&sim.address).unwrap();
    let b = Connection::new_address(&sim.address).unwrap();
    let adapter = "/org/bluez/hci0";
    call(&a, adapter, "org.bluez.Adapter1", "StartDiscovery").unwrap();
    let tree = managed(&a);
    let dev = tree
        .keys()
        .find(|p| p.contains("dev_"))
        .expect("the droid is heard")
        .to_string();
    call(&a, &dev, "org.bluez.Device1", "Connect").unwrap();
    let victim = a.unique_name().to_string();
    let mut forged = dbus::Message::new_signal(
        "/org/freedesktop/DBus",
        "org.freedesktop.DBus",
        "NameOwnerChanged",
    )
    .unwrap()
    .append3(victim.as_str(), victim.as_str(), "");
    forged.set_destination(Some("org.bluez".into()));
    use dbus::channel::Sender;
    b.send(forged).unwrap();
    std::thread::sleep(Duration::from_millis(500));
    assert_eq!(
        prop(&managed(&a), &dev, "org.bluez.Device1", "Connected"),
        Some("true".into()),
        "the forged signal disconnected the droid: {:?}",
        sim.lines()
    );
    // The real thing still works: a leaves the bus and its connection ends.
    drop(a);
    sim.wait_line("left the bus", Duration::from_secs(3));
}

/// The processes whose parent is `pid`, with their state letter (`Z` for a zombie).
fn children_of(pid: u32) -> Vec<(u32, char, String)> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir("/proc").into_iter().flatten().flatten() {
        let Some(p) = entry
            .file_name()
            .to_str()
            .and_then(|n| n.parse::<u32>().ok())
        else {
            continue;
        };
        let Ok(stat) = std::fs::read_to_string(format!("/proc/{p}/stat")) else {
            continue;
        };
        // pid (comm) state ppid …: comm may hold spaces, so split after its ')'.
        let Some((head, rest)) = stat.rsplit_once(')') else {
            continue;
        };
        let comm = head
            .split_once('(')
            .map(|(_, c)| c)
            .unwrap_or("")
            .to_string();
        let mut f = rest.split_whitespace();
        let state = f.next().and_then(|s| s.chars().next()).unwrap_or('?');
        if f.next().and_then(|pp| pp.parse::<u32>().ok()) == Some(pid) {
            out.push((p, state, comm));
        }
    }
    out
}

/// `sim --bluez` killed with SIGKILL (no chance to clean up) takes its private bus with it:
/// its `dbus-daemon` child where that runs, busd (a thread of its own) where not; either way
/// nothing answers on the bus's socket afterwards.
#[test]
fn a_killed_simulator_takes_its_bus_with_it() {
    let mut sim = Sim::start(&["r2d2"]);
    let embedded = sim
        .lines()
        .iter()
        .any(|l| l.contains("bus: busd (embedded)"));
    assert_eq!(
        embedded,
        !dbus_daemon_installed()
            || std::env::var("DROIDCTL_DBUS_DAEMON").as_deref() == Ok("embedded"),
        "busd exactly when dbus-daemon is not there or not asked for: {:?}",
        sim.lines()
    );
    let daemons: Vec<u32> = children_of(sim.child.id())
        .into_iter()
        .filter(|(_, _, comm)| comm.contains("dbus-daemon"))
        .map(|(p, _, _)| p)
        .collect();
    assert_eq!(
        daemons.len(),
        usize::from(!embedded),
        "one private dbus-daemon, or none beside busd"
    );
    let socket = sim.address.strip_prefix("unix:path=").unwrap().to_string();
    assert!(
        std::os::unix::net::UnixStream::connect(&socket).is_ok(),
        "the bus answers"
    );
    sim.child.kill().unwrap();
    let _ = sim.child.wait();
    let gone = |p: u32| match std::fs::read_to_string(format!("/proc/{p}/stat")) {
        Err(_) => true,
        Ok(stat) => stat
            .rsplit_once(')')
            .and_then(|(_, rest)| rest.split_whitespace().next())
            .is_some_and(|s| s == "Z" || s == "X"),
    };
    let deadline = Instant::now() + Duration::from_secs(3);
    while !daemons.iter().all(|p| gone(*p))
        || std::os::unix::net::UnixStream::connect(&socket).is_ok()
    {
        assert!(
            Instant::now() < deadline,
            "the bus ({daemons:?}, {socket}) still runs after the simulator was killed"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = std::fs::remove_dir_all(std::path::Path::new(&socket).parent().unwrap());
}

/// busd, the bus `sim --bluez` runs where `dbus-daemon` is not installed, asked for here
/// where it is: btleplug scans and a mission drives through it as through `dbus-daemon`.
#[test]
fn the_embedded_bus_serves_bluez_clients() {
    let sim = Sim::start_env(&["r2d2"], &[("DROIDCTL_DBUS_DAEMON", "embedded")]);
    assert!(
        sim.lines()
            .iter()
            .any(|l| l.contains("bus: busd (embedded)")),
        "{:?}",
        sim.lines()
    );
    let dir = TempDir::new("busd");
    let out = droidctl(&["scan", "--timeout", "2"], Some(&sim.address), &dir);
    assert!(
        out.status.success() && text(&out.stdout).contains(&sim.names[0]),
        "{}\n{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    let script = dir.file("m.txt", "stance tripod\ndrive 80 0 for 1s\n");
    let out = droidctl(
        &["run", &script, "--name", &sim.names[0], "--json"],
        Some(&sim.address),
        &dir,
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let run = parse_run(&out);
    let last = run.samples.last().expect("telemetry through busd");
    assert_eq!(last["stance"], "tripod", "{last}");
    sim.stop();
}

// -------------------------------------------------------------------------------------------
// Several droids at once (issue 23)
// -------------------------------------------------------------------------------------------

/// Three droids through one adapter, each refusing its first connection (as a droid that
/// needs a retry does): droidctl's attempts take turns, so the adapter never answers
/// `InProgress`; each retry after `le-connection-abort-by-local` succeeds; then one mission
/// drives all three at once through btleplug, in the room they share.
#[test]
fn a_fleet_takes_turns_on_the_adapter_and_drives_all_three_at_once() {
    let sim = Sim::start(&["r2d2", "bb8", "robi", "--fault", "refuse-connect=1"]);
    let dir = TempDir::new("fleet");
    let script = dir.file(
        "fleet.txt",
        "@R2 stance tripod\ntogether {\n  @R2 drive 80 0 for 2s\n  @BB-8 drive 80 0 for 2s\n  \
         @robi drive 120 0 for 2s\n}\n",
    );
    let mut args = vec!["run", &script, "--json"];
    for n in &sim.names {
        args.extend(["--name", n.as_str()]);
    }
    let out = droidctl(&args, Some(&sim.address), &dir);
    let lines = sim.lines();
    assert_eq!(
        out.status.code(),
        Some(0),
        "stderr: {}\nsim:\n{}",
        text(&out.stderr),
        lines.join("\n")
    );
    // Each droid: its refusal, then a connection.
    for n in &sim.names {
        assert!(
            lines
                .iter()
                .any(|l| l.contains(&format!("{n}: fault refuse-connect"))),
            "{n} refused once:\n{}",
            lines.join("\n")
        );
        assert!(
            lines
                .iter()
                .any(|l| l.starts_with(&format!("droidctl sim: {n}: connected"))),
            "{n} connected:\n{}",
            lines.join("\n")
        );
    }
    assert!(
        !lines.iter().any(|l| l.contains("InProgress")),
        "attempts overlapped on the adapter:\n{}",
        lines.join("\n")
    );
    let summaries: Vec<serde_json::Value> = text(&out.stdout)
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|v| v["done"] == true)
        .collect();
    assert_eq!(summaries.len(), 3, "{}", text(&out.stdout));
    for s in &summaries {
        assert!(f(&s["y_cm"]) > 10.0, "every droid drove north: {s}");
        assert_eq!(s["failed_steps"], 0, "{s}");
    }
    sim.stop();
}

/// The virtual adapter's one-attempt-at-a-time rule, as a BlueZ client sees it: while one
/// droid's connection attempt is under way (it refuses, answering after 0.3 s), another's
/// `Connect` is answered `org.bluez.Error.InProgress` at once.
#[test]
fn the_virtual_adapter_allows_one_connection_attempt_at_a_time() {
    let sim = Sim::start(&["r2d2", "bb8", "--fault", "refuse-connect=1"]);
    let c = Connection::new_address(&sim.address).unwrap();
    call(
        &c,
        "/org/bluez/hci0",
        "org.bluez.Adapter1",
        "StartDiscovery",
    )
    .unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let tree = managed(&c);
    let device = |name: &str| {
        tree.iter()
            .find(|(_, ifaces)| {
                ifaces
                    .get("org.bluez.Device1")
                    .and_then(|p| p.get("Name"))
                    .and_then(|v| v.0.as_str())
                    == Some(name)
            })
            .map(|(p, _)| p.to_string())
            .unwrap()
    };
    let (a, b) = (device(&sim.names[0]), device(&sim.names[1]));
    let first = {
        let (bus, a) = (sim.address.clone(), a.clone());
        std::thread::spawn(move || {
            let c = Connection::new_address(&bus).unwrap();
            call(&c, &a, "org.bluez.Device1", "Connect")
        })
    };
    sim.wait_line("fault refuse-connect", Duration::from_secs(5));
    let second = call(&c, &b, "org.bluez.Device1", "Connect");
    assert_eq!(err_name(second), "org.bluez.Error.InProgress");
    let first = first.join().unwrap();
    assert!(err_name(first).contains("Failed"));
    // Once the first attempt is over, the other droid's own attempts go ahead (its first
    // refused too, by the fault, then connected).
    assert!(err_name(call(&c, &b, "org.bluez.Device1", "Connect")).contains("Failed"));
    call(&c, &b, "org.bluez.Device1", "Connect").unwrap();
    sim.stop();
}

/// The cap of droids per adapter (`fleet.max_per_adapter`) and `--adapter`: over the cap, one
/// line saying which droid was not connected and what to do; an adapter that is not there
/// is named with those that are; the one that is works.
#[test]
fn the_adapter_cap_and_adapter_names_are_checked() {
    let sim = Sim::start(&["r2d2", "bb8", "robi"]);
    let dir = TempDir::new("fleet-cap");
    dir.file("config.toml", "[fleet]\nmax_per_adapter = 2\n");
    let script = dir.file("wait.txt", "wait 0.5s\n");
    let mut three = vec!["run", &script];
    for n in &sim.names {
        three.extend(["--name", n.as_str()]);
    }
    let out = droidctl(&three, Some(&sim.address), &dir);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    let err = text(&out.stderr);
    assert!(
        err.contains(&format!(
            "{} not connected: the adapter hci0 already holds 2 droids",
            sim.names[2]
        )) && err.contains("max_per_adapter"),
        "{err}"
    );
    let mut two = vec!["run", &script, "--adapter", "hci9"];
    for n in &sim.names[..2] {
        two.extend(["--name", n.as_str()]);
    }
    let out = droidctl(&two, Some(&sim.address), &dir);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(
        err.contains("no Bluetooth adapter called hci9: this computer has hci0"),
        "{err}"
    );
    two[3] = "hci0";
    let out = droidctl(&two, Some(&sim.address), &dir);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    sim.stop();
}

/// The app as a person starts a fleet: `droidctl` without a name, two droids in range, the
/// picker; `x` marks each, Enter drives both (the roster lists them); `g` mirrors, `w` rolls
/// both; `q` stops and disconnects both.
#[test]
fn the_picker_marks_several_droids_and_the_app_drives_them_mirrored() {
    let sim = Sim::start(&["r2d2", "bb8"]);
    let dir = TempDir::new("picker-fleet");
    let log = dir.0.join("droidctl.log").to_string_lossy().into_owned();
    let config = config_or_defaults(dir.0.join("config.toml"))
        .to_string_lossy()
        .into_owned();
    let mut tui = pty::Tui::start(
        &["--scan-timeout", "2"],
        &[
            ("DBUS_SYSTEM_BUS_ADDRESS", sim.address.as_str()),
            ("DROIDCTL_LOG_FILE", log.as_str()),
            ("DROIDCTL_CONFIG", config.as_str()),
        ],
    );
    tui.wait_for("Several droids are in range", Duration::from_secs(20));
    tui.send(b"x");
    tui.send(b"\x1b[B");
    tui.send(b"x");
    std::thread::sleep(Duration::from_millis(200));
    tui.send(b"\r");
    for n in &sim.names {
        tui.wait_for(&format!("{n} ok"), Duration::from_secs(20));
    }
    tui.wait_for("stance tripod", Duration::from_secs(10));
    tui.send(b"y");
    tui.wait_for("MIRROR", Duration::from_secs(5));
    tui.hold(b"w", Duration::from_millis(2500));
    let screen = tui.text();
    assert!(screen.matches("moving").count() >= 1, "{screen}");
    tui.send(b"q");
    let status = tui.wait_exit(Duration::from_secs(10));
    assert!(status.success(), "{status:?}");
    for n in &sim.names {
        sim.wait_line(
            &format!("{n}: disconnected by the client"),
            Duration::from_secs(5),
        );
        let said = sim.wait_line(
            &format!("{n}: 3.0 s after the disconnect"),
            Duration::from_secs(8),
        );
        assert!(said.ends_with("stopped"), "{n} was left stopped: {said}");
    }
    let lines = sim.stop();
    assert!(!lines.iter().any(|l| l.contains("InProgress")), "{lines:?}");
}

/// The test's config file when it wrote one, else /dev/null: the defaults (a DROIDCTL_CONFIG
/// naming a missing file is an error).
fn config_or_defaults(p: std::path::PathBuf) -> std::path::PathBuf {
    if p.exists() { p } else { "/dev/null".into() }
}
