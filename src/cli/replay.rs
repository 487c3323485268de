//! `--record FILE` (on `drive` and `run`) and `droidctl replay FILE`.

use super::CliError;
use crate::capture::record::Recorder;
use clap::Args;
use std::io::Write as _;
use std::path::PathBuf;

/// `--record FILE [--force]`.
#[derive(Debug, Clone, Default, Args)]
pub struct RecordArgs {
    /// Record everything over the link to FILE, in droidctl's capture format (see
    /// docs/captures.md). An existing FILE is kept unless --force.
    #[arg(long, value_name = "FILE")]
    pub record: Option<PathBuf>,
    /// Replace the files this command writes (--record, and --csv or --jsonl where the
    /// command has them) when they exist; without it an existing file is kept and nothing
    /// starts.
    #[arg(long)]
    pub force: bool,
}

impl RecordArgs {
    /// Create the capture file now, so a refusal comes before anything connects.
    pub fn open(&self) -> Result<Option<Recorder>, CliError> {
        self.record
            .as_deref()
            .map(|p| Recorder::create(p, self.force).map_err(CliError::usage))
            .transpose()
    }
}

/// Finish a recording; a failure to write it is reported, not fatal to the exit status.
pub fn finish(rec: Option<&Recorder>) {
    if let Some(r) = rec
        && let Err(e) = r.finish()
    {
        eprintln!("droidctl: {e}");
    }
}

/// `droidctl replay FILE`.
#[derive(Debug, Clone, Args)]
#[command(
    after_help = "Keys in the app: Space or p pause/play; + and - speed (0.25x to 16x); \
Left/Right seek 5 s; PgUp/PgDn (or Down/Up) seek 60 s; Home/End start/end; . or s single step; \
l the packet log; ? help; q or Esc quit. Nothing is sent anywhere: the status bar says REPLAY."
)]
pub struct ReplayArgs {
    /// A capture: droidctl's (`--record`) or an HCI snoop log (btsnoop).
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    /// Print the telemetry samples as JSON, one per line, then a summary, without the app
    /// (the same samples as `droidctl run --json`).
    #[arg(long)]
    pub json: bool,
    /// Write the telemetry samples to FILE as CSV (columns named with units), without the
    /// app (with --json, both).
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// With --csv: replace FILE when it exists (without it an existing file is kept).
    #[arg(long, requires = "csv")]
    pub force: bool,
    /// With --json or --csv: the sample interval in milliseconds.
    #[arg(long, default_value_t = 100, value_name = "MS", value_parser = clap::value_parser!(u64).range(1..=60_000))]
    pub interval: u64,
    /// The droid model, for a capture that does not name it (a btsnoop log names only the
    /// protocol family; without it R2-D2, BB-8 or Robi 42 by family).
    #[arg(long, value_name = "MODEL", value_parser = super::models::ModelNames::one())]
    pub model: Option<String>,
    /// For a btsnoop log that starts after the GATT discovery: the ATT handle(s) of the
    /// droid's characteristics (decimal or 0x hex; repeat for several).
    #[arg(long, value_name = "N")]
    pub handle: Vec<String>,
}

/// Load the capture and pick the model: `--model`, the capture's, or one of its family's.
/// The `--handle` values.
fn handles(args: &ReplayArgs) -> Result<Vec<u16>, CliError> {
    args.handle
        .iter()
        .map(|h| {
            crate::protocol::wire::parse_uint(h, u16::MAX as u64)
                .map(|v| v as u16)
                .map_err(|e| CliError::usage(format!("--handle: {e}")))
        })
        .collect()
}

pub fn load(args: &ReplayArgs) -> Result<(crate::capture::Capture, crate::model::Model), CliError> {
    let handles = handles(args)?;
    let capture =
        // A file that is missing, unreadable or not a capture is bad input (status 2), as `run`
    // and `plot` say of theirs.
        crate::capture::Capture::load_with(&args.file, &handles).map_err(CliError::usage)?;
    let model = checked_model(
        &capture,
        args.model.as_deref(),
        &args.file.display().to_string(),
    )?;
    Ok((capture, model))
}

/// Check a loaded capture for replay and pick its model: `model` (`--model`), the capture's,
/// or one of its family's. `name` names the file in messages.
pub fn checked_model(
    capture: &crate::capture::Capture,
    model: Option<&str>,
    name: &str,
) -> Result<crate::model::Model, CliError> {
    crate::capture::replay::validate(capture)
        .map_err(|e| CliError::usage(format!("{name}: {e}")))?;
    let model = match model {
        Some(m) => crate::model::Model::parse_id(m).map_err(CliError::usage)?,
        None => match (capture.header.model, capture.family()) {
            (Some(m), _) => m,
            (None, Some(f)) => crate::family::for_protocol(f).representative(),
            (None, None) => {
                return Err(CliError::usage(format!(
                    "{name}: no droid traffic found in this {}",
                    capture.kind
                )));
            }
        },
    };
    if let Some(f) = capture.header.family
        && f != model.protocol()
    {
        return Err(CliError::usage(format!(
            "the capture holds {} traffic; {} speaks {}",
            crate::family::for_protocol(f).name(),
            model.display_name(),
            crate::family::for_model(model).name()
        )));
    }
    Ok(model)
}

/// A capture of several droids: each droid's capture, checked, with its model and name.
type FleetCaptures = Vec<(crate::capture::Capture, crate::model::Model, String)>;

/// Load a capture of several droids, if `args.file` is one.
fn load_fleet(args: &ReplayArgs) -> Result<Option<FleetCaptures>, CliError> {
    let bytes = std::fs::read(&args.file)
        .map_err(|e| CliError::usage(format!("cannot read {}: {e}", args.file.display())))?;
    let shown = args.file.display();
    let droids = if crate::capture::fleet::sniff(&bytes) {
        let split = crate::capture::fleet::read(&String::from_utf8_lossy(&bytes))
            .map_err(|e| CliError::usage(format!("{shown}: {e}")))?;
        // The file's own warnings, once (not once per droid).
        for w in &split.warnings {
            let _ = writeln!(std::io::stderr(), "droidctl: {shown}: {w}");
        }
        split.droids
    } else if crate::capture::btsnoop::sniff(&bytes) {
        // A phone's log of several droids: one droid per connection.
        let handles = handles(args)?;
        match crate::capture::hci::captures_by_connection(&bytes, &handles) {
            Ok(v) if v.len() > 1 => v.into_iter().map(|(_, c)| c).collect(),
            _ => return Ok(None),
        }
    } else {
        return Ok(None);
    };
    let mut out = Vec::with_capacity(droids.len());
    for (i, c) in droids.into_iter().enumerate() {
        crate::capture::replay::validate(&c)
            .map_err(|e| CliError::usage(format!("{shown}: droid {}: {e}", i + 1)))?;
        let given = args.model.as_deref().and_then(crate::model::Model::from_id);
        let model = c
            .header
            .model
            .or(given.filter(|m| Some(m.protocol()) == c.family()))
            .or_else(|| {
                c.family()
                    .map(|f| crate::family::for_protocol(f).representative())
            })
            .ok_or_else(|| CliError::failure(format!("{shown}: droid {}: no model", i + 1)))?;
        let name = c
            .header
            .droid
            .clone()
            .unwrap_or_else(|| format!("{} {}", model.display_name(), i + 1));
        out.push((c, model, name));
    }
    Ok(Some(out))
}

/// `replay --json` of a fleet's capture: each droid's samples and summary, naming it.
fn fleet_json(args: &ReplayArgs, droids: &FleetCaptures) -> Result<i32, CliError> {
    use super::run_output::Tagged;
    use std::io::Write;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let file = args.file.display().to_string();
    for (c, model, name) in droids {
        let summary = crate::capture::replay::samples(
            c,
            *model,
            std::time::Duration::from_millis(args.interval),
            &mut |s| {
                let t = Tagged {
                    droid: name,
                    inner: s,
                };
                serde_json::to_writer(&mut out, &t).map_err(std::io::Error::from)?;
                writeln!(out)
            },
            &mut |from, to| {
                eprintln!(
                    "droidctl: {file}: {name}: no traffic from {:.3} s to {:.3} s: not sampled",
                    from.as_secs_f64(),
                    to.as_secs_f64()
                )
            },
        )
        .map_err(CliError::output)?;
        let t = Tagged {
            droid: name,
            inner: &summary,
        };
        serde_json::to_writer(&mut out, &t).map_err(|e| CliError::output(e.into()))?;
        writeln!(out).map_err(CliError::output)?;
    }
    out.flush().map_err(CliError::output)?;
    Ok(0)
}

pub fn run(args: ReplayArgs) -> Result<i32, CliError> {
    if let Some(droids) = load_fleet(&args)? {
        for (c, _, name) in &droids {
            for w in &c.warnings {
                eprintln!("droidctl: {}: {name}: {w}", args.file.display());
            }
        }
        if args.json {
            return fleet_json(&args, &droids);
        }
        let replays = droids
            .into_iter()
            .map(|(c, m, name)| (crate::capture::replay::Replay::new(c, m), name))
            .collect();
        return play(Played::Fleet(replays), args.file.display().to_string());
    }
    let (capture, model) = load(&args)?;
    for w in &capture.warnings {
        eprintln!("droidctl: {}: {w}", args.file.display());
    }
    if args.json || args.csv.is_some() {
        use std::io::Write;
        let mut files =
            crate::mission::csv::SampleFiles::create(args.csv.as_deref(), None, args.force)
                .map_err(CliError::usage)?;
        let mut out = std::io::BufWriter::new(std::io::stdout().lock());
        let file = args.file.display().to_string();
        let json = args.json;
        // Each sample is written as it is made: memory stays flat whatever the span.
        let summary = crate::capture::replay::samples(
            &capture,
            model,
            std::time::Duration::from_millis(args.interval),
            &mut |s| {
                files.write(s)?;
                if !json {
                    return Ok(());
                }
                serde_json::to_writer(&mut out, s).map_err(std::io::Error::from)?;
                writeln!(out)
            },
            &mut |from, to| {
                eprintln!(
                    "droidctl: {file}: no traffic from {:.3} s to {:.3} s: not sampled",
                    from.as_secs_f64(),
                    to.as_secs_f64()
                )
            },
        )
        .map_err(CliError::output)?;
        files.flush().map_err(CliError::output)?;
        if json {
            serde_json::to_writer(&mut out, &summary).map_err(|e| CliError::output(e.into()))?;
            writeln!(out).map_err(CliError::output)?;
        }
        out.flush().map_err(CliError::output)?;
        return Ok(0);
    }
    let name = capture
        .header
        .droid
        .clone()
        .unwrap_or_else(|| format!("{} ({})", model.display_name(), capture.kind));
    let replay = crate::capture::replay::Replay::new(capture, model);
    play(
        Played::One(Box::new(replay), name),
        args.file.display().to_string(),
    )
}

/// What the app replays: one droid, or a fleet's droids with their names.
enum Played {
    One(Box<crate::capture::replay::Replay>, String),
    Fleet(Vec<(crate::capture::replay::Replay, String)>),
}

/// The app on the capture: the terminal and its keys as `drive` has them, no droid, no
/// gamepad, nothing sent.
fn play(played: Played, file: String) -> Result<i32, CliError> {
    use crate::app::run::{self, AppInputs, AppOptions, ExitReason, Source};
    use ratatui::Terminal;
    use ratatui::backend::CrosstermBackend;
    use tokio::sync::mpsc;

    let config = super::app_config(&crate::config::config_path())?;
    let log_path = crate::logging::init().ok();
    let (model, name) = match &played {
        Played::One(r, name) => (r.model(), name.clone()),
        Played::Fleet(v) => v
            .first()
            .map(|(r, n)| (r.model(), n.clone()))
            .ok_or_else(|| CliError::usage("the capture holds no droid"))?,
    };
    let rt = super::realtime_runtime()?;
    rt.block_on(async move {
        let mut guard = super::term::TerminalGuard::enter()
            .map_err(|e| CliError::failure(format!("cannot use this terminal: {e}")))?;
        let release = guard.release_mode(&config.keyboard);
        let (term_rx, reader) = super::term::spawn_reader();
        let (_pad_tx, pad_rx) = mpsc::channel(1);
        let (quit_tx, quit_rx) = mpsc::channel::<String>(4);
        let signals = tokio::spawn(async move {
            let why = super::signals::terminated().await;
            let _ = quit_tx.send(why.to_string()).await;
        });
        let mut config = config;
        config.gamepad.enabled = false;
        let opts = AppOptions {
            config,
            model,
            droid_name: name,
            log_path,
            release,
            tripod_on_connect: false,
            samples: None,
            remember: None,
        };
        let inputs = AppInputs {
            term: term_rx,
            pad: pad_rx,
            quit: quit_rx,
        };
        let app = tokio::spawn(async move {
            let backend = CrosstermBackend::new(std::io::stdout());
            let mut terminal = Terminal::new(backend)?;
            match played {
                Played::One(replay, _) => {
                    let source = Source::Replay(replay, file);
                    run::run(&mut terminal, source, opts, inputs, crate::ui::draw).await
                }
                Played::Fleet(replays) => {
                    run::run(
                        &mut terminal,
                        Source::FleetReplay(replays, file),
                        opts,
                        inputs,
                        crate::ui::draw,
                    )
                    .await
                }
            }
        });
        let result = app.await;
        reader.abort();
        signals.abort();
        guard.restore();
        match result {
            Ok(Ok(exit)) => {
                if let ExitReason::Signal(s) = &exit.reason {
                    eprintln!("droidctl: {s}: replay ended");
                }
                Ok(0)
            }
            Ok(Err(e)) => Err(CliError::failure(format!("terminal error: {e}"))),
            Err(join) => Err(CliError {
                status: 101,
                message: format!("internal error in the replay: {join}"),
            }),
        }
    })
}
