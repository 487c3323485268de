//! Missions on the Sphero API v1 droids (BB-8, SPRK+, Ollie): `droidctl run SCRIPT --sim bb8`
//! through the binary, and `mission::run` in-process against the simulator, checking where the
//! droid ends up, the collisions it reports and the telemetry streamed on the way; and the
//! lines a v1 droid cannot do, refused before anything is sent.

use droidctl::family::setup::{SetupOptions, connect_setup};
use droidctl::mission::{self, MissionEvent, MissionOptions, Sample};
use droidctl::model::Model;
use droidctl::session::{self, SessionConfig};
use droidctl::sim::{Faults, SimConfig, SimLink};
use serde_json::Value;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::common::scratch;
use scratch::{Scratch, json_lines, path, stderr, stdout};

/// East for 2 s, a pause, then north into the wall (4 m room: the droid's centre stops its
/// radius short of 200 cm from the middle), then a pause against it.
const PATROL: &str = "\
# BB-8: east, then north into the wall
wake
led front 0 0 255
led back 0 0 255
drive 120 90 for 2s
stop
wait 1s
drive 200 0 for 4s
stop
wait 1s
";

/// Where [`PATROL`] ends, by the simulator's figures: east for 2 s at 120/255 of 160 cm/s
/// (after a quarter turn and the braking), plus the drift of the second quarter turn; north
/// until the wall (4 m room: 200 cm from the middle less BB-8's own radius, 3.65 cm).
const END_X: f64 = 145.0;
fn end_y() -> f64 {
    200.0 - SimConfig::for_model(Model::BB8).radius_cm as f64
}

#[test]
fn bb8_mission_drives_turns_hits_the_wall_and_streams() {
    let dir = Scratch::new("cli-run-v1", "patrol");
    let script = dir.file("mission.txt", PATROL);
    let o = dir.run(&["run", path(&script), "--sim", "bb8", "--json"]);
    assert_eq!(o.status.code(), Some(0), "stderr: {}", stderr(&o));
    let lines = json_lines(&stdout(&o));
    let (summary, samples) = lines.split_last().unwrap();
    assert_eq!(summary["done"], Value::Bool(true));
    for k in ["failed_steps", "errors", "timeouts"] {
        assert_eq!(summary[k], Value::from(0), "{k}: {summary:?}");
    }
    // 2 + 1 + 4 + 1 s of steps, the final stop, and the LED and wake requests.
    let t_ms = summary["t_ms"].as_u64().unwrap();
    assert!((8_300..10_000).contains(&t_ms), "{t_ms} ms");
    // The final position: north-east, against the north wall.
    let (x, y) = (
        summary["x_cm"].as_f64().unwrap(),
        summary["y_cm"].as_f64().unwrap(),
    );
    assert!((x - END_X).abs() < 20.0, "x {x}");
    assert!((y - end_y()).abs() <= 0.5, "at the wall: y {y}");
    let bearing = x.atan2(y).to_degrees();
    let dist = (x * x + y * y).sqrt();
    assert!((25.0..50.0).contains(&bearing), "bearing {bearing}");
    assert!((220.0..260.0).contains(&dist), "distance {dist}");
    // One impact: pushing against the wall for the rest of the drive is not more.
    assert_eq!(summary["collisions"], Value::from(1), "{summary:?}");

    // Streaming values arrived: speed and heading while rolling east, then north.
    let f = |s: &serde_json::Map<String, Value>, k: &str| s[k].as_f64();
    let during = |from: u64, to: u64| {
        let v: Vec<_> = samples
            .iter()
            .filter(|s| (from..to).contains(&s["t_ms"].as_u64().unwrap()))
            .collect();
        assert!(v.len() >= 6, "samples every 100 ms from {from} to {to} ms");
        v
    };
    // (Sample times count from the connection; the first drive starts after the setup and
    // the wake and LED requests, about 0.5 s in, and turns for 0.5 s.)
    for s in during(1_300, 2_300) {
        let speed = f(s, "speed").expect("speed streamed");
        assert!((65.0..85.0).contains(&speed), "{s:?}");
        assert_eq!(s["heading"], Value::from(90), "{s:?}");
    }
    for s in during(4_400, 5_000) {
        assert!(f(s, "speed").unwrap() > 60.0, "{s:?}");
        assert_eq!(s["heading"], Value::from(0), "{s:?}");
    }
    let streamed = samples.iter().filter(|s| f(s, "x_cm").is_some()).count();
    assert!(streamed as f64 > 0.9 * samples.len() as f64, "{streamed}");
    // A v1 droid has no dome or legs: those stay empty.
    let last = samples.last().unwrap();
    assert!(last["head_deg"].is_null(), "{last:?}");
    assert!(last["battery_v"].as_f64().unwrap() > 3.5, "{last:?}");
    assert_eq!(
        last["collisions"], summary["collisions"],
        "the last sample is the final state"
    );
    // Deterministic.
    let again = dir.run(&["run", path(&script), "--sim", "bb8", "--json"]);
    assert_eq!(stdout(&again), stdout(&o));
}

#[test]
fn sprk_and_ollie_run_the_same_mission() {
    let dir = Scratch::new("cli-run-v1", "others");
    let script = dir.file(
        "mission.txt",
        "wake\nled front 0 255 0\ndrive 100 180 for 2s\n",
    );
    for model in ["sprk", "ollie"] {
        let o = dir.run(&["run", path(&script), "--sim", model, "--json"]);
        assert_eq!(o.status.code(), Some(0), "{model}: {}", stderr(&o));
        let lines = json_lines(&stdout(&o));
        let summary = lines.last().unwrap();
        assert!(
            summary["y_cm"].as_f64().unwrap() < -50.0,
            "{model}: {summary:?}"
        );
        assert_eq!(summary["failed_steps"], Value::from(0));
    }
}

#[test]
fn lines_a_bb8_cannot_do_are_refused_before_anything_is_sent() {
    let dir = Scratch::new("cli-run-v1", "refused");
    for (line, why) in [
        ("head 30", "no dome"),
        ("stance tripod", "no legs"),
        ("sound 1", "cannot play sounds"),
        ("animation 7", "no animations"),
        ("led logic 200", "no such LED"),
    ] {
        let script = dir.file("bad.txt", &format!("wake\n{line}\ndrive 100 0 for 1s\n"));
        let o = dir.run(&["run", path(&script), "--sim", "bb8", "--json"]);
        assert_eq!(o.status.code(), Some(2), "{line}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(err.contains("bad.txt:2:"), "{line}: {err}");
        assert!(err.contains("BB-8") && err.contains(why), "{line}: {err}");
        assert!(err.contains("nothing was sent"), "{err}");
        assert_eq!(stdout(&o), "", "{line}: no samples");
        let log = std::fs::read_to_string(dir.log()).unwrap_or_default();
        assert!(!log.contains("connected"), "{line}: {log}");
    }
    // Every problem is listed at once, each with its line.
    let script = dir.file("bad.txt", "wake\nhead 30\nstance tripod\nsound 1\n");
    let o = dir.run(&["run", path(&script), "--sim", "bb8"]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    for n in 2..=4 {
        assert!(err.contains(&format!("bad.txt:{n}:")), "{err}");
    }
    // The validation is the model's: SPRK+ is named for itself.
    let o = dir.run(&["run", path(&script), "--sim", "sprk"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("SPRK+"), "{}", stderr(&o));
}

/// The same patrol in-process with `mission::run`, comparing the mission's telemetry with the
/// simulated droid's own state.
#[tokio::test(start_paused = true)]
async fn in_process_mission_telemetry_matches_the_droid() {
    let model = Model::BB8;
    // BB-8's own figures, as `--sim bb8` has them.
    let link = SimLink::new(model, SimConfig::for_model(model), Faults::none());
    let probe = link.probe();
    let config = SessionConfig {
        family: model.protocol(),
        pacing: model.write_pacing(),
        setup: connect_setup(
            model,
            &SetupOptions {
                tripod: false,
                streaming_interval_ms: 100,
                ..Default::default()
            },
        ),
        ..SessionConfig::default()
    };
    let s = session::start(Box::new(link), config);
    let steps = droidctl::script::parse(PATROL).unwrap();
    mission::validate(model, &steps).expect("a BB-8 can do all of it");
    let samples: Arc<Mutex<Vec<Sample>>> = Arc::default();
    let warnings: Arc<Mutex<Vec<String>>> = Arc::default();
    let emit = {
        let (samples, warnings) = (samples.clone(), warnings.clone());
        Arc::new(move |e: MissionEvent| match e {
            MissionEvent::Sample(s) => samples.lock().unwrap().push(s),
            MissionEvent::Warning { message, .. } => warnings.lock().unwrap().push(message),
            MissionEvent::Step { .. } => {}
        })
    };
    let summary = mission::run(&s, model, &steps, MissionOptions::default(), emit)
        .await
        .expect("mission ran");
    assert!(warnings.lock().unwrap().is_empty(), "{warnings:?}");
    assert_eq!(summary.failed_steps, 0);
    let st = probe.state();
    assert!(st.collisions >= 1, "{st:?}");
    assert!(summary.collisions >= 1, "{summary:?}");
    // The summary's position is the droid's, to the streamed centimetre.
    let (x, y) = (summary.x_cm.unwrap(), summary.y_cm.unwrap());
    assert!(
        (x - st.x_cm).abs() <= 0.5 && (y - st.y_cm).abs() <= 0.5,
        "{summary:?} vs {st:?}"
    );
    assert!((x as f64 - END_X).abs() < 20.0 && (y as f64 - end_y()).abs() <= 0.5);
    assert_eq!(st.velocity_cm_s, 0.0);
    // The LED lines reached the droid: main LED blue, back LED full.
    assert_eq!(&st.leds[..4], &[0, 0, 255, 255]);
    // The battery was read with Get Power State.
    let samples = samples.lock().unwrap().clone();
    let last = samples.last().unwrap();
    assert!(
        (last.battery_v.unwrap() - st.battery_v).abs() < 0.05,
        "{last:?}"
    );
    let moving = samples
        .iter()
        .filter(|s| s.speed.is_some_and(|v| v > 60.0) && s.heading.is_some())
        .count();
    assert!(moving > 30, "{moving} samples while rolling");
    let stats = s.stats();
    assert_eq!((stats.errors, stats.timeouts), (0, 0), "{stats:?}");
    s.shutdown_stopped(vec![]).await;
    tokio::time::sleep(Duration::from_secs(1)).await;
    assert_eq!(probe.state().velocity_cm_s, 0.0);
}
