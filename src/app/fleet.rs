//! Several droids: choosing the one the keys drive, mirror mode, every droid's per-second
//! rates and exit stops, and the forwarding of every live droid's session events into the
//! event loop's one channel. One droid is a fleet of one: the same code runs for it.
//!
//! The packet log is the fleet's: every droid's lines, each naming its droid. Mirror mode
//! gives every droid the same input; each droid's controller and family turn it into its own
//! commands (a Robi steers, a BB-8 rolls). The emergency stop and quitting reach every droid,
//! mirror or not.

use super::core::App;
use crate::family::Command;
use crate::session::{LinkState, LogEntry, SessionEvent, SessionHandle};
use std::time::Duration;

impl App {
    /// Drive droid `i` from now on (its gauges, map and scope on screen, as it was left; the
    /// log stays). Every held key is let go by the caller's place check.
    pub fn choose(&mut self, i: usize) {
        if i >= self.len() || i == self.chosen() {
            return;
        }
        self.state.chosen = i;
        let name = self.state.droid().droid_name.clone();
        // The droid left behind gets no more input (its deadman stops it) unless mirrored.
        self.control(false);
        if self.mirroring() {
            self.hint(format!("driving {name} (mirror: all droids)"));
        } else {
            self.hint(format!("driving {name}"));
        }
    }

    /// The next (or previous) droid.
    pub fn choose_next(&mut self, forward: bool) {
        let n = self.len();
        if n < 2 {
            return self.hint("one droid: nothing to choose (name several with --name or --sim)");
        }
        let c = self.chosen();
        self.choose(if forward {
            (c + 1) % n
        } else {
            (c + n - 1) % n
        });
    }

    pub fn toggle_mirror(&mut self) {
        if self.len() < 2 {
            return self.hint("one droid: nothing to mirror (name several with --name or --sim)");
        }
        self.state.mirror = !self.state.mirror;
        // Whoever lost the input stops now.
        self.control(false);
        self.hint(if self.state.mirror {
            "mirror on: every droid gets the same control"
        } else {
            "mirror off: only the chosen droid is driven"
        });
    }

    /// Per-second rates and counters of every droid; returns whether any changed.
    pub fn sample_rates(&mut self, at: Duration) -> bool {
        let mut changed = false;
        for (io, view) in self.io.iter_mut().zip(self.state.droids.iter_mut()) {
            let stats = match (&io.session, &io.player) {
                (Some(s), _) => s.stats(),
                (None, Some(p)) => p.replay.mirror().stats(),
                (None, None) => continue,
            };
            if let Some(rates) = io.rates.sample(stats, at)
                && (view.rate_in, view.rate_out) != rates
            {
                (view.rate_in, view.rate_out) = rates;
                changed = true;
            }
            if view.stats != stats {
                view.stats = stats;
                changed = true;
            }
        }
        changed
    }

    /// The stop each droid is sent on exit (speed 0 at the heading its controller last
    /// commanded), in fleet order; each is also set in its drive slot now.
    pub fn stop_all_for_exit(&mut self) -> Vec<Command> {
        let mut stops = Vec::with_capacity(self.len());
        self.each(|d| stops.push(d.stop_for_exit()));
        stops
    }

    /// An event of droid `i` (forwarded from its session).
    pub fn on_droid_event(&mut self, i: usize, e: DroidEvent) {
        let at = self.now();
        match e {
            DroidEvent::Session(SessionEvent::Notification(n)) => {
                if let Some(mut d) = self.droid(i) {
                    d.on_notification(&n, at);
                }
            }
            DroidEvent::Session(SessionEvent::BadNotification { name, reason }) => {
                tracing::warn!(droid = i, name, %reason, "malformed notification");
            }
            DroidEvent::Log(entry) => {
                if let Some(mut d) = self.droid(i) {
                    d.on_log(&entry);
                }
            }
            DroidEvent::LogLagged(n) => self.state.log.dropped += n,
            DroidEvent::Link(s) => {
                if let Some(mut d) = self.droid(i) {
                    d.on_link(s);
                }
                self.control(false);
            }
            DroidEvent::Battery(v) => {
                if let Some(mut d) = self.droid(i) {
                    d.on_battery(v);
                }
            }
        }
    }
}

/// What a droid's session says, forwarded to the event loop.
pub enum DroidEvent {
    Session(SessionEvent),
    Log(LogEntry),
    /// Log lines lost because the loop fell behind.
    LogLagged(u64),
    Link(LinkState),
    Battery(f32),
}

/// Bound of the channel carrying every droid's events.
const FORWARD_CAPACITY: usize = 4096;

/// Forward every live droid's session events, log, link and battery readings into one
/// channel, tagged with the droid's index. Returns the channel and the forwarding tasks.
pub(super) fn forward(
    droids: &[(
        SessionHandle,
        &'static dyn crate::family::Family,
        crate::model::Model,
    )],
) -> (
    tokio::sync::mpsc::Receiver<(usize, DroidEvent)>,
    Vec<tokio::task::JoinHandle<()>>,
) {
    use tokio::sync::{broadcast, mpsc};
    let (tx, rx) = mpsc::channel(FORWARD_CAPACITY);
    let mut tasks = Vec::new();
    for (i, (s, family, model)) in droids.iter().enumerate() {
        let (s, t, family, model) = (s.clone(), tx.clone(), *family, *model);
        // Subscribed now, before the loop starts: nothing said after this is missed.
        let mut ev = s.subscribe();
        let mut log = s.subscribe_log();
        let mut link = s.watch_state();
        tasks.push(tokio::spawn(async move {
            let (poller, mut battery) = super::battery::spawn(Some(s.clone()), family, model);
            let _poller = AbortOnDrop(poller);
            // The link as it is now, then every change.
            let now = link.borrow_and_update().clone();
            if t.send((i, DroidEvent::Link(now))).await.is_err() {
                return;
            }
            let (mut ev_open, mut log_open, mut link_open, mut bat_open) = (true, true, true, true);
            while ev_open || log_open || link_open || bat_open {
                let e = tokio::select! {
                    e = ev.recv(), if ev_open => match e {
                        Ok(e) => DroidEvent::Session(e),
                        Err(broadcast::error::RecvError::Lagged(n)) => {
                            tracing::warn!(droid = i, n, "notifications lagged");
                            continue
                        }
                        Err(broadcast::error::RecvError::Closed) => { ev_open = false; continue }
                    },
                    e = log.recv(), if log_open => match e {
                        Ok(e) => DroidEvent::Log(e),
                        Err(broadcast::error::RecvError::Lagged(n)) => DroidEvent::LogLagged(n),
                        Err(broadcast::error::RecvError::Closed) => { log_open = false; continue }
                    },
                    r = link.changed(), if link_open => match r {
                        Ok(()) => DroidEvent::Link(link.borrow_and_update().clone()),
                        Err(_) => {
                            link_open = false;
                            DroidEvent::Link(LinkState::Closed { reason: Some("the session ended".into()) })
                        }
                    },
                    v = battery.recv(), if bat_open => match v {
                        Some(v) => DroidEvent::Battery(v),
                        None => { bat_open = false; continue }
                    },
                };
                if t.send((i, e)).await.is_err() {
                    return;
                }
            }
        }));
    }
    (rx, tasks)
}

/// Aborts a task when dropped (a forwarder's battery poller ends with it).
struct AbortOnDrop(tokio::task::JoinHandle<()>);

impl Drop for AbortOnDrop {
    fn drop(&mut self) {
        self.0.abort();
    }
}
