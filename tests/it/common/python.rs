//! The field's Python libraries, found once for every test that runs them: spherov2,
//! sphero-unsw and Sphero's RVR SDK. Each is looked for in its environment variable, then
//! in the venv `.ci/run` makes under `target/`, then in `python3`; a test that cannot have
//! one prints why and is skipped by its caller.

// Shared by tests some of which are Unix-only: on other targets parts go unused.
#![allow(dead_code)]

use std::process::Command;

/// A Python library of the field the tests are judged by.
#[derive(Clone, Copy, Debug)]
pub enum Library {
    /// spherov2.py (`pip install spherov2 bleak paho-mqtt`).
    Spherov2,
    /// sphero-unsw, spherov2's BOLT+ fork (`pip install sphero-unsw bleak`).
    SpheroUnsw,
    /// Sphero's RVR SDK (`pip install sphero-sdk pyserial pyserial-asyncio`).
    SpheroSdk,
}

impl Library {
    fn variable(self) -> &'static str {
        match self {
            Library::Spherov2 => "DROIDCTL_TEST_SPHEROV2_PYTHON",
            Library::SpheroUnsw => "DROIDCTL_TEST_SPHERO_UNSW_PYTHON",
            Library::SpheroSdk => "DROIDCTL_TEST_SPHERO_SDK_PYTHON",
        }
    }

    fn venv(self) -> &'static str {
        match self {
            Library::Spherov2 => "spherov2-venv",
            Library::SpheroUnsw => "sphero-unsw-venv",
            Library::SpheroSdk => "sphero-sdk-venv",
        }
    }

    fn install(self) -> &'static str {
        match self {
            Library::Spherov2 => "spherov2 bleak paho-mqtt",
            Library::SpheroUnsw => "sphero-unsw bleak",
            Library::SpheroSdk => "sphero-sdk pyserial pyserial-asyncio",
        }
    }

    /// The Python to try: the variable's, else `.ci/run`'s venv if it exists, else python3.
    pub fn candidate(self) -> String {
        let venv = format!(
            "{}/target/{}/bin/python",
            env!("CARGO_MANIFEST_DIR"),
            self.venv()
        );
        std::env::var(self.variable()).unwrap_or_else(|_| {
            if std::path::Path::new(&venv).exists() {
                venv
            } else {
                "python3".to_string()
            }
        })
    }

    /// The Python that imports every one of `modules` (comma-separated, as `import` takes
    /// them), or a sentence saying which Python could not and how to give one.
    pub fn python(self, modules: &str) -> Result<String, String> {
        let py = self.candidate();
        let out = Command::new(&py)
            .args(["-c", &format!("import {modules}")])
            .output()
            .map_err(|e| format!("cannot run {py}: {e}"))?;
        if out.status.success() {
            return Ok(py);
        }
        let why = String::from_utf8_lossy(&out.stderr);
        Err(format!(
            "{py} cannot import {modules} ({}); set {} to a Python with `pip install {}` \
             (.ci/run makes target/{})",
            why.trim().lines().last().unwrap_or("no reason given"),
            self.variable(),
            self.install(),
            self.venv()
        ))
    }
}
