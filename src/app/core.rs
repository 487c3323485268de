//! What the event loop owns: the [`AppState`] the screen shows, the control loop, the held
//! keys and the gamepad, the key map, and where the droid comes from (a live session, or a
//! replay's player). The handlers live in their own files: keys ([`super::keys`]), the gamepad
//! ([`super::pad`]), what reaches the droid ([`super::actions`]) and replay
//! ([`super::replay`]); this file keeps the state and the events every source shares.

use super::pacing::FramePacer;
use super::packet_log::LogLine;
use super::player::Player;
use super::state::AppState;
use crate::capture::mirror::Output;
use crate::config::KeyMap;
use crate::family::Family;
use crate::protocol::notify::Notification;
use crate::protocol::wire::LegAction;
use crate::session::{LinkState, LogEntry, SessionHandle};
use crate::teleop::control::{Controller, DroidView};
use crate::teleop::gamepad::PadState;
use crate::teleop::held::HeldKeys;
use std::time::Duration;
use tokio::time::Instant;

/// How long a hint stays on screen.
pub const HINT_TIME: Duration = Duration::from_secs(4);

pub(super) struct App {
    pub state: AppState,
    /// The live session; `None` in replay.
    pub session: Option<SessionHandle>,
    /// The capture played back, in replay.
    pub player: Option<Player>,
    pub controller: Controller,
    pub held: HeldKeys,
    pub pad: PadState,
    pub keymap: KeyMap,
    pub family: &'static dyn Family,
    pub turbo_speed: u8,
    /// Whether a (re)connect's setup puts a droid with legs into tripod.
    pub tripod_on_connect: bool,
    pub start: Instant,
    pub last_tick: Instant,
    /// Something visible changed since the last frame.
    pub dirty: bool,
    /// Replay: what the last advance produced (kept to reuse its allocation).
    pub replayed: Vec<(Duration, Output)>,
    pub pacer: FramePacer,
    /// The other droids of a fleet (`None` with one droid).
    pub fleet: Option<super::fleet::FleetSide>,
    /// The keys and the pad drive the droid swapped in (false for a parked droid outside
    /// mirror mode: it gets no input, its deadman holds it; the e-stop still reaches it).
    pub driven: bool,
    /// In a fleet, the droid whose events are being handled: its log lines are named.
    pub log_droid: Option<std::sync::Arc<str>>,
    /// Where samples are written (`drive --csv`, `--jsonl`).
    pub samples: Option<crate::mission::csv::SampleFiles>,
    /// What the input routing did so far, and where it is published.
    pub trace: InputTrace,
    pub trace_tx: Option<tokio::sync::watch::Sender<InputTrace>>,
}

/// What the input routing did, published after every terminal or gamepad event: the tests
/// and the fuzz harness read it to know which place each key went to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InputTrace {
    /// Terminal and gamepad events handled so far.
    pub handled: u64,
    /// The place on top after the last event.
    pub place: super::place::Place,
    /// How often every held key was let go (a place change, another droid, focus lost).
    pub clears: u64,
    /// Emergency stops raised (keys, the pad).
    pub estops: u64,
    pub chosen: usize,
    pub mirror: bool,
}

impl Default for InputTrace {
    fn default() -> Self {
        InputTrace {
            handled: 0,
            place: super::place::Place::Driving,
            clears: 0,
            estops: 0,
            chosen: 0,
            mirror: false,
        }
    }
}

impl App {
    /// Time since the app started.
    pub fn now(&self) -> Duration {
        Instant::now().duration_since(self.start)
    }

    /// The time telemetry and the screen run on: since the start live, capture time in
    /// replay (so the same capture always folds and draws the same).
    pub fn clock(&self) -> Duration {
        match &self.player {
            Some(p) => p.clock(Instant::now()),
            None => self.now(),
        }
    }

    /// The operator touched a key or the gamepad: frames come fast for a while.
    pub fn touched(&mut self) {
        let now = self.now();
        self.pacer.touched(now);
    }

    pub fn droid_view(&self) -> DroidView {
        DroidView {
            connected: self.state.link == LinkState::Connected,
            has_legs: self.state.model.has_legs(),
            has_dome: self.state.model.has_dome(),
            can_aim: self.state.model.can_aim(),
            stance: self.state.telemetry.stance,
        }
    }

    /// The place that has the keyboard now.
    pub fn place(&self) -> super::place::Place {
        super::place::Place::of(&self.state, self.player.is_some())
    }

    /// Let go of every held key and tell every droid's controller now (its next write is a
    /// stop): the place on top changed, another droid was chosen, mirror mode switched, or
    /// the terminal lost focus.
    pub fn clear_held(&mut self) {
        self.held.release_all();
        self.trace.clears += 1;
        self.control(false);
    }

    /// Publish what the input routing did (for tests and the fuzz harness).
    pub fn traced(&mut self) {
        self.trace.handled += 1;
        self.trace.place = self.place();
        self.trace.chosen = self.chosen();
        self.trace.mirror = self.mirroring();
        if let Some(tx) = &self.trace_tx {
            tx.send_replace(self.trace);
        }
    }

    pub fn hint(&mut self, text: impl Into<String>) {
        self.state.now = self.clock();
        self.state.show_hint(text, HINT_TIME);
        self.dirty = true;
    }

    /// A notification, from the session or the replay, received at `at`.
    pub fn on_notification(&mut self, n: &Notification, at: Duration) {
        self.state.telemetry.apply(n, at);
        self.dirty = true;
        if matches!(n, Notification::Sensors(_) | Notification::RobiFrame(_))
            && let Some(files) = &mut self.samples
        {
            let s = crate::mission::sample_of(&self.state.telemetry, at.as_millis() as u64);
            // A fleet's rows name their droid.
            let written = match &self.log_droid {
                Some(droid) => files.write_for(droid, &s),
                None => files.write(&s),
            };
            if let Err(e) = written {
                self.samples = None;
                self.hint(format!("telemetry file: {e}; no more samples are written"));
            }
        }
    }

    /// Write out what the sample files buffer (every second, and at exit).
    pub fn flush_samples(&mut self) {
        if let Some(files) = &mut self.samples
            && let Err(e) = files.flush()
        {
            self.samples = None;
            self.hint(format!("telemetry file: {e}; no more samples are written"));
        }
    }

    /// A packet-log entry, from the session or the replay.
    pub fn on_log(&mut self, entry: &LogEntry) {
        let line = match &self.log_droid {
            Some(droid) => LogLine::from_droid_entry(entry, droid.clone()),
            None => LogLine::from_entry(entry),
        };
        self.state.log.push(line);
        self.dirty = true;
    }

    pub fn on_battery(&mut self, volts: f32) {
        self.state.telemetry.battery_v = Some(volts);
        self.dirty = true;
    }

    pub fn on_link(&mut self, s: LinkState) {
        if s != LinkState::Connected {
            self.controller.link_lost();
        } else if self.state.link != LinkState::Connected
            && self.tripod_on_connect
            && self.state.model.has_legs()
        {
            // The connect setup asks for tripod.
            self.state.telemetry.stance_requested(LegAction::Tripod);
        }
        self.state.link = s;
        self.control(false);
        self.dirty = true;
    }
}
