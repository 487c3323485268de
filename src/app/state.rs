//! The application state: everything the screen shows, owned by the event loop and updated
//! from events. [`crate::ui`] renders an immutable borrow of it; nothing here draws.

use super::borders::Borders;
pub use super::overlay::Overlay;
use super::packet_log::PacketLog;
use super::place::Place;
use crate::config::{Context, KeyMap, Needs};
use crate::family::catalog::{self, Entry};
use crate::model::Model;
use crate::session::{LinkState, SessionStats};
use crate::telemetry::Telemetry;
pub use crate::teleop::control::ControlView;
use std::path::PathBuf;
use std::sync::{Arc, LazyLock};
use std::time::Duration;

/// The shipped bindings and their hints, parsed once per process: a screen made without a
/// configuration (tests, benches, [`AppState::new`]) reads them; the app passes its own
/// ([`AppState::with_keys`]) and parses nothing more.
static SHIPPED_KEYS: LazyLock<(Arc<KeyMap>, Arc<Borders>)> = LazyLock::new(|| {
    let km = crate::config::Config::defaults().keymap;
    let borders = Borders::new(&km);
    (Arc::new(km), Arc::new(borders))
});

/// Gamepad status for the status bar.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum GamepadStatus {
    /// Disabled in the config.
    Disabled,
    /// No gamepad support here (e.g. no /dev/input): normal, shown, not an error.
    Unavailable(String),
    /// Working, no pad plugged in.
    NoPad,
    Connected(String),
}

/// How key releases are known.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeyboardMode {
    /// The terminal reports releases (kitty keyboard protocol).
    ReleaseEvents,
    /// Releases are inferred from the auto-repeat stopping.
    Emulated,
}

/// Which pane has the keyboard.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Focus {
    /// Keys drive the droid.
    Drive,
    /// Keys scroll the packet log (the droid is held stopped).
    Log,
}

/// A titled group of the help overlay (one per place keys are read, and the gamepad).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HelpSection {
    pub title: String,
    pub lines: Vec<HelpLine>,
}

/// One line of the help overlay: keys and what they do.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HelpLine {
    pub keys: String,
    pub action: String,
    /// Listed only where it applies (R2's help lists no BOLT keys).
    pub needs: Needs,
}

impl HelpSection {
    /// The lines that apply to `model` (`fleet`: several droids).
    pub fn applying(&self, model: Model, fleet: bool) -> HelpSection {
        HelpSection {
            title: self.title.clone(),
            lines: self
                .lines
                .iter()
                .filter(|l| l.needs.applies(model, fleet))
                .cloned()
                .collect(),
        }
    }
}

/// One key of the context footer: the key as bound, the footer's word for it, what it needs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FooterKey {
    pub key: String,
    pub word: String,
    pub needs: Needs,
    /// Kept when the row is too narrow (the help and quit keys: `?` shows the rest).
    pub keep: bool,
    /// What the key does (`None`: not one binding, as help's "other keys").
    pub action: Option<crate::config::Action>,
}

/// How long a hint stays on screen.
pub const HINT_TIME: Duration = Duration::from_secs(4);

/// A message shown for a while (e.g. "R2 can't roll on two legs — switching to tripod").
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Hint {
    pub text: String,
    pub until: Duration,
    /// What was said at start (remembered settings over the configuration, unreadable
    /// files) and until when: later hints are shown after it instead of hiding it.
    pub kept: Option<(String, Duration)>,
}

impl Hint {
    /// `text` for `for_` from `now`, after what `prev` keeps on screen.
    pub fn after(prev: Option<&Hint>, text: String, now: Duration, for_: Duration) -> Hint {
        match prev
            .and_then(|h| h.kept.clone())
            .filter(|(_, until)| *until > now)
        {
            Some((kept, until)) => Hint {
                text: format!("{kept} · {text}"),
                until: (now + for_).max(until),
                kept: Some((kept, until)),
            },
            None => Hint {
                text,
                until: now + for_,
                kept: None,
            },
        }
    }
}

/// What the screen shows: the droids (one droid is a fleet of one), which one the keys drive
/// and the screen follows, and what belongs to no droid (the packet log, the overlay, hints).
#[derive(Debug, Clone)]
pub struct AppState {
    /// Time since the app started (drives the collision flash and hints).
    pub now: Duration,
    /// Every droid, in fleet order; never empty.
    pub droids: Vec<DroidState>,
    /// The droid the keys drive and the screen follows.
    pub chosen: usize,
    /// Driving input goes to every droid.
    pub mirror: bool,
    /// Every droid's packets, each line naming its droid in a fleet.
    pub log: PacketLog,
    pub overlay: Overlay,
    pub focus: Focus,
    pub gamepad: GamepadStatus,
    pub keyboard: KeyboardMode,
    pub log_path: Option<PathBuf>,
    pub hint: Option<Hint>,
    /// The help overlay's sections (driving keys, the packet log, palettes, …, the gamepad),
    /// generated from the bindings as configured ([`crate::app::help`]).
    pub help: Vec<HelpSection>,
    /// The help overlay's page keys as configured, for its footer (`PgDn/PgUp`).
    pub help_nav: String,
    /// Page of the help overlay shown when the bindings do not fit the terminal at once.
    /// The UI clamps it to the last page.
    pub help_page: usize,
    /// The context footer's keys, per place keys are read ([`crate::app::help::footer`]).
    pub footer: Vec<(Context, Vec<FooterKey>)>,
    /// The bindings as configured: overlays' border hints are built from them
    /// ([`crate::app::help::border`]), so no hint can name a key that does something else.
    pub keymap: Arc<KeyMap>,
    /// Every overlay's and panel's key hint, worded once from [`Self::keymap`] (a frame only
    /// reads them).
    pub borders: Arc<Borders>,
    pub animations: Vec<Entry>,
    pub sounds: Vec<Entry>,
    /// A collision flashes this long.
    pub collision_flash: Duration,
    /// The colours the screen is drawn in (`[display] theme`, `NO_COLOR`).
    pub theme: crate::config::Theme,
}

/// What the screen shows of one droid.
#[derive(Debug, Clone)]
pub struct DroidState {
    pub model: Model,
    /// The droid's name ("D2-1A2B", or "R2-D2 (simulated)").
    pub droid_name: String,
    pub link: LinkState,
    pub stats: SessionStats,
    /// Packets per second in and out, over the last second.
    pub rate_in: f32,
    pub rate_out: f32,
    pub telemetry: Telemetry,
    pub control: ControlView,
    /// The lights as last commanded.
    pub leds: LedView,
    /// Replaying a capture (nothing is sent): where, how fast.
    pub replay: Option<ReplayView>,
    /// What BOLT's matrix shows, as droidctl drew it.
    pub matrix: super::view::matrix::MatrixView,
    /// The scope: which channels, what window, paused or following (kept per droid: each
    /// droid's view is as it was left when it is chosen again).
    pub scope: super::view::scope::ScopeView,
    /// Streaming and collision detection as asked for and as sent.
    pub monitor: super::view::scope::MonitorView,
    /// The Sphero Edu program running on it (`--program`), if any.
    pub program: Option<super::view::program::ProgramView>,
    /// Where the droid started in its fleet's room, cm: its locator's (0, 0) there. The map
    /// draws in room coordinates with it; `None` (a real droid: nobody knows where it
    /// stood) draws from the droid's own start, as its locator counts.
    pub room_origin: Option<(f32, f32)>,
}

impl DroidState {
    pub fn new(model: Model, droid_name: String) -> Self {
        DroidState {
            model,
            droid_name,
            link: LinkState::Connecting,
            stats: SessionStats::default(),
            rate_in: 0.0,
            rate_out: 0.0,
            telemetry: Telemetry::default(),
            control: ControlView::default(),
            leds: LedView::default(),
            replay: None,
            matrix: Default::default(),
            scope: super::view::scope::ScopeView::for_model(model),
            monitor: super::view::scope::MonitorView::new(
                model,
                crate::tuning::StreamRequest {
                    rate_hz: 10,
                    sensors: crate::family::stream::all_groups(model),
                },
                crate::tuning::CollisionConfig::default(),
            ),
            program: None,
            room_origin: None,
        }
    }
}

/// A replay, for the status bar.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayView {
    /// The capture file, as given.
    pub file: String,
    /// Capture time shown, and the capture's length.
    pub position: Duration,
    pub duration: Duration,
    pub speed: f64,
    pub paused: bool,
    /// Events applied so far, and in all.
    pub events_done: usize,
    pub events: usize,
}

/// The lights as droidctl last commanded them (droids do not report their LEDs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LedView {
    pub main: Option<[u8; 3]>,
    pub back: Option<u8>,
}

impl Place {
    /// The place on top for what `state` shows (`replay`: a capture plays): an open
    /// overlay's (the registry's, [`Overlay::place`]), else the focused log, a replay or
    /// driving.
    pub fn of(state: &AppState, replay: bool) -> Place {
        match state.overlay.place() {
            Some(p) => p,
            None if state.focus == Focus::Log => Place::Log,
            None if replay => Place::Replay,
            None => Place::Driving,
        }
    }
}

impl AppState {
    /// The screen of one droid.
    pub fn new(model: Model, droid_name: String) -> Self {
        AppState::for_droids(vec![DroidState::new(model, droid_name)])
    }

    /// The screen of a fleet with the shipped bindings (`droids` must not be empty; an empty
    /// list gets a placeholder R2-D2 rather than a panic).
    pub fn for_droids(droids: Vec<DroidState>) -> Self {
        let (keymap, borders) = SHIPPED_KEYS.clone();
        AppState::with_keys(droids, keymap, borders)
    }

    /// The screen of a fleet read with `keymap`, whose hints are `borders` (built from it by
    /// [`Borders::new`]).
    pub fn with_keys(
        mut droids: Vec<DroidState>,
        keymap: Arc<KeyMap>,
        borders: Arc<Borders>,
    ) -> Self {
        if droids.is_empty() {
            droids.push(DroidState::new(Model::DEFAULT, String::new()));
        }
        AppState {
            now: Duration::ZERO,
            droids,
            chosen: 0,
            mirror: false,
            log: PacketLog::default(),
            overlay: Overlay::None,
            focus: Focus::Drive,
            gamepad: GamepadStatus::NoPad,
            keyboard: KeyboardMode::Emulated,
            log_path: None,
            hint: None,
            help: Vec::new(),
            help_nav: String::new(),
            help_page: 0,
            footer: Vec::new(),
            keymap,
            borders,
            animations: catalog::animations(),
            sounds: catalog::sounds(),
            collision_flash: Duration::from_millis(1500),
            theme: crate::config::Theme::Dark,
        }
    }

    /// The droid the screen follows.
    pub fn droid(&self) -> &DroidState {
        &self.droids[self.chosen.min(self.droids.len() - 1)]
    }

    pub fn droid_mut(&mut self) -> &mut DroidState {
        let i = self.chosen.min(self.droids.len() - 1);
        &mut self.droids[i]
    }

    /// The roster strip's view of a fleet (`None` with one droid: the screen is then as it
    /// always was).
    pub fn roster(&self) -> Option<super::roster::Roster> {
        (self.droids.len() > 1).then(|| super::roster::Roster::of(self))
    }

    /// Whether the collision flash is on now (the droid shown).
    pub fn flashing(&self) -> bool {
        self.droid()
            .telemetry
            .last_collision
            .is_some_and(|c| self.now.saturating_sub(c.at) < self.collision_flash)
    }

    /// When the screen changes by itself next (a hint or the collision flash ends), if ever.
    pub fn next_change(&self) -> Option<Duration> {
        let hint = self.hint.as_ref().map(|h| h.until);
        let flash = self
            .droid()
            .telemetry
            .last_collision
            .map(|c| c.at + self.collision_flash);
        [hint, flash]
            .into_iter()
            .flatten()
            .filter(|t| *t > self.now)
            .min()
    }

    /// The hint to show now, if any.
    pub fn current_hint(&self) -> Option<&str> {
        self.hint
            .as_ref()
            .filter(|h| self.now < h.until)
            .map(|h| h.text.as_str())
    }

    pub fn show_hint(&mut self, text: impl Into<String>, for_: Duration) {
        self.hint = Some(Hint::after(self.hint.as_ref(), text.into(), self.now, for_));
    }

    /// A hint no later hint hides while it lasts (what is said at start).
    pub fn show_kept_hint(&mut self, text: impl Into<String>, for_: Duration) {
        let text = text.into();
        let until = self.now + for_;
        self.hint = Some(Hint {
            text: text.clone(),
            until,
            kept: Some((text, until)),
        });
    }
}
