//! The built binary run with arguments, and the one-line usage-error contract, shared by the
//! CLI tests.

#![allow(dead_code)]

use std::process::{Child, Command, ExitStatus, Output, Stdio};
use std::time::{Duration, Instant};

pub fn droidctl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(args)
        // A panic would print a backtrace note: make sure it would show up.
        .env("RUST_BACKTRACE", "1")
        .env_remove("RUST_LOG")
        .output()
        .expect("run droidctl")
}

/// The binary run apart from the user's setup: the default configuration, its log in the
/// temporary directory as `log`, no standard input.
pub fn droidctl_isolated(args: &[&str], log: &str) -> Output {
    Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(args)
        .env("DROIDCTL_CONFIG", "/dev/null")
        .env("DROIDCTL_LOG_FILE", std::env::temp_dir().join(log))
        .stdin(Stdio::null())
        .output()
        .expect("run droidctl")
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8(o.stdout.clone()).expect("utf-8 stdout")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8(o.stderr.clone()).expect("utf-8 stderr")
}

/// Exit status 2, one line on stderr, nothing on stdout, no panic; the line.
pub fn usage_error(args: &[&str]) -> String {
    let o = droidctl(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert_eq!(stdout(&o), "", "{args:?}");
    assert!(err.ends_with('\n'), "{args:?}: {err:?}");
    assert_eq!(err.lines().count(), 1, "{args:?}: {err:?}");
    assert!(err.starts_with("droidctl: error: "), "{args:?}: {err:?}");
    for bad in ["panicked", "backtrace", "RUST_BACKTRACE", "thread '"] {
        assert!(!err.contains(bad), "{args:?}: {err:?}");
    }
    err
}

/// The child's status once it has ended, or `None` if it is still running after `limit`.
pub fn exited_within(child: &mut Child, limit: Duration) -> Option<ExitStatus> {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("the child's status") {
            return Some(status);
        }
        if start.elapsed() >= limit {
            return None;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// The child's status; panics saying `what` did not end if it runs past `limit`.
pub fn exit_within(child: &mut Child, limit: Duration, what: &str) -> ExitStatus {
    exited_within(child, limit).unwrap_or_else(|| {
        let _ = child.kill();
        panic!("{what} did not end within {limit:?}")
    })
}

/// The child's whole output; past `limit` it is killed and the test fails with its stderr,
/// saying `what` did not finish.
pub fn finish(mut child: Child, limit: Duration, what: &str) -> Output {
    if exited_within(&mut child, limit).is_none() {
        let _ = child.kill();
        let out = child.wait_with_output().expect("the killed child's output");
        panic!(
            "{what} did not finish within {limit:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    child.wait_with_output().expect("the child's output")
}
