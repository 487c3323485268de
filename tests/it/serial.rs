//! `--serial PORT` end to end: droidctl's own serial client against `droidctl sim --serial
//! rvr` on its pseudo-terminal — a mission driven and stopped, the bridge's drive and
//! emergency stop, the link lost when the simulator exits (the droid stopped, reconnect
//! attempts said), and the port's errors in words.

#![cfg(unix)]

use crate::common::cli::{droidctl, stderr, usage_error};
use crate::common::serial_sim::SerialSim;
use serde_json::Value;
use std::io::{BufRead, BufReader, Write};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("droidctl-serial-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn drives(sim: &SerialSim) -> Vec<(u64, u64)> {
    sim.packets()
        .iter()
        .filter(|(d, p)| d == "in" && p["command"] == "drive-with-heading")
        .filter_map(|(_, p)| {
            Some((
                p["fields"]["speed"].as_u64()?,
                p["fields"]["heading"].as_u64()?,
            ))
        })
        .collect()
}

/// Every command droidctl wrote is named, addressed as RVR's UART wants (target 0x01/0x02,
/// no source: as Sphero's SDK sends), and answered without error when it asked.
fn all_named_and_answered(sim: &SerialSim) {
    // The simulator's trace is read as it is printed: a command just seen may have its answer
    // a line later. Wait (boundedly) for every answer, and judge the very trace the wait ended
    // on: a fresh look could hold a command written since, its answer not yet printed (the
    // drive slot's re-send of an e-stop comes a pacing interval after the stop itself).
    let end = std::time::Instant::now() + std::time::Duration::from_secs(5);
    let packets = loop {
        let packets = sim.packets();
        if every_answer_in(&packets) || std::time::Instant::now() >= end {
            break packets;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    for (dir, p) in &packets {
        if dir != "in" {
            continue;
        }
        assert_eq!(p["kind"], "command", "{p}");
        assert!(p["command"].is_string(), "unnamed: {p}");
        assert!(matches!(p["tid"].as_u64(), Some(1 | 2)), "{p}");
        assert!(p["sid"].is_null(), "{p}");
        let asks = p["flag_names"]
            .as_array()
            .is_some_and(|f| f.iter().any(|n| n == "requests_response"));
        if asks {
            let answer = packets.iter().find(|(d, r)| {
                d == "out"
                    && r["kind"] == "response"
                    && r["seq"] == p["seq"]
                    && r["did"] == p["did"]
                    && r["cid"] == p["cid"]
            });
            let Some((_, r)) = answer else {
                panic!("unanswered: {p}")
            };
            assert!(r["err"].is_null() || r["err"] == 0, "{r}");
        }
    }
}

/// Whether every command in `packets` that asked for an answer has one.
fn every_answer_in(packets: &[(String, serde_json::Value)]) -> bool {
    packets
        .iter()
        .filter(|(d, p)| {
            d == "in"
                && p["flag_names"]
                    .as_array()
                    .is_some_and(|f| f.iter().any(|n| n == "requests_response"))
        })
        .all(|(_, p)| {
            packets.iter().any(|(d, r)| {
                d == "out"
                    && r["kind"] == "response"
                    && r["seq"] == p["seq"]
                    && r["did"] == p["did"]
                    && r["cid"] == p["cid"]
            })
        })
}

#[test]
fn a_mission_drives_and_stops_the_rvr_on_a_serial_port() {
    let dir = scratch("mission");
    let mission = dir.join("m.txt");
    std::fs::write(&mission, "wake\ndrive 80 90 for 1s\nstop\n").unwrap();
    let sim = SerialSim::start();
    let out = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args([
            "run",
            mission.to_str().unwrap(),
            "--serial",
            &sim.path,
            "--json",
        ])
        .env("DROIDCTL_CONFIG", "/dev/null")
        .env("DROIDCTL_LOG_FILE", dir.join("log"))
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert_eq!(out.status.code(), Some(0), "{text}\n{}", stderr(&out));
    let last: Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
    assert_eq!(last["done"], true, "{last}");
    assert_eq!(last["timeouts"], 0, "{last}");
    assert_eq!(last["failed_steps"], 0, "{last}");
    // It rolled: 80 toward 90° for a second, then stopped at that heading.
    assert!(last["x_cm"].as_f64().unwrap() > 20.0, "{last}");
    sim.wait_for(5, "the stop", |d, p| {
        d == "in" && p["command"] == "drive-with-heading" && p["fields"]["speed"] == 0
    });
    let d = drives(&sim);
    let moving = d.iter().position(|&(s, h)| s == 80 && h == 90);
    let stopped = d.iter().rposition(|&(s, _)| s == 0);
    assert!(
        matches!((moving, stopped), (Some(m), Some(s)) if m < s),
        "{d:?}"
    );
    all_named_and_answered(&sim);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The bridge on standard input/output, its lines gathered.
struct Bridge {
    child: Child,
    stdin: Option<ChildStdin>,
    lines: Arc<Mutex<Vec<Value>>>,
    stderr: std::path::PathBuf,
}

impl Bridge {
    fn start(dir: &std::path::Path, port: &str) -> Bridge {
        let stderr = dir.join("bridge.stderr");
        let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
            .args(["bridge", "--stdio", "--serial", port])
            .env("DROIDCTL_CONFIG", "/dev/null")
            .env("DROIDCTL_LOG_FILE", dir.join("log"))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(std::fs::File::create(&stderr).unwrap())
            .spawn()
            .unwrap();
        let lines = Arc::new(Mutex::new(Vec::new()));
        let out = child.stdout.take().unwrap();
        {
            let lines = lines.clone();
            std::thread::spawn(move || {
                for l in BufReader::new(out).lines() {
                    let Ok(l) = l else { break };
                    if let Ok(v) = serde_json::from_str(&l) {
                        lines.lock().unwrap_or_else(|e| e.into_inner()).push(v);
                    }
                }
            });
        }
        let stdin = child.stdin.take();
        Bridge {
            child,
            stdin,
            lines,
            stderr,
        }
    }

    fn send(&mut self, line: &str) {
        let stdin = self.stdin.as_mut().unwrap();
        writeln!(stdin, "{line}").unwrap();
        stdin.flush().unwrap();
    }

    fn wait(&self, secs: u64, what: &str, f: impl Fn(&Value) -> bool) -> Value {
        let end = Instant::now() + Duration::from_secs(secs);
        loop {
            let lines = self.lines.lock().unwrap_or_else(|e| e.into_inner()).clone();
            if let Some(v) = lines.iter().find(|v| f(v)) {
                return v.clone();
            }
            let kinds: Vec<&Value> = lines.iter().filter(|v| v["type"] != "telemetry").collect();
            assert!(
                Instant::now() < end,
                "no {what} within {secs} s: {kinds:?}\n{}",
                std::fs::read_to_string(&self.stderr).unwrap_or_default()
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for Bridge {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[test]
fn the_bridge_drives_stops_at_once_and_survives_the_serial_link_lost() {
    let dir = scratch("bridge");
    let mut sim = SerialSim::start();
    let mut bridge = Bridge::start(&dir, &sim.path);
    let hello = bridge.wait(10, "hello", |v| v["type"] == "hello");
    let droid = hello["droids"][0]["droid"].as_str().unwrap().to_string();
    assert!(droid.starts_with("RV-"), "{hello}");
    assert!(
        hello["droids"][0]["origin"]
            .as_str()
            .is_some_and(|o| o.contains("serial")),
        "{hello}"
    );
    bridge.wait(10, "ready", |v| v["type"] == "link" && v["ready"] == true);
    bridge.send(r#"{"v":1,"cmd":"drive","speed":100,"heading":0}"#);
    sim.wait_for(5, "the drive", |d, p| {
        d == "in" && p["command"] == "drive-with-heading" && p["fields"]["speed"] == 100
    });
    let before = drives(&sim).len();
    bridge.send(r#"{"v":1,"cmd":"estop","id":7}"#);
    bridge.wait(5, "the e-stop's reply", |v| {
        v["type"] == "reply" && v["id"] == 7
    });
    sim.wait_for(5, "the stop", |d, p| {
        d == "in" && p["command"] == "drive-with-heading" && p["fields"]["speed"] == 0
    });
    assert!(
        drives(&sim)[before..].iter().any(|&(s, _)| s == 0),
        "{:?}",
        drives(&sim)
    );
    all_named_and_answered(&sim);

    // Rolling again when the simulator exits: its pseudo-terminal goes, the link is lost as a
    // Bluetooth one is, and the drive the bridge held is dropped (the droid stopped).
    bridge.send(r#"{"v":1,"cmd":"drive","speed":60,"heading":90}"#);
    sim.wait_for(5, "the second drive", |d, p| {
        d == "in" && p["command"] == "drive-with-heading" && p["fields"]["speed"] == 60
    });
    assert_eq!(sim.interrupt(), Some(0));
    bridge.wait(10, "the droid stopped for the lost link", |v| {
        v["type"] == "stopped" && v["reason"] == "link_lost"
    });
    // And reconnecting, attempt after attempt, each saying why.
    let again = bridge.wait(20, "a second reconnect attempt", |v| {
        v["type"] == "link"
            && v["state"] == "reconnecting"
            && v["attempt"].as_u64().is_some_and(|a| a >= 2)
    });
    let reason = again["reason"].as_str().unwrap_or_default();
    assert!(
        reason.contains("no serial port") && reason.contains(&sim.path),
        "{again}"
    );
    drop(bridge);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_ports_errors_are_said_in_words() {
    let dir = scratch("errors");
    let mission = dir.join("m.txt");
    std::fs::write(&mission, "drive 50 0 for 1s\n").unwrap();
    let m = mission.to_str().unwrap();
    let run = |port: &str| {
        let o = droidctl(&["run", m, "--serial", port]);
        assert_eq!(o.status.code(), Some(1), "{port}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(!e.contains("panicked"), "{e}");
        e
    };
    let missing = dir.join("ttyNONE");
    let e = run(missing.to_str().unwrap());
    assert!(
        e.contains("no serial port") && e.contains("/dev/serial0"),
        "{e}"
    );
    let e = run(m);
    assert!(e.contains("is not a serial port"), "{e}");
    // Another program holding the port (as pyserial's exclusive mode and minicom lock it).
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        let sim = SerialSim::start();
        let held = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&sim.path)
            .unwrap();
        // SAFETY: flock on a descriptor this test owns.
        assert_eq!(
            unsafe { libc::flock(held.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) },
            0
        );
        let e = run(&sim.path);
        assert!(e.contains("in use by another program"), "{e}");
        drop(held);
    }
    // `--serial` is one droid on one port: not with the simulator or Bluetooth's choices.
    for other in [["--sim", "rvr"], ["--name", "RV-1"]] {
        let o = droidctl(&["run", m, "--serial", "/dev/ttyS0", other[0], other[1]]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains("cannot be used with"), "{}", stderr(&o));
    }
    // `scan` looks over Bluetooth only: no serial ports it was not asked about.
    let help = droidctl(&["scan", "--help"]);
    assert!(
        !crate::common::cli::stdout(&help)
            .to_lowercase()
            .contains("serial")
    );
    // Only RVR has a serial port to simulate.
    let e = usage_error(&["sim", "--serial", "r2d2"]);
    assert!(e.contains("no serial port"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `serve --serial PORT`: the RVR on a serial port relayed over TCP, driven from elsewhere
/// with `--remote` as if the relay had reached it over Bluetooth.
#[test]
fn serve_relays_the_rvr_on_a_serial_port_to_remote_clients() {
    let dir = scratch("serve");
    let mission = dir.join("m.txt");
    std::fs::write(&mission, "drive 70 180 for 1s\nstop\n").unwrap();
    let sim = SerialSim::start();
    let mut serve = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args([
            "serve",
            "--listen",
            "127.0.0.1:0",
            "--json",
            "--serial",
            &sim.path,
        ])
        .env("DROIDCTL_LOG_FILE", dir.join("serve.log"))
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(serve.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    let listening: Value = serde_json::from_str(&first).unwrap();
    assert_eq!(listening["event"], "listening", "{first}");
    let address = listening["address"].as_str().unwrap().to_string();
    let out = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args([
            "run",
            mission.to_str().unwrap(),
            "--remote",
            &address,
            "--json",
        ])
        .env("DROIDCTL_CONFIG", "/dev/null")
        .env("DROIDCTL_LOG_FILE", dir.join("run.log"))
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let _ = serve.kill();
    let _ = serve.wait();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let d = drives(&sim);
    assert!(d.contains(&(70, 180)), "{d:?}");
    assert!(
        d.iter().rposition(|&(s, _)| s == 0) > d.iter().position(|&d| d == (70, 180)),
        "{d:?}"
    );
    all_named_and_answered(&sim);
    let _ = std::fs::remove_dir_all(&dir);
}
