//! A child's output, read line by line on a thread of its own so the child never blocks on
//! a full pipe, and looked at from the test whenever it likes: what was said so far, or a
//! bounded wait for a line.

// Shared by tests some of which are Unix-only: on other targets parts go unused.
#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The lines read so far from one of a child's pipes, and whether the pipe has ended.
#[derive(Clone, Default)]
pub struct Lines(Arc<Mutex<(Vec<String>, bool)>>);

impl Lines {
    /// Read `from` until it ends, keeping every line.
    pub fn collect(from: impl Read + Send + 'static) -> Lines {
        let lines = Lines::default();
        let keep = lines.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(from).lines() {
                let Ok(line) = line else { break };
                keep.0
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .0
                    .push(line);
            }
            keep.0.lock().unwrap_or_else(|e| e.into_inner()).1 = true;
        });
        lines
    }

    /// Every line so far.
    pub fn all(&self) -> Vec<String> {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).0.clone()
    }

    /// Wait (up to `limit`) until the pipe has ended, so that [`Self::all`] holds everything
    /// the child said: a child that has exited may still have lines in the pipe that this
    /// side has not read yet. Whether it ended.
    pub fn wait_end(&self, limit: Duration) -> bool {
        let start = Instant::now();
        loop {
            if self.0.lock().unwrap_or_else(|e| e.into_inner()).1 {
                return true;
            }
            if start.elapsed() >= limit {
                return false;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// Every line so far, one text.
    pub fn text(&self) -> String {
        self.all().join("\n")
    }

    /// The first line containing `what`; panics with everything said after `limit`.
    pub fn wait_for(&self, what: &str, limit: Duration) -> String {
        let start = Instant::now();
        loop {
            if let Some(l) = self.all().into_iter().find(|l| l.contains(what)) {
                return l;
            }
            assert!(
                start.elapsed() < limit,
                "no {what:?} within {limit:?}; the child said:\n{}",
                self.text()
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

/// The first line of `from` (a child's stdout), read on a thread and waited for up to
/// `limit`; `None` when none came. The rest of `from` is read and handed to the receiver,
/// so a child that says more than one line never blocks.
pub fn first_line(
    from: impl Read + Send + 'static,
    limit: Duration,
) -> (Option<String>, std::sync::mpsc::Receiver<String>) {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut out = BufReader::new(from);
        let mut first = String::new();
        let _ = out.read_line(&mut first);
        let _ = tx.send(first);
        let mut rest = String::new();
        let _ = out.read_to_string(&mut rest);
        let _ = tx.send(rest);
    });
    (rx.recv_timeout(limit).ok(), rx)
}
