//! tracing to a log file (never to the terminal, which the TUI owns). The file lives in the
//! platform state directory (`~/.local/state/droidctl/droidctl.log` on Linux) unless
//! `DROIDCTL_LOG_FILE` says otherwise; it is rotated at start-up once it passes 10 MiB so it
//! stays bounded. `DROIDCTL_LOG` sets the filter (default `info`).

use std::fs::{self, File, OpenOptions};
use std::path::PathBuf;
use std::sync::Mutex;

const MAX_LOG_BYTES: u64 = 10 * 1024 * 1024;

/// Where the log goes.
pub fn log_path() -> PathBuf {
    match std::env::var_os("DROIDCTL_LOG_FILE") {
        Some(p) => PathBuf::from(p),
        None => default_log_path(),
    }
}

/// Where the log goes on this system when `DROIDCTL_LOG_FILE` does not say.
pub fn default_log_path() -> PathBuf {
    let dir = directories::ProjectDirs::from("", "", "droidctl")
        .map(|d| {
            d.state_dir()
                .unwrap_or_else(|| d.data_local_dir())
                .to_path_buf()
        })
        .unwrap_or_else(std::env::temp_dir);
    dir.join("droidctl.log")
}

fn open(path: &PathBuf) -> std::io::Result<File> {
    if let Some(dir) = path.parent() {
        fs::create_dir_all(dir)?;
    }
    if fs::metadata(path)
        .map(|m| m.len() > MAX_LOG_BYTES)
        .unwrap_or(false)
    {
        let _ = fs::rename(path, path.with_extension("log.1"));
    }
    OpenOptions::new().create(true).append(true).open(path)
}

/// Start logging to the file; returns its path, or why it could not be opened (the program
/// goes on without a log).
pub fn init() -> Result<PathBuf, String> {
    let path = log_path();
    let file = open(&path).map_err(|e| format!("cannot open log file {}: {e}", path.display()))?;
    let filter = tracing_subscriber::EnvFilter::try_from_env("DROIDCTL_LOG")
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info"));
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(Mutex::new(file))
        .with_ansi(false)
        .try_init()
        .map_err(|e| format!("cannot start logging: {e}"))?;
    tracing::info!(version = env!("CARGO_PKG_VERSION"), "droidctl started");
    Ok(path)
}
