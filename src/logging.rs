//! tracing to a log file (never to the terminal, which the TUI owns). The file lives in the
//! platform state directory (`~/.local/state/droidctl/droidctl.log` on Linux) unless
//! `DROIDCTL_LOG_FILE` says otherwise; it is rotated (to `droidctl.log.1`) once it passes
//! 10 MiB, at start-up and while droidctl runs, so it stays bounded however much is logged
//! (a Sphero Edu program's calls in the app, say). `DROIDCTL_LOG` sets the filter (default
//! `info`). At the usual place it is one of droidctl's own files ([`crate::own_file`]): a FIFO
//! or a symbolic link there is not written (the program goes on without a log); a file
//! `DROIDCTL_LOG_FILE` names is opened as it is.

use std::fs::{self, File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use tokio::time::{Duration, Instant};

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

/// Open the log at `path`, rotated first when past `max` bytes; `own`: droidctl's own, at the
/// usual place.
fn open(path: &Path, max: u64, own: bool) -> std::io::Result<File> {
    if let Some(dir) = path.parent() {
        fs::create_dir_all(dir)?;
    }
    // Only a regular file is rotated (a link is renamed itself, not its target).
    if fs::symlink_metadata(path)
        .map(|m| m.is_file() && m.len() > max)
        .unwrap_or(false)
    {
        let _ = fs::rename(path, path.with_extension("log.1"));
    }
    let mut options = OpenOptions::new();
    options.create(true).append(true);
    open_with(path, &options, own)
}

/// `options` on `path`, through [`crate::own_file`] when it is droidctl's own.
fn open_with(path: &Path, options: &OpenOptions, own: bool) -> std::io::Result<File> {
    if own {
        crate::own_file::open(path, options, crate::own_file::Links::Refuse)
    } else {
        options.open(path)
    }
}

/// The log file, rotated when a write would take it past its bound: the file and the one
/// before it hold at most twice the bound.
pub struct BoundedFile {
    path: PathBuf,
    /// `None` only while rotating (Windows renames no open file).
    file: Option<File>,
    written: u64,
    max: u64,
    /// droidctl's own file at the usual place ([`open`]'s `own`).
    own: bool,
}

impl BoundedFile {
    /// Open `path` for appending, rotated first if it is already past `max` bytes.
    pub fn open(path: &Path, max: u64, own: bool) -> std::io::Result<BoundedFile> {
        let file = open(path, max, own)?;
        let written = file.metadata().map(|m| m.len()).unwrap_or(0);
        Ok(BoundedFile {
            path: path.to_path_buf(),
            file: Some(file),
            written,
            max,
            own,
        })
    }
}

impl Write for BoundedFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let full = self.written > 0 && self.written.saturating_add(buf.len() as u64) > self.max;
        if full || self.file.is_none() {
            self.file = None;
            let _ = fs::rename(&self.path, self.path.with_extension("log.1"));
            // Not renamed (another process holds it open): start it again rather than grow.
            let mut options = OpenOptions::new();
            options.create(true).write(true).truncate(true);
            self.file = Some(open_with(&self.path, &options, self.own)?);
            self.written = 0;
        }
        let Some(file) = self.file.as_mut() else {
            return Ok(buf.len());
        };
        // A single write larger than the bound is cut to it.
        let keep = buf.len().min(self.max.max(1) as usize);
        let n = file.write(&buf[..keep])?;
        self.written += n as u64;
        // What was cut counts as written: the caller has nothing more to send.
        Ok(if n == keep { buf.len() } else { n })
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match self.file.as_mut() {
            Some(f) => f.flush(),
            None => Ok(()),
        }
    }
}

/// A bound on lines something logs: `burst` at once, then `per_second` on average; what is
/// held back is counted, to be said when lines are let through again.
#[derive(Debug)]
pub struct LineBudget {
    per_second: f64,
    burst: f64,
    tokens: f64,
    at: Option<Instant>,
    held: u64,
}

impl LineBudget {
    pub fn new(per_second: u32, burst: u32) -> LineBudget {
        LineBudget {
            per_second: per_second as f64,
            burst: burst as f64,
            tokens: burst as f64,
            at: None,
            held: 0,
        }
    }

    /// Whether a line may be logged at `now`: `Some(held)` with the lines held back since the
    /// last one let through, `None` to hold this one back.
    pub fn take(&mut self, now: Instant) -> Option<u64> {
        let since = self
            .at
            .map_or(Duration::ZERO, |at| now.saturating_duration_since(at));
        self.at = Some(now);
        self.tokens = (self.tokens + since.as_secs_f64() * self.per_second).min(self.burst);
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            Some(std::mem::take(&mut self.held))
        } else {
            self.held += 1;
            None
        }
    }
}

/// Start logging to the file; returns its path, or why it could not be opened (the program
/// goes on without a log).
pub fn init() -> Result<PathBuf, String> {
    let path = log_path();
    let own = std::env::var_os("DROIDCTL_LOG_FILE").is_none();
    let file = BoundedFile::open(&path, MAX_LOG_BYTES, own)
        .map_err(|e| format!("cannot open log file {}: {e}", path.display()))?;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_log_file_is_rotated_while_written_not_only_at_start() {
        let dir = std::env::temp_dir().join(format!("droidctl-log-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("droidctl.log");
        let mut f = BoundedFile::open(&path, 1000, false).unwrap();
        let line = [b'x'; 99];
        for _ in 0..1000 {
            f.write_all(&line).unwrap();
            f.write_all(b"\n").unwrap();
        }
        f.flush().unwrap();
        let len = |p: &Path| fs::metadata(p).map(|m| m.len()).unwrap_or(0);
        assert!(len(&path) <= 1000, "{}", len(&path));
        assert!(len(&path.with_extension("log.1")) <= 1000);
        assert!(len(&path.with_extension("log.1")) > 0, "rotated");
        // One write bigger than the bound is cut to it.
        f.write_all(&[b'y'; 5000]).unwrap();
        assert!(len(&path) <= 1000, "{}", len(&path));
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_line_budget_lets_a_burst_through_then_a_rate_and_counts_the_rest() {
        let t0 = Instant::now();
        let mut b = LineBudget::new(10, 5);
        let through = (0..100).filter(|_| b.take(t0).is_some()).count();
        assert_eq!(through, 5);
        // A second later: ten more, the first saying 95 were held back.
        let t1 = t0 + Duration::from_secs(1);
        assert_eq!(b.take(t1), Some(95));
        let more = (0..100).filter(|_| b.take(t1).is_some()).count();
        assert_eq!(more, 4, "the burst caps what a second saves");
    }

    #[cfg(unix)]
    #[test]
    /// Issue 37 point 13: a FIFO or a symbolic link at the usual place is not written.
    fn the_own_log_is_a_regular_file_or_nothing() {
        let dir = std::env::temp_dir().join(format!("droidctl-logging-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let target = dir.join("precious");
        fs::write(&target, "precious").unwrap();
        let link = dir.join("droidctl.log");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        assert!(open(&link, MAX_LOG_BYTES, true).is_err());
        assert_eq!(fs::read_to_string(&target).unwrap(), "precious");
        let fifo = dir.join("fifo.log");
        let at = fifo.clone();
        let opened = crate::own_file::testing::with_fifo(&fifo, "opening", move || {
            open(&at, MAX_LOG_BYTES, true).map(|_| ())
        });
        assert!(opened.is_err());
        let plain = dir.join("plain.log");
        open(&plain, MAX_LOG_BYTES, true).unwrap();
        open(&plain, MAX_LOG_BYTES, true).unwrap();
        let _ = fs::remove_dir_all(&dir);
    }
}
