//! The app set up for its droids: each droid's view and IO half made the same way, live or
//! replayed, one droid or a fleet.

use super::core::App;
use super::droid::DroidIo;
use super::pacing::FramePacer;
use super::player::Player;
use super::rates::Rates;
use super::remember::Remembered;
use super::state::{AppState, DroidState, GamepadStatus, KeyboardMode};
use crate::capture::replay::Replay;
use crate::config::{Action, Config};
use crate::family::Family;
use crate::model::Model;
use crate::session::{SessionHandle, SessionStats};
use crate::teleop::control::Controller;
use crate::teleop::gamepad::PadState;
use crate::teleop::held::{HeldKeys, ReleaseMode};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;
use tokio::time::Instant;

/// How the app is set up.
pub struct AppOptions {
    pub config: Config,
    pub model: Model,
    pub droid_name: String,
    pub log_path: Option<PathBuf>,
    pub release: ReleaseMode,
    /// Whether the session's connect setup puts a droid with legs into tripod (the app then
    /// shows the stance as requested on every connect).
    pub tripod_on_connect: bool,
    /// Where every sample the droid streams is written (`drive --csv`, `--jsonl`).
    pub samples: Option<crate::mission::csv::SampleFiles>,
    /// Where settings are remembered per droid model ([`super::remember`]); `None`: nothing
    /// is remembered (replay, tests).
    pub remember: Option<PathBuf>,
}

/// Where a droid comes from.
pub(super) enum Origin {
    /// A live session: the droid is driven.
    Live {
        session: SessionHandle,
        model: Model,
        name: String,
        family: &'static dyn Family,
        /// Where it started in its fleet's room, when known (the map draws it there).
        room_origin: Option<(f32, f32)>,
    },
    /// A capture played back (the file's name shown): nothing is sent anywhere.
    Replay {
        replay: Box<Replay>,
        name: String,
        file: String,
    },
}

/// The app for `droids` (at least one), in fleet order.
pub(super) fn build(droids: Vec<Origin>, opts: AppOptions) -> App {
    let config = opts.config;
    let keymap = Arc::new(config.keymap.clone());
    let start = Instant::now();
    let live = droids.iter().any(|d| matches!(d, Origin::Live { .. }));
    let mut views = Vec::with_capacity(droids.len());
    let mut remembered: std::collections::HashMap<Model, Remembered> = Default::default();
    let mut warnings: Vec<String> = Vec::new();
    // The first droid's model's log filter and mirror mode (the log and mirror are the app's).
    let mut first: Option<Remembered> = None;
    let mut io = Vec::with_capacity(droids.len());
    for origin in droids {
        let (model, name, family, session, player, room_origin) = match origin {
            Origin::Live {
                session,
                model,
                name,
                family,
                room_origin,
            } => (model, name, family, Some(session), None, room_origin),
            Origin::Replay { replay, name, file } => {
                let model = replay.model();
                let family = crate::family::for_model(model);
                let player = Player::new(*replay, file, start);
                (model, name, family, None, Some(player), None)
            }
        };
        let mut view = DroidState::new(model, name.clone());
        view.room_origin = room_origin;
        view.monitor =
            super::view::scope::MonitorView::new(model, config.stream_request(), config.collision);
        // What this model's droids were left with last time (live only: a replay is the
        // capture's).
        let kept = match (&opts.remember, &session) {
            (Some(dir), Some(_)) => remembered
                .entry(model)
                .or_insert_with(|| {
                    let (r, warning) = Remembered::load(dir, model);
                    warnings.extend(warning);
                    let over =
                        r.over_config(config.control.cruise_speed, config.stream_request().rate_hz);
                    if !over.is_empty() {
                        let key = keymap.shown(Action::ForgetSettings).unwrap_or_default();
                        // The key first: a narrow screen cuts the end of a hint.
                        warnings.push(format!(
                            "remembered for {} ({key} forgets): {}",
                            model.display_name(),
                            over.join(", ")
                        ));
                    }
                    r
                })
                .clone(),
            _ => Remembered::default(),
        };
        let mut control = config.control.clone();
        if let Some(c) = kept.cruise {
            control.cruise_speed = c;
        }
        if let Some(ch) = kept.channels() {
            view.scope.channels = ch;
        }
        if let Some(w) = kept.scope_window {
            view.scope.window = w;
        }
        let pending_rate = kept
            .stream_rate_hz
            .filter(|r| *r != view.monitor.request.rate_hz);
        first.get_or_insert(kept);
        let mut controller = Controller::with_family(control, family);
        controller.set_tracks(model.has_tracks());
        view.control = controller.view().clone();
        if let Some(s) = &session {
            // Its link state arrives first thing through its forwarder (`super::fleet`), so a
            // droid already connected is seen connecting (and a tripod setup shown).
            // What the droid announced before we listened (Robi's handshake).
            for n in s.greeting() {
                view.telemetry.apply(&n, Duration::ZERO);
            }
        } else {
            // What the capture's droid was told is in the capture, not in this config; the
            // screen shows the capture's commands, as they were sent.
            view.monitor.live = false;
            view.monitor.plan = None;
            view.control.source = "capture";
        }
        let stats = session
            .as_ref()
            .map_or(SessionStats::default(), |s| s.stats());
        io.push(DroidIo {
            session,
            player,
            controller,
            family,
            name: Arc::from(name.as_str()),
            rates: Rates::new(stats, Duration::ZERO),
            last_tick: start,
            pending_rate,
        });
        views.push(view);
    }
    let borders = Arc::new(super::borders::Borders::new(&keymap));
    let mut state = AppState::with_keys(views, keymap.clone(), borders);
    if let Some(first) = first {
        if let Some(f) = &first.log_filter {
            state.log.set_filter(super::packet_log::LogFilter::parse(f));
        }
        state.mirror = first.mirror.unwrap_or(false) && state.droids.len() > 1;
    }
    if !warnings.is_empty() {
        state.show_kept_hint(warnings.join(" · "), super::state::HINT_TIME * 3);
    }
    state.log_path = opts.log_path;
    state.keyboard = match opts.release {
        ReleaseMode::Reported => KeyboardMode::ReleaseEvents,
        ReleaseMode::Emulated { .. } => KeyboardMode::Emulated,
    };
    state.gamepad = if config.gamepad.enabled {
        GamepadStatus::NoPad
    } else {
        GamepadStatus::Disabled
    };
    // A replay drives nothing (Space pauses it): its help names no stop.
    state.help_nav = super::help::nav(&keymap, live);
    state.theme = config.display.theme;
    state.footer = super::help::footer(&keymap, live);
    state.help = if live {
        super::help::live(&config)
    } else {
        super::help::replay(&keymap)
    };
    App {
        area: Default::default(),
        state,
        io,
        replayed: Vec::new(),
        pacer: FramePacer::new(Duration::ZERO),
        held: HeldKeys::new(opts.release),
        pad: PadState::new(config.gamepad.clone()),
        keymap,
        turbo_speed: config.control.turbo_speed,
        tripod_on_connect: opts.tripod_on_connect,
        remember: opts.remember,
        default_cruise: config.control.cruise_speed,
        default_rate: config.stream_request().rate_hz,
        forget_asked: None,
        samples: opts.samples,
        start,
        dirty: true,
        trace: Default::default(),
        trace_tx: None,
    }
}
