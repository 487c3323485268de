//! The event loop: one task owns the app; terminal input, gamepad events, session
//! notifications, the packet log, link-state changes, battery readings and the control tick
//! all arrive here over bounded channels, and each goes to its handler ([`super::keys`],
//! [`super::pad`], [`super::core`], [`super::replay`]). Every outside input is a parameter, so
//! tests drive it with fakes under paused time and render into ratatui's `TestBackend`.

pub use super::build::AppOptions;
use super::build::{Origin, build};
pub use super::core::ExitReason;
use super::core::{App, InputTrace};
use super::input::TermEvent;
use super::player::Player;
use super::state::AppState;
use crate::capture::replay::Replay;
use crate::family::Command;
use crate::model::Model;
use crate::session::SessionHandle;
use crate::teleop::gamepad::PadEvent;
use ratatui::{Frame, Terminal, backend::Backend};
use std::time::Duration;
use tokio::sync::{mpsc, watch};
use tokio::time::{Instant, MissedTickBehavior, interval, sleep_until};

/// Everything from outside the app.
pub struct AppInputs {
    pub term: mpsc::Receiver<TermEvent>,
    pub pad: mpsc::Receiver<PadEvent>,
    /// Signals (SIGTERM, SIGHUP, Ctrl-C from outside the terminal): the reason.
    pub quit: mpsc::Receiver<String>,
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

/// Where the app's droids come from: the one choice the app loop's one entry point ([`run`])
/// takes. A session or a fleet converts into it (`run(&mut t, session, …)`).
pub enum Source {
    /// A live session: the droid is driven.
    Live(SessionHandle),
    /// A live fleet: the roster strip shows every droid, the keys drive the chosen one (or
    /// all, mirrored), the e-stop and quitting reach all. `opts.model` and `opts.droid_name`
    /// are ignored: each droid's come from the fleet. A fleet of one is the one-droid app.
    /// With a sender, what the input routing did is published after every terminal and
    /// gamepad event ([`InputTrace`]: the place on top, held keys let go, emergency stops):
    /// the safety tests and the fuzz harness read it to know where each key went.
    Fleet(crate::fleet::Fleet, Option<watch::Sender<InputTrace>>),
    /// A capture played back: nothing is sent anywhere (the status bar says REPLAY). The
    /// string names the file.
    Replay(Box<Replay>, String),
    /// A fleet's capture: every droid's replay on one clock, the roster and the choice of
    /// droid as live (nothing is sent); in fleet order, each with its name. The string names
    /// the file.
    FleetReplay(Vec<(Replay, String)>, String),
}

impl From<SessionHandle> for Source {
    fn from(session: SessionHandle) -> Source {
        Source::Live(session)
    }
}

impl From<crate::fleet::Fleet> for Source {
    fn from(fleet: crate::fleet::Fleet) -> Source {
        Source::Fleet(fleet, None)
    }
}

/// Run the app until the operator quits, a signal arrives, or input ends: the one entry
/// point of the app loop, live or replayed, one droid or a fleet.
pub async fn run<B: Backend>(
    terminal: &mut Terminal<B>,
    source: impl Into<Source>,
    opts: AppOptions,
    inputs: AppInputs,
    draw: DrawFn,
) -> std::io::Result<Exit> {
    run_with_programs(terminal, source, opts, inputs, Vec::new(), draw).await
}

/// [`run`] with Sphero Edu programs running beside the app (`--program`): each droid's
/// program status, shown in the status bar, the gauges and the end banner
/// ([`super::program_status`]).
pub async fn run_with_programs<B: Backend>(
    terminal: &mut Terminal<B>,
    source: impl Into<Source>,
    opts: AppOptions,
    inputs: AppInputs,
    programs: super::program_status::ProgramFeeds,
    draw: DrawFn,
) -> std::io::Result<Exit> {
    let (droids, trace) = match source.into() {
        Source::Live(session) => (
            vec![Origin::Live {
                session,
                model: opts.model,
                name: opts.droid_name.clone(),
                family: crate::family::for_model(opts.model),
                room_origin: None,
            }],
            None,
        ),
        Source::Fleet(fleet, trace) => (live(&fleet), trace),
        Source::Replay(replay, file) => (
            vec![Origin::Replay {
                replay,
                name: opts.droid_name.clone(),
                file,
            }],
            None,
        ),
        Source::FleetReplay(replays, file) => (
            replays
                .into_iter()
                .map(|(r, name)| Origin::Replay {
                    replay: Box::new(r),
                    name,
                    file: file.clone(),
                })
                .collect(),
            None,
        ),
    };
    run_droids(terminal, droids, opts, inputs, programs, draw, trace).await
}

/// The droids of a live fleet, in its order.
fn live(fleet: &crate::fleet::Fleet) -> Vec<Origin> {
    fleet
        .members()
        .iter()
        .map(|m| Origin::Live {
            session: m.session.clone(),
            model: m.model,
            name: m.name.clone(),
            family: m.family,
            room_origin: m.room_origin,
        })
        .collect()
}

async fn run_droids<B: Backend>(
    terminal: &mut Terminal<B>,
    droids: Vec<Origin>,
    opts: AppOptions,
    mut inputs: AppInputs,
    programs: super::program_status::ProgramFeeds,
    draw: DrawFn,
    trace: Option<watch::Sender<InputTrace>>,
) -> std::io::Result<Exit> {
    if droids.is_empty() {
        return Err(std::io::Error::other("no droid to drive"));
    }
    let rate_hz = opts.config.control.rate_hz;
    let lives: Vec<_> = droids
        .iter()
        .filter_map(|d| match d {
            Origin::Live {
                session,
                model,
                family,
                ..
            } => Some((session.clone(), *family, *model)),
            Origin::Replay { .. } => None,
        })
        .collect();
    // Every live droid's events, subscribed before anything can be missed.
    let (mut events, forwarders) = super::fleet::forward(&lives);
    let (mut program_rx, program_tasks) = super::program_status::forward(programs);
    let mut programs_open = !program_tasks.is_empty();
    let mut app = build(droids, opts);
    app.trace_tx = trace;
    let start = app.start;
    let period = Duration::from_secs_f64(1.0 / rate_hz.clamp(1, 50) as f64);
    let mut tick = interval(period);
    tick.set_missed_tick_behavior(MissedTickBehavior::Delay);
    let mut second = interval(Duration::from_secs(1));
    second.set_missed_tick_behavior(MissedTickBehavior::Skip);
    let mut pad_open = true;
    // Closed channels would fire their select branch forever: disable them instead.
    let mut events_open = !lives.is_empty();

    #[cfg(feature = "test-hooks")]
    let crash_at = crash_deadline(start);
    let reason = loop {
        let expiry = app.held.next_expiry().map(|d| start + d);
        let change = next_change(&app);
        let playing = app
            .io
            .iter()
            .any(|d| d.player.as_ref().is_some_and(Player::running));
        let busy = playing || app.state.droids.iter().any(|d| !d.control.deadman);
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
                #[cfg(feature = "test-hooks")]
                if crash_at.is_some_and(|t| Instant::now() >= t) {
                    panic!("test panic requested by DROIDCTL_TEST_PANIC_AFTER_MS");
                }
            }
            e = events.recv(), if events_open => match e {
                Some((i, e)) => app.on_droid_event(i, e),
                None => events_open = false,
            },
            p = program_rx.recv(), if programs_open => match p {
                Some((i, s)) => app.on_program(i, s),
                None => programs_open = false,
            },
            _ = second.tick() => {
                // Rates per second of the session's time: capture time in replay.
                if app.sample_rates(app.clock()) {
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
                    app.area = terminal
                        .draw(|f| draw(f, &app.state))
                        .map_err(|e| std::io::Error::other(e.to_string()))?
                        .area;
                    app.dirty = false;
                }
            }
        }
    };
    app.flush_samples();
    app.save_remembered();
    for f in forwarders.into_iter().chain(program_tasks) {
        f.abort();
    }
    // Every droid gets its stop now (the operator sees them stopped before the sessions
    // write them).
    let stops = app.stop_all_for_exit();
    let stop = stops.first().cloned().unwrap_or_else(|| {
        let model = app.state.droid().model;
        crate::family::intent::stop_command(
            crate::family::for_model(model),
            model,
            Default::default(),
        )
    });
    Ok(Exit {
        reason,
        state: app.state,
        stop,
        stops,
    })
}

/// The test hook of the crash path (stop first, then restore the terminal: `tests/e2e_pty.rs`):
/// the loop panics `DROIDCTL_TEST_PANIC_AFTER_MS` ms after it started. Built only with the
/// `test-hooks` feature, so a droidctl built without it never reads that variable.
#[cfg(feature = "test-hooks")]
fn crash_deadline(start: Instant) -> Option<Instant> {
    std::env::var("DROIDCTL_TEST_PANIC_AFTER_MS")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
        .map(|ms| start + Duration::from_millis(ms))
}

/// When something on screen ends by itself (a hint, the collision flash): redraw then. In
/// replay the screen's clock is capture time, which moves only while playing.
fn next_change(app: &App) -> Option<Instant> {
    let t = app.state.next_change()?;
    match app.io.get(app.chosen()).and_then(|d| d.player.as_ref()) {
        None => Some(app.start + t),
        Some(p) if p.running() => {
            let ahead = t.saturating_sub(app.state.now).div_f64(p.speed());
            Some(Instant::now() + ahead)
        }
        Some(_) => None,
    }
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
