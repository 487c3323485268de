//! The requests to end droidctl from outside, on every platform: Ctrl-C everywhere (when the
//! terminal is not in raw mode, which turns it into a key), SIGTERM and SIGHUP on Unix, and
//! Ctrl-Break and the console window closing on Windows. Whoever waits stops the droid first,
//! then exits.

use std::sync::atomic::{AtomicI32, Ordering};

/// The exit status a signal that ended a command asks for (128 + its number on Unix, the
/// shells' convention: Ctrl+c 130), or 0 while none has come. Set by [`terminated`] when it
/// returns, read by [`interrupted_status`].
static INTERRUPTED: AtomicI32 = AtomicI32::new(0);

/// The status a command that failed because it was interrupted exits with (`Some(130)` after
/// Ctrl+c), once the droids are stopped; `None` when no signal ended it.
pub fn interrupted_status() -> Option<i32> {
    match INTERRUPTED.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s),
    }
}

fn record(status: i32) {
    INTERRUPTED.store(status, Ordering::SeqCst);
}

/// Wait until the process is asked to end; returns what asked, for the message
/// (`SIGTERM: stopped the droid and exited`). Never returns when the signals cannot be watched.
///
/// On Windows, closing the console gives the process a few seconds (Windows' limit is 5 s)
/// before it is killed: enough for the stop, which is bounded by 3 s.
pub async fn terminated() -> &'static str {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{SignalKind, signal};
        match (
            signal(SignalKind::interrupt()),
            signal(SignalKind::terminate()),
            signal(SignalKind::hangup()),
        ) {
            (Ok(mut int), Ok(mut term), Ok(mut hup)) => tokio::select! {
                _ = int.recv() => { record(128 + 2); "SIGINT" },
                _ = term.recv() => { record(128 + 15); "SIGTERM" },
                _ = hup.recv() => { record(128 + 1); "SIGHUP" },
            },
            _ => std::future::pending().await,
        }
    }
    #[cfg(windows)]
    {
        use tokio::signal::windows::{ctrl_break, ctrl_c, ctrl_close};
        match (ctrl_c(), ctrl_break(), ctrl_close()) {
            (Ok(mut int), Ok(mut brk), Ok(mut close)) => tokio::select! {
                // Windows has no signal numbers: 130 for each, as for Ctrl+c elsewhere.
                _ = int.recv() => { record(130); "Ctrl-C" },
                _ = brk.recv() => { record(130); "Ctrl-Break" },
                _ = close.recv() => { record(130); "console closed" },
            },
            _ => std::future::pending().await,
        }
    }
    #[cfg(not(any(unix, windows)))]
    {
        match tokio::signal::ctrl_c().await {
            Ok(()) => {
                record(130);
                "Ctrl-C"
            }
            Err(_) => std::future::pending().await,
        }
    }
}
