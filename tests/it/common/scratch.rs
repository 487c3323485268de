//! A scratch directory per test and the binary run inside it (no tempfile crate in this
//! project), shared by the `droidctl run` tests (and, through `#[path]`, by
//! tests/edu_engine.rs).

// Each area uses its own subset.
#![allow(dead_code)]

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

pub struct Scratch(pub PathBuf);

impl Scratch {
    /// A fresh directory named for the test file (`prefix`) and the test (`name`).
    pub fn new(prefix: &str, name: &str) -> Self {
        let dir =
            std::env::temp_dir().join(format!("droidctl-{prefix}-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    pub fn file(&self, name: &str, text: &str) -> PathBuf {
        let p = self.0.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    pub fn log(&self) -> PathBuf {
        self.0.join("droidctl.log")
    }

    /// Run droidctl in this directory with the log file inside it.
    pub fn run(&self, args: &[&str]) -> Output {
        Command::new(env!("CARGO_BIN_EXE_droidctl"))
            .args(args)
            .current_dir(&self.0)
            .env("DROIDCTL_LOG_FILE", self.log())
            .env_remove("DROIDCTL_LOG")
            .output()
            .expect("run droidctl")
    }

    /// The same, with how long it took.
    pub fn run_timed(&self, args: &[&str]) -> (Output, Duration) {
        let t0 = Instant::now();
        let out = self.run(args);
        (out, t0.elapsed())
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

pub type Obj = serde_json::Map<String, Value>;

/// Every line of `text` as a JSON object.
pub fn json_lines(text: &str) -> Vec<Obj> {
    text.lines()
        .map(|l| match serde_json::from_str::<Value>(l) {
            Ok(Value::Object(m)) => m,
            other => panic!("not a JSON object: {l:?} ({other:?})"),
        })
        .collect()
}
