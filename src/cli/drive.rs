//! `droidctl` / `droidctl drive`: the full-screen teleop app.

use super::CliError;
use super::term::{self, TerminalGuard};
use crate::app::run::{self, AppInputs, AppOptions, ExitReason};
use crate::config::Config;
use crate::fleet::Fleet;
use crate::link::Link;
use crate::model::Model;
use crate::sim::{Faults, SimConfig, SimLink};
use clap::Args;
use ratatui::Terminal;
use ratatui::backend::CrosstermBackend;
use std::sync::{Mutex, OnceLock};
use tokio::sync::mpsc;

#[derive(Debug, Clone, Default, Args)]
pub struct DriveArgs {
    /// Drive a simulated droid in-process (r2d2 without a MODEL); several at once, sharing
    /// one room: --sim r2d2,bb8,robi.
    #[arg(long, num_args = 0..=1, default_missing_value = "r2d2", value_name = "MODEL[,MODEL…]",
          value_parser = super::models::ModelNames::list(),
          add = clap_complete::ArgValueCompleter::new(super::complete::model_list))]
    pub sim: Option<String>,
    #[command(flatten)]
    pub ble: super::connect::BleArgs,
    #[command(flatten)]
    pub record: super::replay::RecordArgs,
    /// Write every telemetry sample the droid streams to FILE as CSV (columns named with
    /// units).
    #[arg(long, value_name = "FILE")]
    pub csv: Option<std::path::PathBuf>,
    /// Write every telemetry sample to FILE as JSON lines (the objects `run --json` prints).
    #[arg(long, value_name = "FILE")]
    pub jsonl: Option<std::path::PathBuf>,
    /// Run a Sphero Edu JavaScript program on the droid (every droid of a fleet) with the
    /// screen live; the emergency stop ends it and the motion (see docs/edu-programs.md).
    #[arg(long, value_name = "PROGRAM.js")]
    pub program: Option<std::path::PathBuf>,
    /// The memory the program's engine may use, MiB (bounded on Linux; see
    /// docs/edu-programs.md).
    #[arg(long, value_name = "MIB", default_value_t = crate::edu::child::DEFAULT_MEMORY_MIB,
          value_parser = clap::value_parser!(u64).range(16..=65_536))]
    pub program_memory: u64,
}

/// `--program FILE`, read and checked before anything connects (a syntax error is exit 2).
fn program(args: &DriveArgs) -> Result<Option<crate::edu::Program>, CliError> {
    let Some(path) = &args.program else {
        return Ok(None);
    };
    let shown = path.display().to_string();
    let text = crate::text_file::read(path, crate::text_file::MAX_SCRIPT_BYTES)
        .map_err(|e| CliError::usage(format!("cannot read program {shown}: {e}")))?;
    let engine = super::program::engine_options(args.program_memory);
    super::program::parse(text, &shown, &engine).map(Some)
}

/// A program's lines in the log: this many at once, then this many a second.
const PROGRAM_LINES_BURST: u32 = 500;
const PROGRAM_LINES_PER_S: u32 = 50;

/// How a program beside the app ended.
#[derive(Debug)]
enum ProgramEnd {
    Ended,
    /// By the operator's emergency stop.
    Stopped(String),
    /// By its own error (or its engine's end): the app's exit status is 1.
    Failed(String),
}

/// The program on every droid of the fleet, as tasks beside the app: its calls and warnings
/// go to the log file, its status to the screen (each droid's, by fleet index); each ends
/// with its droid's result.
fn start_programs(
    fleet: &Fleet,
    program: Option<crate::edu::Program>,
) -> (
    Vec<tokio::task::JoinHandle<ProgramEnd>>,
    crate::app::program_status::ProgramFeeds,
) {
    let Some(program) = program else {
        return (Vec::new(), Vec::new());
    };
    let program = std::sync::Arc::new(program);
    let mut feeds = Vec::new();
    let tasks = fleet
        .members()
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let (session, model, name) = (m.session.clone(), m.model, m.name.clone());
            let program = program.clone();
            let (progress, feed) = crate::edu::progress::channel(&program.path);
            feeds.push((i, feed));
            tokio::spawn(async move {
                let who = name.clone();
                // A program that calls in a tight loop must not fill the log: a burst, then a
                // few lines a second, and how many were left out.
                let budget = std::sync::Mutex::new(crate::logging::LineBudget::new(
                    PROGRAM_LINES_PER_S,
                    PROGRAM_LINES_BURST,
                ));
                let emit: crate::mission::Emit = std::sync::Arc::new(move |e| {
                    if matches!(e, crate::mission::MissionEvent::Sample(_)) {
                        return;
                    }
                    let now = tokio::time::Instant::now();
                    let held = budget.lock().map(|mut b| b.take(now)).unwrap_or(Some(0));
                    let Some(held) = held else { return };
                    if held > 0 {
                        tracing::info!(droid = %who, held, "program: lines not logged (too many)");
                    }
                    match e {
                        crate::mission::MissionEvent::Step { t_ms, line, text } => {
                            tracing::info!(droid = %who, t_ms, line, %text, "program")
                        }
                        crate::mission::MissionEvent::Warning { line, message, .. } => {
                            tracing::warn!(droid = %who, ?line, %message, "program")
                        }
                        crate::mission::MissionEvent::Sample(_) => {}
                    }
                });
                let opts = crate::edu::ProgramOptions {
                    progress: Some(progress),
                    ..Default::default()
                };
                let start = tokio::time::Instant::now();
                let r = crate::edu::run(&session, model, &program, opts, emit, start).await;
                tracing::info!(droid = %name, ?r, "program ended");
                match r {
                    Ok(_) => ProgramEnd::Ended,
                    // The operator's emergency stop ended it: the operator's choice, not the
                    // program's failure.
                    Err(e) if crate::edu::run::ended_by_emergency_stop(&e) => {
                        ProgramEnd::Stopped(format!("{name}: {e}"))
                    }
                    Err(e) => ProgramEnd::Failed(format!("{name}: {e}")),
                }
            })
        })
        .collect();
    (tasks, feeds)
}

/// The simulated models asked for (`--sim r2d2,bb8`), none without `--sim`.
pub fn sim_models(sim: &Option<String>) -> Result<Vec<Model>, CliError> {
    match sim {
        None => Ok(Vec::new()),
        Some(list) => super::fleet::sim_models(list),
    }
}

static PANIC_MESSAGE: Mutex<Option<String>> = Mutex::new(None);
static PANIC_FLEET: OnceLock<Fleet> = OnceLock::new();

/// On a panic: ask the session to stop the droid at once (a synchronous slot write), keep
/// the message for after the terminal is restored; a panic outside the app task restores the
/// terminal itself and prints as usual.
fn install_panic_hook() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if let Some(fleet) = PANIC_FLEET.get() {
            // Every droid, at the last heading written: a stop at heading 0 would turn it.
            fleet.estop_all();
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
    let config = super::app_config(&config_path)?;
    let sims = sim_models(&args.sim)?;
    let program = program(&args)?;
    if super::fleet::is_fleet(sims.len(), &args.ble) {
        return run_fleet(args, sims, config, program);
    }
    let model = sims.first().copied();
    let recorder = args.record.open()?;
    let samples = sample_files(&args, false)?;
    let log_path = crate::logging::init().ok();
    let rt = super::realtime_runtime()?;
    rt.block_on(async move {
        let (link, model, name) = match model {
            Some(m) => {
                let link: Box<dyn Link> =
                    Box::new(SimLink::new(m, SimConfig::for_model(m), Faults::none()));
                (link, m, format!("{} (simulated)", m.display_name()))
            }
            None => {
                let c = args
                    .ble
                    .connect(super::connect::Chooser::Screen(
                        config.keymap.clone(),
                        config.display.theme,
                    ))
                    .await?;
                if !c.others.is_empty() {
                    // Several marked in the picker: drive them all (the files name each
                    // droid on every row).
                    let samples = sample_files(&args, true)?;
                    return drive_several(c, config, log_path, recorder, samples, program).await;
                }
                (c.link, c.model, c.name)
            }
        };
        let link = match &recorder {
            Some(r) => {
                r.start(&crate::capture::record::Recorder::header_for(model, &name));
                r.wrap(link)
            }
            None => link,
        };
        let origin = if args.sim.is_some() {
            "simulated"
        } else {
            "connected"
        };
        let fleet = Fleet::start(vec![crate::fleet::DroidSpec {
            session: super::fleet::session_config(model, &config, true),
            name,
            model,
            link,
            origin: origin.into(),
            room_origin: None,
        }]);
        let result = drive(fleet, config, log_path, samples, program).await;
        super::replay::finish(recorder.as_ref());
        result
    })
}

/// `--csv` and `--jsonl`, created now so a refusal comes before anything connects; a fleet's
/// rows start with their droid.
fn sample_files(
    args: &DriveArgs,
    fleet: bool,
) -> Result<Option<crate::mission::csv::SampleFiles>, CliError> {
    use crate::mission::csv::SampleFiles;
    let (csv, jsonl) = (args.csv.as_deref(), args.jsonl.as_deref());
    if csv.is_none() && jsonl.is_none() {
        return Ok(None);
    }
    let files = if fleet {
        SampleFiles::create_for_fleet(csv, jsonl, args.record.force)
    } else {
        SampleFiles::create(csv, jsonl, args.record.force)
    };
    files.map(Some).map_err(CliError::usage)
}

/// Several droids: find them all, start a session each, and run the app on the fleet.
fn run_fleet(
    args: DriveArgs,
    sims: Vec<Model>,
    config: Config,
    program: Option<crate::edu::Program>,
) -> Result<i32, CliError> {
    let recorder = args.record.open()?;
    let samples = sample_files(&args, true)?;
    let log_path = crate::logging::init().ok();
    let rt = super::realtime_runtime()?;
    rt.block_on(async move {
        let found = super::fleet::find_all(&sims, &args.ble, &config).await?;
        drive_found(found, config, log_path, recorder, samples, program).await
    })
}

/// The droids marked in the picker, as a fleet.
async fn drive_several(
    first: super::connect::Connected,
    config: Config,
    log_path: Option<std::path::PathBuf>,
    recorder: Option<crate::capture::record::Recorder>,
    samples: Option<crate::mission::csv::SampleFiles>,
    program: Option<crate::edu::Program>,
) -> Result<i32, CliError> {
    let super::connect::Connected {
        link,
        model,
        name,
        others,
        ..
    } = first;
    let found: Vec<super::fleet::Found> = std::iter::once((link, model, name))
        .chain(others.into_iter().map(|c| (c.link, c.model, c.name)))
        .map(|(link, model, name)| super::fleet::Found {
            link,
            model,
            name,
            origin: "Bluetooth".into(),
            room_origin: None,
        })
        .collect();
    drive_found(found, config, log_path, recorder, samples, program).await
}

/// Drive the droids found, recording them all into one capture when asked.
async fn drive_found(
    mut found: Vec<super::fleet::Found>,
    config: Config,
    log_path: Option<std::path::PathBuf>,
    recorder: Option<crate::capture::record::Recorder>,
    samples: Option<crate::mission::csv::SampleFiles>,
    program: Option<crate::edu::Program>,
) -> Result<i32, CliError> {
    super::fleet::record_all(recorder.as_ref(), &mut found);
    let specs = found
        .into_iter()
        .map(|f| {
            let cfg = super::fleet::session_config(f.model, &config, true);
            f.into_spec(cfg)
        })
        .collect();
    let result = drive(Fleet::start(specs), config, log_path, samples, program).await;
    super::replay::finish(recorder.as_ref());
    result
}

async fn drive(
    fleet: Fleet,
    config: Config,
    log_path: Option<std::path::PathBuf>,
    samples: Option<crate::mission::csv::SampleFiles>,
    program: Option<crate::edu::Program>,
) -> Result<i32, CliError> {
    let Some(first) = fleet.member(0) else {
        return Err(CliError::usage("no droid to drive"));
    };
    let (model, name) = (first.model, first.name.clone());
    let _ = PANIC_FLEET.set(fleet.clone());
    install_panic_hook();
    let setup_tripod = true;

    let mut guard = TerminalGuard::enter()
        .map_err(|e| CliError::failure(format!("cannot use this terminal: {e}")))?;
    let release = guard.release_mode(&config.keyboard);
    tracing::info!(?release, %name, "starting the TUI");

    let (term_rx, reader) = term::spawn_reader();
    // Gamepad.
    let (pad_tx, pad_rx) = mpsc::channel(256);
    if config.gamepad.enabled {
        if let Err(e) = crate::teleop::gamepad::spawn(pad_tx, config.gamepad.mappings.clone()) {
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
        tripod_on_connect: setup_tripod,
        samples,
        remember: crate::app::remember::default_dir(),
    };
    let inputs = AppInputs {
        term: term_rx,
        pad: pad_rx,
        quit: quit_rx,
    };
    // The app runs as its own task so a panic in it is caught here: the droid is stopped first,
    // then the terminal restored, then the message shown.
    let app_fleet = fleet.clone();
    let (programs, feeds) = start_programs(&fleet, program);
    let app = tokio::spawn(async move {
        let backend = CrosstermBackend::new(std::io::stdout());
        // The alternate screen was cleared on entry; `Terminal::clear` would also ask the
        // terminal for the cursor position, which some terminals never answer.
        let mut terminal = Terminal::new(backend)?;
        let draw = crate::ui::draw;
        run::run_with_programs(&mut terminal, app_fleet, opts, inputs, feeds, draw).await
    });
    let result = app.await;
    // A program still running ends with the app (the stops below stop its motion).
    let mut program_results = Vec::new();
    for p in programs {
        if p.is_finished() {
            program_results.push(
                p.await
                    .unwrap_or_else(|e| ProgramEnd::Failed(e.to_string())),
            );
        } else {
            p.abort();
        }
    }
    // Every droid: its app stop, then sleep when configured; after a crash there is no
    // controller to ask, and each session stops at the last heading it wrote. The sessions'
    // own budget (1 s of final writes, 1.5 s to close) fits inside the fleet's 3 s.
    let stops: Vec<_> = match &result {
        Ok(Ok(exit)) => exit.stops.clone(),
        _ => Vec::new(),
    };
    fleet
        .shutdown_all(|i| {
            let m = fleet.members()[i].model;
            run::exit_commands(m, stops.get(i).cloned(), sleep_on_exit)
        })
        .await;
    reader.abort();
    signals.abort();
    guard.restore();
    let mut program_failed = false;
    for r in program_results {
        match r {
            ProgramEnd::Ended => eprintln!("droidctl: the program ended"),
            ProgramEnd::Stopped(e) => eprintln!("droidctl: the program: {e}"),
            ProgramEnd::Failed(e) => {
                program_failed = true;
                eprintln!("droidctl: the program failed: {e}");
            }
        }
    }
    match result {
        Ok(Ok(exit)) => {
            if let ExitReason::Signal(s) = &exit.reason {
                if fleet.len() > 1 {
                    eprintln!(
                        "droidctl: {s}: stopped the {} droids and exited",
                        fleet.len()
                    );
                } else {
                    eprintln!("droidctl: {s}: stopped the droid and exited");
                }
            }
            // A program that failed fails the run, as `droidctl run PROGRAM.js` does.
            Ok(i32::from(program_failed))
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
