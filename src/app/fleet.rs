//! The app on a fleet. [`App`] keeps the driven droid's screen, session and controller in its
//! own fields, as with one droid; every other droid is [`Parked`] here with its own
//! [`AppState`], session and controller (so its own deadman). Choosing another droid swaps
//! it in; an event for a parked droid is handled by swapping it in for that call
//! ([`App::with_droid`]), so every handler is the one-droid handler.
//!
//! The packet log is the fleet's: every droid's lines, each naming its droid, in the screen
//! shown (it stays put when another droid is chosen). Mirror mode gives every droid the
//! same input; each droid's controller and family turn it into its own commands (a Robi
//! steers, a BB-8 rolls). The emergency stop and quitting reach every droid, mirror or not.

use super::core::App;
use super::rates::Rates;
use super::roster::{Roster, RosterEntry};
use super::state::AppState;
use crate::family::{Command, Family};
use crate::session::{LinkState, LogEntry, SessionHandle};
use crate::teleop::control::Controller;
use std::sync::Arc;
use std::time::Duration;

/// A droid of the fleet that the keys do not drive right now.
pub(super) struct Parked {
    pub state: AppState,
    pub session: Option<SessionHandle>,
    /// In replay, its capture's player.
    pub player: Option<super::player::Player>,
    pub controller: Controller,
    pub family: &'static dyn Family,
}

/// What the app keeps of a fleet beyond the driven droid.
pub(super) struct FleetSide {
    /// By droid; `None` at `chosen`, whose parts live in [`App`].
    pub parked: Vec<Option<Parked>>,
    pub chosen: usize,
    pub mirror: bool,
    pub names: Vec<Arc<str>>,
    pub rates: Vec<Rates>,
}

impl App {
    /// The number of droids (1 without a fleet).
    pub fn droids(&self) -> usize {
        self.fleet.as_ref().map_or(1, |f| f.parked.len())
    }

    /// Run `f` on droid `i` as if it were the only one: its state, session, controller and
    /// family are swapped in for the call. Nested calls run on the droid swapped in.
    pub fn with_droid<R>(&mut self, i: usize, f: impl FnOnce(&mut App) -> R) -> R {
        let Some(mut side) = self.fleet.take() else {
            return f(self);
        };
        // Its log lines go to the fleet's log (on screen), named.
        let tag = std::mem::replace(&mut self.log_droid, side.names.get(i).cloned());
        let r = match side.parked.get_mut(i).and_then(Option::take) {
            Some(mut p) if i != side.chosen => {
                self.swap_in(&mut p);
                // The fleet's log stays on screen.
                std::mem::swap(&mut self.state.log, &mut p.state.log);
                let r = f(self);
                std::mem::swap(&mut self.state.log, &mut p.state.log);
                self.swap_in(&mut p);
                side.parked[i] = Some(p);
                r
            }
            _ => f(self),
        };
        self.log_droid = tag;
        self.fleet = Some(side);
        r
    }

    fn swap_in(&mut self, p: &mut Parked) {
        std::mem::swap(&mut self.state, &mut p.state);
        std::mem::swap(&mut self.session, &mut p.session);
        std::mem::swap(&mut self.player, &mut p.player);
        std::mem::swap(&mut self.controller, &mut p.controller);
        std::mem::swap(&mut self.family, &mut p.family);
    }

    /// `f` on every droid but the driven one, each swapped in; `driven` says whether the keys
    /// and the pad drive it meanwhile (mirror mode).
    pub fn each_other(&mut self, mut f: impl FnMut(&mut App)) {
        let (n, chosen, mirror) = match &self.fleet {
            Some(s) => (s.parked.len(), s.chosen, s.mirror),
            None => return,
        };
        for i in (0..n).filter(|i| *i != chosen) {
            self.with_droid(i, |a| {
                a.driven = mirror;
                f(a);
                a.driven = true;
            });
        }
    }

    /// The droid the keys drive (0 without a fleet).
    pub fn chosen(&self) -> usize {
        self.fleet.as_ref().map_or(0, |s| s.chosen)
    }

    /// Whether mirror mode is on.
    pub fn mirroring(&self) -> bool {
        self.fleet.as_ref().is_some_and(|s| s.mirror)
    }

    /// Drive droid `i` from now on (its gauges, map and hints on screen; the log stays).
    pub fn choose(&mut self, i: usize) {
        let Some(mut side) = self.fleet.take() else {
            return;
        };
        if i >= side.parked.len() || i == side.chosen {
            self.fleet = Some(side);
            return;
        }
        let Some(mut next) = side.parked[i].take() else {
            self.fleet = Some(side);
            return;
        };
        // The screen's own settings and the fleet's log stay on screen.
        let s = &mut next.state;
        std::mem::swap(&mut s.log, &mut self.state.log);
        s.focus = self.state.focus;
        s.overlay = self.state.overlay.clone();
        s.gamepad = self.state.gamepad.clone();
        s.keyboard = self.state.keyboard;
        self.swap_in(&mut next);
        side.parked[side.chosen] = Some(next);
        side.chosen = i;
        let name = side.names[i].clone();
        let mirror = side.mirror;
        self.fleet = Some(side);
        // The droid left behind gets no more input (its deadman stops it) unless mirrored.
        self.control(false);
        if mirror {
            self.hint(format!("driving {name} (mirror: all droids)"));
        } else {
            self.hint(format!("driving {name}"));
        }
    }

    /// The next (or previous) droid.
    pub fn choose_next(&mut self, forward: bool) {
        let Some(side) = &self.fleet else {
            return self.hint("one droid: nothing to choose (name several with --name or --sim)");
        };
        let n = side.parked.len();
        let i = if forward {
            (side.chosen + 1) % n
        } else {
            (side.chosen + n - 1) % n
        };
        self.choose(i);
    }

    pub fn toggle_mirror(&mut self) {
        let Some(side) = &mut self.fleet else {
            return self.hint("one droid: nothing to mirror (name several with --name or --sim)");
        };
        side.mirror = !side.mirror;
        let on = side.mirror;
        // Whoever lost the input stops now.
        self.control(false);
        self.hint(if on {
            "mirror on: every droid gets the same control"
        } else {
            "mirror off: only the chosen droid is driven"
        });
    }

    /// A packet-log entry of droid `i`: into the fleet's log, named.
    pub fn on_droid_log(&mut self, i: usize, entry: &LogEntry) {
        self.with_droid(i, |a| a.on_log(entry));
    }

    /// Per-second rates of every droid; returns whether any changed.
    pub fn sample_fleet_rates(&mut self, at: Duration) -> bool {
        let Some(mut side) = self.fleet.take() else {
            return false;
        };
        let mut changed = false;
        for i in 0..side.parked.len() {
            let stats = self.with_droid_stats(&side, i);
            if let Some(st) = stats
                && let Some((rin, rout)) = side.rates[i].sample(st, at)
            {
                let state = match side.parked[i].as_mut() {
                    Some(p) => &mut p.state,
                    None => &mut self.state,
                };
                if (state.rate_in, state.rate_out) != (rin, rout) {
                    (state.rate_in, state.rate_out) = (rin, rout);
                    changed = true;
                }
            }
        }
        self.fleet = Some(side);
        changed
    }

    fn with_droid_stats(&self, side: &FleetSide, i: usize) -> Option<crate::session::SessionStats> {
        match side.parked.get(i)? {
            Some(p) => p.session.as_ref().map(SessionHandle::stats),
            None => self.session.as_ref().map(SessionHandle::stats),
        }
    }

    /// The roster strip's view of the fleet now.
    pub fn roster(&self) -> Option<Roster> {
        let side = self.fleet.as_ref()?;
        let droids = side
            .parked
            .iter()
            .map(|p| {
                let (state, control) = match p {
                    Some(p) => (&p.state, p.controller.view()),
                    None => (&self.state, self.controller.view()),
                };
                let t = &state.telemetry;
                RosterEntry {
                    name: state.droid_name.clone(),
                    model: state.model,
                    link: state.link.clone(),
                    battery_v: t.battery_v,
                    rate_in: state.rate_in,
                    rate_out: state.rate_out,
                    moving: control.speed > 0 && !control.estop,
                    position: t.x_cm.zip(t.y_cm),
                }
            })
            .collect();
        Some(Roster {
            droids,
            chosen: side.chosen,
            mirror: side.mirror,
        })
    }

    /// The stop each droid is sent on exit (speed 0 at the heading its controller last
    /// commanded), in fleet order; each is also set in its droid's drive slot now.
    pub fn stop_all_for_exit(&mut self) -> Vec<Command> {
        let mut stops = Vec::with_capacity(self.droids());
        for i in 0..self.droids() {
            let stop = self.with_droid(i, |a| {
                let stop = a.family.drive(0, a.controller.view().heading, false);
                a.set(crate::session::Slot::Drive, stop.clone());
                stop
            });
            stops.push(stop);
        }
        stops
    }

    /// A link-state change of droid `i`.
    pub fn on_droid_link(&mut self, i: usize, s: LinkState) {
        self.with_droid(i, |a| a.on_link(s));
    }
}

/// What a parked droid's session says, forwarded to the event loop.
pub enum DroidEvent {
    Session(crate::session::SessionEvent),
    Log(LogEntry),
    /// Log lines lost because the loop fell behind.
    LogLagged(u64),
    Link(LinkState),
    Battery(f32),
}

/// Bound of the channel carrying every parked droid's events.
const FORWARD_CAPACITY: usize = 4096;

/// Set the app up for `fleet` (its first droid is already in the app): park the others and
/// start forwarding their events. Returns the channel and the forwarding tasks.
pub(super) fn attach(
    app: &mut App,
    fleet: &crate::fleet::Fleet,
    config: &crate::config::Config,
    log_path: Option<std::path::PathBuf>,
) -> (
    tokio::sync::mpsc::Receiver<(usize, DroidEvent)>,
    Vec<tokio::task::JoinHandle<()>>,
) {
    use tokio::sync::{broadcast, mpsc};
    let (tx, rx) = mpsc::channel(FORWARD_CAPACITY);
    let mut tasks = Vec::new();
    let mut parked = vec![None];
    for (i, m) in fleet.members().iter().enumerate().skip(1) {
        let mut state = AppState::new(m.model, m.name.clone());
        state.log_path = log_path.clone();
        state.keyboard = app.state.keyboard;
        state.gamepad = app.state.gamepad.clone();
        state.help = app.state.help.clone();
        state.help_nav = app.state.help_nav.clone();
        for n in m.session.greeting() {
            state.telemetry.apply(&n, Duration::ZERO);
        }
        state.link = m.session.state();
        let controller = Controller::with_family(config.control.clone(), m.family);
        state.control = controller.view().clone();
        parked.push(Some(Parked {
            state,
            session: Some(m.session.clone()),
            player: None,
            controller,
            family: m.family,
        }));
        // Its session's events, log, link and battery into the one channel.
        let (s, t, family, model) = (m.session.clone(), tx.clone(), m.family, m.model);
        tasks.push(tokio::spawn(async move {
            let mut ev = s.subscribe();
            let mut log = s.subscribe_log();
            let mut link = s.watch_state();
            let (poller, mut battery) = super::battery::spawn(Some(s.clone()), family, model);
            let _poller = AbortOnDrop(poller);
            let (mut ev_open, mut log_open, mut link_open, mut bat_open) = (true, true, true, true);
            while ev_open || log_open || link_open || bat_open {
                let e = tokio::select! {
                    e = ev.recv(), if ev_open => match e {
                        Ok(e) => DroidEvent::Session(e),
                        Err(broadcast::error::RecvError::Lagged(_)) => continue,
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
    app.fleet = Some(FleetSide {
        parked,
        chosen: 0,
        mirror: false,
        names: fleet
            .members()
            .iter()
            .map(|m| Arc::from(m.name.as_str()))
            .collect(),
        rates: fleet
            .members()
            .iter()
            .map(|m| Rates::new(m.session.stats(), app.clock()))
            .collect(),
    });
    (rx, tasks)
}

/// Aborts a task when dropped (a forwarder's battery poller ends with it).
struct AbortOnDrop(tokio::task::JoinHandle<()>);

impl Drop for AbortOnDrop {
    fn drop(&mut self) {
        self.0.abort();
    }
}

impl App {
    /// An event of droid `i` (forwarded from its session).
    pub fn on_droid_event(&mut self, i: usize, e: DroidEvent) {
        match e {
            DroidEvent::Session(crate::session::SessionEvent::Notification(n)) => {
                let at = self.now();
                self.with_droid(i, |a| a.on_notification(&n, at));
            }
            DroidEvent::Session(crate::session::SessionEvent::BadNotification { name, reason }) => {
                tracing::warn!(droid = i, name, %reason, "malformed notification");
            }
            DroidEvent::Log(entry) => self.on_droid_log(i, &entry),
            DroidEvent::LogLagged(n) => self.state.log.dropped += n,
            DroidEvent::Link(s) => self.on_droid_link(i, s),
            DroidEvent::Battery(v) => self.with_droid(i, |a| a.on_battery(v)),
        }
    }
}

/// Set the app up for replaying a fleet's capture (its first droid's replay is already in
/// the app): park the others, each with its own player started now.
pub(super) fn attach_replays(
    app: &mut App,
    others: Vec<(crate::capture::replay::Replay, String)>,
    config: &crate::config::Config,
    file: &str,
) {
    let mut parked = vec![None];
    let mut names = vec![Arc::from(app.state.droid_name.as_str())];
    for (replay, name) in others {
        let model = replay.model();
        let family = crate::family::for_model(model);
        let mut state = AppState::new(model, name.clone());
        state.help = app.state.help.clone();
        state.help_nav = app.state.help_nav.clone();
        state.keyboard = app.state.keyboard;
        state.gamepad = app.state.gamepad.clone();
        names.push(Arc::from(name.as_str()));
        parked.push(Some(Parked {
            state,
            session: None,
            player: Some(super::player::Player::new(
                replay,
                file.to_string(),
                app.start,
            )),
            controller: Controller::with_family(config.control.clone(), family),
            family,
        }));
    }
    let rates = parked
        .iter()
        .map(|_| Rates::new(Default::default(), Duration::ZERO))
        .collect();
    app.fleet = Some(FleetSide {
        parked,
        chosen: 0,
        mirror: false,
        names,
        rates,
    });
}
