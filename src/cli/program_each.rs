//! `droidctl run --each A.js B.js … --sim MODEL`: a class's Sphero Edu programs, each on a
//! fresh simulated droid of its own, one after another, in simulated time. One line per
//! file says how it went: it ended (when, and where the droid stopped), its error with the
//! line, or its time limit. Exit 1 when any did not end by itself.

use super::CliError;
use super::mission_run::{RunArgs, mission_session, warning};
use super::run_output::RunOutput;
use crate::edu::run::{ProgramOptions, TIME_LIMIT};
use crate::mission::{MissionEvent, MissionOptions, Summary};
use crate::model::Model;
use crate::sim::{Faults, SimConfig, SimLink};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

/// How one program went.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
enum Outcome {
    /// It ended by itself (`startProgram` returned, or `exitProgram()`).
    Ended,
    /// A syntax error, a misspelt call, an exception: nothing more ran.
    Error,
    /// Its time limit ended it.
    TimeLimit,
}

/// One program's line (and `--json` object).
#[derive(Debug, serde::Serialize)]
struct Line {
    program: String,
    result: Outcome,
    #[serde(skip_serializing_if = "Option::is_none")]
    message: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    t_ms: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    x_cm: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    y_cm: Option<f32>,
}

impl Line {
    fn text(&self) -> String {
        let at = match (self.x_cm, self.y_cm) {
            (Some(x), Some(y)) => format!(", final position ({x:.1}, {y:.1}) cm"),
            _ => String::new(),
        };
        let t = self
            .t_ms
            .map(|t| format!(" after {:.2} s", t as f64 / 1000.0))
            .unwrap_or_default();
        match self.result {
            Outcome::Ended => format!("{}: ended{t}{at}", self.program),
            Outcome::Error | Outcome::TimeLimit => self.message.clone().unwrap_or_default(),
        }
    }
}

/// The files of `run --each`: SCRIPT and the PROGRAMs after it.
fn files(args: &RunArgs, first: PathBuf) -> Vec<PathBuf> {
    std::iter::once(first)
        .chain(args.more.iter().cloned())
        .collect()
}

pub fn run(args: &RunArgs, sims: &[Model], first: PathBuf) -> Result<i32, CliError> {
    let model = match sims {
        [m] if args.ble.name.is_empty() && args.ble.remote.is_empty() => *m,
        _ => {
            return Err(CliError::usage(
                "--each runs each program on a simulated droid of its own: give one model \
                 with --sim MODEL (run --each A.js B.js --sim bolt)",
            ));
        }
    };
    if args.record.record.is_some() || args.csv.is_some() {
        return Err(CliError::usage(
            "--each prints one line per program: --record and --csv are for one run",
        ));
    }
    let engine = super::program::engine_options(args.program_memory);
    let out = Arc::new(RunOutput::new(None));
    let _ = crate::logging::init();
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .enable_io()
        .start_paused(true)
        .build()
        .map_err(|e| CliError::failure(format!("cannot start the runtime: {e}")))?;
    let mut failed = 0;
    for path in files(args, first) {
        let shown = path.display().to_string();
        let line = match read(&path, &shown, &engine) {
            Err(message) => Line {
                program: shown.clone(),
                result: Outcome::Error,
                message: Some(message),
                t_ms: None,
                x_cm: None,
                y_cm: None,
            },
            Ok(program) => rt.block_on(one(args, model, &program)),
        };
        if line.result != Outcome::Ended {
            failed += 1;
        }
        out.stdout(|w| {
            if args.json {
                serde_json::to_writer(&mut *w, &line).map_err(std::io::Error::from)?;
                writeln!(w)
            } else {
                writeln!(w, "{}", line.text())
            }
        });
        if out.stdout_failed() {
            break;
        }
    }
    rt.shutdown_background();
    out.result()?;
    Ok(if failed > 0 { 1 } else { 0 })
}

/// A file read and checked: the error as its line says it.
fn read(
    path: &std::path::Path,
    shown: &str,
    engine: &crate::edu::EngineOptions,
) -> Result<crate::edu::Program, String> {
    let text = crate::text_file::read(path, crate::text_file::MAX_SCRIPT_BYTES)
        .map_err(|e| format!("{shown}: cannot read it: {e}"))?;
    if !crate::edu::is_program(path, &text) {
        return Err(format!(
            "{shown}: not a Sphero Edu program (a .js file, or one with `function startProgram`)"
        ));
    }
    super::program::parse(text, shown, engine).map_err(|e| {
        e.message.replace(
            "\nthe program has an error; nothing was sent",
            "; nothing was run",
        )
    })
}

/// One program on a fresh simulated droid.
async fn one(args: &RunArgs, model: Model, program: &crate::edu::Program) -> Line {
    let mission = MissionOptions {
        interval: Duration::from_millis(args.interval),
        ..MissionOptions::default()
    };
    let opts = super::program::options(args, mission, true);
    let link = SimLink::new(model, SimConfig::for_model(model), Faults::none());
    let (config, mission) = mission_session(model, opts.mission.clone());
    let session = crate::session::start(Box::new(link), config);
    let who = format!("{}: ", program.path);
    let emit: crate::mission::Emit = Arc::new(move |e| {
        if let MissionEvent::Warning {
            t_ms,
            line,
            message,
        } = e
        {
            warning(&who, t_ms, line, &message);
        }
    });
    let opts = ProgramOptions { mission, ..opts };
    let start = tokio::time::Instant::now();
    let ended = tokio::select! {
        e = crate::edu::run::run_to_end(&session, model, program, opts, emit, start) => e,
        sig = super::signals::terminated() => crate::edu::run::Ended {
            result: Err(crate::mission::MissionError(format!(
                "{sig}: program interrupted, the droid was stopped"
            ))),
            summary: None,
        },
    };
    session.shutdown_stopped(Vec::new()).await;
    let s: Option<&Summary> = ended.summary.as_ref();
    let (result, message) = match &ended.result {
        Ok(_) => (Outcome::Ended, None),
        Err(e) if e.0.contains(TIME_LIMIT) => (Outcome::TimeLimit, Some(e.0.clone())),
        Err(e) => (Outcome::Error, Some(e.0.clone())),
    };
    Line {
        program: program.path.clone(),
        result,
        message,
        t_ms: s.map(|s| s.t_ms),
        x_cm: s.and_then(|s| s.x_cm),
        y_cm: s.and_then(|s| s.y_cm),
    }
}
