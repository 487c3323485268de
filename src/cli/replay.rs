//! `--record FILE` (on `drive` and `run`) and `droidctl replay FILE`.

use super::CliError;
use crate::capture::record::Recorder;
use clap::Args;
use std::path::PathBuf;

/// `--record FILE [--force]`.
#[derive(Debug, Clone, Default, Args)]
pub struct RecordArgs {
    /// Record everything over the link to FILE, in droidctl's capture format (see README,
    /// "Captures"). An existing FILE is kept unless --force.
    #[arg(long, value_name = "FILE")]
    pub record: Option<PathBuf>,
    /// With --record: replace FILE if it exists.
    #[arg(long, requires = "record")]
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
    /// With --json: the sample interval in milliseconds.
    #[arg(long, default_value_t = 100, value_name = "MS", value_parser = clap::value_parser!(u64).range(1..=60_000))]
    pub interval: u64,
    /// The droid model, for a capture that does not name it (a btsnoop log names only the
    /// protocol family): r2d2, r2q5, bb9e, bb8, sprk, ollie or robi.
    #[arg(long, value_name = "MODEL")]
    pub model: Option<String>,
    /// For a btsnoop log that starts after the GATT discovery: the ATT handle(s) of the
    /// droid's characteristics (decimal or 0x hex; repeat for several).
    #[arg(long, value_name = "N")]
    pub handle: Vec<String>,
}

/// Load the capture and pick the model: `--model`, the capture's, or one of its family's.
pub fn load(args: &ReplayArgs) -> Result<(crate::capture::Capture, crate::model::Model), CliError> {
    let handles = args
        .handle
        .iter()
        .map(|h| {
            crate::protocol::wire::parse_uint(h, u16::MAX as u64)
                .map(|v| v as u16)
                .map_err(|e| CliError::usage(format!("--handle: {e}")))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let capture =
        crate::capture::Capture::load_with(&args.file, &handles).map_err(CliError::failure)?;
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
        Some(m) => crate::model::Model::from_id(m)
            .ok_or_else(|| CliError::usage(format!("unknown model {m:?}")))?,
        None => match (capture.header.model, capture.family()) {
            (Some(m), _) => m,
            (None, Some(f)) => crate::family::for_protocol(f).representative(),
            (None, None) => {
                return Err(CliError::failure(format!(
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

pub fn run(args: ReplayArgs) -> Result<i32, CliError> {
    let (capture, model) = load(&args)?;
    for w in &capture.warnings {
        eprintln!("droidctl: {}: {w}", args.file.display());
    }
    if args.json {
        use std::io::Write;
        let mut out = std::io::BufWriter::new(std::io::stdout().lock());
        let file = args.file.display().to_string();
        // Each sample is written as it is made: memory stays flat whatever the span.
        let summary = crate::capture::replay::samples(
            &capture,
            model,
            std::time::Duration::from_millis(args.interval),
            &mut |s| {
                serde_json::to_writer(&mut out, s).map_err(std::io::Error::other)?;
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
        serde_json::to_writer(&mut out, &summary).map_err(|e| CliError::output(e.into()))?;
        writeln!(out).map_err(CliError::output)?;
        out.flush().map_err(CliError::output)?;
        return Ok(0);
    }
    play(capture, model, args.file.display().to_string())
}

/// The app on the capture: the terminal and its keys as `drive` has them, no droid, no
/// gamepad, nothing sent.
fn play(
    capture: crate::capture::Capture,
    model: crate::model::Model,
    file: String,
) -> Result<i32, CliError> {
    use crate::app::run::{self, AppInputs, AppOptions, ExitReason, Source};
    use ratatui::Terminal;
    use ratatui::backend::CrosstermBackend;
    use tokio::sync::mpsc;

    let config = crate::config::Config::load(&crate::config::config_path()).map_err(|e| {
        CliError::usage(format!(
            "{e}\nFix the file (or move it away to use the defaults) and try again."
        ))
    })?;
    let log_path = crate::logging::init().ok();
    let name = capture
        .header
        .droid
        .clone()
        .unwrap_or_else(|| format!("{} ({})", model.display_name(), capture.kind));
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
        };
        let inputs = AppInputs {
            term: term_rx,
            pad: pad_rx,
            quit: quit_rx,
        };
        let replay = crate::capture::replay::Replay::new(capture, model);
        let app = tokio::spawn(async move {
            let backend = CrosstermBackend::new(std::io::stdout());
            let mut terminal = Terminal::new(backend)?;
            let source = Source::Replay(Box::new(replay), file);
            run::run_source(&mut terminal, source, opts, inputs, crate::ui::draw).await
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
