//! Judged by the field (issue 38): Sphero Edu programs written the way Sphero's docs and
//! teachers write them (tests/edu_field/*.js: sensors read on the first line, sounds, lights
//! in loops, an animation, an un-awaited helper, a collision handler without `exitProgram`),
//! each beside its twin written line for line with spherov2.py's own `SpheroEduAPI`
//! (tests/edu_field/NAME.py, run by tests/edu_field/twin.py). On every model a program's
//! `// Models:` line names, droidctl runs the JavaScript (`run P.js --sim MODEL --json
//! --record`) and spherov2 runs the twin against a fresh `droidctl serve --sim MODEL
//! --record`; then:
//! - where the simulated droid ends agrees within 4 cm and 5°: droidctl's from the last
//!   sample of `--json` (taken with the droid at rest), the twin's from the simulator itself
//!   (serve's `droid_released` event carries the simulated body's pose);
//! - the lights and the matrix end the same, exactly: the light and matrix commands of each
//!   capture are played into a fresh simulated droid of the model, and its final lights and
//!   matrix compared.
//!
//! A program that runs until stopped says `// Timeout: SECONDS` (droidctl's `--timeout`; the
//! twin sets `HOLD`). The twins run on the real clock (spherov2 has no other), so each
//! program is a few seconds long; the pairs run three at a time, and a disagreement must show
//! in each of three runs of the twin ([`TRIES`]).
//!
//! Skipped, with a message, only where no Python with spherov2 is at hand
//! (found as `common::python` says; `.ci/run` makes a venv with spherov2 and
//! points the variable at it).

// Unix: `kill -TERM` for serve (as tests/it/relay_e2e.rs, whose Serve this uses).
#![cfg(unix)]

use crate::relay_e2e::{Serve, TempDir, finish, python_with};
use droidctl::capture::{Capture, Event};
use droidctl::gatt::Endpoint;
use droidctl::model::Model;
use droidctl::sim::SimConfig;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::Duration;

/// How far apart the two ends may be (issue 38).
const CM: f64 = 4.0;
const DEG: f64 = 5.0;
/// Pairs at once: each twin mostly waits on the real clock, but spherov2's timing suffers
/// on a loaded machine ([`TRIES`]).
const AT_ONCE: usize = 3;

fn field_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/edu_field")
}

/// One field program: its name, the models it is for, and its time limit when its events
/// keep it going.
#[derive(Debug, Clone)]
struct Program {
    name: String,
    models: Vec<String>,
    timeout: Option<String>,
}

/// Every `tests/edu_field/NAME.js`, with its twin checked to be there.
fn programs() -> Vec<Program> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(field_dir()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "js") {
            continue;
        }
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        assert!(
            path.with_extension("py").exists(),
            "{name}.js has no spherov2 twin {name}.py"
        );
        let text = std::fs::read_to_string(&path).unwrap();
        let header = |key: &str| {
            text.lines()
                .find_map(|l| l.strip_prefix(&format!("// {key}:")))
                .map(|v| v.trim().to_string())
        };
        let models: Vec<String> = header("Models")
            .unwrap_or_else(|| panic!("{name}.js: no `// Models:` line"))
            .split_whitespace()
            .map(str::to_string)
            .collect();
        out.push(Program {
            name,
            models,
            timeout: header("Timeout"),
        });
    }
    out.sort_by(|a, b| a.name.cmp(&b.name));
    out
}

/// Where the droid ended: x, y (cm), and the way it faces (degrees).
#[derive(Debug, Clone, Copy)]
struct Pose {
    x: f64,
    y: f64,
    yaw: f64,
}

fn num(v: &Value, what: &str) -> f64 {
    v.as_f64()
        .unwrap_or_else(|| panic!("{what} is not a number: {v}"))
}

/// droidctl's run of `P.js` on `model`: the pose of its last sample, and the capture.
fn run_js(p: &Program, model: &str, dir: &TempDir) -> Result<(Pose, String), String> {
    let cap = dir.path(&format!("{}-{model}-js.cap", p.name));
    let js = field_dir().join(format!("{}.js", p.name));
    let mut args = vec![
        "run".to_string(),
        js.to_string_lossy().into_owned(),
        "--sim".into(),
        model.into(),
        "--json".into(),
        "--record".into(),
        cap.clone(),
    ];
    if let Some(t) = &p.timeout {
        args.extend(["--timeout".into(), t.clone()]);
    }
    let out = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(&args)
        .env(
            "DROIDCTL_LOG_FILE",
            dir.path(&format!("{}-{model}.log", p.name)),
        )
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    // A program ended by its time limit is a program that ran as written.
    let timed_out = p.timeout.is_some() && err.contains("time limit");
    if !(out.status.success() || timed_out) {
        return Err(format!("droidctl run {}.js --sim {model}: {err}", p.name));
    }
    let last = text
        .lines()
        .filter_map(|l| serde_json::from_str::<Value>(l).ok())
        .rfind(|v| v.get("done").is_none() && v.get("x_cm").is_some())
        .ok_or_else(|| format!("{}.js on {model}: no sample in {text}", p.name))?;
    let pose = Pose {
        x: num(&last["x_cm"], "x_cm"),
        y: num(&last["y_cm"], "y_cm"),
        yaw: num(&last["yaw_deg"], "yaw_deg"),
    };
    Ok((pose, cap))
}

/// spherov2's run of the twin on a fresh `serve --sim model`: the simulated body's pose as
/// its client went, and serve's capture.
fn run_twin(
    py: &str,
    p: &Program,
    model: &str,
    dir: &TempDir,
    try_no: usize,
) -> Result<(Pose, String), String> {
    let cap = dir.path(&format!("{}-{model}-py{try_no}.cap", p.name));
    let serve = Serve::start(&[model], &["--record", &cap], dir);
    let port = serve.address.rsplit(':').next().unwrap().to_string();
    let name = format!(
        "{}0001",
        Model::from_id(model).and_then(|m| m.name_prefix()).unwrap()
    );
    let twin = field_dir().join(format!("{}.py", p.name));
    let child = Command::new(py)
        .arg(field_dir().join("twin.py"))
        .args([&port, &name])
        .arg(&twin)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let out = finish(child, Duration::from_secs(90), "the spherov2 twin");
    if !out.status.success() {
        return Err(format!(
            "{}.py on {model}: {}",
            p.name,
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let released = serve.wait_event("droid_released", |e| e["event"] == "droid_released");
    serve.stop();
    let pose = &released["pose"];
    Ok((
        Pose {
            x: num(&pose["x_cm"], "x_cm"),
            y: num(&pose["y_cm"], "y_cm"),
            yaw: num(&pose["yaw_deg"], "yaw_deg"),
        },
        cap,
    ))
}

/// What the droid shows after a capture's commands: its lights, and BOLT's matrix, in the
/// order they came to be (the same state twice in a row once), taken while the droid is awake
/// (spherov2 puts it to sleep as its API closes); the last is the end state.
fn shows(model: &str, cap: &str) -> Vec<String> {
    let m = Model::from_id(model).unwrap();
    let c = Capture::load(Path::new(cap)).unwrap_or_else(|e| panic!("{cap}: {e}"));
    let mut d = droidctl::sim::wire_droid(m, SimConfig::for_model(m));
    let mut seen: Vec<String> = Vec::new();
    for t in &c.events {
        if let Event::Out(Endpoint::Api, bytes) = &t.event {
            d.receive(bytes, t.at);
            if d.state().awake {
                let now = format!(
                    "lights {:?} {}",
                    d.state().leds,
                    d.shows().unwrap_or_default()
                );
                if seen.last() != Some(&now) {
                    seen.push(now);
                }
            }
        }
    }
    seen
}

/// Where the two ends still disagree, with what is known of why: measured and printed, not
/// failed (their lights are judged). Each is a lead for the next fix; the tolerance
/// is the goal. Empty: every pair is judged.
const KNOWN: &[(&str, &str, &str)] = &[];

// A spin while rolling (`figure_eight`): droidctl's `spin` is paced as spherov2's is, a step
// per answer with its heading a function of the time since the call (src/edu/timeline.rs
// `spin_turned`), so both end the spin past its duration alike. What was left was transport
// timing: spherov2's pacing counts from the end of each write, and its writes through serve
// took 1-2 ms (4.3 cm over a figure eight on Mini), so the twin paces from the start of each
// write, as droidctl's simulated link does (twin.py `paced_from_write_start`).

// R2-D2's and R2-Q5's tripod: spherov2's SpheroEduAPI asks for three legs as it starts
// (utils.py `set_robot_state_on_start`, THREE_LEGS) and does not wait for them; the droid rolls
// only on three legs (shared/spec/droid-facts.md section 2), and droidctl waits for the stance
// before the first roll. spherov2's first roll then lost as much as its setup's round trips
// left of the 2 s stance change (5-10 cm on the simulated R2-D2): transport timing, not a
// semantic, so the twin starts its program once the droid says it stands (twin.py
// `on_tripod`), as droidctl's first roll does.

/// spherov2 lights RVR's main light with BOLT's matrix command (its `ToyUtil.set_main_led`
/// tries `set_compressed_frame_player_one_color` first, and its RVR class has it), so no RVR
/// light changes; droidctl lights every RVR light as spherov2's own fallback mapping says
/// (utils.py). RVR's lights are judged where a program leaves its main light alone.
fn judges_lights(p: &Program, model: &str) -> bool {
    let js = std::fs::read_to_string(field_dir().join(format!("{}.js", p.name))).unwrap();
    model != "rvr" || !js.contains("setMainLed(")
}

/// The angle between two headings, 0..=180.
fn apart(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

/// One run of the twin against droidctl's run: agreed (what was said), or how it differs.
fn compare(
    p: &Program,
    model: &str,
    js: (Pose, &str),
    twin: (Pose, &str),
) -> Result<String, String> {
    let ((js, js_cap), (twin, py_cap)) = (js, twin);
    let d = (js.x - twin.x).hypot(js.y - twin.y);
    let turn = apart(js.yaw, twin.yaw);
    let said = format!(
        "{}.js on {model}: droidctl ends at ({:.1}, {:.1}) facing {:.1}°, spherov2 at ({:.1}, \
         {:.1}) facing {:.1}°: {d:.1} cm, {turn:.1}° apart",
        p.name, js.x, js.y, js.yaw, twin.x, twin.y, twin.yaw
    );
    let known = KNOWN.iter().find(|k| k.0 == p.name && k.1 == model);
    let mut wrong = Vec::new();
    let said = match known {
        Some((.., why)) => format!("{said} (known: {why})"),
        None if d > CM || turn > DEG => {
            wrong.push(said.clone());
            said
        }
        None => said,
    };
    let (ours, theirs) = (shows(model, js_cap), shows(model, py_cap));
    if judges_lights(p, model) && ours.last() != theirs.last() {
        wrong.push(format!(
            "{}.js on {model}: lights and matrix end differently:\n droidctl: {:?}\n spherov2: \
             {:?}",
            p.name,
            ours.last(),
            theirs.last()
        ));
    }
    if ours.is_empty() {
        wrong.push(format!("{}.js on {model}: droidctl lit nothing", p.name));
    }
    if wrong.is_empty() {
        Ok(said)
    } else {
        Err(wrong.join("\n"))
    }
}

/// How many runs of a twin a disagreement must show in. droidctl's run is in simulated time
/// and the same every time; spherov2's is on the real clock, where a loaded machine (the
/// suite's other tests, other builds) overruns its sleeps: a roll's stop 100-200 ms late is
/// 5-15 cm, seen in one run in ten on a busy machine. A real disagreement is in every run.
const TRIES: usize = 3;

/// One program on one model: droidctl and spherov2 agree, or how they differ (every try).
fn judge(py: &str, p: &Program, model: &str) -> Result<String, String> {
    let dir = TempDir::new(&format!("twin-{}-{model}", p.name));
    let (js, js_cap) = run_js(p, model, &dir)?;
    let mut tries = Vec::new();
    for i in 0..TRIES {
        // A twin that failed is a try too: once, under load, spherov2 read "Bad response
        // checksum" from R2-D2 through serve (not found yet; it is said when every try fails).
        let (twin, py_cap) = match run_twin(py, p, model, &dir, i) {
            Ok(twin) => twin,
            Err(why) => {
                tries.push(why);
                continue;
            }
        };
        match compare(p, model, (js, &js_cap), (twin, &py_cap)) {
            Ok(said) => return Ok(said),
            Err(why) => tries.push(why),
        }
    }
    Err(tries.join("\n"))
}

#[test]
fn field_programs_end_where_their_spherov2_twins_end() {
    let py = match python_with("spherov2.sphero_edu, spherov2.adapter.tcp_adapter") {
        Ok(py) => py,
        Err(why) => {
            println!("SKIPPED field_programs_end_where_their_spherov2_twins_end: {why}");
            return;
        }
    };
    let programs = programs();
    let mut pairs: Vec<(Program, String)> = Vec::new();
    for p in &programs {
        for m in &p.models {
            pairs.push((p.clone(), m.clone()));
        }
    }
    // The models the issue names are each judged.
    for m in ["bolt", "mini", "sprk", "bb8", "r2d2", "rvr"] {
        assert!(
            pairs.iter().any(|(_, pm)| pm == m),
            "no field program for {m}"
        );
    }
    let queue = Mutex::new(pairs);
    let results = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..AT_ONCE {
            s.spawn(|| {
                loop {
                    let Some((p, m)) = queue.lock().unwrap().pop() else {
                        return;
                    };
                    let r = judge(&py, &p, &m);
                    results.lock().unwrap().push(r);
                }
            });
        }
    });
    let results = results.into_inner().unwrap();
    for r in results.iter().flatten() {
        eprintln!("{r}");
    }
    let wrong: Vec<&String> = results.iter().filter_map(|r| r.as_ref().err()).collect();
    assert!(
        wrong.is_empty(),
        "{} of {} field programs disagree with spherov2:\n{}",
        wrong.len(),
        results.len(),
        wrong
            .iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>()
            .join("\n")
    );
}
