//! The event loop: one task owns the app; terminal input, gamepad events, session
//! notifications, the packet log, link-state changes, battery readings and the control tick
//! all arrive here over bounded channels, and each goes to its handler ([`super::keys`],
//! [`super::pad`], [`super::core`], [`super::replay`]). Every outside input is a parameter, so
//! tests drive it with fakes under paused time and render into ratatui's `TestBackend`.

use super::core::App;
use super::input::TermEvent;
use super::pacing::FramePacer;
use super::player::Player;
use super::rates::Rates;
use super::state::{AppState, GamepadStatus, KeyboardMode};
use crate::capture::replay::Replay;
use crate::config::Config;
use crate::family::Command;
use crate::model::Model;
use crate::session::{LinkState, SessionEvent, SessionHandle};
use crate::teleop::control::Controller;
use crate::teleop::gamepad::{PadEvent, PadState};
use crate::teleop::held::{HeldKeys, ReleaseMode};
use ratatui::{Frame, Terminal, backend::Backend};
use std::path::PathBuf;
use std::time::Duration;
use tokio::sync::{broadcast, mpsc, watch};
use tokio::time::{Instant, MissedTickBehavior, interval, sleep_until};

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
}

/// Everything from outside the app.
pub struct AppInputs {
    pub term: mpsc::Receiver<TermEvent>,
    pub pad: mpsc::Receiver<PadEvent>,
    /// Signals (SIGTERM, SIGHUP, Ctrl-C from outside the terminal): the reason.
    pub quit: mpsc::Receiver<String>,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ExitReason {
    /// The operator quit.
    Quit,
    /// A signal.
    Signal(String),
    /// The terminal input ended.
    InputClosed,
}

/// How the loop ended, with the stop to send before restoring the terminal.
pub struct Exit {
    pub reason: ExitReason,
    pub state: AppState,
    /// Speed 0 at the last commanded heading.
    pub stop: Command,
    /// Every droid's stop, in fleet order (the first is `stop`).
    pub stops: Vec<Command>,
}

pub type DrawFn = fn(&mut Frame, &AppState);

/// Where the app's droid comes from.
pub enum Source {
    /// A live session: the droid is driven.
    Live(SessionHandle),
    /// A capture played back: nothing is sent anywhere. The string names the file.
    Replay(Box<Replay>, String),
}

/// Run the app until the operator quits, a signal arrives, or input ends.
pub async fn run<B: Backend>(
    terminal: &mut Terminal<B>,
    session: SessionHandle,
    opts: AppOptions,
    inputs: AppInputs,
    draw: DrawFn,
) -> std::io::Result<Exit> {
    run_source(terminal, Source::Live(session), opts, inputs, draw).await
}

/// The app, set up for its source.
fn build(source: Source, opts: AppOptions) -> App {
    let config = opts.config;
    let keymap = config.keymap.clone();
    let mut state = AppState::new(opts.model, opts.droid_name);
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
    state.help_nav = super::help::nav(&keymap);
    let start = Instant::now();
    let family = crate::family::for_model(opts.model);
    state.monitor =
        super::monitor::MonitorView::new(opts.model, config.stream_request(), config.collision);
    let (session, player) = match source {
        Source::Live(s) => {
            state.help = super::help::live(&config);
            (Some(s), None)
        }
        Source::Replay(r, file) => {
            // What the capture's droid was told is in the capture, not in this config.
            state.monitor.live = false;
            state.monitor.plan = None;
            state.help = super::help::replay(&keymap);
            (None, Some(Player::new(*r, file, start)))
        }
    };
    let mut app = App {
        state,
        session,
        player,
        replayed: Vec::new(),
        pacer: FramePacer::new(Duration::ZERO),
        controller: Controller::with_family(config.control.clone(), family),
        held: HeldKeys::new(opts.release),
        pad: PadState::new(config.gamepad.clone()),
        keymap,
        family,
        turbo_speed: config.control.turbo_speed,
        tripod_on_connect: opts.tripod_on_connect,
        samples: opts.samples,
        start,
        last_tick: start,
        dirty: true,
        fleet: None,
        driven: true,
        log_droid: None,
        trace: Default::default(),
        trace_tx: None,
    };
    app.controller.set_tracks(app.state.model.has_tracks());
    app.state.control = app.controller.view().clone();
    if app.player.is_some() {
        // Replay shows the commands in the capture, as they were sent.
        app.state.control.source = "capture";
    }
    app
}

/// Run the app on a live session or a replay (the status bar says REPLAY; nothing is sent).
pub async fn run_source<B: Backend>(
    terminal: &mut Terminal<B>,
    source: Source,
    opts: AppOptions,
    inputs: AppInputs,
    draw: DrawFn,
) -> std::io::Result<Exit> {
    run_with(terminal, source, None, None, opts, inputs, draw).await
}

/// Run the app on a fleet: the roster strip shows every droid, the keys drive the chosen one
/// (or all, mirrored), the e-stop and quitting reach all. `opts.model` and
/// `opts.droid_name` are ignored: each droid's come from the fleet. A fleet of one is the
/// one-droid app.
pub async fn run_fleet<B: Backend>(
    terminal: &mut Terminal<B>,
    fleet: crate::fleet::Fleet,
    mut opts: AppOptions,
    inputs: AppInputs,
    draw: DrawFn,
) -> std::io::Result<Exit> {
    let Some(first) = fleet.member(0) else {
        return Err(std::io::Error::other("a fleet without droids"));
    };
    opts.model = first.model;
    opts.droid_name = first.name.clone();
    let source = Source::Live(first.session.clone());
    let fleet = (fleet.len() > 1).then_some(fleet);
    run_with(terminal, source, fleet, None, opts, inputs, draw).await
}

/// [`run_fleet`], publishing after every terminal and gamepad event what the input routing
/// did ([`InputTrace`]: the place on top, held keys let go, emergency stops): the safety
/// tests and the fuzz harness read it to know where each key went.
///
/// [`InputTrace`]: super::core::InputTrace
pub async fn run_fleet_traced<B: Backend>(
    terminal: &mut Terminal<B>,
    fleet: crate::fleet::Fleet,
    mut opts: AppOptions,
    inputs: AppInputs,
    draw: DrawFn,
    trace: watch::Sender<super::core::InputTrace>,
) -> std::io::Result<Exit> {
    let Some(first) = fleet.member(0) else {
        return Err(std::io::Error::other("a fleet without droids"));
    };
    opts.model = first.model;
    opts.droid_name = first.name.clone();
    let source = Source::Live(first.session.clone());
    let fleet = (fleet.len() > 1).then_some(fleet);
    run_traced(
        terminal,
        source,
        fleet,
        None,
        opts,
        inputs,
        draw,
        Some(trace),
    )
    .await
}

/// Replay a fleet's capture: every droid's replay on one clock, the roster and the choice
/// of droid as live (nothing is sent). `replays` in fleet order, each with its name.
pub async fn run_fleet_replay<B: Backend>(
    terminal: &mut Terminal<B>,
    mut replays: Vec<(Replay, String)>,
    file: String,
    mut opts: AppOptions,
    inputs: AppInputs,
    draw: DrawFn,
) -> std::io::Result<Exit> {
    if replays.is_empty() {
        return Err(std::io::Error::other("a capture without droids"));
    }
    let (first, name) = replays.remove(0);
    opts.model = first.model();
    opts.droid_name = name;
    let rest = (!replays.is_empty()).then_some((replays, file.clone()));
    let source = Source::Replay(Box::new(first), file);
    run_with(terminal, source, None, rest, opts, inputs, draw).await
}

/// A fleet's other droids: live, or replayed (their replays and the file's name).
type OtherReplays = Option<(Vec<(Replay, String)>, String)>;

async fn run_with<B: Backend>(
    terminal: &mut Terminal<B>,
    source: Source,
    fleet: Option<crate::fleet::Fleet>,
    replays: OtherReplays,
    opts: AppOptions,
    inputs: AppInputs,
    draw: DrawFn,
) -> std::io::Result<Exit> {
    run_traced(terminal, source, fleet, replays, opts, inputs, draw, None).await
}

#[allow(clippy::too_many_arguments)]
async fn run_traced<B: Backend>(
    terminal: &mut Terminal<B>,
    source: Source,
    fleet: Option<crate::fleet::Fleet>,
    replays: OtherReplays,
    opts: AppOptions,
    mut inputs: AppInputs,
    draw: DrawFn,
    trace: Option<watch::Sender<super::core::InputTrace>>,
) -> std::io::Result<Exit> {
    let rate_hz = opts.config.control.rate_hz;
    let parked_config = (opts.config.clone(), opts.log_path.clone());
    let mut app = build(source, opts);
    app.trace_tx = trace;
    // The other droids of a fleet, and one channel carrying their events.
    let (mut fleet_rx, forwarders) = match &fleet {
        Some(f) => super::fleet::attach(&mut app, f, &parked_config.0, parked_config.1),
        None => (mpsc::channel(1).1, Vec::new()),
    };
    let mut fleet_open = fleet.is_some();
    if let Some((others, file)) = replays {
        super::fleet::attach_replays(&mut app, others, &parked_config.0, &file);
    }
    let start = app.start;
    let family = app.family;
    let session = app.session.clone();

    // A replay has no session: its channels are closed from the start.
    let (mut log_rx, mut events_rx, mut link_rx) = match &session {
        Some(s) => (s.subscribe_log(), s.subscribe(), s.watch_state()),
        None => (
            broadcast::channel(1).1,
            broadcast::channel(1).1,
            watch::channel(LinkState::Connecting).1,
        ),
    };
    // What the droid announced before we listened (Robi's handshake).
    for n in session.iter().flat_map(SessionHandle::greeting) {
        app.state.telemetry.apply(&n, Duration::ZERO);
    }
    let period = Duration::from_secs_f64(1.0 / rate_hz.clamp(1, 50) as f64);
    let mut tick = interval(period);
    tick.set_missed_tick_behavior(MissedTickBehavior::Delay);
    let mut second = interval(Duration::from_secs(1));
    second.set_missed_tick_behavior(MissedTickBehavior::Skip);
    let (poller, mut battery_rx) = super::battery::spawn(session.clone(), family, app.state.model);
    let stats = |app: &App| match &app.session {
        Some(s) => s.stats(),
        None => app.state.stats,
    };
    let mut rates = Rates::new(stats(&app), app.clock());
    let mut pad_open = true;
    // Closed channels would fire their select branch forever: disable them instead.
    let live = app.session.is_some();
    let (mut events_open, mut log_open, mut link_open, mut battery_open) = (live, live, live, true);

    // Test hook for the crash path (stop first, then restore the terminal): panic after this
    // many ms. Only read from the environment, never set by droidctl itself.
    let crash_at = std::env::var("DROIDCTL_TEST_PANIC_AFTER_MS")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
        .map(|ms| start + Duration::from_millis(ms));
    let reason = loop {
        let expiry = app.held.next_expiry().map(|d| start + d);
        // Something on screen ends by itself (a hint, the collision flash): redraw then. In
        // replay the screen's clock is capture time, which moves only while playing.
        let change = app.state.next_change().and_then(|t| match &app.player {
            None => Some(start + t),
            Some(p) if p.running() => {
                let ahead = t.saturating_sub(app.state.now).div_f64(p.speed());
                Some(Instant::now() + ahead)
            }
            Some(_) => None,
        });
        let playing = app.player.as_ref().is_some_and(Player::running);
        let busy = playing || !app.state.control.deadman;
        let frame_at = start + app.pacer.next_frame(app.now(), busy);
        tokio::select! {
            e = inputs.term.recv() => match e {
                Some(e) => {
                    if let Some(r) = app.on_term(e) {
                        break r;
                    }
                }
                None => break ExitReason::InputClosed,
            },
            e = inputs.pad.recv(), if pad_open => match e {
                Some(e) => app.on_pad(e),
                None => pad_open = false,
            },
            q = inputs.quit.recv() => {
                break ExitReason::Signal(q.unwrap_or_else(|| "quit".into()));
            }
            _ = sleep_until(expiry.unwrap_or_else(Instant::now)), if expiry.is_some() => {
                // Emulated release: the repeats stopped.
                let now = app.now();
                if !app.held.expire(now).is_empty() {
                    app.control(false);
                }
            }
            _ = tick.tick() => {
                app.control(true);
                if crash_at.is_some_and(|t| Instant::now() >= t) {
                    panic!("test panic requested by DROIDCTL_TEST_PANIC_AFTER_MS");
                }
            }
            e = events_rx.recv(), if events_open => match e {
                Ok(SessionEvent::Notification(n)) => {
                    let at = app.now();
                    app.with_droid(0, |a| a.on_notification(&n, at));
                }
                Ok(SessionEvent::BadNotification { name, reason }) => {
                    tracing::warn!(name, %reason, "malformed notification");
                }
                Err(broadcast::error::RecvError::Lagged(n)) => tracing::warn!(n, "notifications lagged"),
                Err(broadcast::error::RecvError::Closed) => events_open = false,
            },
            e = log_rx.recv(), if log_open => match e {
                Ok(entry) => app.on_droid_log(0, &entry),
                Err(broadcast::error::RecvError::Lagged(n)) => app.state.log.dropped += n,
                Err(broadcast::error::RecvError::Closed) => log_open = false,
            },
            r = link_rx.changed(), if link_open => {
                if r.is_ok() {
                    let s = link_rx.borrow_and_update().clone();
                    app.on_droid_link(0, s);
                } else {
                    link_open = false;
                    app.on_droid_link(0, LinkState::Closed { reason: Some("the session ended".into()) });
                }
            }
            v = battery_rx.recv(), if battery_open => match v {
                Some(v) => app.with_droid(0, |a| a.on_battery(v)),
                None => battery_open = false,
            },
            e = fleet_rx.recv(), if fleet_open => match e {
                Some((i, e)) => app.on_droid_event(i, e),
                None => fleet_open = false,
            },
            _ = second.tick() => {
                // Rates per second of the session's time: capture time in replay.
                let st = stats(&app);
                if let Some((rate_in, rate_out)) = rates.sample(st, app.clock())
                    && (rate_in, rate_out) != (app.state.rate_in, app.state.rate_out)
                {
                    app.state.rate_in = rate_in;
                    app.state.rate_out = rate_out;
                    app.dirty = true;
                }
                if st != app.state.stats {
                    app.state.stats = st;
                    app.dirty = true;
                }
                if app.sample_fleet_rates(app.clock()) {
                    app.dirty = true;
                }
                app.flush_samples();
            }
            _ = sleep_until(change.unwrap_or_else(Instant::now)), if change.is_some() && !app.dirty => {
                app.dirty = true;
            }
            _ = sleep_until(frame_at), if app.dirty || playing => {
                let now = app.now();
                app.pacer.drawn(now);
                app.replay_frame();
                if app.dirty {
                    app.state.now = app.clock();
                    app.state.stats = stats(&app);
                    if app.fleet.is_some() {
                        app.state.roster = app.roster();
                    }
                    terminal
                        .draw(|f| draw(f, &app.state))
                        .map_err(|e| std::io::Error::other(e.to_string()))?;
                    app.dirty = false;
                }
            }
        }
    };
    poller.abort();
    app.flush_samples();
    for f in forwarders {
        f.abort();
    }
    // Every droid gets its stop now (the operator sees them stopped before the sessions
    // write them); the chosen one's state goes back to its place first.
    if app.fleet.is_some() {
        app.choose(0);
    }
    let stops = app.stop_all_for_exit();
    let stop = stops
        .first()
        .cloned()
        .unwrap_or_else(|| family.drive(0, app.controller.view().heading, false));
    Ok(Exit {
        reason,
        state: app.state,
        stop,
        stops,
    })
}

/// The commands to send on exit after the session's stop at its last heading: the app's own
/// stop (its heading, which the operator saw), and sleep when configured (and the family
/// can).
pub fn exit_commands(
    model: Model,
    exit_stop: impl IntoIterator<Item = Command>,
    sleep_on_exit: bool,
) -> Vec<Command> {
    let mut v: Vec<Command> = exit_stop.into_iter().collect();
    if sleep_on_exit && let Some(sleep) = crate::family::for_model(model).sleep() {
        v.push(sleep);
    }
    v
}
