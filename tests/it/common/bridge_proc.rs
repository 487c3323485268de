//! `droidctl bridge` as a process for the bridge's tests (MQTT, Home Assistant, the
//! examples): a scratch directory, the process with its stderr kept, and what a test waits
//! for on a [`Sub`].

#![allow(dead_code)]

use super::mosquitto::Sub;
use serde_json::Value;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

pub fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "droidctl-bridge-mqtt-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The bridge as a process; its stderr kept in a file.
pub struct BridgeProc {
    pub child: Child,
    pub stderr: PathBuf,
}

impl BridgeProc {
    pub fn start(dir: &std::path::Path, args: &[&str]) -> BridgeProc {
        BridgeProc::start_bin(dir, env!("CARGO_BIN_EXE_droidctl"), args)
    }

    /// As [`BridgeProc::start`], with the droidctl binary at `bin` (a release build, to
    /// measure it).
    pub fn start_bin(dir: &std::path::Path, bin: &str, args: &[&str]) -> BridgeProc {
        static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let stderr = dir.join(format!("bridge-{n}.stderr"));
        let child = Command::new(bin)
            .arg("bridge")
            .args(args)
            .env("DROIDCTL_CONFIG", "/dev/null")
            .env("RUST_BACKTRACE", "1")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(&stderr).unwrap())
            .spawn()
            .expect("run droidctl bridge");
        BridgeProc { child, stderr }
    }

    pub fn stderr(&self) -> String {
        std::fs::read_to_string(&self.stderr).unwrap_or_default()
    }

    /// Wait for the process to end; its status code.
    pub fn wait(&mut self, secs: u64) -> Option<i32> {
        let end = Instant::now() + Duration::from_secs(secs);
        loop {
            if let Some(s) = self.child.try_wait().unwrap() {
                return s.code();
            }
            assert!(
                Instant::now() < end,
                "the bridge did not end: {}",
                self.stderr()
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for BridgeProc {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

pub fn speed(v: &Value) -> f64 {
    v["speed"].as_f64().unwrap_or(0.0)
}

/// Everything `sub` receives until `done` holds of it or `secs` pass.
pub fn gather(
    sub: &Sub,
    secs: u64,
    done: impl Fn(&[(String, Value)]) -> bool,
) -> Vec<(String, Value)> {
    let end = Instant::now() + Duration::from_secs(secs);
    let mut got = Vec::new();
    while !done(&got) {
        let Some(left) = end.checked_duration_since(Instant::now()) else {
            break;
        };
        match sub.rx.recv_timeout(left) {
            Ok(m) => got.push(m),
            Err(_) => break,
        }
    }
    got
}

/// End the bridge as Ctrl-C does, and wait for it.
pub fn interrupt(bridge: &mut BridgeProc) {
    let _ = Command::new("kill")
        .args(["-INT", &bridge.child.id().to_string()])
        .status();
    assert_eq!(bridge.wait(15), Some(0), "{}", bridge.stderr());
}
