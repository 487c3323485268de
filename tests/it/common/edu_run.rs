//! A Sphero Edu program run in process on one simulated link, its session and options as
//! `droidctl run` starts them: what it said, and its summary. Shared by `edu_infrared.rs`
//! and `edu_charger.rs`.

#![allow(dead_code)]

use droidctl::edu::{EngineOptions, Program, ProgramOptions};
use droidctl::mission::{Emit, MissionEvent, MissionOptions, Summary};
use droidctl::model::Model;
use droidctl::sim::SimLink;
use std::sync::{Arc, Mutex};

/// The engine as these tests start it: this test binary is not droidctl.
pub fn engine() -> EngineOptions {
    EngineOptions {
        exe: Some(env!("CARGO_BIN_EXE_droidctl").into()),
        ..EngineOptions::default()
    }
}

/// Run `text` (shown as `name`) on `link`, a simulated `model`, from `start` (a fleet's
/// droids share one). Panics naming the program if it fails.
pub async fn run_program(
    link: SimLink,
    model: Model,
    text: &str,
    name: &str,
    start: tokio::time::Instant,
) -> (Summary, Vec<String>) {
    let (cfg, mission) = droidctl::cli::run::mission_session(model, MissionOptions::default());
    let session = droidctl::session::start(Box::new(link), cfg);
    let program = Program::new_with(text.to_string(), name.to_string(), &engine()).unwrap();
    let opts = ProgramOptions {
        mission,
        ..ProgramOptions::default()
    };
    let seen = Arc::new(Mutex::new(Vec::new()));
    let emit: Emit = {
        let seen = seen.clone();
        Arc::new(move |e: MissionEvent| {
            if let MissionEvent::Step { text, .. } = e {
                seen.lock().unwrap().push(text);
            }
        })
    };
    let r = droidctl::edu::run(&session, model, &program, opts, emit, start).await;
    session.shutdown(Vec::new()).await;
    let said = seen.lock().unwrap().clone();
    let summary = r.unwrap_or_else(|e| panic!("{name}: {e}: {said:?}"));
    (summary, said)
}
