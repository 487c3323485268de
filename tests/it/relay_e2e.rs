//! End to end through the real binaries over loopback: `droidctl serve --sim` with
//! `droidctl run --remote` (the same telemetry as `--sim`), `droidctl scan --remote`, the app
//! driving through the relay in a pseudo-terminal, and a Python client written from the
//! protocol (`tests/relay_client.py`) driving a simulated R2-D2 through `serve`.

// Unix: pseudo-terminals and `kill -TERM`.
#![cfg(unix)]

use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Output, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// A scratch directory per test, removed on drop.
pub(crate) struct TempDir(pub(crate) std::path::PathBuf);

impl TempDir {
    pub(crate) fn new(tag: &str) -> TempDir {
        let p = std::env::temp_dir().join(format!("droidctl-relay-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).unwrap();
        TempDir(p)
    }

    fn file(&self, name: &str, text: &str) -> String {
        let p = self.0.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_string_lossy().into_owned()
    }

    pub(crate) fn path(&self, name: &str) -> String {
        self.0.join(name).to_string_lossy().into_owned()
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A running `droidctl serve --sim … --json` on a free loopback port.
pub(crate) struct Serve {
    child: Child,
    /// `127.0.0.1:PORT`.
    pub(crate) address: String,
    events: Arc<Mutex<Vec<Value>>>,
    pub(crate) stderr: Arc<Mutex<Vec<String>>>,
}

impl Serve {
    pub(crate) fn start(models: &[&str], extra: &[&str], dir: &TempDir) -> Serve {
        let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
            .args(["serve", "--listen", "127.0.0.1:0", "--json", "--sim"])
            .args(models)
            .args(extra)
            .env("DROIDCTL_LOG_FILE", dir.path("serve.log"))
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start droidctl serve");
        let events = Arc::new(Mutex::new(Vec::new()));
        let stderr = Arc::new(Mutex::new(Vec::new()));
        {
            let events = events.clone();
            let out = child.stdout.take().unwrap();
            std::thread::spawn(move || {
                for line in BufReader::new(out).lines() {
                    let Ok(line) = line else { break };
                    let v: Value = serde_json::from_str(&line)
                        .unwrap_or_else(|e| panic!("not JSON on stdout: {e}: {line}"));
                    events.lock().unwrap().push(v);
                }
            });
            let lines = stderr.clone();
            let err = child.stderr.take().unwrap();
            std::thread::spawn(move || {
                for line in BufReader::new(err).lines() {
                    let Ok(line) = line else { break };
                    lines.lock().unwrap().push(line);
                }
            });
        }
        let mut s = Serve {
            child,
            address: String::new(),
            events,
            stderr,
        };
        let listening = s.wait_event("listening", |e| e["event"] == "listening");
        s.address = listening["address"].as_str().unwrap().to_string();
        s
    }

    fn events(&self) -> Vec<Value> {
        self.events.lock().unwrap().clone()
    }

    pub(crate) fn wait_event(&self, what: &str, f: impl Fn(&Value) -> bool) -> Value {
        let start = Instant::now();
        loop {
            if let Some(e) = self.events().into_iter().find(&f) {
                return e;
            }
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "no {what} event from serve: {:#?}\n{}",
                self.events(),
                self.stderr.lock().unwrap().join("\n")
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// SIGTERM: it must stop every droid and exit 0. Its stderr lines.
    pub(crate) fn stop(mut self) -> Vec<String> {
        let _ = Command::new("kill")
            .args(["-TERM", &self.child.id().to_string()])
            .status();
        let start = Instant::now();
        let status = loop {
            if let Some(s) = self.child.try_wait().unwrap() {
                break s;
            }
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "serve did not stop"
            );
            std::thread::sleep(Duration::from_millis(20));
        };
        // Let the reader threads take the last lines.
        std::thread::sleep(Duration::from_millis(100));
        let lines = self.stderr.lock().unwrap().clone();
        assert!(status.success(), "{status:?}\n{}", lines.join("\n"));
        lines
    }
}

impl Drop for Serve {
    fn drop(&mut self) {
        if matches!(self.child.try_wait(), Ok(None)) {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

fn droidctl(args: &[&str], dir: &TempDir) -> Output {
    Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(args)
        .stdin(Stdio::null())
        .env("DROIDCTL_LOG_FILE", dir.path("droidctl.log"))
        .env("DROIDCTL_CONFIG", "/dev/null")
        // No Bluetooth is needed for any of this.
        .env(
            "DBUS_SYSTEM_BUS_ADDRESS",
            "unix:path=/nonexistent/droidctl-test/bus",
        )
        .output()
        .expect("run droidctl")
}

use crate::common::mission_run;
use mission_run::{Run, f, parse_run, text};

/// The same mission through `serve --sim` + `run --remote` and against `--sim`.
fn mission_matches(model: &str, mission: &str) -> (Run, Run) {
    let dir = TempDir::new(model);
    let serve = Serve::start(&[model], &[], &dir);
    let script = dir.file("mission.txt", mission);
    let t0 = Instant::now();
    let remote = droidctl(
        &["run", &script, "--remote", &serve.address, "--json"],
        &dir,
    );
    let took = t0.elapsed();
    assert_eq!(
        remote.status.code(),
        Some(0),
        "stderr: {}\nserve: {}",
        text(&remote.stderr),
        serve.stderr.lock().unwrap().join("\n")
    );
    let reference = droidctl(&["run", &script, "--sim", model, "--json"], &dir);
    assert_eq!(
        reference.status.code(),
        Some(0),
        "{}",
        text(&reference.stderr)
    );
    let (remote, reference) = (parse_run(&remote), parse_run(&reference));
    mission_run::assert_matches(&remote, &reference, took);
    // The relay saw one droid connected, and released it stopped when the mission ended.
    serve.wait_event("droid connected", |e| e["event"] == "droid_connected");
    serve.wait_event("droid released", |e| {
        e["event"] == "droid_released" && e["stopped"] == true
    });
    let lines = serve.stop();
    assert!(
        lines.iter().any(|l| l.contains("stopped and released")),
        "{lines:?}"
    );
    (remote, reference)
}

/// API v2: the anti-DoS unlock, sensor streaming, a stance change and a drive.
#[test]
fn r2d2_mission_through_the_relay_matches_the_simulator() {
    let (remote, _) = mission_matches("r2d2", "stance tripod\ndrive 80 90 for 1.5s\nwait 0.3s\n");
    let last = &remote.samples[remote.samples.len() - 1];
    assert_eq!(last["stance"], "tripod", "{last}");
}

/// API v1: the wake sequence over three characteristics, then driving.
#[test]
fn bb8_mission_through_the_relay_matches_the_simulator() {
    mission_matches("bb8", "drive 80 90 for 1.5s\nwait 0.3s\n");
}

/// Robi 42: the relay has no read, so the handshake read is skipped; the start
/// confirmation still starts the frames, and the remote control drives.
#[test]
fn robi_mission_through_the_relay_matches_the_simulator() {
    let (remote, reference) = mission_matches("robi", "drive 200 0 for 2s\nwait 0.3s\n");
    let frames = |r: &Run| f(&r.samples[r.samples.len() - 1]["frames"]);
    assert!(frames(&remote) >= 15.0, "frames flow: {}", frames(&remote));
    assert!((frames(&remote) - frames(&reference)).abs() <= 5.0);
}

#[test]
fn scan_lists_the_droids_behind_the_relay() {
    let dir = TempDir::new("scan");
    let serve = Serve::start(&["r2d2", "bb8", "robi"], &[], &dir);
    let out = droidctl(
        &[
            "scan",
            "--remote",
            &serve.address,
            "--json",
            "--timeout",
            "1",
        ],
        &dir,
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let rows: Vec<Value> = text(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let models: Vec<&str> = rows.iter().map(|r| r["model"].as_str().unwrap()).collect();
    assert_eq!(models, ["r2d2", "bb8", "robi"]);
    assert_eq!(rows[0]["name"], "D2-0001");
    assert_eq!(rows[0]["address"], "5E:D0:00:00:00:01");
    // The table, for people.
    let out = droidctl(&["scan", "--remote", &serve.address], &dir);
    let table = text(&out.stdout);
    assert!(table.starts_with("NAME"), "{table}");
    assert!(
        table.contains("BB-0002") && table.contains("BB-8"),
        "{table}"
    );
    // Nobody there: one line, status 1.
    let port = serve.address.rsplit(':').next().unwrap().to_string();
    serve.stop();
    let out = droidctl(&["scan", "--remote", &format!("127.0.0.1:{port}")], &dir);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(err.contains("cannot reach the relay"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

#[test]
fn two_droids_need_a_name_and_a_held_droid_waits_its_turn() {
    let dir = TempDir::new("choose");
    let serve = Serve::start(&["r2d2", "r2q5"], &[], &dir);
    let script = dir.file("m.txt", "wait 2s\n");
    // Several droids and no --name: one line saying so.
    let out = droidctl(&["run", &script, "--remote", &serve.address], &dir);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(err.contains("several droids behind the relay"), "{err}");
    assert!(err.contains("D2-0001") && err.contains("Q5-0002"), "{err}");
    // One client holds Q5-0002…
    let mut first = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["run", &script, "--remote", &serve.address, "--name", "Q5"])
        .env("DROIDCTL_LOG_FILE", dir.path("first.log"))
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    serve.wait_event("the first holds it", |e| e["event"] == "droid_connected");
    // …so the relay refuses it to a second one, naming the holder; the second retries with
    // its backoff and gets it once the first is done.
    let short = dir.file("short.txt", "wait 0.2s\n");
    let second = droidctl(
        &[
            "run",
            &short,
            "--remote",
            &serve.address,
            "--name",
            "Q5-0002",
        ],
        &dir,
    );
    assert_eq!(second.status.code(), Some(0), "{}", text(&second.stderr));
    assert!(first.wait().unwrap().success());
    let refused = serve.wait_event("refusal", |e| e["event"] == "request_failed");
    assert_eq!(refused["request"], "INIT");
    let why = refused["error"].as_str().unwrap();
    assert!(why.contains("in use by client"), "{why}");
    let connected = serve
        .events()
        .iter()
        .filter(|e| e["event"] == "droid_connected")
        .count();
    assert_eq!(connected, 2);
    serve.stop();
}

#[test]
fn listening_beyond_loopback_warns() {
    let dir = TempDir::new("warn");
    let serve = {
        // Bound on every interface, but nothing but this check talks to it.
        let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
            .args(["serve", "--listen", "0.0.0.0:0", "--sim"])
            .env("DROIDCTL_LOG_FILE", dir.path("serve.log"))
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut err = BufReader::new(child.stderr.take().unwrap());
        let mut first = String::new();
        err.read_line(&mut first).unwrap();
        let _ = child.kill();
        let _ = child.wait();
        first
    };
    assert!(
        serve.contains("warning") && serve.contains("no authentication"),
        "{serve}"
    );
}

// ---------------------------------------------------------------------------------------------
// A Python client written from the protocol (spherov2's relay is a Python program).
// ---------------------------------------------------------------------------------------------

fn python3() -> Option<&'static str> {
    let ok = Command::new("python3")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    ok.then_some("python3")
}

/// `tests/relay_client.py` scans, finds, inits, unlocks, subscribes, wakes, changes the
/// stance, turns streaming on and drives the simulated R2-D2 through `serve`, reading back
/// the wake and stance responses and the locator samples.
#[test]
fn a_python_client_drives_r2d2_through_serve() {
    let Some(py) = python3() else {
        println!("SKIPPED a_python_client_drives_r2d2_through_serve: no python3 on PATH");
        return;
    };
    let dir = TempDir::new("python");
    let serve = Serve::start(&["r2d2", "bb8"], &[], &dir);
    let (host, port) = serve.address.rsplit_once(':').unwrap();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/relay_client.py");
    let mut child = Command::new(py)
        .args([script, host, port])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            panic!("the Python client did not finish");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "python: {}\nserve: {}",
        text(&out.stderr),
        serve.stderr.lock().unwrap().join("\n")
    );
    let seen: Value = serde_json::from_str(text(&out.stdout).trim()).unwrap();
    assert_eq!(seen["scanned"], serde_json::json!(["D2-0001", "BB-0002"]));
    assert_eq!(seen["not_found"], true, "{seen}");
    assert_eq!(seen["wake_response"], true, "{seen}");
    assert_eq!(seen["stance_response"], true, "{seen}");
    assert!(f(&seen["samples"]) >= 5.0, "{seen}");
    // Driving toward 0° moves it along +y.
    assert!(f(&seen["y_cm"]) > 40.0, "{seen}");
    serve.wait_event("released stopped", |e| {
        e["event"] == "droid_released" && e["stopped"] == true
    });
    serve.stop();
}

// ---------------------------------------------------------------------------------------------
// The app through the relay, in a pseudo-terminal.
// ---------------------------------------------------------------------------------------------

use crate::common::pty;

/// The droid's y position as the sensors panel shows it ("pos x … y … cm").
fn shown_y(screen: &str) -> Option<f32> {
    let line = screen.lines().find(|l| l.contains("pos x"))?;
    let after = &line[line.find(" y ")? + 3..];
    after.split_whitespace().next()?.parse().ok()
}

/// `droidctl --remote HOST:PORT --name D2-0001`: the app connects through the relay, shows
/// the droid's notifications (the packet log, the position), drives it with `w`, and `q`
/// quits, the relay releasing the droid stopped.
#[test]
fn the_app_drives_through_the_relay() {
    let dir = TempDir::new("app");
    let serve = Serve::start(&["r2d2"], &[], &dir);
    let log = dir.path("app.log");
    let config = "/dev/null".to_string();
    let mut tui = pty::Tui::start(
        &["--remote", &serve.address, "--name", "D2-0001"],
        &[
            ("DROIDCTL_LOG_FILE", log.as_str()),
            ("DROIDCTL_CONFIG", config.as_str()),
            (
                "DBUS_SYSTEM_BUS_ADDRESS",
                "unix:path=/nonexistent/droidctl-test/bus",
            ),
        ],
    );
    let screen = tui.wait_for("connected", Duration::from_secs(20));
    assert!(screen.contains("D2-0001"), "the droid's name:\n{screen}");
    tui.wait_for("stance tripod", Duration::from_secs(10));
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
    let released = serve.wait_event("released", |e| e["event"] == "droid_released");
    assert_eq!(released["stopped"], true);
    let closed = serve.wait_event("closed", |e| {
        e["event"] == "client_closed" && e["writes"].as_u64().unwrap_or(0) > 0
    });
    assert!(
        closed["notifications"].as_u64().unwrap_or(0) > 10,
        "{closed}"
    );
    serve.stop();
}

/// Issue 39 point 6: `--remote HOST` with several droids behind the relay opens the picker (as
/// a Bluetooth scan does) instead of ending; the droid chosen there is the one driven.
#[test]
fn several_droids_behind_a_relay_open_the_picker() {
    let dir = TempDir::new("picker");
    let serve = Serve::start(&["r2d2", "r2q5"], &[], &dir);
    let log = dir.path("app.log");
    let mut tui = pty::Tui::start(
        &["--remote", &serve.address],
        &[
            ("DROIDCTL_LOG_FILE", log.as_str()),
            ("DROIDCTL_CONFIG", "/dev/null"),
            (
                "DBUS_SYSTEM_BUS_ADDRESS",
                "unix:path=/nonexistent/droidctl-test/bus",
            ),
        ],
    );
    let screen = tui.wait_for("Q5-0002", Duration::from_secs(20));
    assert!(screen.contains("D2-0001"), "both droids listed:\n{screen}");
    // The second one, by its digit.
    tui.send(b"2");
    let screen = tui.wait_for("connected", Duration::from_secs(20));
    assert!(screen.contains("Q5-0002"), "the droid chosen:\n{screen}");
    tui.send(b"q");
    let status = tui.wait_exit(Duration::from_secs(10));
    assert!(status.success(), "{status:?}");
    serve.stop();
}

// ---------------------------------------------------------------------------------------------
// spherov2.py itself, when a Python with it is at hand (`pip install spherov2`, and bleak for
// its server). The Python is found as `common::python` says (the variable, the venv, python3); without
// it these tests say they are skipped.
// ---------------------------------------------------------------------------------------------

/// A Python that imports all of `modules`, or why not.
pub(crate) fn python_with(modules: &str) -> Result<String, String> {
    crate::common::python::Library::Spherov2.python(modules)
}

/// Wait for a child with a limit; its output.
pub(crate) fn finish(mut child: Child, limit: Duration, what: &str) -> Output {
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            panic!("{what} did not finish: {}", text(&out.stderr));
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    child.wait_with_output().unwrap()
}

/// spherov2's `tcp_adapter` and Sphero Edu API drive the simulated R2-D2 through
/// `droidctl serve`.
#[test]
fn spherov2_tcp_adapter_drives_through_serve() {
    let py = match python_with("spherov2.adapter.tcp_adapter, spherov2.sphero_edu") {
        Ok(py) => py,
        Err(why) => {
            println!("SKIPPED spherov2_tcp_adapter_drives_through_serve: {why}");
            return;
        }
    };
    let dir = TempDir::new("spherov2-adapter");
    let serve = Serve::start(&["r2d2"], &[], &dir);
    let port = serve.address.rsplit(':').next().unwrap().to_string();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/relay_spherov2.py");
    let child = Command::new(&py)
        .args([script, &port, "D2-0001"])
        .current_dir(&dir.0)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let out = finish(child, Duration::from_secs(60), "the spherov2 client");
    assert!(out.status.success(), "{}", text(&out.stderr));
    let seen: Value = serde_json::from_str(text(&out.stdout).trim()).unwrap();
    assert_eq!(seen["listed"], serde_json::json!(["D2-0001"]), "{seen}");
    assert_eq!(seen["class"], "R2D2", "{seen}");
    assert!(
        f(&seen["location"]["y"]) > 30.0,
        "it rolled forward: {seen}"
    );
    serve.wait_event("released stopped", |e| {
        e["event"] == "droid_released" && e["stopped"] == true
    });
    serve.stop();
}

/// A running `droidctl sim --bluez MODEL… [--trace --json]`: its bus, its droids' names (in
/// the order given), and with `--trace --json` its trace lines.
pub(crate) struct Bluez {
    child: Child,
    pub(crate) bus: String,
    pub(crate) names: Vec<String>,
    pub(crate) trace: Arc<Mutex<Vec<Value>>>,
}

impl Bluez {
    pub(crate) fn start(models: &[&str], dir: &TempDir) -> Bluez {
        let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
            .args(["sim", "--bluez"])
            .args(models)
            .args(["--trace", "--json"])
            .env("DROIDCTL_LOG_FILE", dir.path("bluez.log"))
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut out = BufReader::new(child.stdout.take().unwrap());
        let mut first = String::new();
        out.read_line(&mut first).unwrap();
        let bus = first
            .trim()
            .strip_prefix("DBUS_SYSTEM_BUS_ADDRESS=")
            .unwrap_or_else(|| panic!("export line, got {first:?}"))
            .to_string();
        std::thread::spawn(move || for _ in out.lines() {});
        let mut names = Vec::new();
        let mut err = BufReader::new(child.stderr.take().unwrap());
        while names.len() < models.len() {
            let mut line = String::new();
            if err.read_line(&mut line).unwrap() == 0 {
                panic!("sim --bluez ended");
            }
            if let Some(rest) = line.strip_prefix("droidctl sim: ")
                && let Some((n, _)) = rest.split_once(" (")
                && !rest.starts_with("serving")
            {
                names.push(n.to_string());
            }
        }
        // The trace (JSON lines on stderr), read on so the simulator never blocks on it.
        let trace = Arc::new(Mutex::new(Vec::new()));
        let lines = trace.clone();
        std::thread::spawn(move || {
            for line in err.lines() {
                let Ok(line) = line else { break };
                if let Ok(v) = serde_json::from_str::<Value>(&line) {
                    lines.lock().unwrap().push(v);
                }
            }
        });
        Bluez {
            child,
            bus,
            names,
            trace,
        }
    }

    pub(crate) fn stop(self) {
        let _ = Command::new("kill")
            .args(["-TERM", &self.child.id().to_string()])
            .status();
        let _ = finish(self.child, Duration::from_secs(10), "sim --bluez");
    }
}

/// `droidctl run --remote` through spherov2's own `tcp_server` (bleak), which reaches the
/// droid on the virtual BlueZ of `droidctl sim --bluez`: the same telemetry as `--sim`.
#[test]
fn droidctl_drives_through_spherov2_tcp_server() {
    let py = match python_with("spherov2.adapter.tcp_server, bleak") {
        Ok(py) => py,
        Err(why) => {
            println!("SKIPPED droidctl_drives_through_spherov2_tcp_server: {why}");
            return;
        }
    };
    let dir = TempDir::new("spherov2-server");
    // The virtual BlueZ with one R2-D2.
    let bluez = Bluez::start(&["r2d2"], &dir);
    let (bus, name) = (bluez.bus.clone(), bluez.names[0].clone());
    // spherov2's server on a free loopback port (it listens on 0.0.0.0 unless told).
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let mut server = Command::new(&py)
        .args([
            "-m",
            "spherov2.adapter.tcp_server",
            "127.0.0.1",
            &port.to_string(),
        ])
        .env("DBUS_SYSTEM_BUS_ADDRESS", &bus)
        .current_dir(&dir.0)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let relay = format!("127.0.0.1:{port}");
    let start = Instant::now();
    while std::net::TcpStream::connect(&relay).is_err() {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "spherov2's server did not listen"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    let script = dir.file(
        "mission.txt",
        "stance tripod\ndrive 80 90 for 1.5s\nwait 0.3s\n",
    );
    let remote = droidctl(
        &[
            "run", &script, "--remote", &relay, "--name", &name, "--json",
        ],
        &dir,
    );
    let reference = droidctl(&["run", &script, "--sim", "--json"], &dir);
    let _ = server.kill();
    let _ = server.wait();
    bluez.stop();
    assert_eq!(remote.status.code(), Some(0), "{}", text(&remote.stderr));
    let (a, b) = (parse_run(&remote).summary, parse_run(&reference).summary);
    let off = (f(&a["x_cm"]) - f(&b["x_cm"])).hypot(f(&a["y_cm"]) - f(&b["y_cm"]));
    assert!(f(&b["x_cm"]).abs() > 30.0, "{b}");
    assert!(off <= 8.0, "final position {a} vs {b}");
    assert_eq!(a["errors"], b["errors"]);
}

/// `serve --record`: each droid session becomes a capture that `droidctl replay` plays back to
/// where the droid went; an existing capture is not overwritten.
#[test]
fn serve_records_each_droid_session_for_replay() {
    let dir = TempDir::new("record");
    let cap = dir.path("serve.txt");
    let cap_arg = cap.clone();
    let serve = Serve::start(&["bb9e"], &["--record", &cap_arg], &dir);
    let script = dir.file("mission.txt", "drive 100 90 for 1.5s\nwait 0.3s\n");
    let live = droidctl(
        &["run", &script, "--remote", &serve.address, "--json"],
        &dir,
    );
    assert_eq!(live.status.code(), Some(0), "{}", text(&live.stderr));
    let live = parse_run(&live);
    serve.wait_event("droid released", |e| e["event"] == "droid_released");
    serve.stop();

    let capture = std::fs::read_to_string(&cap).expect("the capture was written");
    assert!(capture.starts_with("droidctl-capture 1\n"), "{capture}");
    assert!(capture.contains("# model: bb9e"), "{capture}");
    assert!(
        capture.contains(" mark gatt-write 00020005-"),
        "the unlock: {capture}"
    );
    assert!(capture.contains(" out api 8d"), "commands: {capture}");
    assert!(capture.contains(" in notify "), "notifications: {capture}");
    assert!(capture.trim_end().ends_with(" end"), "finished: {capture}");

    let replay = droidctl(&["replay", &cap_arg, "--json"], &dir);
    assert_eq!(replay.status.code(), Some(0), "{}", text(&replay.stderr));
    let replayed = parse_run(&replay);
    let last = |r: &Run| r.samples[r.samples.len() - 1].clone();
    let (a, b) = (last(&replayed), last(&live));
    let off = (f(&a["x_cm"]) - f(&b["x_cm"])).hypot(f(&a["y_cm"]) - f(&b["y_cm"]));
    assert!(f(&b["x_cm"]) > 30.0, "the droid drove east: {b}");
    assert!(off < 5.0, "replay ends where the live run did: {a} vs {b}");

    // A second server may not overwrite it.
    let again = droidctl(
        &[
            "serve",
            "--listen",
            "127.0.0.1:0",
            "--sim",
            "--record",
            &cap_arg,
        ],
        &dir,
    );
    assert_eq!(again.status.code(), Some(2), "{}", text(&again.stderr));
    assert!(
        text(&again.stderr).contains("exists"),
        "{}",
        text(&again.stderr)
    );
}

/// A fleet across machines (issue 23 point 5): droids behind two relays and one local droid,
/// one mission driving all three at once. `NAME@HOST` picks a droid of a relay holding
/// several.
#[test]
fn a_fleet_mixes_droids_behind_two_relays_and_a_local_one() {
    let dir = TempDir::new("fleet");
    let a = Serve::start(&["r2d2"], &[], &dir);
    let b = Serve::start(&["bb8", "sprk"], &[], &dir);
    let script = dir.file(
        "fleet.txt",
        "@R2 stance tripod\ntogether {\n  @R2 drive 80 0 for 2s\n  @BB-8 drive 80 0 for 2s\n  \
         @robi drive 120 0 for 2s\n}\n",
    );
    let bb = format!("BB-0001@{}", b.address);
    let out = droidctl(
        &[
            "run", &script, "--json", "--sim", "robi", "--remote", &a.address, "--remote", &bb,
        ],
        &dir,
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let summaries: Vec<Value> = text(&out.stdout)
        .lines()
        .filter_map(|l| serde_json::from_str::<Value>(l).ok())
        .filter(|v| v["done"] == true)
        .collect();
    let names: Vec<&str> = summaries
        .iter()
        .filter_map(|s| s["droid"].as_str())
        .collect();
    assert_eq!(names, ["Robi 42", "D2-0001", "BB-0001"]);
    for s in &summaries {
        assert!(f(&s["y_cm"]) > 10.0, "every droid drove north: {s}");
    }
    for serve in [&a, &b] {
        serve.wait_event("its droid connected", |e| e["event"] == "droid_connected");
        serve.wait_event("its droid released", |e| e["event"] == "droid_released");
    }
    let released = b.wait_event("BB-8 released", |e| e["event"] == "droid_released");
    assert_eq!(released["name"], "BB-0001", "the named droid of the two");
    a.stop();
    b.stop();
}

/// spherov2's Sphero Edu API on a simulated BOLT or Mini (tests/sphero_edu.py): `how` is
/// `["tcp", PORT]` or `["bleak"]`. The JSON it prints.
fn sphero_edu(py: &str, how: &[&str], name: &str, bus: Option<&str>, dir: &TempDir) -> Value {
    edu_script(py, "sphero_edu.py", how, name, bus, dir)
}

/// Run `tests/SCRIPT ARGS… NAME` with spherov2's Python (on the bus `bus` for bleak); the
/// JSON it prints.
fn edu_script(
    py: &str,
    script: &str,
    how: &[&str],
    name: &str,
    bus: Option<&str>,
    dir: &TempDir,
) -> Value {
    let script = format!("{}/tests/{script}", env!("CARGO_MANIFEST_DIR"));
    let mut cmd = Command::new(py);
    cmd.arg(script)
        .args(how)
        .arg(name)
        .current_dir(&dir.0)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    if let Some(bus) = bus {
        cmd.env("DBUS_SYSTEM_BUS_ADDRESS", bus);
    }
    let out = finish(
        cmd.spawn().unwrap(),
        Duration::from_secs(90),
        "the Sphero Edu client",
    );
    assert!(out.status.success(), "{name}: {}", text(&out.stderr));
    serde_json::from_str(text(&out.stdout).trim()).unwrap()
}

/// It rolled at heading 90: east (+x), far more than sideways. How far depends on when the
/// client's stop and its last streamed location arrive (38 to 60 cm for 1.5 s at speed 100,
/// more spread on a loaded machine): the direction is what is checked, with a clear distance.
fn rolled_east(seen: &Value) {
    let (x, y) = (f(&seen["location"]["x"]), f(&seen["location"]["y"]));
    assert!(x > 20.0 && y.abs() < x / 3.0, "rolled east: {seen}");
}

/// Issue 19 point 4: spherov2's Sphero Edu API drives a simulated BOLT and a simulated Mini
/// through `droidctl serve` (its TCP adapter): roll, the location in the rolled direction; the
/// BOLT's matrix character is in the served session's capture, answered with success.
#[test]
fn sphero_edu_drives_bolt_and_mini_through_serve() {
    let py = match python_with("spherov2.adapter.tcp_adapter, spherov2.sphero_edu") {
        Ok(py) => py,
        Err(why) => {
            println!("SKIPPED sphero_edu_drives_bolt_and_mini_through_serve: {why}");
            return;
        }
    };
    let dir = TempDir::new("sphero-edu-serve");
    let cap = dir.path("serve.txt");
    let serve = Serve::start(&["bolt", "mini"], &["--record", &cap], &dir);
    let port = serve.address.rsplit(':').next().unwrap().to_string();
    let bolt = sphero_edu(&py, &["tcp", &port], "SB-0001", None, &dir);
    assert_eq!(bolt["class"], "BOLT", "{bolt}");
    rolled_east(&bolt);
    let mini = sphero_edu(&py, &["tcp", &port], "SM-0002", None, &dir);
    assert_eq!(mini["class"], "Mini", "{mini}");
    rolled_east(&mini);
    serve.wait_event("both released", |e| {
        e["event"] == "droid_released" && e["name"] == "SM-0002"
    });
    serve.stop();
    let capture = std::fs::read_to_string(&cap).expect("the capture was written");
    // Set Single Character 'A' in red to the secondary (8D 3A 12 01 1A 42 …), and its answer
    // from the secondary with error 0 (8D 39 01 12 1A 42 SEQ 00 …).
    let compact = capture.to_ascii_lowercase().replace(' ', "");
    assert!(compact.contains("8d3a12011a42"), "{capture}");
    assert!(
        compact.contains("ff000041"),
        "the character and colour: {capture}"
    );
    assert!(compact.contains("8d3901121a42"), "answered: {capture}");
}

/// Issue 19 point 4: the same through bleak on the virtual BlueZ of `droidctl sim --bluez`,
/// whose trace shows the BOLT's matrix drawing the character.
#[test]
fn sphero_edu_drives_bolt_and_mini_through_bleak() {
    let py = match python_with("spherov2.adapter.bleak_adapter, spherov2.sphero_edu, bleak") {
        Ok(py) => py,
        Err(why) => {
            println!("SKIPPED sphero_edu_drives_bolt_and_mini_through_bleak: {why}");
            return;
        }
    };
    let dir = TempDir::new("sphero-edu-bleak");
    let bluez = Bluez::start(&["bolt", "mini"], &dir);
    let bolt = sphero_edu(&py, &["bleak"], &bluez.names[0], Some(&bluez.bus), &dir);
    assert_eq!(bolt["class"], "BOLT", "{bolt}");
    rolled_east(&bolt);
    let mini = sphero_edu(&py, &["bleak"], &bluez.names[1], Some(&bluez.bus), &dir);
    assert_eq!(mini["class"], "Mini", "{mini}");
    rolled_east(&mini);
    let trace = bluez.trace.lock().unwrap().clone();
    bluez.stop();
    let shown = trace
        .iter()
        .filter(|t| t["packet"]["kind"] == "state")
        .map(|t| t["packet"]["shows"].as_str().unwrap_or("").to_string())
        .collect::<Vec<_>>();
    assert!(
        shown.contains(&"matrix: character 'A' in #ff0000".to_string()),
        "{shown:?}"
    );
}

// ---------------------------------------------------------------------------------------------
// Issue 32: spherov2's Sphero Edu API against every simulated model it drives, through
// `droidctl serve --sim` (tests/sphero_edu_models.py; tests/it/sim_models.rs checks the same in
// process and in simulated time).
// ---------------------------------------------------------------------------------------------

/// Run tests/sphero_edu_models.py on each of `models`, each served alone (the droids of one
/// `serve` share a room, where rolling east to the wall would meet the next one); check each
/// result.
fn edu_models(test: &str, models: &[(&str, &str)]) {
    let py = match python_with("spherov2.adapter.tcp_adapter, spherov2.sphero_edu") {
        Ok(py) => py,
        Err(why) => {
            println!("SKIPPED {test}: {why}");
            return;
        }
    };
    let dir = TempDir::new(test);
    for (id, class) in models {
        let serve = Serve::start(&[id], &[], &dir);
        let port = serve.address.rsplit(':').next().unwrap().to_string();
        let name = format!(
            "{}0001",
            droidctl::model::Model::from_id(id)
                .and_then(|m| m.name_prefix())
                .unwrap(),
        );
        let how = ["tcp", port.as_str()];
        let seen = edu_script(&py, "sphero_edu_models.py", &how, &name, None, &dir);
        edu_checks(&name, class, &seen);
        serve.stop();
    }
}

/// Everything tests/sphero_edu_models.py saw of droid `name`, of spherov2's `class`.
fn edu_checks(name: &str, class: &str, seen: &Value) {
    assert_eq!(seen["class"], class, "{seen}");
    edu_spin_turned_once(name, seen);
    edu_gyro_read_the_spin(name, seen);
    edu_hit_head_on(name, seen);
    edu_went_where_it_says(name, seen);
}

/// spin(360, 1): the streamed yaw went once round, one way, and never turned back.
pub(crate) fn edu_spin_turned_once(name: &str, seen: &Value) {
    let yaws: Vec<f64> = seen["yaw"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| f(&s[1]))
        .collect();
    assert!(yaws.len() > 20, "{name}: yaw sampled: {seen}");
    let steps: Vec<f64> = yaws
        .windows(2)
        .map(|w| (w[1] - w[0] + 540.0).rem_euclid(360.0) - 180.0)
        .collect();
    let total: f64 = steps.iter().sum();
    assert!(
        (total.abs() - 360.0).abs() < 20.0,
        "{name}: turned {total}° for spin(360, 1): {yaws:?}"
    );
    let back = steps
        .iter()
        .map(|s| -s * total.signum())
        .fold(0.0, f64::max);
    assert!(back < 5.0, "{name}: turned back by {back}°: {yaws:?}");
}

/// spin(360, 1): the streamed gyroscope read the turn while it lasted (issue 38 point 11: over
/// `serve` it read 0 on about half the samples of a spin, the simulated body turning to each
/// new heading at full rate, then standing). Samples from 0.5 s to 0.9 s, when the spin is
/// under way and the samples taken then are of it: each reads at least 100°/s (the spin
/// averages 360°/s; RVR turns slower).
fn edu_gyro_read_the_spin(name: &str, seen: &Value) {
    let during: Vec<f64> = seen["gyro"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| (0.5..0.9).contains(&f(&s[0])))
        .map(|s| f(&s[1]))
        .collect();
    assert!(during.len() > 5, "{name}: gyroscope sampled: {seen}");
    assert!(
        during.iter().all(|z| z.abs() >= 100.0),
        "{name}: the gyroscope while spinning: {during:?}"
    );
}

/// The roll east ended against the east wall head-on: the hit is on the robot's forward axis
/// (RVR reports no collisions to spherov2's Edu API).
pub(crate) fn edu_hit_head_on(name: &str, seen: &Value) {
    let hits = seen["collisions"].as_array().unwrap();
    if name.starts_with("RV-") {
        return;
    }
    let c = hits
        .first()
        .unwrap_or_else(|| panic!("{name}: no collision: {seen}"));
    assert_eq!(c["y_axis"], true, "{name}: head-on is on y: {c}");
    assert_eq!(c["x_axis"], false, "{name}: {c}");
    assert!(f(&c["accel_y"]) < 0.0, "{name}: braking ahead: {c}");
}

/// Where spherov2 says the droid is: the v1 droids' raw motors drove it north (forward, as
/// aimed), the roll east took it to the east wall (the room is 4 m, the droid starts in the
/// middle), keeping its northing.
fn edu_went_where_it_says(name: &str, seen: &Value) {
    let north = if seen["raw_location"].is_null() {
        0.0
    } else {
        let (x, y) = (f(&seen["raw_location"]["x"]), f(&seen["raw_location"]["y"]));
        assert!(y > 20.0 && x.abs() < 5.0, "{name}: raw motors: {seen}");
        y
    };
    let (x, y) = (f(&seen["location"]["x"]), f(&seen["location"]["y"]));
    assert!(
        x > 150.0 && (y - north).abs() < 10.0,
        "{name}: rolled east to the wall: {seen}"
    );
}

#[test]
fn sphero_edu_drives_each_star_wars_droid() {
    edu_models(
        "sphero_edu_drives_each_star_wars_droid",
        &[("r2d2", "R2D2"), ("r2q5", "R2Q5"), ("bb9e", "BB9E")],
    );
}

#[test]
fn sphero_edu_drives_each_v1_droid() {
    edu_models(
        "sphero_edu_drives_each_v1_droid",
        &[("bb8", "BB8"), ("sprk", "Sprk2"), ("ollie", "Ollie")],
    );
}

#[test]
fn sphero_edu_drives_bolt_mini_and_rvr() {
    edu_models(
        "sphero_edu_drives_bolt_mini_and_rvr",
        &[("bolt", "BOLT"), ("mini", "Mini"), ("rvr", "RVR")],
    );
}

/// The same over bleak on the virtual BlueZ for the v1 droids, whose trace decodes every
/// Roll spherov2 sends (five bytes, with its reverse flag) with its fields.
#[test]
fn sphero_edu_drives_each_v1_droid_through_bleak_and_the_trace_reads_its_rolls() {
    let test = "sphero_edu_drives_each_v1_droid_through_bleak_and_the_trace_reads_its_rolls";
    let py = match python_with("spherov2.adapter.bleak_adapter, spherov2.sphero_edu, bleak") {
        Ok(py) => py,
        Err(why) => {
            println!("SKIPPED {test}: {why}");
            return;
        }
    };
    let dir = TempDir::new("sphero-edu-v1-bleak");
    let mut trace = Vec::new();
    // One bus each: droids served together share a room, and these all end at the east wall.
    for (model, class) in [("bb8", "BB8"), ("sprk", "Sprk2"), ("ollie", "Ollie")] {
        let bluez = Bluez::start(&[model], &dir);
        let name = &bluez.names[0];
        let how = ["bleak"];
        let seen = edu_script(
            &py,
            "sphero_edu_models.py",
            &how,
            name,
            Some(&bluez.bus),
            &dir,
        );
        edu_checks(name, class, &seen);
        trace.extend(bluez.trace.lock().unwrap().clone());
        bluez.stop();
    }
    let rolls: Vec<&Value> = trace
        .iter()
        .filter(|t| t["packet"]["command"] == "roll")
        .collect();
    assert!(rolls.len() > 30, "spherov2 rolled: {} rolls", rolls.len());
    for r in rolls {
        let fields = &r["packet"]["fields"];
        for k in ["speed", "heading", "state", "reverse"] {
            assert!(!fields[k].is_null(), "{k} of {r}");
        }
    }
}
