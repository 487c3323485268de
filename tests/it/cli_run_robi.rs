//! Missions on Robi 42: `droidctl run SCRIPT --sim robi --json` through the binary, where
//! `drive SPEED HEADING` reads the heading as a turn (0 straight, 1..=180 right, 359..=180
//! left) and the samples carry the motor speeds, frames and the odometry from them; the lines
//! Robi cannot do, refused before anything is sent; and `mission::run` in-process against the
//! simulator, comparing the mission's odometry with where the robot really is.

use droidctl::family::setup::{SetupOptions, connect_setup};
use droidctl::mission::{self, MissionEvent, MissionOptions, Sample};
use droidctl::model::Model;
use droidctl::session::{self, SessionConfig};
use droidctl::sim::{Faults, SimConfig, SimLink};
use serde_json::Value;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::common::scratch;
use scratch::{Obj, Scratch, json_lines, path, stderr, stdout};

fn f(s: &Obj, k: &str) -> f64 {
    s[k].as_f64()
        .unwrap_or_else(|| panic!("{k} is a number: {s:?}"))
}

/// Straight ahead for 2 s, then half right while driving for 1 s, then stop.
const RIGHT: &str = "\
# Robi 42: straight, then bend right
drive 200 0 for 2s
drive 200 45 for 1s
stop
wait 1s
";

/// The mirror image: half left (heading 315 is 45° to the left).
const LEFT: &str = "\
# Robi 42: straight, then bend left
drive 200 0 for 2s
drive 200 315 for 1s
stop
wait 1s
";

/// Run a script on the simulated Robi; the samples and the summary.
fn run_robi(dir: &Scratch, name: &str, text: &str) -> (Vec<Obj>, Obj) {
    let script = dir.file(name, text);
    let o = dir.run(&["run", path(&script), "--sim", "robi", "--json"]);
    assert_eq!(o.status.code(), Some(0), "stderr: {}", stderr(&o));
    let mut lines = json_lines(&stdout(&o));
    let summary = lines.pop().unwrap();
    assert_eq!(summary["done"], Value::Bool(true));
    for k in ["failed_steps", "errors", "timeouts"] {
        assert_eq!(summary[k], Value::from(0), "{k}: {summary:?}");
    }
    (lines, summary)
}

#[test]
fn a_right_turn_while_driving_bends_the_path_right() {
    let dir = Scratch::new("cli-run-robi", "right");
    let (samples, summary) = run_robi(&dir, "right.txt", RIGHT);
    // 2 + 1 + 1 s of steps and the final stop's 0.3 s.
    let t_ms = summary["t_ms"].as_u64().unwrap();
    assert!((4_200..5_000).contains(&t_ms), "{t_ms} ms");
    let last = samples.last().unwrap();
    let (x, y) = (f(&summary, "x_cm"), f(&summary, "y_cm"));
    assert_eq!(
        (f(last, "x_cm"), f(last, "y_cm")),
        (x, y),
        "the last sample is the end"
    );
    // Forward along +y for 2 s at 200/255 of 30 cm/s (≈ 47 cm), then a bend to the right:
    // x grows, the heading ends between straight ahead and straight back.
    assert!(y > 45.0, "{summary:?}");
    assert!(x > 5.0, "the path bends right: {summary:?}");
    let heading = f(last, "heading");
    assert!(
        heading > 45.0 && heading < 180.0,
        "heading {heading}: {last:?}"
    );

    // The samples carry the motor speeds, frames and lost frames.
    let during = |from: u64, to: u64| -> Vec<&Obj> {
        let v: Vec<&Obj> = samples
            .iter()
            .filter(|s| (from..to).contains(&s["t_ms"].as_u64().unwrap()))
            .collect();
        assert!(v.len() >= 4, "samples every 100 ms from {from} to {to} ms");
        v
    };
    // Straight: both wheels at 200/255 of 10 rad/s (steering 128 is 1/255 right of the
    // middle, so the right wheel turns a hair slower).
    for s in during(600, 1_900) {
        let (l, r) = (f(s, "motor_left_rad_s"), f(s, "motor_right_rad_s"));
        assert!((l - 7.87).abs() < 0.05 && (r - 7.81).abs() < 0.05, "{s:?}");
        assert!((f(s, "speed") - 23.5).abs() < 0.5, "{s:?}");
    }
    // Bending right: the left (outer) wheel at full, the right (inner) one slower.
    for s in during(2_400, 2_900) {
        let (l, r) = (f(s, "motor_left_rad_s"), f(s, "motor_right_rad_s"));
        assert!(l > 9.9 && r > 3.0 && r < 4.5, "{s:?}");
    }
    // Stopped: both wheels still.
    for s in during(3_500, 4_000) {
        assert_eq!(
            (f(s, "motor_left_rad_s"), f(s, "motor_right_rad_s")),
            (0.0, 0.0),
            "{s:?}"
        );
    }
    // Frames arrive at ≈ 10/s, a few lost on the air (one in 40).
    let frames = f(last, "frames");
    let lost = f(last, "lost_frames");
    let secs = t_ms as f64 / 1000.0;
    assert!(
        (frames - 10.0 * secs).abs() < 4.0,
        "{frames} frames in {secs} s"
    );
    assert!((1.0..=2.0).contains(&lost), "{lost} lost");
    let counts: Vec<f64> = samples
        .iter()
        .filter_map(|s| s["frames"].as_f64())
        .collect();
    assert!(counts.windows(2).all(|w| w[1] >= w[0]), "{counts:?}");
    // A Robi has no battery reading, dome or legs: those stay empty, nothing pretends.
    assert!(
        last["battery_v"].is_null() && last["head_deg"].is_null(),
        "{last:?}"
    );
    assert_eq!(last["collisions"], Value::from(0));

    // Deterministic.
    let (again, _) = run_robi(&dir, "right.txt", RIGHT);
    assert_eq!(again, samples);
}

#[test]
fn a_left_turn_while_driving_bends_the_path_left() {
    let dir = Scratch::new("cli-run-robi", "left");
    let (samples, summary) = run_robi(&dir, "left.txt", LEFT);
    let (x, y) = (f(&summary, "x_cm"), f(&summary, "y_cm"));
    assert!(y > 45.0, "{summary:?}");
    assert!(x < -5.0, "the path bends left: {summary:?}");
    let heading = f(samples.last().unwrap(), "heading");
    assert!(heading > 180.0 && heading < 315.0, "heading {heading}");
    // The right (outer) wheel at full this time.
    let turning: Vec<&Obj> = samples
        .iter()
        .filter(|s| (2_400..2_900).contains(&s["t_ms"].as_u64().unwrap()))
        .collect();
    assert!(turning.len() >= 4);
    for s in turning {
        let (l, r) = (f(s, "motor_left_rad_s"), f(s, "motor_right_rad_s"));
        assert!(r > 9.9 && l > 3.0 && l < 4.5, "{s:?}");
    }
    // Mirror images of each other, to within the 1/255 the straight byte leans right.
    let (_, right) = run_robi(&dir, "right.txt", RIGHT);
    assert!(
        (f(&right, "x_cm") + x).abs() < 4.0,
        "{right:?} vs {summary:?}"
    );
    assert!(
        (f(&right, "y_cm") - y).abs() < 4.0,
        "{right:?} vs {summary:?}"
    );
}

#[test]
fn lines_robi_cannot_do_are_refused_before_anything_is_sent() {
    let dir = Scratch::new("cli-run-robi", "refused");
    for line in ["stance tripod", "sound 1", "head 30", "led front 0 0 255"] {
        let script = dir.file("bad.txt", &format!("drive 100 0 for 1s\n{line}\nstop\n"));
        let o = dir.run(&["run", path(&script), "--sim", "robi", "--json"]);
        assert_eq!(o.status.code(), Some(2), "{line}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(err.contains("bad.txt:2:"), "{line}: {err}");
        assert!(
            err.contains("Robi 42") && err.contains("drive, stop and wait"),
            "{line}: {err}"
        );
        assert!(err.contains("nothing was sent"), "{err}");
        assert_eq!(stdout(&o), "", "{line}: no samples");
        let log = std::fs::read_to_string(dir.log()).unwrap_or_default();
        assert!(!log.contains("connected"), "{line}: {log}");
    }
    // Every problem at once, each with its line.
    let script = dir.file("bad.txt", "stance tripod\ndrive 100 0 for 1s\nsound 1\n");
    let o = dir.run(&["run", path(&script), "--sim", "robi"]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(
        err.contains("bad.txt:1:") && err.contains("bad.txt:3:"),
        "{err}"
    );
    assert!(!err.contains("bad.txt:2:"), "{err}");
}

/// [`RIGHT`] in-process with `mission::run`: the mission's odometry (from the motor speeds in
/// the frames) against the simulated robot's own state.
#[tokio::test(start_paused = true)]
async fn in_process_odometry_matches_the_robot() {
    let model = Model::Robi42;
    let link = SimLink::new(model, SimConfig::for_model(model), Faults::none());
    let probe = link.probe();
    let config = SessionConfig {
        family: model.protocol(),
        pacing: model.write_pacing(),
        setup: connect_setup(model, &SetupOptions::default()),
        ..SessionConfig::default()
    };
    let s = session::start(Box::new(link), config);
    let steps = droidctl::script::parse(RIGHT).unwrap();
    mission::validate(model, &steps).expect("Robi can do all of it");
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
    let st = probe.state();
    assert_eq!(st.velocity_cm_s, 0.0, "{st:?}");
    let (x, y) = (summary.x_cm.unwrap(), summary.y_cm.unwrap());
    // The frames report the wheels' commanded speed, so odometry runs a few centimetres
    // ahead of a robot that ramps its speed up and down.
    assert!(
        (x - st.x_cm).abs() < 8.0 && (y - st.y_cm).abs() < 8.0,
        "odometry ({x}, {y}) vs {st:?}"
    );
    assert!(
        st.x_cm > 5.0 && st.yaw_deg > 45.0 && st.yaw_deg < 180.0,
        "{st:?}"
    );
    let last = samples.lock().unwrap().last().cloned().unwrap();
    let heading = last.heading.unwrap() as f32;
    assert!((heading - st.yaw_deg).abs() < 12.0, "{last:?} vs {st:?}");
    // The frames were counted.
    assert!(last.frames.unwrap() > 30, "{last:?}");
    s.shutdown_stopped(vec![]).await;
    tokio::time::sleep(Duration::from_secs(1)).await;
    assert_eq!(probe.state().velocity_cm_s, 0.0);
}
