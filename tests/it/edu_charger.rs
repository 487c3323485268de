//! Sphero Edu's `onCharging` and `onNotCharging`, end to end: a person puts the simulated
//! droid on its charger and takes it off (the simulator's probe: nothing in a program can),
//! the droid reports it as a real one does (v2: battery state changed; v1: its power
//! notification), and the program's handlers fire, once each, in that order. In simulated
//! time, the session and program started as `droidctl run` starts them.

use droidctl::model::Model;
use droidctl::sim::{Faults, SimConfig, SimLink};
use std::time::Duration;

use crate::common::edu_run;
use edu_run::run_program;

const PROGRAM: &str = "const seen = [];\n\
    registerEvent(EventType.onCharging, () => { seen.push(\"on\"); });\n\
    registerEvent(EventType.onNotCharging, () => { seen.push(\"off\"); });\n\
    async function startProgram() {\n\
    \x20 await delay(6);\n\
    \x20 speak(\"seen \" + seen.join(), false);\n\
    \x20 await roll(0, 80, 1);\n\
    \x20 exitProgram();\n\
    }\n";

/// What the program said, and how far the droid rolled at the end (it cannot roll while it
/// sits on the charger).
async fn run(model: Model, on_at: f32, off_at: f32) -> (Vec<String>, f32) {
    let link = SimLink::new(model, SimConfig::for_model(model), Faults::none());
    let probe = link.probe();
    let person = async {
        tokio::time::sleep(Duration::from_secs_f32(on_at)).await;
        probe.set_on_charger(true);
        tokio::time::sleep(Duration::from_secs_f32(off_at - on_at)).await;
        probe.set_on_charger(false);
    };
    let start = tokio::time::Instant::now();
    let ((summary, said), ()) = tokio::join!(
        run_program(link, model, PROGRAM, "charger.js", start),
        person
    );
    let rolled = summary
        .x_cm
        .unwrap_or(0.0)
        .hypot(summary.y_cm.unwrap_or(0.0));
    (said, rolled)
}

fn seen(said: &[String]) -> String {
    said.iter()
        .find_map(|t| t.split("says \"seen ").nth(1))
        .unwrap_or("(nothing)")
        .trim_end_matches('"')
        .to_string()
}

#[tokio::test(start_paused = true)]
async fn on_and_off_the_charger_fire_charging_then_not_charging() {
    for model in [Model::Bolt, Model::Mini, Model::BB8, Model::SprkPlus] {
        let (said, rolled) = run(model, 2.0, 4.0).await;
        assert_eq!(seen(&said), "on,off", "{model:?}: {said:?}");
        assert!(
            rolled > 20.0,
            "{model:?} rolls once off the charger: {rolled}"
        );
    }
}

#[tokio::test(start_paused = true)]
async fn a_droid_left_on_its_charger_does_not_roll() {
    let (said, rolled) = run(Model::Bolt, 2.0, 30.0).await;
    assert_eq!(seen(&said), "on", "{said:?}");
    assert!(rolled < 1.0, "on the charger: {rolled}");
}
