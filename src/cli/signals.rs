//! The requests to end droidctl from outside, on every platform: Ctrl-C everywhere (when the
//! terminal is not in raw mode, which turns it into a key), SIGTERM and SIGHUP on Unix, and
//! Ctrl-Break and the console window closing on Windows. Whoever waits stops the droid first,
//! then exits.

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
                _ = int.recv() => "SIGINT",
                _ = term.recv() => "SIGTERM",
                _ = hup.recv() => "SIGHUP",
            },
            _ => std::future::pending().await,
        }
    }
    #[cfg(windows)]
    {
        use tokio::signal::windows::{ctrl_break, ctrl_c, ctrl_close};
        match (ctrl_c(), ctrl_break(), ctrl_close()) {
            (Ok(mut int), Ok(mut brk), Ok(mut close)) => tokio::select! {
                _ = int.recv() => "Ctrl-C",
                _ = brk.recv() => "Ctrl-Break",
                _ = close.recv() => "console closed",
            },
            _ => std::future::pending().await,
        }
    }
    #[cfg(not(any(unix, windows)))]
    {
        match tokio::signal::ctrl_c().await {
            Ok(()) => "Ctrl-C",
            Err(_) => std::future::pending().await,
        }
    }
}
