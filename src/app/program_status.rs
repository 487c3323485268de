//! The Sphero Edu program running beside the app (`droidctl --program P.js`), as the screen
//! shows it (issue 38 point 10): its name, state and the line it waits on in the status bar,
//! its drive in the gauges (input "program" instead of "deadman"), and its end or error in a
//! banner that stays until a key.
//!
//! The runtime publishes each droid's program through a `watch` ([`crate::edu::progress`]);
//! [`forward`] turns every droid's into one bounded channel the event loop reads, so one task
//! owns the state, as for every other input.

use super::core::App;
pub use super::view::program::{ProgramView, end_words, file_name, shown, state_words};
use crate::edu::progress::ProgramStatus;
use tokio::sync::{mpsc, watch};

/// Each droid's program status, by fleet index (droids without a program have none).
pub type ProgramFeeds = Vec<(usize, watch::Receiver<ProgramStatus>)>;

/// Statuses waiting for the loop at most: each is a droid's latest, so a full channel only
/// delays a forwarder, which then sends the newest.
const CAPACITY: usize = 32;

/// Every droid's program status into one channel, tagged with its index; and the tasks.
pub(super) fn forward(
    feeds: ProgramFeeds,
) -> (
    mpsc::Receiver<(usize, ProgramStatus)>,
    Vec<tokio::task::JoinHandle<()>>,
) {
    let (tx, rx) = mpsc::channel(CAPACITY);
    let tasks = feeds
        .into_iter()
        .map(|(i, mut feed)| {
            let tx = tx.clone();
            tokio::spawn(async move {
                // The status as it is now, then every change until the runtime is gone.
                loop {
                    let s = feed.borrow_and_update().clone();
                    if tx.send((i, s)).await.is_err() || feed.changed().await.is_err() {
                        return;
                    }
                }
            })
        })
        .collect();
    (rx, tasks)
}

impl App {
    /// Droid `i`'s program changed: the status bar, the gauges and, at its end, the banner.
    pub(super) fn on_program(&mut self, i: usize, status: ProgramStatus) {
        let Some(mut d) = self.droid(i) else {
            return;
        };
        let view = ProgramView {
            status,
            acknowledged: false,
        };
        if d.view.program.as_ref() == Some(&view) {
            return;
        }
        d.view.program = Some(view);
        *d.dirty = true;
        // The gauges follow the program's drive now, not at the next control tick.
        d.apply(Vec::new());
    }

    /// A key was pressed: every end banner is seen. The key still does what it does (the
    /// emergency stop is never taken by a banner).
    pub(super) fn acknowledge_programs(&mut self) {
        for d in &mut self.state.droids {
            if let Some(p) = &mut d.program
                && p.banner()
            {
                p.acknowledged = true;
                self.dirty = true;
            }
        }
    }
}
