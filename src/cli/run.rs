//! `droidctl run SCRIPT [--sim [MODEL]] [--json] [--interval MS]`: run a mission script on
//! one droid (here), on a fleet ([`super::fleet_run`]), or a Sphero Edu program
//! ([`super::program`]); what they share is [`super::mission_run`].

use super::CliError;
pub use super::mission_run::{RunArgs, mission_session, report_link, report_link_of, run_on};
use super::mission_run::{finish_recording, finish_run, recorded, run_recorded};
use super::run_output::RunOutput;
use crate::mission::{self, MissionOptions};
use crate::model::Model;
use crate::sim::{Faults, SimConfig, SimLink};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

/// Resolve `--sim MODEL[,MODEL…]` vs the script path: `droidctl run --sim mission.txt` puts
/// the script where the model would go.
pub(super) fn resolve(args: &RunArgs) -> Result<(PathBuf, Vec<Model>), CliError> {
    let mut script = args.script.clone();
    let models = match &args.sim {
        None => Vec::new(),
        Some(m) if m.contains(',') => super::fleet::sim_models(m)?,
        Some(m) => match Model::from_id(m) {
            Some(model) if crate::sim::simulates(model) => vec![model],
            Some(other) => {
                return Err(CliError::usage(format!(
                    "{} is not simulated yet: use one of {}",
                    other.display_name(),
                    crate::sim::simulated_ids().join(", ")
                )));
            }
            None if script.is_none() => {
                script = Some(PathBuf::from(m));
                vec![Model::DEFAULT]
            }
            None => {
                return Err(CliError::usage(
                    Model::parse_id(m).err().unwrap_or_default(),
                ));
            }
        },
    };
    let script = script.ok_or_else(|| CliError::usage("run needs a SCRIPT file"))?;
    Ok((script, models))
}

pub fn run(args: RunArgs) -> Result<i32, CliError> {
    let (path, sims) = resolve(&args)?;
    let text = crate::text_file::read(&path, crate::text_file::MAX_SCRIPT_BYTES)
        .map_err(|e| CliError::usage(format!("cannot read script {}: {e}", path.display())))?;
    let shown = path.display().to_string();
    let script_errors = |errs: Vec<crate::script::ScriptError>| {
        let lines: Vec<String> = errs
            .iter()
            .map(|e| format!("{shown}:{}: {}", e.line, e.message))
            .collect();
        CliError::usage(format!(
            "the script has errors; nothing was sent\n{}",
            lines.join("\n")
        ))
    };
    if crate::edu::is_program(&path, &text) {
        return super::program::run(&args, sims, text, &shown);
    }
    if args.each {
        return Err(CliError::usage(format!(
            "{shown} is a mission script: --each runs Sphero Edu programs (.js)"
        )));
    }
    if !args.more.is_empty() {
        return Err(CliError::usage(format!(
            "{shown} is a mission script: only Sphero Edu programs (.js) run one per droid; \
             a mission gives each droid its own lines with `@NAME` (docs/missions.md)"
        )));
    }
    let items = crate::script::parse_fleet(&text).map_err(script_errors)?;
    if super::fleet::is_fleet(sims.len(), &args.ble) || crate::script::is_fleet(&items) {
        return super::fleet_run::run(&args, sims, &items, script_errors);
    }
    let sim = sims.first().copied();
    let steps = crate::script::plain_steps(&items);
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
    let opts = MissionOptions {
        interval: Duration::from_millis(args.interval),
        ..MissionOptions::default()
    };
    let json = args.json;
    let result = match sim {
        Some(model) => {
            mission::validate(model, &steps).map_err(script_errors)?;
            let _ = crate::logging::init();
            // Simulated time: the clock jumps whenever everything waits, so a 60 s mission
            // takes a fraction of a second and behaves exactly as in real time.
            // IO only for the signal handlers (Ctrl-C stops the mission).
            let rt = tokio::runtime::Builder::new_current_thread()
                .enable_time()
                .enable_io()
                .start_paused(true)
                .build()
                .map_err(|e| CliError::failure(format!("cannot start the runtime: {e}")))?;
            let out = out.clone();
            rt.block_on(async move {
                let link = SimLink::new(model, SimConfig::for_model(model), Faults::none());
                let name = format!("{} (simulated)", model.display_name());
                let link = recorded(recorder, Box::new(link), model, &name);
                let r = run_recorded(link, model, &steps, opts, json, recorder, out).await;
                let kept = finish_recording(recorder);
                (r.map_err(CliError::failure), kept)
            })
        }
        None => {
            let _ = crate::logging::init();
            let rt = super::realtime_runtime()?;
            let out = out.clone();
            rt.block_on(async move {
                let c = match args.ble.connect(super::connect::Chooser::Prompt).await {
                    Ok(c) => c,
                    Err(e) => return (Err(e), finish_recording(recorder)),
                };
                if let Err(e) = mission::validate(c.model, &steps) {
                    return (Err(script_errors(e)), finish_recording(recorder));
                }
                let link = recorded(recorder, c.link, c.model, &c.name);
                let r = run_recorded(link, c.model, &steps, opts, json, recorder, out).await;
                let kept = finish_recording(recorder);
                (r.map_err(CliError::failure), kept)
            })
        }
    };
    let (result, kept) = result;
    finish_run(result, kept, json, &out)
}
