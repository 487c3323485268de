//! `droidctl run` on several droids: the droids named (`--sim r2d2,bb8`, repeated `--name`
//! and `--remote`) form a fleet, the script's `@NAME` lines go to their droid, `together`
//! blocks run at once. Output as for one droid with each line naming its droid: `--json`
//! samples and summaries gain a `droid` field. Simulated fleets run in simulated time and
//! give the same output every run.

use super::CliError;
use super::mission_run::{
    RunArgs, ended, finish_recording, mission_session, report_link_of, sample_line, summary_line,
    warning,
};
use super::run_output::{OUTPUT_GONE, RunOutput, Tagged};
use crate::fleet::Fleet;
use crate::fleet::mission::{self as fleet_mission, FleetEmit};
use crate::mission::{MissionEvent, MissionOptions, Summary};
use crate::model::Model;
use crate::script::{Item, ScriptError};
use std::sync::Arc;
use std::time::Duration;

pub fn run(
    args: &RunArgs,
    sims: Vec<Model>,
    items: &[Item],
    script_errors: impl Fn(Vec<ScriptError>) -> CliError,
) -> Result<i32, CliError> {
    let recorder = args.record.open()?;
    let config = crate::config::Config::load(&crate::config::config_path())
        .map_err(|e| CliError::usage(e.to_string()))?;
    let opts = MissionOptions {
        interval: Duration::from_millis(args.interval),
        ..MissionOptions::default()
    };
    let json = args.json;
    // `--csv FILE`: every droid's samples, the droid first on each row.
    let files = match &args.csv {
        Some(p) => Some(
            crate::mission::csv::SampleFiles::create_for_fleet(Some(p), None, args.record.force)
                .map_err(CliError::usage)?,
        ),
        None => None,
    };
    let out = Arc::new(RunOutput::new(files));
    let _ = crate::logging::init();
    let only_sims =
        args.ble.name.is_empty() && args.ble.remote.is_empty() && args.ble.serial.is_none();
    let rt = if only_sims {
        // Simulated time, as for one simulated droid.
        tokio::runtime::Builder::new_current_thread()
            .enable_time()
            .enable_io()
            .start_paused(true)
            .build()
            .map_err(|e| CliError::failure(format!("cannot start the runtime: {e}")))?
    } else {
        super::realtime_runtime()?
    };
    let summaries = rt.block_on(async {
        let mut found = super::fleet::find_all(&sims, &args.ble, &config).await?;
        if found.is_empty() {
            return Err(CliError::usage(
                "this mission addresses droids by name: say which droids with --sim \
                 MODEL[,MODEL…], --name (repeatable) or --remote (repeatable)",
            ));
        }
        super::fleet::record_all(recorder.as_ref(), &mut found);
        // Each droid's session and options (its own streaming plan and setup).
        let mut per_droid = Vec::with_capacity(found.len());
        let specs = found
            .into_iter()
            .map(|f| {
                let (cfg, o) = mission_session(f.model, opts.clone());
                per_droid.push(o);
                f.into_spec(cfg)
            })
            .collect();
        let fleet = Fleet::start(specs);
        let plan = match fleet_mission::plan(&fleet, items) {
            Ok(p) => p,
            Err(e) => {
                fleet.shutdown_all(|_| Vec::new()).await;
                return Err(script_errors(e));
            }
        };
        let reporters: Vec<_> = fleet
            .members()
            .iter()
            .map(|m| {
                let who = format!("{}: ", m.name);
                tokio::spawn(report_link_of(m.session.watch_state(), who))
            })
            .collect();
        let r = tokio::select! {
            r = fleet_mission::run(
                &fleet,
                &plan,
                &per_droid,
                printer(&fleet, json, &opts, recorder.clone(), out.clone()),
            ) => r,
            sig = super::signals::terminated() => Err(crate::mission::MissionError(format!(
                "{sig}: mission interrupted, every droid was stopped"
            ))),
            _ = out.closed() => Err(crate::mission::MissionError(OUTPUT_GONE.into())),
        };
        for t in reporters {
            t.abort();
        }
        if let Some(rec) = &recorder {
            for i in 0..fleet.len() {
                rec.for_droid(i)
                    .record(crate::capture::Event::Mark("mission-end".into()));
            }
        }
        fleet.shutdown_all(|_| Vec::new()).await;
        out.flush_csv();
        // In the runtime: under simulated time the `end` line has the mission's time.
        let kept = finish_recording(recorder.as_ref());
        let summaries = r.map_err(|e| CliError::failure(e.to_string()));
        Ok((
            summaries.map(|s| fleet.names().into_iter().zip(s).collect::<Vec<_>>()),
            kept,
        ))
    });
    let (summaries, kept) = summaries?;
    finish_fleet(summaries, kept, json, &out)
}

/// How a run on several droids ends once they are stopped (a mission and a program alike):
/// a summary per droid (tagged with its name in JSON), or the error after what the output
/// said; then whether the recording was kept. Status 1 when any droid's step failed.
pub(super) fn finish_fleet(
    summaries: Result<Vec<(String, Summary)>, CliError>,
    kept: Result<(), CliError>,
    json: bool,
    out: &RunOutput,
) -> Result<i32, CliError> {
    let summaries = ended(summaries, out)?;
    let mut failed = 0;
    for (name, s) in &summaries {
        failed += s.failed_steps;
        if json {
            let t = Tagged {
                droid: name,
                inner: s,
            };
            out.stdout(|w| {
                serde_json::to_writer(&mut *w, &t).map_err(std::io::Error::from)?;
                writeln!(w)
            });
        } else {
            out.stdout(|w| writeln!(w, "{name}: {}", summary_line(s, false)));
        }
    }
    out.result()?;
    kept?;
    Ok(if failed > 0 { 1 } else { 0 })
}

/// Print each droid's steps, samples and warnings as they come, naming the droid; with a
/// recorder, mark each droid's mission start and steps in its lines of the capture (replay
/// samples from there, as for one droid).
pub(super) fn printer(
    fleet: &Fleet,
    json: bool,
    opts: &MissionOptions,
    recorder: Option<crate::capture::record::Recorder>,
    out: Arc<RunOutput>,
) -> FleetEmit {
    use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
    let names = fleet.names();
    let per_line = (1000 / opts.interval.as_millis().max(1)).max(1) as u64;
    let counts: Vec<AtomicU64> = names.iter().map(|_| Default::default()).collect();
    let marked: Vec<AtomicBool> = names.iter().map(|_| Default::default()).collect();
    Arc::new(move |i, e| {
        let name = names.get(i).map(String::as_str).unwrap_or("?");
        if let Some(rec) = &recorder {
            let rec = rec.for_droid(i);
            match &e {
                MissionEvent::Sample(s)
                    if !marked
                        .get(i)
                        .is_some_and(|m| m.swap(true, Ordering::Relaxed)) =>
                {
                    rec.mark_before(Duration::from_millis(s.t_ms), "mission-start");
                }
                MissionEvent::Step { line, text, .. } => {
                    // The droid's own line, as a one-droid capture has it (replay reads it).
                    let own = text
                        .strip_prefix('@')
                        .and_then(|r| r.split_once(char::is_whitespace))
                        .map_or(text.as_str(), |(_, rest)| rest.trim());
                    rec.record(crate::capture::Event::Mark(format!("step {line} {own}")));
                }
                _ => {}
            }
        }
        if let MissionEvent::Sample(s) = &e {
            out.csv_sample(Some(name), s);
        }
        match e {
            MissionEvent::Sample(s) if json => {
                let t = Tagged {
                    droid: name,
                    inner: &s,
                };
                out.stdout(|w| {
                    serde_json::to_writer(&mut *w, &t).map_err(std::io::Error::from)?;
                    writeln!(w)
                });
            }
            MissionEvent::Sample(s) => {
                let n = counts
                    .get(i)
                    .map_or(0, |c| c.fetch_add(1, Ordering::Relaxed));
                if !n.is_multiple_of(per_line) {
                    return;
                }
                let line = sample_line(&s);
                // `[   1.00s] pos …` becomes `[   1.00s] D2-0001 pos …`.
                out.stdout(|w| match line.split_once("] ") {
                    Some((t, rest)) => writeln!(w, "{t}] {name} {rest}"),
                    None => writeln!(w, "{name} {line}"),
                });
            }
            MissionEvent::Step { t_ms, line, text } if !json => out.stdout(|w| {
                writeln!(
                    w,
                    "[{:>8.2}s] {name} line {line}: {text}",
                    t_ms as f64 / 1000.0
                )
            }),
            MissionEvent::Step { .. } => {}
            MissionEvent::Warning {
                t_ms,
                line,
                message,
            } => warning(&format!("{name}: "), t_ms, line, &message),
        }
    })
}
