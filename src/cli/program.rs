//! `droidctl run PROGRAM.js`: a Sphero Edu JavaScript program ([`crate::edu`]) with every
//! option `run` has: `--sim` in simulated time, `--name`, `--remote`, fleets (the program runs
//! on each droid), `--json`, `--csv`, `--record`, Ctrl+c. A syntax error is exit 2 before
//! anything is sent; an uncaught exception stops the droid and is exit 1 naming the line.

use super::CliError;
use super::fleet_run::{finish_fleet, printer};
use super::mission_run::{
    RunArgs, finish_recording, finish_run, mission_session, report_link_of, run_session,
};
use super::run_output::{OUTPUT_GONE, RunOutput};
use crate::edu::{Program, ProgramOptions};
use crate::fleet::Fleet;
use crate::mission::{MissionError, MissionOptions, Summary};
use crate::model::Model;
use crate::sim::{Faults, SimConfig, SimLink};
use std::sync::Arc;
use std::time::Duration;

/// A program's text as a [`Program`], checked in the engine's child: a syntax error, or a
/// program too deeply nested to parse, is a usage error (exit 2) naming where; an engine that
/// cannot start is a failure (exit 1).
pub(super) fn parse(
    text: String,
    shown: &str,
    engine: &crate::edu::EngineOptions,
) -> Result<Program, CliError> {
    use crate::edu::CheckError;
    Program::new_with(text, shown.to_string(), engine).map_err(|e| match e {
        CheckError::Syntax(e) => CliError::usage(format!(
            "{shown}:{}:{}: {}\nthe program has an error; nothing was sent",
            e.line, e.column, e.message
        )),
        CheckError::Unparsable(m) => CliError::usage(format!(
            "{shown}: {m}\nthe program has an error; nothing was sent"
        )),
        CheckError::Engine(m) => CliError::failure(format!("{shown}: {m}; nothing was sent")),
    })
}

/// `--program-memory`: how the engine's child is started.
pub(super) fn engine_options(memory_mib: u64) -> crate::edu::EngineOptions {
    let default = crate::edu::EngineOptions::default();
    crate::edu::EngineOptions {
        // 0: arguments made in code (`DriveArgs::default()`), not by clap.
        memory_mib: if memory_mib == 0 {
            default.memory_mib
        } else {
            memory_mib
        },
        ..default
    }
}

/// The programs after the first (`run a.js b.js …`): each read (bounded) and checked before
/// anything is sent.
fn more_programs(
    args: &RunArgs,
    engine: &crate::edu::EngineOptions,
) -> Result<Vec<Program>, CliError> {
    args.more
        .iter()
        .map(|path| {
            let shown = path.display().to_string();
            let text = crate::text_file::read(path, crate::text_file::MAX_SCRIPT_BYTES)
                .map_err(|e| CliError::usage(format!("cannot read program {shown}: {e}")))?;
            if !crate::edu::is_program(path, &text) {
                return Err(CliError::usage(format!(
                    "{shown} is not a Sphero Edu program (a .js file, or one with \
                     `function startProgram`)"
                )));
            }
            parse(text, &shown, engine)
        })
        .collect()
}

pub fn run(args: &RunArgs, sims: Vec<Model>, text: String, shown: &str) -> Result<i32, CliError> {
    let engine = engine_options(args.program_memory);
    if args.each {
        let first = args.script.clone().unwrap_or_else(|| shown.into());
        return super::program_each::run(args, &sims, first);
    }
    let program = parse(text, shown, &engine)?;
    let mut programs = vec![program];
    programs.extend(more_programs(args, &engine)?);
    let program = &programs[0];
    let mission = MissionOptions {
        interval: Duration::from_millis(args.interval),
        ..MissionOptions::default()
    };
    // The timeout is the program's, on droidctl's clock; how long it may compute without
    // waiting is another bound (a tiny timeout ends the program at its timeout).
    let only_sims = args.ble.name.is_empty() && args.ble.remote.is_empty();
    let opts = options(args, mission, !sims.is_empty() && only_sims);
    if super::fleet::is_fleet(sims.len(), &args.ble) {
        return fleet(args, sims, &programs, opts);
    }
    if programs.len() > 1 {
        return Err(CliError::usage(format!(
            "{} programs for one droid: give a fleet, one droid a program \
             (--sim bolt,bolt, or --name twice)",
            programs.len()
        )));
    }
    let recorder = args.record.open()?;
    let recorder = recorder.as_ref();
    let files = match &args.csv {
        Some(p) => Some(
            crate::mission::csv::SampleFiles::create(Some(p), None, args.record.force)
                .map_err(CliError::usage)?,
        ),
        None => None,
    };
    let out = Arc::new(RunOutput::new(files));
    let json = args.json;
    let _ = crate::logging::init();
    let failed_summary: Arc<std::sync::Mutex<Option<Summary>>> = Arc::default();
    let (rt, sim) = match sims.first().copied() {
        // Simulated time, as missions: the clock jumps whenever everything waits.
        Some(model) => (paused_runtime()?, Some(model)),
        None => (super::realtime_runtime()?, None),
    };
    let r = rt.block_on(async {
        let (link, model, name) = match sim {
            Some(model) => {
                let link = SimLink::new(model, SimConfig::for_model(model), Faults::none());
                let name = format!("{} (simulated)", model.display_name());
                (Box::new(link) as Box<dyn crate::link::Link>, model, name)
            }
            None => match args.ble.connect(super::connect::Chooser::Prompt).await {
                Ok(c) => (c.link, c.model, c.name),
                Err(e) => return (Err(e), finish_recording(recorder)),
            },
        };
        let link = match recorder {
            Some(r) => {
                r.start(&crate::capture::record::Recorder::header_for(model, &name));
                r.wrap(link)
            }
            None => link,
        };
        let p = program;
        let slot = failed_summary.clone();
        let r = run_session(
            link,
            model,
            opts.mission.clone(),
            json,
            recorder,
            out.clone(),
            {
                let opts = opts.clone();
                move |session, mission, emit| async move {
                    let opts = ProgramOptions { mission, ..opts };
                    let start = tokio::time::Instant::now();
                    let e =
                        crate::edu::run::run_to_end(&session, model, p, opts, emit, start).await;
                    if e.result.is_err() {
                        *crate::sync::lock(&slot) = e.summary;
                    }
                    e.result
                }
            },
        )
        .await;
        let kept = finish_recording(recorder);
        (r.map_err(CliError::failure), kept)
    });
    // An engine still spinning in a program that never yields is not waited for.
    rt.shutdown_background();
    let (result, kept) = r;
    // A call the droid does not have is bad input, found before anything was sent (exit 2).
    let result = result.map_err(|e| {
        if e.message.contains(crate::edu::engine::FOUND_BEFORE) {
            CliError::usage(e.message)
        } else {
            e
        }
    });
    if json
        && let Err(e) = &result
        && let Some(s) = crate::sync::lock(&failed_summary).take()
    {
        out.stdout(|w| writeln!(w, "{}", ended_line(&s, &e.message)));
    }
    finish_run(result, kept, json, &out)
}

/// `--json`'s summary of a program that failed or hit its time limit: the summary as for a
/// program that ended, with why it did not (`"ended": "error"` or `"time_limit"`, and the
/// error).
fn ended_line(s: &Summary, error: &str) -> String {
    let mut v = serde_json::to_value(s).unwrap_or_default();
    if let Some(o) = v.as_object_mut() {
        let how = if error.contains(crate::edu::run::TIME_LIMIT) {
            "time_limit"
        } else {
            "error"
        };
        o.insert("ended".into(), how.into());
        o.insert("error".into(), error.into());
    }
    v.to_string()
}

/// A program's options: its `--timeout`, or under `--sim` droidctl's own time limit
/// ([`crate::edu::run::SIM_TIME_LIMIT`]).
pub(super) fn options(args: &RunArgs, mission: MissionOptions, sim: bool) -> ProgramOptions {
    let given = args.timeout.map(Duration::from_secs_f64);
    ProgramOptions {
        mission,
        timeout: given.or(sim.then_some(crate::edu::run::SIM_TIME_LIMIT)),
        default_limit: given.is_none() && sim,
        ..ProgramOptions::default()
    }
}

fn paused_runtime() -> Result<tokio::runtime::Runtime, CliError> {
    tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .enable_io()
        .start_paused(true)
        .build()
        .map_err(|e| CliError::failure(format!("cannot start the runtime: {e}")))
}

/// The number of programs does not match the fleet (several programs are one per droid).
fn one_each(programs: usize, droids: usize) -> Result<(), CliError> {
    if programs > 1 && programs != droids {
        return Err(CliError::usage(format!(
            "{programs} programs for {droids} droids: give one program for every droid, or \
             one for all"
        )));
    }
    Ok(())
}

/// The program on every droid of a fleet at once (or each droid its own, in order), each its
/// own run from one start.
fn fleet(
    args: &RunArgs,
    sims: Vec<Model>,
    programs: &[Program],
    opts: ProgramOptions,
) -> Result<i32, CliError> {
    let only_sims =
        args.ble.name.is_empty() && args.ble.remote.is_empty() && args.ble.serial.is_none();
    if only_sims {
        one_each(programs.len(), sims.len())?;
    }
    let recorder = args.record.open()?;
    let config = crate::config::Config::load(&crate::config::config_path())
        .map_err(|e| CliError::usage(e.to_string()))?;
    let files = match &args.csv {
        Some(p) => Some(
            crate::mission::csv::SampleFiles::create_for_fleet(Some(p), None, args.record.force)
                .map_err(CliError::usage)?,
        ),
        None => None,
    };
    let out = Arc::new(RunOutput::new(files));
    let json = args.json;
    let _ = crate::logging::init();
    let rt = if only_sims {
        paused_runtime()?
    } else {
        super::realtime_runtime()?
    };
    let r = rt.block_on(async {
        let mut found = super::fleet::find_all(&sims, &args.ble, &config).await?;
        one_each(programs.len(), found.len())?;
        super::fleet::record_all(recorder.as_ref(), &mut found);
        let mut per_droid = Vec::with_capacity(found.len());
        let specs = found
            .into_iter()
            .map(|f| {
                let (cfg, o) = mission_session(f.model, opts.mission.clone());
                per_droid.push(o);
                f.into_spec(cfg)
            })
            .collect();
        let fleet = Fleet::start(specs);
        let reporters: Vec<_> = fleet
            .members()
            .iter()
            .map(|m| {
                tokio::spawn(report_link_of(
                    m.session.watch_state(),
                    format!("{}: ", m.name),
                ))
            })
            .collect();
        let emit = printer(&fleet, json, &opts.mission, recorder.clone(), out.clone());
        let start = tokio::time::Instant::now();
        let runs = fleet.members().iter().enumerate().map(|(i, m)| {
            let emit = emit.clone();
            let one: crate::mission::Emit = Arc::new(move |e| emit(i, e));
            let o = ProgramOptions {
                mission: per_droid.get(i).cloned().unwrap_or_default(),
                ..opts.clone()
            };
            let name = m.name.clone();
            let program = programs.get(i).unwrap_or(&programs[0]);
            async move {
                crate::edu::run(&m.session, m.model, program, o, one, start)
                    .await
                    .map_err(|e| MissionError(format!("{name}: {e}")))
            }
        });
        let all = futures_util::future::join_all(runs);
        let r: Result<Vec<Summary>, MissionError> = tokio::select! {
            r = all => r.into_iter().collect(),
            sig = super::signals::terminated() => Err(MissionError(format!(
                "{sig}: program interrupted, every droid was stopped"
            ))),
            _ = out.closed() => Err(MissionError(OUTPUT_GONE.into())),
        };
        for t in reporters {
            t.abort();
        }
        fleet.shutdown_all(|_| Vec::new()).await;
        out.flush_csv();
        let kept = finish_recording(recorder.as_ref());
        Ok::<_, CliError>((
            r.map(|s| fleet.names().into_iter().zip(s).collect::<Vec<_>>()),
            kept,
        ))
    });
    rt.shutdown_background();
    let (summaries, kept) = r?;
    let summaries = summaries.map_err(|e| CliError::failure(e.to_string()));
    finish_fleet(summaries, kept, json, &out)
}
