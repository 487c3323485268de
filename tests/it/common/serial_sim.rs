//! `droidctl sim --serial rvr --trace --json` as a process for the serial tests: the
//! pseudo-terminal's path it prints, and its trace (one JSON object per packet the simulated
//! RVR received or sent) gathered from stderr.

#![allow(dead_code)]
#![cfg(unix)]

use super::lines::{Lines, first_line};
use serde_json::Value;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

pub struct SerialSim {
    pub child: Child,
    /// What clients open: a symbolic link to the pseudo-terminal (`--link`), gone with the
    /// simulator. Not the terminal's own `/dev/pts/N`: the kernel gives a closed one's number
    /// to the next terminal opened (another test's), which a reconnecting client would reach.
    pub path: String,
    /// The pseudo-terminal itself.
    pub pty: String,
    dir: std::path::PathBuf,
    lines: Lines,
}

impl SerialSim {
    pub fn start() -> SerialSim {
        static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("droidctl-serial-sim-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let link = dir.join("ttyRVR");
        let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
            .args(["sim", "--serial", "rvr", "--trace", "--json", "--link"])
            .arg(&link)
            .env("RUST_BACKTRACE", "1")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start droidctl sim --serial rvr");
        let lines = Lines::collect(child.stderr.take().unwrap());
        let (first, _rest) = first_line(child.stdout.take().unwrap(), Duration::from_secs(10));
        let first = first.expect("droidctl sim --serial printed its path");
        let pty = first.trim().to_string();
        assert!(pty.starts_with("/dev/"), "a device path, got {first:?}");
        assert!(link.exists(), "--link made no {}", link.display());
        SerialSim {
            child,
            path: link.to_string_lossy().into_owned(),
            pty,
            dir,
            lines,
        }
    }

    /// Everything it said on stderr so far.
    pub fn stderr(&self) -> String {
        self.lines.text()
    }

    /// The traced packets so far: (`dir`, `packet`).
    pub fn packets(&self) -> Vec<(String, Value)> {
        self.lines
            .all()
            .iter()
            .filter_map(|l| serde_json::from_str::<Value>(l).ok())
            .filter_map(|v| {
                Some((
                    v.get("dir")?.as_str()?.to_string(),
                    v.get("packet")?.clone(),
                ))
            })
            .collect()
    }

    /// Wait until a traced packet satisfies `f`; panics with the trace after `secs`.
    pub fn wait_for(&self, secs: u64, what: &str, f: impl Fn(&str, &Value) -> bool) -> Value {
        let end = Instant::now() + Duration::from_secs(secs);
        loop {
            if let Some((_, p)) = self.packets().into_iter().find(|(d, p)| f(d, p)) {
                return p;
            }
            assert!(
                Instant::now() < end,
                "no {what} within {secs} s; the simulator said:\n{}",
                self.stderr()
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// End it as Ctrl-C does; its status.
    pub fn interrupt(&mut self) -> Option<i32> {
        let _ = Command::new("kill")
            .args(["-INT", &self.child.id().to_string()])
            .status();
        let end = Instant::now() + Duration::from_secs(10);
        loop {
            if let Some(s) = self.child.try_wait().unwrap() {
                // Everything it said read to the end before anyone judges the trace.
                assert!(
                    self.lines.wait_end(Duration::from_secs(10)),
                    "sim --serial's stderr did not end"
                );
                return s.code();
            }
            assert!(Instant::now() < end, "sim --serial did not stop");
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for SerialSim {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}
