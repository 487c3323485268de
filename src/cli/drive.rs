//! `droidctl` / `droidctl drive`: the full-screen teleop app.

use super::CliError;
use super::term::{self, TerminalGuard};
use crate::app::run::{self, AppInputs, AppOptions, ExitReason};
use crate::config::Config;
use crate::family::setup::{SetupOptions, connect_setup};
use crate::link::Link;
use crate::model::Model;
use crate::session::{self, SessionConfig, SessionHandle};
use crate::sim::{Faults, SimConfig, SimLink};
use clap::Args;
use ratatui::Terminal;
use ratatui::backend::CrosstermBackend;
use std::sync::{Mutex, OnceLock};
use std::time::Duration;
use tokio::sync::mpsc;

#[derive(Debug, Clone, Default, Args)]
pub struct DriveArgs {
    /// Drive a simulated droid in-process: r2d2 (default), r2q5, bb9e, bb8, sprk, ollie or robi.
    #[arg(long, num_args = 0..=1, default_missing_value = "r2d2", value_name = "MODEL")]
    pub sim: Option<String>,
    #[command(flatten)]
    pub ble: super::connect::BleArgs,
    #[command(flatten)]
    pub record: super::replay::RecordArgs,
}

/// The simulated model asked for, if any.
pub fn sim_model(sim: &Option<String>) -> Result<Option<Model>, CliError> {
    match sim {
        None => Ok(None),
        Some(m) => match Model::from_id(m) {
            Some(model) if crate::sim::simulates(model) => Ok(Some(model)),
            _ => Err(CliError::usage(format!(
                "unknown simulated model {m:?}: use one of {}",
                crate::sim::simulated_ids().join(", ")
            ))),
        },
    }
}

static PANIC_MESSAGE: Mutex<Option<String>> = Mutex::new(None);
static PANIC_SESSION: OnceLock<(SessionHandle, Model)> = OnceLock::new();

/// On a panic: ask the session to stop the droid at once (a synchronous slot write), keep
/// the message for after the terminal is restored; a panic outside the app task restores the
/// terminal itself and prints as usual.
fn install_panic_hook() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if let Some((s, model)) = PANIC_SESSION.get() {
            // At the last heading written: a stop at heading 0 would turn the droid.
            s.stop_now(crate::family::for_model(*model));
        }
        crate::capture::record::flush_all();
        let in_app = std::thread::current().name() != Some("main");
        if in_app && term::active() {
            if let Ok(mut m) = PANIC_MESSAGE.lock() {
                *m = Some(info.to_string());
            }
        } else {
            term::restore();
            default(info);
        }
    }));
}

pub fn run(args: DriveArgs) -> Result<i32, CliError> {
    let config_path = crate::config::config_path();
    let config = Config::load(&config_path).map_err(|e| {
        CliError::usage(format!(
            "{e}\nFix the file (or move it away to use the defaults) and try again."
        ))
    })?;
    let model = sim_model(&args.sim)?;
    let recorder = args.record.open()?;
    let log_path = crate::logging::init().ok();
    let rt = super::realtime_runtime()?;
    rt.block_on(async move {
        let (link, model, name) = match model {
            Some(m) => {
                let link: Box<dyn Link> =
                    Box::new(SimLink::new(m, SimConfig::for_model(m), Faults::none()));
                (link, m, format!("{} (simulated)", m.display_name()))
            }
            None => connect_real(&args).await?,
        };
        let link = match &recorder {
            Some(r) => {
                r.start(&crate::capture::record::Recorder::header_for(model, &name));
                r.wrap(link)
            }
            None => link,
        };
        let result = drive(link, model, name, config, log_path).await;
        super::replay::finish(recorder.as_ref());
        result
    })
}

/// Find and connect to a real droid over Bluetooth.
async fn connect_real(args: &DriveArgs) -> Result<(Box<dyn Link>, Model, String), CliError> {
    let c = args.ble.connect(super::connect::Chooser::Screen).await?;
    Ok((c.link, c.model, c.name))
}

/// The session the app drives `model` through, as the configuration sets it: the connect
/// setup (tripod, sensor streaming), the request timeout, the pacing (0: the model's).
pub fn session_config(model: Model, config: &Config) -> SessionConfig {
    let setup = SetupOptions {
        tripod: true,
        streaming_interval_ms: config.control.streaming_interval_ms,
    };
    let pacing = match config.session.pacing_ms {
        0 => model.write_pacing(),
        ms => Duration::from_millis(ms),
    };
    SessionConfig {
        family: model.protocol(),
        request_timeout: Duration::from_millis(config.session.request_timeout_ms),
        pacing,
        setup: connect_setup(model, &setup),
        ..SessionConfig::default()
    }
}

async fn drive(
    link: Box<dyn Link>,
    model: Model,
    name: String,
    config: Config,
    log_path: Option<std::path::PathBuf>,
) -> Result<i32, CliError> {
    let session = session::start(link, session_config(model, &config));
    let _ = PANIC_SESSION.set((session.clone(), model));
    install_panic_hook();

    let mut guard = TerminalGuard::enter()
        .map_err(|e| CliError::failure(format!("cannot use this terminal: {e}")))?;
    let release = guard.release_mode(&config.keyboard);
    tracing::info!(?release, %name, "starting the TUI");

    let (term_rx, reader) = term::spawn_reader();
    // Gamepad.
    let (pad_tx, pad_rx) = mpsc::channel(256);
    if config.gamepad.enabled {
        if let Err(e) = crate::teleop::gamepad::spawn(pad_tx) {
            tracing::warn!(error = %e, "no gamepad thread");
        }
    } else {
        drop(pad_tx);
    }
    // Signals.
    let (quit_tx, quit_rx) = mpsc::channel::<String>(4);
    let signals = tokio::spawn(async move {
        let why = super::signals::terminated().await;
        let _ = quit_tx.send(why.to_string()).await;
    });

    let sleep_on_exit = config.control.sleep_on_exit;
    let opts = AppOptions {
        config,
        model,
        droid_name: name,
        log_path: log_path.clone(),
        release,
        tripod_on_connect: true,
    };
    let inputs = AppInputs {
        term: term_rx,
        pad: pad_rx,
        quit: quit_rx,
    };
    // The app runs as its own task so a panic in it is caught here: the droid is stopped first,
    // then the terminal restored, then the message shown.
    let app_session = session.clone();
    let app = tokio::spawn(async move {
        let backend = CrosstermBackend::new(std::io::stdout());
        // The alternate screen was cleared on entry; `Terminal::clear` would also ask the
        // terminal for the cursor position, which some terminals never answer.
        let mut terminal = Terminal::new(backend)?;
        run::run(&mut terminal, app_session, opts, inputs, crate::ui::draw).await
    });
    let result = app.await;
    let stop_cmds = match &result {
        Ok(Ok(exit)) => run::exit_commands(model, Some(exit.stop.clone()), sleep_on_exit),
        // A crash: no controller to ask; the session stops at the last heading it wrote.
        _ => run::exit_commands(model, Vec::new(), sleep_on_exit),
    };
    // The session's own budget (1 s of final writes, 1.5 s to close) fits inside this one.
    let _ = tokio::time::timeout(Duration::from_secs(3), session.shutdown_stopped(stop_cmds)).await;
    reader.abort();
    signals.abort();
    guard.restore();
    match result {
        Ok(Ok(exit)) => {
            if let ExitReason::Signal(s) = &exit.reason {
                eprintln!("droidctl: {s}: stopped the droid and exited");
            }
            Ok(0)
        }
        Ok(Err(e)) => Err(CliError::failure(format!("terminal error: {e}"))),
        Err(join) => {
            let msg = PANIC_MESSAGE
                .lock()
                .ok()
                .and_then(|mut m| m.take())
                .unwrap_or_else(|| join.to_string());
            let log = log_path
                .map(|p| format!(" Details are in {}.", p.display()))
                .unwrap_or_default();
            Err(CliError {
                status: 101,
                message: format!("internal error, the droid was sent a stop: {msg}.{log}"),
            })
        }
    }
}
