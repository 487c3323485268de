//! What the event loop owns: the [`AppState`] the screen shows (every droid's view, the
//! packet log, the overlay), each droid's IO half ([`DroidIo`]: its session or replay, its
//! controller and family) in the same order, the held keys and the gamepad, and the key map.
//! Nothing is swapped: "the chosen droid" is an index, "every droid" is a loop. The handlers
//! live in their own files: keys ([`super::keys`]), the gamepad ([`super::pad`]), what
//! reaches a droid ([`super::droid`], [`super::actions`]), several droids
//! ([`super::fleet`]) and replay ([`super::replay`]).

use super::droid::{DroidIo, DroidMut};
use super::pacing::FramePacer;
use super::place::Place;
use super::state::{AppState, HINT_TIME};
use crate::capture::mirror::Output;
use crate::config::KeyMap;
use crate::teleop::gamepad::PadState;
use crate::teleop::held::HeldKeys;
use std::time::Duration;
use tokio::time::Instant;

/// Why the app loop ended (the terminal's keys, a signal or the end of input).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ExitReason {
    /// The operator quit.
    Quit,
    /// A signal.
    Signal(String),
    /// The terminal input ended.
    InputClosed,
}

pub(super) struct App {
    pub state: AppState,
    /// Each droid's IO half, in the order of `state.droids`.
    pub io: Vec<DroidIo>,
    /// Keys held in the driving place (filled only there, let go when the place changes).
    pub held: HeldKeys,
    pub pad: PadState,
    /// The bindings, shared with the screen's [`AppState::keymap`].
    pub keymap: std::sync::Arc<KeyMap>,
    pub turbo_speed: u8,
    /// Whether a (re)connect's setup puts a droid with legs into tripod.
    pub tripod_on_connect: bool,
    pub start: Instant,
    /// Something visible changed since the last frame.
    pub dirty: bool,
    /// Replay: what the last advance produced (kept to reuse its allocation).
    pub replayed: Vec<(Duration, Output)>,
    pub pacer: FramePacer,
    /// Where samples are written (`drive --csv`, `--jsonl`).
    pub samples: Option<crate::mission::csv::SampleFiles>,
    /// What the input routing did so far, and where it is published.
    pub trace: InputTrace,
    pub trace_tx: Option<tokio::sync::watch::Sender<InputTrace>>,
    /// Where settings are remembered per model (`None`: nothing is).
    pub remember: Option<std::path::PathBuf>,
    /// The configuration's cruise speed and streaming rate (what forgetting goes back to).
    pub default_cruise: u8,
    pub default_rate: u16,
    /// When the forget key was pressed once (it asks before it forgets).
    pub forget_asked: Option<Duration>,
    /// The terminal's area at the last frame (where the mouse's clicks land).
    pub area: ratatui::layout::Rect,
}

/// What the input routing did, published after every terminal or gamepad event: the tests
/// and the fuzz harness read it to know which place each key went to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InputTrace {
    /// Terminal and gamepad events handled so far.
    pub handled: u64,
    /// The place on top after the last event.
    pub place: Place,
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
            place: Place::Driving,
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
    /// replay (so the same capture always folds and draws the same). Every droid of a
    /// replayed fleet plays on one clock: the chosen one's.
    pub fn clock(&self) -> Duration {
        match self
            .io
            .get(self.state.chosen)
            .and_then(|d| d.player.as_ref())
        {
            Some(p) => p.clock(Instant::now()),
            None => self.now(),
        }
    }

    /// The number of droids (one droid is a fleet of one).
    pub fn len(&self) -> usize {
        self.io.len()
    }

    /// The droid the keys drive.
    pub fn chosen(&self) -> usize {
        self.state.chosen
    }

    /// Whether mirror mode is on.
    pub fn mirroring(&self) -> bool {
        self.state.mirror
    }

    /// Whether driving input reaches droid `i`: the chosen one, or every one mirrored.
    pub fn driven(&self, i: usize) -> bool {
        i == self.state.chosen || self.state.mirror
    }

    /// Whether this is a replay (nothing is sent).
    pub fn replaying(&self) -> bool {
        self.io.iter().any(|d| d.player.is_some())
    }

    /// Droid `i`, with what its handlers share with the rest of the app (the hint, the log,
    /// the sample files). `None` for an index out of range.
    pub fn droid(&mut self, i: usize) -> Option<DroidMut<'_>> {
        let fleet = self.io.len() > 1;
        let now = self.now();
        let AppState {
            droids,
            log,
            hint,
            now: screen_now,
            ..
        } = &mut self.state;
        Some(DroidMut {
            view: droids.get_mut(i)?,
            io: self.io.get_mut(i)?,
            log,
            hint,
            screen_now,
            now,
            dirty: &mut self.dirty,
            samples: &mut self.samples,
            fleet,
            tripod_on_connect: self.tripod_on_connect,
        })
    }

    /// `f` on every droid, in order.
    pub fn each(&mut self, mut f: impl FnMut(&mut DroidMut<'_>)) {
        for i in 0..self.io.len() {
            if let Some(mut d) = self.droid(i) {
                f(&mut d);
            }
        }
    }

    /// The operator touched a key or the gamepad: frames come fast for a while.
    pub fn touched(&mut self) {
        let now = self.now();
        self.pacer.touched(now);
    }

    /// The place that has the keyboard now.
    pub fn place(&self) -> Place {
        Place::of(&self.state, self.replaying())
    }

    /// Let go of every held key and tell every droid's controller now (its next write is a
    /// stop): the place on top changed, another droid was chosen, mirror mode switched, or
    /// the terminal lost focus.
    pub fn clear_held(&mut self) {
        self.held.release_all();
        for d in &mut self.io {
            d.controller.let_go();
        }
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

    /// Write out what the sample files buffer (every second, and at exit).
    pub fn flush_samples(&mut self) {
        if let Some(files) = &mut self.samples
            && let Err(e) = files.flush()
        {
            self.samples = None;
            self.hint(format!("telemetry file: {e}; no more samples are written"));
        }
    }
}
