//! One droid of the app: its IO half ([`DroidIo`]: where its commands go and what turns
//! input into them) and the handle its handlers run on ([`DroidMut`]: its view and IO, and
//! what it shares with the rest of the app — the hint line, the packet log, the sample
//! files). A droid's events (notifications, log lines, link changes, battery readings) and
//! its control tick are handled here, on the droid they belong to; the control loop's
//! intents are lowered here by the droid's family (motion into the drive slot, the dome into
//! the head slot, the e-stop's stop into the session's urgent path).

use super::packet_log::{LogLine, PacketLog};
use super::player::Player;
use super::rates::Rates;
use super::state::{DroidState, HINT_TIME, Hint};
use crate::family::intent::{Intent, Unsupported};
use crate::family::{Command, Family};
use crate::protocol::notify::Notification;
use crate::protocol::wire::LegAction;
use crate::session::{LinkState, LogEntry, SessionHandle, Slot};
use crate::teleop::control::{Controller, DroidView, Inputs, Out};
use std::sync::Arc;
use std::time::Duration;
use tokio::time::Instant;

/// Where a droid's commands go and what makes them.
pub(super) struct DroidIo {
    /// The live session; `None` in replay.
    pub session: Option<SessionHandle>,
    /// The capture played back, in replay.
    pub player: Option<Player>,
    pub controller: Controller,
    pub family: &'static dyn Family,
    /// Its name, for its packet-log lines and sample rows in a fleet.
    pub name: Arc<str>,
    pub rates: Rates,
    /// When its control loop last ticked.
    pub last_tick: Instant,
    /// A remembered streaming rate to ask for once connected.
    pub pending_rate: Option<u16>,
}

/// A droid and what its handlers share with the app.
pub(super) struct DroidMut<'a> {
    pub view: &'a mut DroidState,
    pub io: &'a mut DroidIo,
    pub log: &'a mut PacketLog,
    pub hint: &'a mut Option<Hint>,
    /// The screen's clock (hints run on it).
    pub screen_now: &'a mut Duration,
    /// Time since the app started.
    pub now: Duration,
    pub dirty: &'a mut bool,
    pub samples: &'a mut Option<crate::mission::csv::SampleFiles>,
    /// Several droids: log lines and sample rows name theirs.
    pub fleet: bool,
    pub tripod_on_connect: bool,
}

impl DroidMut<'_> {
    /// Its clock: capture time in replay, else time since the start.
    pub fn clock(&self) -> Duration {
        match &self.io.player {
            Some(p) => p.clock(Instant::now()),
            None => self.now,
        }
    }

    pub fn hint(&mut self, text: impl Into<String>) {
        let at = self.clock();
        *self.screen_now = at;
        *self.hint = Some(Hint::after(self.hint.as_ref(), text.into(), at, HINT_TIME));
        *self.dirty = true;
    }

    pub fn droid_view(&self) -> DroidView {
        let m = self.view.model;
        DroidView {
            connected: self.view.link == LinkState::Connected,
            has_legs: m.has_legs(),
            has_dome: m.has_dome(),
            can_aim: m.can_aim(),
            stance: self.view.telemetry.stance,
        }
    }

    /// A notification, from the session or the replay, received at `at`.
    pub fn on_notification(&mut self, n: &Notification, at: Duration) {
        self.view.telemetry.apply(n, at);
        *self.dirty = true;
        if matches!(n, Notification::Sensors(_) | Notification::RobiFrame(_))
            && let Some(files) = self.samples.as_mut()
        {
            let s = crate::mission::sample_of(&self.view.telemetry, at.as_millis() as u64);
            // A fleet's rows name their droid.
            let written = if self.fleet {
                files.write_for(&self.io.name, &s)
            } else {
                files.write(&s)
            };
            if let Err(e) = written {
                *self.samples = None;
                self.hint(format!("telemetry file: {e}; no more samples are written"));
            }
        }
    }

    /// A packet-log entry, from the session or the replay.
    pub fn on_log(&mut self, entry: &LogEntry) {
        if entry.dir == crate::session::Direction::Out
            && let crate::session::LogItem::Packet {
                packet: crate::family::Packet::V2(p),
                ..
            } = &entry.item
        {
            self.view.matrix.sent(p.did, p.cid, &p.data);
        }
        let line = if self.fleet {
            LogLine::from_droid_entry(entry, self.io.name.clone())
        } else {
            LogLine::from_entry(entry)
        };
        self.log.push(line);
        *self.dirty = true;
    }

    pub fn on_battery(&mut self, volts: f32) {
        self.view.telemetry.battery_v = Some(volts);
        *self.dirty = true;
    }

    /// Its link changed: a lost link forgets what was sent; a (re)connect that asks for
    /// tripod shows the stance as requested.
    pub fn on_link(&mut self, s: LinkState) {
        let connected = s == LinkState::Connected && self.view.link != LinkState::Connected;
        if s != LinkState::Connected {
            self.io.controller.link_lost();
        } else if connected && self.tripod_on_connect && self.view.model.has_legs() {
            self.view.telemetry.stance_requested(LegAction::Tripod);
        }
        self.view.link = s;
        // The streaming rate remembered for this model, asked for once (and made the setup
        // of every reconnect).
        if connected && let Some(rate_hz) = self.io.pending_rate.take() {
            let m = &self.view.monitor;
            let draft = super::view::scope::TuningDraft {
                rate_hz,
                sensors: m.request.sensors,
                collision: m.collision,
            };
            self.apply_tuning(draft);
        }
        *self.dirty = true;
    }

    /// Carry out the control loop's outputs.
    pub fn apply(&mut self, outs: Vec<Out>) {
        for o in outs {
            match o {
                // Motion is a latest-wins value: the drive slot.
                Out::Do(
                    i @ (Intent::Drive { .. }
                    | Intent::Steer { .. }
                    | Intent::RawMotors { .. }
                    | Intent::Stop { .. }),
                ) => self.set_lowered(Slot::Drive, &i),
                // The dome is a latest-wins value, as driving is.
                Out::Do(i @ Intent::Head(_)) => self.set_lowered(Slot::Head, &i),
                Out::Do(Intent::Stance(a)) => self.stance(a),
                Out::Do(Intent::StartAim) => {
                    // A droid with nothing to send for it still shows its back light on.
                    self.act(&Intent::StartAim, "aim");
                    self.view.leds.back = Some(255);
                }
                Out::Do(Intent::ResetAim) => {
                    // A droid with nothing to send for it still shows its back light off.
                    self.act(&Intent::ResetAim, "aim");
                    self.view.leds.back = Some(0);
                }
                Out::Do(i) => {
                    if !self.act(&i, i.what()) {
                        self.hint(Unsupported::of(self.view.model, &i).to_string());
                    }
                }
                Out::Hint(h) => self.hint(h),
            }
        }
        // Redraw only when what the screen shows of the control changed: an idle control
        // loop ticks without drawing. In replay the screen shows the capture's commands
        // instead (`super::replay`).
        // A program beside the app drives too: its drive is shown while the operator's is
        // idle.
        let view =
            super::program_status::shown(self.io.controller.view(), self.view.program.as_ref());
        if self.io.player.is_none() && view != self.view.control {
            self.view.control = view;
            *self.dirty = true;
        }
    }

    /// Set a continuous control's latest value (nothing in replay).
    pub fn set(&self, slot: Slot, c: Command) {
        if let Some(s) = &self.io.session {
            s.set(slot, c);
        }
    }

    /// Set `slot` to what `intent` is on this droid, as its family lowers it; a droid that
    /// cannot do it is told in a hint.
    fn set_lowered(&mut self, slot: Slot, intent: &Intent) {
        match self.io.family.lower(self.view.model, intent) {
            Ok(commands) => commands.into_iter().for_each(|c| self.set(slot, c)),
            Err(e) => self.hint(e.to_string()),
        }
    }

    /// Send what `intent` is on this droid, as its family lowers it (each command's failure a
    /// hint naming `what`); `false` when the droid cannot do it, and nothing is sent.
    pub fn act(&mut self, intent: &Intent, what: &str) -> bool {
        match self.io.family.lower(self.view.model, intent) {
            Ok(commands) => {
                for c in commands {
                    self.send(c, what);
                }
                true
            }
            Err(_) => false,
        }
    }

    /// Send a one-shot command; a failure is a hint naming `what`.
    pub fn send(&mut self, c: Command, what: &str) {
        let Some(session) = &self.io.session else {
            return;
        };
        if let Err(e) = session.send(c) {
            self.hint(format!("{what} not sent: {e}"));
        }
    }

    fn stance(&mut self, a: LegAction) {
        let Ok(commands) = self.io.family.lower(self.view.model, &Intent::Stance(a)) else {
            return self.hint("this droid has no legs");
        };
        let Some(session) = &self.io.session else {
            return;
        };
        match commands.into_iter().try_for_each(|c| session.send(c)) {
            Ok(()) => self.view.telemetry.stance_requested(a),
            Err(e) => self.hint(format!("stance not sent: {e}")),
        }
    }

    /// The emergency stop on this droid: latched in its controller and written at once,
    /// ahead of pacing, whatever the app believed of it (idle droids too).
    pub fn estop(&mut self) {
        let stop = self.io.controller.estop_now();
        // One command for the urgent path; never none (see `intent::stop_command`).
        let family = self.io.family;
        let stop = crate::family::intent::one_command(family, self.view.model, &stop)
            .unwrap_or_else(|| family.stop_after(None));
        if let Some(s) = &self.io.session {
            s.emergency_stop(stop);
        }
        self.apply(Vec::new());
    }

    /// One press of a one-shot drive action (speed, turbo, stance, aim, tank).
    pub fn press(&mut self, a: crate::config::Action) {
        let view = self.droid_view();
        let outs = self.io.controller.on_press(a, &view);
        self.apply(outs);
    }

    /// Its control tick with `inp` (the fixed-rate `heartbeat`, or an immediate update after
    /// input changed); every droid's tick measures from the same instant `now`.
    pub fn control(&mut self, inp: &Inputs, heartbeat: bool, now: Instant) {
        let dt = if heartbeat {
            now.duration_since(self.io.last_tick)
        } else {
            Duration::ZERO
        };
        if heartbeat {
            self.io.last_tick = now;
        }
        let view = self.droid_view();
        let outs = self.io.controller.tick(inp, dt, &view, heartbeat);
        self.apply(outs);
    }

    /// The stop sent on exit (speed 0 at the heading its controller last commanded), also
    /// set in its drive slot now.
    pub fn stop_for_exit(&mut self) -> Command {
        let heading = self.io.controller.view().heading;
        let stop = crate::family::intent::stop_command(self.io.family, self.view.model, heading);
        self.set(Slot::Drive, stop.clone());
        stop
    }
}
