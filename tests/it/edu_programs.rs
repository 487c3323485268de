//! `droidctl run PROGRAM.js`: Sphero Edu JavaScript programs end to end, as a teacher runs
//! them: the examples run as written, in simulated time; errors say where, before anything
//! is sent (syntax) or with the droid stopped (exceptions); a program that never waits
//! cannot hang droidctl (`--timeout`, Ctrl+c).

use serde_json::Value;
use std::process::{Command, Stdio};
use std::time::Duration;

use crate::common::scratch;
use scratch::{Scratch, json_lines, path, stderr, stdout};

fn example(name: &str) -> String {
    format!("{}/examples/edu/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn summary(out: &std::process::Output) -> scratch::Obj {
    json_lines(&stdout(out))
        .into_iter()
        .find(|o| o.get("done") == Some(&Value::Bool(true)))
        .expect("a summary line")
}

fn num(o: &scratch::Obj, k: &str) -> f64 {
    o.get(k).and_then(Value::as_f64).unwrap_or(f64::NAN)
}

#[test]
fn the_examples_run_as_written_in_simulated_time() {
    let dir = Scratch::new("edu", "examples");
    // The square: four sides, back where it started.
    let sq = example("square.js");
    let (out, wall) = dir.run_timed(&["run", &sq, "--sim", "bolt", "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let s = summary(&out);
    assert!(num(&s, "t_ms") >= 6000.0, "{s:?}");
    assert!(
        num(&s, "x_cm").abs() < 5.0 && num(&s, "y_cm").abs() < 5.0,
        "a closed square: {s:?}"
    );
    assert!(wall < Duration::from_secs(20), "simulated time: {wall:?}");
    // Pong: three hits, then exitProgram().
    let (out, _) = dir.run_timed(&["run", &example("pong.js"), "--sim", "bolt", "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert_eq!(summary(&out)["collisions"], 3, "{}", stdout(&out));
    // The matrix program: its steps name their lines.
    let (out, _) = dir.run_timed(&["run", &example("matrix.js"), "--sim", "bolt"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(text.contains("line 12: scrollMatrixText"), "{text}");
    // The text takes 16 columns at 10 frames/s: the spin starts 1.6 s after it.
    let at = |needle: &str| -> f64 {
        let line = text.lines().find(|l| l.contains(needle)).unwrap();
        line[1..line.find('s').unwrap()].trim().parse().unwrap()
    };
    let took = at("line 13: spin") - at("line 12: scrollMatrixText");
    assert!((took - 1.6).abs() < 0.05, "{text}");
}

#[test]
fn a_minute_long_program_takes_well_under_a_minute() {
    let dir = Scratch::new("edu", "minute");
    let p = dir.file(
        "minute.js",
        "async function startProgram() {\n  for (let i = 0; i < 6; i++) {\n    await roll(i * 60, 60, 5);\n    await delay(5);\n  }\n}\n",
    );
    let (out, wall) = dir.run_timed(&["run", path(&p), "--sim", "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(num(&summary(&out), "t_ms") >= 60_000.0);
    assert!(wall < Duration::from_secs(20), "simulated time: {wall:?}");
}

/// A program's recording replays: its calls are marked as steps (`step 2 roll(0, 80, 2)`),
/// which are not mission lines and must not make replay refuse the capture.
#[test]
fn a_programs_recording_replays() {
    let dir = Scratch::new("edu", "replay");
    let p = dir.file(
        "rec.js",
        "async function startProgram() {\n  await roll(0, 80, 2);\n  setMainLed({ r: 0, g: 0, b: 255 });\n  await delay(1);\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "bolt", "--record", "rec.drc"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let capture = dir.0.join("rec.drc");
    let text = std::fs::read_to_string(&capture).unwrap();
    assert!(text.contains("step 2 roll(0, 80, 2)"), "{text}");
    let out = dir.run(&["replay", capture.to_str().unwrap(), "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let samples = json_lines(&stdout(&out));
    let last = samples
        .iter()
        .rev()
        .find(|s| s.get("x_cm").is_some())
        .unwrap();
    assert!(
        last["y_cm"].as_f64().unwrap_or(0.0).abs() > 10.0,
        "{last:?}"
    );
}

#[test]
fn a_syntax_error_is_exit_2_with_line_and_column_and_nothing_is_sent() {
    let dir = Scratch::new("edu", "syntax");
    let p = dir.file(
        "bad.js",
        "async function startProgram() {\n  await roll(0, 50, 1);\n  setMainLed({ r: 1, g: 2, b: 3 }\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "bolt", "--json"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("bad.js:4:1: SyntaxError"), "{err}");
    assert!(err.contains("nothing was sent"), "{err}");
    assert!(stdout(&out).is_empty(), "nothing ran: {}", stdout(&out));
}

#[test]
fn an_exception_stops_the_droid_and_names_its_line() {
    let dir = Scratch::new("edu", "exception");
    let p = dir.file(
        "oops.js",
        "async function startProgram() {\n  setSpeed(120);\n  await delay(1);\n  const n = undefinedValue + 3;\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "bolt", "--json"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("oops.js:4: ReferenceError: undefinedValue is not defined"),
        "{err}"
    );
    assert!(err.contains("droid stopped"), "{err}");
    // The last sample: slowing to a stop (the simulated body brakes over a few tenths).
    // The samples (the summary comes last, with the error: `"ended": "error"`).
    let samples: Vec<_> = json_lines(&stdout(&out))
        .into_iter()
        .filter(|s| s.get("done").is_none())
        .collect();
    let last = samples.last().expect("samples");
    let top = samples.iter().map(|s| num(s, "speed")).fold(0.0, f64::max);
    assert!(
        num(last, "speed") < top / 2.0,
        "stopping: {last:?}, top {top}"
    );
    // A thrown error names its line too.
    let p = dir.file(
        "throw.js",
        "async function startProgram() {\n  await delay(0.2);\n  throw new Error(\"boom\");\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "bolt"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("throw.js:3: Error: boom"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn a_call_a_robot_does_not_have_is_an_error_naming_the_robots_it_is_on() {
    let dir = Scratch::new("edu", "not-on");
    let p = dir.file(
        "m.js",
        "async function startProgram() {\n  await delay(0.1);\n  setMatrixCharacter(\"A\", { r: 255, g: 0, b: 0 });\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "r2d2"]);
    // Found before anything is sent: bad input.
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(
        err.contains(
            "m.js:3: TypeError: setMatrixCharacter() is not on R2-D2 (it is on Sphero BOLT, Sphero BOLT+)"
        ),
        "{err}"
    );
}

#[test]
fn a_program_that_never_waits_cannot_hang_droidctl() {
    let dir = Scratch::new("edu", "spin");
    let p = dir.file(
        "busy.js",
        "async function startProgram() {\n  setSpeed(80);\n  while (true) {}\n}\n",
    );
    let child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["run", path(&p), "--sim", "bolt", "--timeout", "1"])
        .current_dir(&dir.0)
        .env("DROIDCTL_LOG_FILE", dir.log())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let out = crate::common::cli::finish(child, Duration::from_secs(60), "droidctl");
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("without waiting"), "{}", stderr(&out));
    // A program that waits forever ends at --timeout, on the simulated clock.
    let p = dir.file(
        "forever.js",
        "async function startProgram() {\n  while (true) { await delay(1); }\n}\n",
    );
    let (out, wall) = dir.run_timed(&["run", path(&p), "--sim", "bolt", "--timeout", "120"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("--timeout"), "{}", stderr(&out));
    assert!(wall < Duration::from_secs(30), "{wall:?}");
}

#[cfg(unix)]
#[test]
fn ctrl_c_ends_a_program_that_never_waits() {
    let dir = Scratch::new("edu", "ctrl-c");
    let p = dir.file(
        "busy.js",
        "async function startProgram() {\n  setSpeed(80);\n  while (true) {}\n}\n",
    );
    let child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["run", path(&p), "--sim", "bolt"])
        .current_dir(&dir.0)
        .env("DROIDCTL_LOG_FILE", dir.log())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(700));
    let pid = child.id().to_string();
    let sent = Command::new("kill").args(["-INT", &pid]).status().unwrap();
    assert!(sent.success());
    let out = crate::common::cli::finish(child, Duration::from_secs(60), "droidctl");
    // 128 + SIGINT once the droid is stopped (docs/exit-status.md).
    assert_eq!(out.status.code(), Some(130), "{}", stderr(&out));
    assert!(stderr(&out).contains("SIGINT"), "{}", stderr(&out));
}

#[test]
fn the_docs_list_every_call_with_its_robots() {
    let docs = std::fs::read_to_string(format!(
        "{}/docs/edu-programs.md",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("docs/edu-programs.md");
    let table = droidctl::edu::calls::markdown();
    assert!(
        docs.contains(&table),
        "docs/edu-programs.md must hold the table of calls as src/edu/calls.rs has it:\n{table}"
    );
}

/// The sensors read what the simulated droid streams, in Sphero Edu's shapes and units; the
/// program throws (exit 1) on anything else.
const SENSORS: &str = r#"function check(ok, what) { if (!ok) throw new Error(what); }
async function startProgram() {
  check(getSpeed() === 0 && getHeading() === 0, "targets start at 0");
  await roll(90, 100, 2);
  await delay(0.5);
  const at = getLocation();
  check(at !== null && at.x > 30 && Math.abs(at.y) < 5, "location east: " + JSON.stringify(at));
  check(getDistance() > 30, "distance: " + getDistance());
  check(getHeading() === 90 && getSpeed() === 0, "targets after roll: " + getHeading() + " " + getSpeed());
  const o = getOrientation();
  check(o !== null && typeof o.yaw === "number", "orientation: " + JSON.stringify(o));
  const a = getAcceleration();
  check(a !== null && Math.abs(a.z) > 0.5, "acceleration: " + JSON.stringify(a));
  check(getGyroscope() !== null && getVelocity() !== null, "gyro and velocity");
  check(getElapsedTime() >= 2.5, "elapsed: " + getElapsedTime());
  setMainLed({ r: 10, g: 20, b: 30 });
  const m = getMainLed();
  check(m.r === 10 && m.g === 20 && m.b === 30, "main led: " + JSON.stringify(m));
  setSpeed(60);
  await delay(1);
  const v = getVelocity();
  check(Math.hypot(v.x, v.y) > 10, "velocity while rolling: " + JSON.stringify(v));
  stopRoll();
}
"#;

#[test]
fn sensors_read_what_the_droid_streams() {
    let dir = Scratch::new("edu", "sensors");
    let p = dir.file("sensors.js", SENSORS);
    let out = dir.run(&["run", path(&p), "--sim", "bolt"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
}

/// R2-D2's own calls: the dome, stances waited for, its lights, a sound, speech printed.
const R2: &str = r#"async function startProgram() {
  setDomePosition(45);
  await setStance(Stance.Tripod);
  await setStance(Stance.Bipod);
  setHoloProjectorLed(255);
  setLogicDisplayLeds(128);
  playSound("1915");
  speak("beep boop");
  await roll(0, 80, 1);
}
"#;

#[test]
fn r2d2s_calls_run_and_speech_is_printed() {
    let dir = Scratch::new("edu", "r2");
    let p = dir.file("r2.js", R2);
    let out = dir.run(&["run", path(&p), "--sim", "r2d2"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(text.contains("R2-D2 says \"beep boop\""), "{text}");
    // The stance change is waited for: the next line comes after it (R2-D2 starts in bipod,
    // so the change to tripod, which takes time, comes first).
    let at = |needle: &str| -> f64 {
        let line = text.lines().find(|l| l.contains(needle)).unwrap();
        line[1..line.find('s').unwrap()].trim().parse().unwrap()
    };
    assert!(
        at("line 4: setStance") - at("line 3: setStance") > 0.5,
        "{text}"
    );
}

#[test]
fn a_runaway_loop_of_calls_is_an_error_not_unbounded_memory() {
    let dir = Scratch::new("edu", "many");
    let p = dir.file(
        "many.js",
        "async function startProgram() {\n  for (let i = 0; i < 100000; i++) { setMainLed({ r: i % 256, g: 0, b: 0 }); }\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "bolt"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("many.js:2: RangeError: more than 1000 calls without waiting"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn a_bad_matrix_animation_is_an_error_naming_its_line_and_what_is_wrong() {
    let dir = Scratch::new("edu", "bad-animation");
    let p = dir.file(
        "a.js",
        "const F = [];\nfor (let y = 0; y < 8; y++) F.push([0, 0, 0, 0, 0, 0, 0, 0]);\nF[2][5] = 3;\n\
         registerMatrixAnimation({ frames: [F], palette: [{ r: 0, g: 0, b: 0 }, { r: 9, g: 9, b: 9 }], fps: 5 });\n\
         async function startProgram() {\n  playMatrixAnimation(0);\n  await delay(1);\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "bolt"]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(
        err.contains("a.js:4: RangeError: registerMatrixAnimation: frame 0 row 2 column 5 is 3, not a palette index 0 to 1"),
        "{err}"
    );
    // Playing what was never registered is an error too.
    let q = dir.file(
        "b.js",
        "async function startProgram() {\n  await delay(0.1);\n  playMatrixAnimation(0, false);\n}\n",
    );
    let out = dir.run(&["run", path(&q), "--sim", "bolt"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains(
            "b.js:3: RangeError: playMatrixAnimation(0): no such animation (0 registered)"
        ),
        "{}",
        stderr(&out)
    );
}

/// `rawMotor` on the API v1 robots goes out as their Set Raw Motors (spherov2's `raw_motor`
/// drives them too): the simulated BB-8, SPRK+ and Ollie roll forward on equal power and
/// stop when the duration is over; opposite power turns them in place (briefly: open-loop, it
/// spins them like a top, Ollie past a whole turn in 0.5 s, which the yaw cannot tell from
/// none).
#[test]
fn raw_motors_drive_the_api_v1_robots() {
    let dir = Scratch::new("edu", "raw-v1");
    let p = dir.file(
        "raw.js",
        "function check(ok, what) { if (!ok) throw new Error(what); }\n\
         async function startProgram() {\n\
         \x20 await rawMotor(150, 150, 1);\n\
         \x20 await delay(0.5);\n\
         \x20 const a = getLocation();\n\
         \x20 check(Math.hypot(a.x, a.y) > 20, \"rolled: \" + JSON.stringify(a));\n\
         \x20 await delay(2);\n\
         \x20 const b = getLocation();\n\
         \x20 check(Math.hypot(b.x - a.x, b.y - a.y) < 1, \"stopped: \" + JSON.stringify(b));\n\
         \x20 const yaw = getOrientation().yaw;\n\
         \x20 await rawMotor(120, -120, 0.3);\n\
         \x20 await delay(0.5);\n\
         \x20 const c = getLocation();\n\
         \x20 check(Math.hypot(c.x - b.x, c.y - b.y) < 5, \"in place: \" + JSON.stringify(c));\n\
         \x20 check(Math.abs(getOrientation().yaw - yaw) > 20, \"turned: \" + getOrientation().yaw);\n\
         }\n",
    );
    for model in ["bb8", "sprk", "ollie"] {
        let out = dir.run(&["run", path(&p), "--sim", model]);
        assert_eq!(out.status.code(), Some(0), "{model}: {}", stderr(&out));
    }
}

/// Full power on both raw motors throws a rolling robot off the floor (Sphero's docs for
/// `rawMotor`); the simulated one hops, and a program's `onFreefall` and `onLanding` fire, in
/// that order, once each.
#[test]
fn a_hop_at_full_raw_power_fires_freefall_then_landing() {
    let dir = Scratch::new("edu", "hop");
    let p = dir.file(
        "hop.js",
        "const seen = [];\n\
         function check(ok, what) { if (!ok) throw new Error(what); }\n\
         registerEvent(EventType.onFreefall, async () => { seen.push(\"fall\"); });\n\
         registerEvent(EventType.onLanding, async () => { seen.push(\"land\"); });\n\
         async function startProgram() {\n\
         \x20 await delay(1);\n\
         \x20 check(seen.length === 0, \"nothing before: \" + seen);\n\
         \x20 await rawMotor(255, 255, 1);\n\
         \x20 await delay(1);\n\
         \x20 check(seen.join() === \"fall,land\", \"fall then land: \" + seen);\n\
         \x20 await roll(0, 200, 1);\n\
         \x20 await rawMotor(150, 150, 1);\n\
         \x20 await delay(1);\n\
         \x20 check(seen.length === 2, \"rolling and half power do not hop: \" + seen);\n\
         \x20 exitProgram();\n\
         }\n",
    );
    for model in ["bolt", "mini", "bb8"] {
        let out = dir.run(&["run", path(&p), "--sim", model]);
        assert_eq!(out.status.code(), Some(0), "{model}: {}", stderr(&out));
    }
    // RVR drives on treads: full power does not lift it.
    let q = dir.file(
        "rvr.js",
        "let fell = false;\nregisterEvent(EventType.onFreefall, () => { fell = true; });\n\
         async function startProgram() {\n  await rawMotor(255, 255, 1);\n  await delay(1);\n  if (fell) throw new Error(\"RVR fell\");\n  exitProgram();\n}\n",
    );
    let out = dir.run(&["run", path(&q), "--sim", "rvr"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
}

/// Opposite full power spins a ball like a top, past the ±2000°/s its gyroscope measures:
/// `onGyroMax` fires once for the spin (Sphero's docs: "spinning the robot around like a top").
/// A spin at the control system's pace does not fire it.
#[test]
fn a_top_spin_fires_gyro_max_once() {
    let dir = Scratch::new("edu", "gyro-max");
    let p = dir.file(
        "top.js",
        "let maxed = 0;\n\
         registerEvent(EventType.onGyroMax, () => { maxed += 1; });\n\
         function check(ok, what) { if (!ok) throw new Error(what); }\n\
         async function startProgram() {\n\
         \x20 await spin(720, 1);\n\
         \x20 await delay(0.5);\n\
         \x20 check(maxed === 0, \"a spin at the control system's pace: \" + maxed);\n\
         \x20 await rawMotor(255, -255, 1);\n\
         \x20 await delay(1);\n\
         \x20 check(maxed === 1, \"one top spin: \" + maxed);\n\
         \x20 exitProgram();\n\
         }\n",
    );
    for model in ["bolt", "sprk"] {
        let out = dir.run(&["run", path(&p), "--sim", model]);
        assert_eq!(out.status.code(), Some(0), "{model}: {}", stderr(&out));
    }
}

/// `onColor` fires as spherov2's does: when RVR's colour sensor sees a new colour (its
/// palette index changes) with enough confidence, not at every reading: the simulated floor
/// is one grey, so it fires once, with that grey.
#[test]
fn on_color_fires_once_per_colour_seen() {
    let dir = Scratch::new("edu", "on-color");
    let p = dir.file(
        "colour.js",
        "const seen = [];\n\
         registerEvent(EventType.onColor, (c) => { seen.push(c.r + \",\" + c.g + \",\" + c.b); });\n\
         async function startProgram() {\n\
         \x20 await roll(0, 60, 2);\n\
         \x20 await delay(2);\n\
         \x20 if (seen.join(\" \") !== \"128,128,128\") throw new Error(\"seen: \" + seen.join(\" \"));\n\
         \x20 const c = getColor();\n\
         \x20 if (c.r !== 128) throw new Error(\"getColor: \" + JSON.stringify(c));\n\
         \x20 exitProgram();\n\
         }\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "rvr"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
}

/// A program that waits for something that never comes (a promise nothing resolves, with no
/// event to run) ends at once with the droid stopped and says why, rather than running on
/// forever in simulated time.
#[test]
fn a_program_waiting_for_nothing_ends_and_says_why() {
    let dir = Scratch::new("edu", "stuck");
    let p = dir.file(
        "stuck.js",
        "async function startProgram() {\n  setSpeed(80);\n  await delay(0.5);\n  await new Promise(() => {});\n}\n",
    );
    let (out, wall) = dir.run_timed(&["run", path(&p), "--sim", "bolt", "--json"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("stuck.js:3: the program can go no further")
            && err.contains("it waits for a promise that nothing resolves"),
        "{err}"
    );
    assert!(wall < Duration::from_secs(20), "{wall:?}");
}

/// Issue 37: 990 pending long spins, or strobes, are a few numbers each (they were 7 GB and
/// 2.7 GB of listed steps), and `--timeout 2` ends the run on the simulated clock at once; a
/// call past 24 h is an error naming its line. (A `delay(0)` every 100 calls: the engine of a
/// debug build on a busy machine may take more than the 2 s it is given to make 990 calls.)
#[test]
fn hundreds_of_long_timed_calls_pending_end_at_the_timeout_promptly() {
    let dir = Scratch::new("edu", "long");
    for (name, call) in [
        ("spins.js", "spin(360 * 8000, 1)"),
        ("strobes.js", "strobe({ r: 255, g: 0, b: 0 }, 0.05, 10000)"),
    ] {
        let p = dir.file(
            name,
            &format!(
                "async function startProgram() {{\n  for (let i = 0; i < 990; i++) {{\n    {call};\n    \
                 if (i % 100 === 99) await delay(0);\n  }}\n  await delay(3600);\n}}\n"
            ),
        );
        let (out, wall) = dir.run_timed(&["run", path(&p), "--sim", "bolt", "--timeout", "2"]);
        assert_eq!(out.status.code(), Some(1), "{name}: {}", stderr(&out));
        assert!(
            stderr(&out).contains("--timeout"),
            "{name}: {}",
            stderr(&out)
        );
        assert!(wall < Duration::from_secs(30), "{name}: {wall:?}");
        eprintln!("{name}: {wall:?}");
    }
    let p = dir.file(
        "forever.js",
        "async function startProgram() {\n  setSpeed(50);\n  await spin(1e12, 1);\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "bolt"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("forever.js:3: RangeError: spin: turning 1250000000 s is past"),
        "{}",
        stderr(&out)
    );
}
