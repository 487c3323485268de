//! What every `droidctl run` shares, one droid or a fleet, a mission or a Sphero Edu program:
//! the arguments, a droid's mission session and how it reports its link, the capture being
//! recorded, the output lines (samples, the summary) and how a run ends. The command itself
//! (which of them runs) is [`super::run`].

use super::CliError;
use super::run_output::{OUTPUT_GONE, RunOutput, note};
use crate::family::setup::{SetupOptions, connect_setup};
use crate::link::Link;
use crate::mission::{self, MissionEvent, MissionOptions, Summary};
use crate::model::Model;
use crate::session::{self, LinkState, SessionConfig};
use clap::Args;
use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;

#[derive(Debug, Args)]
pub struct RunArgs {
    /// The mission script (see docs/missions.md; `@NAME` lines and `together { }` blocks
    /// for several droids), or a Sphero Edu JavaScript program (`.js`, see
    /// docs/edu-programs.md).
    #[arg(value_name = "SCRIPT")]
    pub script: Option<PathBuf>,
    /// Sphero Edu programs for the other droids of a fleet, one each in order: the first
    /// droid runs SCRIPT, the second the first PROGRAM, and so on (a broadcaster and its
    /// follower: `run beacon.js follow.js --sim bolt,bolt`). Without them every droid runs
    /// SCRIPT.
    #[arg(value_name = "PROGRAM")]
    pub more: Vec<PathBuf>,
    /// Sphero Edu programs: run SCRIPT and each PROGRAM after it on a fresh simulated droid
    /// of its own (--sim MODEL), one after another, and print one line per file: ended, its
    /// error with the line, or its time limit. Exit 1 when any did not end by itself.
    #[arg(long)]
    pub each: bool,
    /// Run against a simulated droid (r2d2 without a MODEL); the mission runs in simulated
    /// time. Several share one room: --sim r2d2,bb8,robi.
    #[arg(long, num_args = 0..=1, default_missing_value = "r2d2", value_name = "MODEL[,MODEL…]",
          value_parser = super::models::ModelNames::list_or_other(),
          add = clap_complete::ArgValueCompleter::new(super::complete::model_list))]
    pub sim: Option<String>,
    /// One JSON object per telemetry sample, then a summary object.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub ble: super::connect::BleArgs,
    /// Telemetry sample interval in milliseconds.
    #[arg(long, default_value_t = 100, value_name = "MS", value_parser = clap::value_parser!(u64).range(1..=60_000))]
    pub interval: u64,
    #[command(flatten)]
    pub record: super::replay::RecordArgs,
    /// A Sphero Edu program (`PROGRAM.js`): end it after SECONDS on droidctl's clock
    /// (simulated with --sim). Apart from it, a program computing 5 s without waiting ends.
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    pub timeout: Option<f64>,
    /// A Sphero Edu program: the memory its engine may use, MiB (bounded on Linux; see
    /// docs/edu-programs.md).
    #[arg(long, value_name = "MIB", default_value_t = crate::edu::child::DEFAULT_MEMORY_MIB,
          value_parser = clap::value_parser!(u64).range(16..=65_536))]
    pub program_memory: u64,
    /// Also write every sample to FILE as CSV (columns named with units; see docs/monitoring.md; a fleet's
    /// rows start with the droid).
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
}

/// `--timeout`: seconds, more than 0 and at most a day.
fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && v <= 86_400.0 => Ok(v),
        _ => Err(format!(
            "`{s}` is not a number of seconds (more than 0, at most 86400)"
        )),
    }
}

/// A mission's warning on stderr, at its time and line; `who` names the droid of a fleet
/// (`"R2-D2: "`) or is empty.
pub(super) fn warning(who: &str, t_ms: u64, line: Option<usize>, message: &str) {
    let at = line.map(|l| format!("line {l}: ")).unwrap_or_default();
    note(format_args!(
        "[{:>8.2}s] {who}warning: {at}{message}",
        t_ms as f64 / 1000.0
    ));
}

/// A run's result once the droid is stopped; on an error, the output that went away is why
/// the run ended: that is said first (or nothing, for a closed pipe).
pub(super) fn ended<T>(result: Result<T, CliError>, out: &RunOutput) -> Result<T, CliError> {
    result.or_else(|e| {
        out.result()?;
        Err(e)
    })
}

/// How a run on one droid ends once the droid is stopped (a mission and a program alike):
/// the summary line, or the error after what the output said; then whether the recording was
/// kept. Status 1 when a step failed.
pub(super) fn finish_run(
    result: Result<Summary, CliError>,
    kept: Result<(), CliError>,
    json: bool,
    out: &RunOutput,
) -> Result<i32, CliError> {
    let summary = ended(result, out)?;
    out.stdout(|w| writeln!(w, "{}", summary_line(&summary, json)));
    out.result()?;
    kept?;
    Ok(if summary.failed_steps > 0 { 1 } else { 0 })
}

/// End a recording: an incomplete capture is a failure of the run (exit 1), said in one line.
pub(super) fn finish_recording(
    rec: Option<&crate::capture::record::Recorder>,
) -> Result<(), CliError> {
    match rec.map(|r| r.finish()) {
        Some(Err(e)) => Err(CliError::failure(e)),
        _ => Ok(()),
    }
}

/// `link` recorded by `recorder` (which starts its clock and writes its header now).
pub(super) fn recorded(
    recorder: Option<&crate::capture::record::Recorder>,
    link: Box<dyn Link>,
    model: Model,
    name: &str,
) -> Box<dyn Link> {
    match recorder {
        Some(r) => {
            r.start(&crate::capture::record::Recorder::header_for(model, name));
            r.wrap(link)
        }
        None => link,
    }
}

/// Run the mission over any link, printing as it goes.
pub async fn run_on(
    link: Box<dyn Link>,
    model: Model,
    steps: &[crate::script::Step],
    opts: MissionOptions,
    json: bool,
) -> Result<Summary, String> {
    let out = Arc::new(RunOutput::new(None));
    run_recorded(link, model, steps, opts, json, None, out).await
}

/// [`run_on`], marking the mission's start and end in the capture being recorded (replay
/// samples from the same start, so a replayed `--sim` mission prints the same telemetry).
pub async fn run_recorded(
    link: Box<dyn Link>,
    model: Model,
    steps: &[crate::script::Step],
    opts: MissionOptions,
    json: bool,
    recorder: Option<&crate::capture::record::Recorder>,
    out: Arc<RunOutput>,
) -> Result<Summary, String> {
    run_session(
        link,
        model,
        opts,
        json,
        recorder,
        out,
        |session, opts, emit| async move { mission::run(&session, model, steps, opts, emit).await },
    )
    .await
}

/// The session, outputs, recording marks and signals of a run on one droid around `body`
/// (a mission's steps, or a Sphero Edu program, `crate::edu`): `body` gets the session, the
/// options with the connect setup, and where its events go.
pub async fn run_session<F, Fut>(
    link: Box<dyn Link>,
    model: Model,
    opts: MissionOptions,
    json: bool,
    recorder: Option<&crate::capture::record::Recorder>,
    out: Arc<RunOutput>,
    body: F,
) -> Result<Summary, String>
where
    F: FnOnce(session::SessionHandle, MissionOptions, mission::Emit) -> Fut,
    Fut: std::future::Future<Output = Result<Summary, mission::MissionError>>,
{
    let printer = out.clone();
    let (config, opts) = mission_session(model, opts);
    let session = session::start(link, config);
    let samples_per_line = (1000 / opts.interval.as_millis().max(1)).max(1) as u64;
    let count = std::sync::atomic::AtomicU64::new(0);
    let marker = recorder.cloned();
    let marked = std::sync::atomic::AtomicBool::new(false);
    let emit: Arc<dyn Fn(MissionEvent) + Send + Sync> = Arc::new(move |e| {
        match (&marker, &e) {
            (Some(r), MissionEvent::Sample(s))
                if !marked.swap(true, std::sync::atomic::Ordering::Relaxed) =>
            {
                r.mark_before(std::time::Duration::from_millis(s.t_ms), "mission-start");
            }
            // Steps too: a replay needs the stance changes the mission asked for when it did.
            (Some(r), MissionEvent::Step { line, text, .. }) => {
                r.record(crate::capture::Event::Mark(format!("step {line} {text}")));
            }
            _ => {}
        }
        if let MissionEvent::Sample(s) = &e {
            printer.csv_sample(None, s);
        }
        match e {
            MissionEvent::Sample(s) if json => printer.stdout(|w| {
                serde_json::to_writer(&mut *w, &s).map_err(std::io::Error::from)?;
                writeln!(w)
            }),
            MissionEvent::Sample(s) => {
                let n = count.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if n.is_multiple_of(samples_per_line) {
                    printer.stdout(|w| writeln!(w, "{}", sample_line(&s)));
                }
            }
            MissionEvent::Step { t_ms, line, text } if !json => printer
                .stdout(|w| writeln!(w, "[{:>8.2}s] line {line}: {text}", t_ms as f64 / 1000.0)),
            MissionEvent::Step { .. } => {}
            MissionEvent::Warning {
                t_ms,
                line,
                message,
            } => warning("", t_ms, line, &message),
        }
    });
    let link_lines = tokio::spawn(report_link(session.watch_state()));
    // Ctrl-C (also while reconnecting), SIGTERM and SIGHUP (console close on Windows) end the
    // mission with a stop.
    let interrupted = super::signals::terminated();
    let result = tokio::select! {
        r = body(session.clone(), opts, emit) => r,
        sig = interrupted => Err(mission::MissionError(format!("{sig}: mission interrupted, the droid was stopped"))),
        _ = out.closed() => Err(mission::MissionError(OUTPUT_GONE.into())),
    };
    if let Some(r) = recorder {
        r.record(crate::capture::Event::Mark("mission-end".into()));
    }
    link_lines.abort();
    // Never connected: say why the last attempt failed (a droid refusing the connection).
    let result = result.map_err(|e| match session.state() {
        LinkState::Reconnecting { reason, .. } if e.0.starts_with("no connection within") => {
            format!("{e}: {reason}")
        }
        _ => e.to_string(),
    });
    // Stop first (at the last heading: a stop at heading 0 would turn the droid), then close.
    session.shutdown_stopped(Vec::new()).await;
    out.flush_csv();
    result
}

/// A mission's session settings for `model`, and its options with the connect setup they
/// hold: sensors streamed at least as often as the samples are taken (10/s at the least),
/// capped to what the droid's link carries (said on stderr); a `stream` line of the mission
/// changes it.
pub fn mission_session(model: Model, opts: MissionOptions) -> (SessionConfig, MissionOptions) {
    // Stream at least as often as the samples are taken (10/s at the least), capped to what
    // the droid's link carries; a `stream` line of the mission changes it.
    let interval_ms = opts.interval.as_millis().clamp(10, 100) as u16;
    let tripod = opts.setup.tripod;
    let request = crate::tuning::StreamRequest {
        rate_hz: 1000 / interval_ms,
        sensors: crate::family::stream::all_groups(model),
    };
    let setup = SetupOptions {
        tripod,
        ..opts.setup
    };
    let setup = match crate::family::stream::plan_for(model, request) {
        Some(plan) => {
            if let Some(capped) = &plan.note {
                note(format_args!("droidctl: streaming: {capped}"));
            }
            setup.with_plan(&plan)
        }
        None => setup,
    };
    let config = SessionConfig {
        family: model.protocol(),
        model: Some(model),
        pacing: model.write_pacing(),
        setup: connect_setup(model, &setup),
        ..SessionConfig::default()
    };
    let opts = MissionOptions { setup, ..opts };
    (config, opts)
}

/// A lost link and the reconnect, on stderr as they happen (`[    4.52s] link lost: the droid
/// disconnected — reconnecting (attempt 1)`, `[    5.06s] reconnected`), the time counted from
/// the first connection. Nothing before it: a droid that cannot be reached gets one error line
/// at the end.
pub async fn report_link(state: tokio::sync::watch::Receiver<LinkState>) {
    report_link_of(state, String::new()).await
}

/// [`report_link`] for one droid of a fleet: `who` (`"D2-0001: "`) after the time, and its
/// first connection too (each droid's progress is visible).
pub async fn report_link_of(mut state: tokio::sync::watch::Receiver<LinkState>, who: String) {
    let mut since: Option<tokio::time::Instant> = None;
    let mut lost = false;
    let mut waiting = false;
    loop {
        let now = state.borrow_and_update().clone();
        match (now, since) {
            (LinkState::Connected, None) => {
                since = Some(tokio::time::Instant::now());
                if !who.is_empty() {
                    let _ = writeln!(std::io::stderr(), "droidctl: {who}connected");
                }
            }
            // A droid of a fleet still connecting: say why each attempt failed.
            (LinkState::Reconnecting { attempt, reason }, None) if !who.is_empty() => {
                let _ = writeln!(
                    std::io::stderr(),
                    "droidctl: {who}connection attempt {attempt} failed: {reason} — retrying"
                );
            }
            (LinkState::Connected, Some(t0)) if lost => {
                lost = false;
                waiting = false;
                let _ = writeln!(
                    std::io::stderr(),
                    "[{:>8.2}s] {who}reconnected",
                    t0.elapsed().as_secs_f64()
                );
            }
            // Said once: the link waits for the adapter, whatever the attempts.
            (LinkState::Reconnecting { reason, .. }, Some(_))
                if reason == crate::link::ADAPTER_OFF_WAITING && waiting => {}
            (LinkState::Reconnecting { reason, .. }, Some(t0))
                if reason == crate::link::ADAPTER_OFF_WAITING =>
            {
                waiting = true;
                lost = true;
                let _ = writeln!(
                    std::io::stderr(),
                    "[{:>8.2}s] {who}{reason}",
                    t0.elapsed().as_secs_f64()
                );
            }
            (LinkState::Reconnecting { attempt, reason }, Some(t0)) => {
                let what = if lost {
                    "reconnect failed"
                } else {
                    "link lost"
                };
                lost = true;
                let _ = writeln!(
                    std::io::stderr(),
                    "[{:>8.2}s] {who}{what}: {reason} — reconnecting (attempt {attempt})",
                    t0.elapsed().as_secs_f64()
                );
            }
            _ => {}
        }
        if state.changed().await.is_err() {
            return;
        }
    }
}

fn opt(v: Option<f32>, prec: usize) -> String {
    v.map(|v| crate::units::fixed(f64::from(v), prec))
        .unwrap_or_else(|| "-".into())
}

/// What every sample line starts with: its time, where the droid is, how fast, its heading.
fn sample_where(s: &mission::Sample) -> String {
    format!(
        "[{:>8.2}s] pos ({}, {}) cm  speed {} cm/s  heading {}",
        s.t_ms as f64 / 1000.0,
        opt(s.x_cm, 1),
        opt(s.y_cm, 1),
        opt(s.speed, 0),
        s.heading
            .map(|h| format!("{h}°"))
            .unwrap_or_else(|| "-".into()),
    )
}

pub fn sample_line(s: &mission::Sample) -> String {
    // Robi 42 reports wheels and frames, not a dome, stance or battery.
    if let (Some(l), Some(r)) = (s.motor_left_rad_s, s.motor_right_rad_s) {
        return format!(
            "{}  motors L {l:.2} R {r:.2} rad/s  frames {} lost {}",
            sample_where(s),
            s.frames.unwrap_or(0),
            s.lost_frames.unwrap_or(0),
        );
    }
    // The dome and the stance only where the droid reports them (R2): not `head -°  stance
    // unknown` for BB-8 or BOLT.
    let head = s
        .head_deg
        .map(|h| format!("  head {}°", opt(Some(h), 0)))
        .unwrap_or_default();
    let stance = match (&s.stance, &s.stance_to) {
        (Some(st), _) => format!("  stance {st}"),
        (None, Some(to)) => format!("  stance → {to}"),
        (None, None) => String::new(),
    };
    format!(
        "{}{head}{stance}  battery {} V  collisions {}",
        sample_where(s),
        opt(s.battery_v, 2),
        s.collisions
    )
}

/// The summary line (`--json`: the summary object).
pub fn summary_line(s: &Summary, json: bool) -> String {
    if json {
        serde_json::to_string(s).unwrap_or_default()
    } else {
        format!(
            "done in {:.2} s: sent {}, received {}, errors {}, timeouts {}, collisions {}, failed steps {}, final position ({}, {}) cm",
            s.t_ms as f64 / 1000.0,
            s.sent,
            s.received,
            s.errors,
            s.timeouts,
            s.collisions,
            s.failed_steps,
            opt(s.x_cm, 1),
            opt(s.y_cm, 1)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sample_lines_show_no_negative_zero_and_only_what_the_droid_has() {
        let mut t = crate::telemetry::Telemetry {
            pitch: Some(-0.0),
            x_cm: Some(-0.01),
            ..Default::default()
        };
        let s = mission::sample_of(&t, 1000);
        let line = sample_line(&s);
        assert!(line.contains("pos (0.0, -)"), "{line}");
        assert!(
            !line.contains("  head ") && !line.contains("stance"),
            "{line}"
        );
        let json = serde_json::to_string(&s).unwrap();
        assert!(json.contains("\"pitch_deg\":0.0"), "{json}");
        t.head_deg = Some(-0.3);
        t.stance = crate::telemetry::Stance::Tripod;
        let line = sample_line(&mission::sample_of(&t, 1000));
        assert!(line.contains("head 0°  stance tripod"), "{line}");
    }
}
