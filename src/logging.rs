//! tracing to a log file (never to the terminal, which the TUI owns). The file lives in the
//! platform state directory (`~/.local/state/droidctl/droidctl.log` on Linux) unless
//! `DROIDCTL_LOG_FILE` says otherwise; it is rotated at start-up once it passes 10 MiB so it
//! stays bounded. `DROIDCTL_LOG` sets the filter (default `info`). At the usual place it is
//! one of droidctl's own files ([`crate::own_file`]): a FIFO or a symbolic link there is not
//! written (the program goes on without a log); a file `DROIDCTL_LOG_FILE` names is opened as
//! it is.

use std::fs::{self, File, OpenOptions};
use std::path::{Path, PathBuf};
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

/// Open the log at `path`; `own`: droidctl's own, at the usual place.
fn open(path: &Path, own: bool) -> std::io::Result<File> {
    if let Some(dir) = path.parent() {
        fs::create_dir_all(dir)?;
    }
    // Only a regular file is rotated (a link is renamed itself, not its target).
    if fs::symlink_metadata(path)
        .map(|m| m.is_file() && m.len() > MAX_LOG_BYTES)
        .unwrap_or(false)
    {
        let _ = fs::rename(path, path.with_extension("log.1"));
    }
    let mut options = OpenOptions::new();
    options.create(true).append(true);
    if own {
        crate::own_file::open(path, &options, crate::own_file::Links::Refuse)
    } else {
        options.open(path)
    }
}

/// Start logging to the file; returns its path, or why it could not be opened (the program
/// goes on without a log).
pub fn init() -> Result<PathBuf, String> {
    let path = log_path();
    let own = std::env::var_os("DROIDCTL_LOG_FILE").is_none();
    let file =
        open(&path, own).map_err(|e| format!("cannot open log file {}: {e}", path.display()))?;
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

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    /// Issue 37 point 13: a FIFO or a symbolic link at the usual place is not written.
    #[test]
    fn the_own_log_is_a_regular_file_or_nothing() {
        let dir = std::env::temp_dir().join(format!("droidctl-logging-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let target = dir.join("precious");
        fs::write(&target, "precious").unwrap();
        let link = dir.join("droidctl.log");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        assert!(open(&link, true).is_err());
        assert_eq!(fs::read_to_string(&target).unwrap(), "precious");
        let fifo = dir.join("fifo.log");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(made.success());
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let _ = tx.send(open(&fifo, true).map(|_| ()));
        });
        let opened = rx
            .recv_timeout(std::time::Duration::from_secs(5))
            .expect("opening blocked on the FIFO");
        assert!(opened.is_err());
        let plain = dir.join("plain.log");
        open(&plain, true).unwrap();
        open(&plain, true).unwrap();
        let _ = fs::remove_dir_all(&dir);
    }
}
