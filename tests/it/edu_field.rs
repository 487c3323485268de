//! Sphero Edu programs as the field writes them (issue 38 points 5 to 9): the calls real
//! programs use (sounds, `buildString`, timers, `console.log`, RVR's lights and drive), errors
//! found before anything is sent (a misspelt call, a call not on the robot, syntax errors
//! placed where they are), un-awaited helpers that throw, the time limit under `--sim`, a
//! class's programs with `--each`, and `--json`'s summary of a program that failed.

use serde_json::Value;
use std::time::Duration;

use crate::common::scratch;
use scratch::{Scratch, json_lines, path, stderr, stdout};

/// The time of the first output line holding `needle` (`[    1.00s] line 3: …`).
fn at(text: &str, needle: &str) -> f64 {
    let line = text
        .lines()
        .find(|l| l.contains(needle))
        .unwrap_or_else(|| panic!("no line with {needle:?} in:\n{text}"));
    line[1..line.find('s').unwrap()].trim().parse().unwrap()
}

const FIELD: &str = r#"async function blink() {
  setMainLed({ r: 0, g: 0, b: 255 });
}
async function startProgram() {
  await Sound.Animal.Cat.play(true);
  await Sound.Effects.play(false);
  Sound.play(false);
  console.log(buildString("speed ", 80, "!"), { a: 1 });
  const f = getRandomFloat(1, 2);
  if (!(f >= 1 && f < 2)) throw new Error("getRandomFloat " + f);
  const t0 = getCurrentTime();
  setFrontLed({ r: 1, g: 2, b: 3 });
  const front = getFrontLed();
  if (front.r !== 1 || front.b !== 3) throw new Error("getFrontLed " + JSON.stringify(front));
  setBackLed({ r: 4, g: 5, b: 6 });
  if (getBackLed().g !== 5) throw new Error("getBackLed");
  let ticks = 0;
  const every = setInterval(() => { ticks++; }, 100);
  const never = setTimeout(() => { throw new Error("cleared timeout ran"); }, 200);
  clearTimeout(never);
  setTimeout(blink, 300);
  await rollToDistance(0, 80, 30);
  clearInterval(every);
  const n = ticks;
  await delay(0.5);
  if (ticks !== n || n < 3) throw new Error("interval " + n + " then " + ticks);
  if (getMainLed().b !== 255) throw new Error("setTimeout's blink did not run");
  if (getDistance() < 29) throw new Error("rollToDistance: " + getDistance());
  if (getCurrentTime() - t0 < 0.5) throw new Error("getCurrentTime " + t0);
}
"#;

#[test]
fn the_calls_field_programs_use_run() {
    let dir = Scratch::new("edu-field", "calls");
    let p = dir.file("field.js", FIELD);
    let out = dir.run(&["run", path(&p), "--sim", "bolt"]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{}\n{text}", stderr(&out));
    // A sound with wait takes its (guessed) length; without, the program goes on at once.
    assert!(
        text.contains("Sphero BOLT plays sound \"Animal.Cat\""),
        "{text}"
    );
    assert!(text.contains("plays a random Effects sound"), "{text}");
    assert!(text.contains("plays a random sound"), "{text}");
    let waited = at(&text, "playSound(\"Effects\"") - at(&text, "playSound(\"Animal.Cat\"");
    assert!((waited - 1.0).abs() < 0.01, "{text}");
    assert!(
        text.contains(r#"console.log("speed 80! {\"a\":1}")"#),
        "{text}"
    );
    assert!(
        text.contains("line 22: rollToDistance(0, 80, 30)"),
        "{text}"
    );
}

#[test]
fn rvr_drives_to_a_distance_reads_a_colour_channel_and_sets_its_own_lights() {
    let dir = Scratch::new("edu-field", "rvr");
    let p = dir.file(
        "rvr.js",
        "async function startProgram() {\n  setLeftHeadlightLed({ r: 255, g: 0, b: 0 });\n  setRightHeadlightLed({ r: 0, g: 255, b: 0 });\n  setLeftLed({ r: 0, g: 0, b: 255 });\n  setRightLed({ r: 9, g: 9, b: 9 });\n  await driveToDistance(90, 100, 40);\n  await delay(0.5);\n  const r = getColorChannel(\"r\");\n  if (typeof r !== \"number\" || r !== getColor().r) throw new Error(\"channel \" + r);\n  if (getDistance() < 39) throw new Error(\"distance \" + getDistance());\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "rvr", "--record", "rvr.drc"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    // The lights went to RVR as spherov2 sends them: Set All LEDs with a 32-bit mask, the
    // left headlight's bits 3..5.
    let capture = std::fs::read_to_string(dir.0.join("rvr.drc")).unwrap();
    let left = capture.lines().any(|l| {
        // `… out api 8d 3a 11 01 1a 1a SEQ 00000038 ff0000 …`: DID 0x1A, CID 0x1A.
        l.contains(" out api ")
            && l.find("1a1a")
                .is_some_and(|i| l[i + 6..].starts_with("00000038ff0000"))
    });
    assert!(left, "no left headlight command in the capture:\n{capture}");
    // Not RVR: found before anything is sent.
    let out = dir.run(&["run", path(&p), "--sim", "bolt"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("rvr.js:2: TypeError: setLeftHeadlightLed() is not on Sphero BOLT"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn r2_plays_its_own_clip_for_a_sound_it_knows_and_says_the_others() {
    let dir = Scratch::new("edu-field", "r2");
    let p = dir.file(
        "r2.js",
        "async function startProgram() {\n  await Sound.R2.Excited.play(true);\n  await Sound.Animal.Dog.play(false);\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "r2d2"]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(!text.contains("plays sound \"R2.Excited\""), "{text}");
    assert!(text.contains("R2-D2 plays sound \"Animal.Dog\""), "{text}");
}

#[test]
fn a_misspelt_call_is_exit_2_with_what_it_meant_before_anything_is_sent() {
    let dir = Scratch::new("edu-field", "typo");
    let p = dir.file(
        "typo.js",
        "async function startProgram() {\n  await roll(0, 80, 2);\n  setMainLED({ r: 255, g: 0, b: 0 });\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "bolt"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("typo.js:3:3: setMainLED() is not a Sphero Edu call"),
        "{err}"
    );
    assert!(err.contains("did you mean setMainLed()?"), "{err}");
    assert!(stdout(&out).is_empty(), "nothing ran: {}", stdout(&out));
}

#[test]
fn a_call_not_on_the_robot_is_found_before_the_first_call_is_sent() {
    let dir = Scratch::new("edu-field", "not-on");
    let p = dir.file(
        "m.js",
        "async function startProgram() {\n  await roll(0, 80, 2);\n  setMatrixCharacter(\"A\", { r: 255, g: 0, b: 0 });\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "r2d2"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("m.js:3: TypeError: setMatrixCharacter() is not on R2-D2"),
        "{err}"
    );
    assert!(
        !stdout(&out).contains("roll("),
        "nothing was sent: {}",
        stdout(&out)
    );
}

#[test]
fn an_unawaited_helper_that_throws_fails_the_program_with_its_line() {
    let dir = Scratch::new("edu-field", "unawaited");
    let p = dir.file(
        "course.js",
        "async function flash() {\n  await delay(0.5);\n  throw new Error(\"flash broke\");\n}\nasync function startProgram() {\n  flash();\n  await roll(0, 60, 2);\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "bolt"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("course.js:3: Error: flash broke"), "{err}");
    assert!(err.contains("not awaited"), "{err}");
}

#[test]
fn syntax_errors_name_their_real_line_and_column() {
    let dir = Scratch::new("edu-field", "syntax");
    let cases = [
        (
            "brace.js",
            "async function startProgram() {\n  for (let i = 0; i < 3; i++) {\n    await roll(0, 50, 1);\n\n  setMainLed({ r: 1, g: 2, b: 3 });\n}\n",
            "brace.js:2:31: SyntaxError: this `{` is never closed",
        ),
        (
            "string.js",
            "async function startProgram() {\n  await delay(1);\n  await speak(\"hello, false);\n}\n",
            "string.js:3:15: SyntaxError: this string is never closed",
        ),
        (
            "await.js",
            "function helper() {\n  await delay(1);\n}\nasync function startProgram() {\n  helper();\n}\n",
            "await.js:2:",
        ),
    ];
    for (name, src, want) in cases {
        let p = dir.file(name, src);
        let out = dir.run(&["run", path(&p), "--sim", "bolt"]);
        assert_eq!(out.status.code(), Some(2), "{name}: {}", stderr(&out));
        let err = stderr(&out);
        assert!(err.contains(want), "{name}: {err}");
        assert!(!err.contains("abrupt end"), "{name}: {err}");
        if name == "await.js" {
            assert!(err.contains("`async`"), "{err}");
        }
    }
}

#[test]
fn a_program_that_never_ends_stops_at_the_sim_limit_and_says_so() {
    let dir = Scratch::new("edu-field", "limit");
    let p = dir.file(
        "bounce.js",
        "async function startProgram() {\n  while (true) {\n    await roll(0, 60, 1);\n    await roll(180, 60, 1);\n  }\n}\n",
    );
    let (out, wall) = dir.run_timed(&["run", path(&p), "--sim", "bolt", "--json"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("300 s of simulated time"), "{err}");
    assert!(err.contains("--timeout SECONDS"), "{err}");
    assert!(wall < Duration::from_secs(60), "{wall:?}");
    // The summary comes last, as for a program that ended, saying why it did not.
    let lines = json_lines(&stdout(&out));
    let last = lines.last().expect("a summary");
    assert_eq!(last.get("done"), Some(&Value::Bool(true)), "{last:?}");
    assert_eq!(last["ended"], "time_limit", "{last:?}");
    assert!(last["t_ms"].as_f64().unwrap() >= 300_000.0, "{last:?}");
    // --timeout sets another limit.
    let out = dir.run(&[
        "run",
        path(&p),
        "--sim",
        "bolt",
        "--timeout",
        "10",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let lines = json_lines(&stdout(&out));
    let t = lines.last().unwrap()["t_ms"].as_f64().unwrap();
    assert!((10_000.0..11_000.0).contains(&t), "{t}");
}

#[test]
fn json_ends_with_a_summary_when_a_program_errors() {
    let dir = Scratch::new("edu-field", "json-error");
    let p = dir.file(
        "oops.js",
        "async function startProgram() {\n  await roll(0, 80, 1);\n  throw new Error(\"boom\");\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "bolt", "--json"]);
    assert_eq!(out.status.code(), Some(1));
    let lines = json_lines(&stdout(&out));
    let last = lines.last().expect("a summary");
    assert_eq!(last.get("done"), Some(&Value::Bool(true)), "{last:?}");
    assert_eq!(last["ended"], "error");
    assert!(
        last["error"]
            .as_str()
            .unwrap()
            .contains("oops.js:3: Error: boom"),
        "{last:?}"
    );
}

#[test]
fn each_runs_a_class_of_programs_one_line_per_file() {
    let dir = Scratch::new("edu-field", "each");
    let good = dir.file(
        "good.js",
        "async function startProgram() {\n  await roll(0, 80, 2);\n}\n",
    );
    let bad = dir.file(
        "bad.js",
        "async function startProgram() {\n  await delay(1);\n  null.x;\n}\n",
    );
    let forever = dir.file(
        "forever.js",
        "async function startProgram() {\n  while (true) { await delay(1); }\n}\n",
    );
    let typo = dir.file(
        "typo.js",
        "async function startProgram() {\n  rol(0, 80, 2);\n}\n",
    );
    let out = dir.run(&[
        "run",
        "--each",
        path(&good),
        path(&bad),
        path(&forever),
        path(&typo),
        "--sim",
        "bolt",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let text = stdout(&out);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 4, "{text}");
    // (The time counts from the run's start: the droid's setup and first sample, then the
    // two-second roll.)
    let ended = lines[0]
        .split("ended after ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|t| t.parse::<f64>().ok())
        .unwrap_or_else(|| panic!("{text}"));
    assert!((2.0..5.0).contains(&ended), "{text}");
    assert!(lines[1].contains("bad.js:3: TypeError"), "{text}");
    assert!(lines[2].contains("forever.js: time limit"), "{text}");
    assert!(lines[3].contains("did you mean roll()?"), "{text}");
    // Each on a fresh droid: the same program twice ends in the same place.
    let out = dir.run(&[
        "run",
        "--each",
        path(&good),
        path(&good),
        "--sim",
        "bolt",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let lines = json_lines(&stdout(&out));
    assert_eq!(lines.len(), 2);
    assert_eq!(lines[0]["result"], "ended");
    assert_eq!(lines[0]["y_cm"], lines[1]["y_cm"], "{lines:?}");
}

/// A program's capture replays and plots: what a robot without a speaker says is marked as a
/// step (`step 2 Sphero BOLT plays sound "Animal.Cat"`) and is not read as a mission line.
#[test]
fn a_programs_capture_with_sounds_and_speech_replays_and_plots() {
    let dir = Scratch::new("edu-field", "record");
    let p = dir.file(
        "rec.js",
        "async function startProgram() {\n  await Sound.Animal.Cat.play(true);\n  setMainLed({ r: 255, g: 0, b: 0 });\n  await roll(0, 80, 2);\n  await speak(\"done\", false);\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "bolt", "--record", "rec.drc"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let capture = dir.0.join("rec.drc");
    let text = std::fs::read_to_string(&capture).unwrap();
    assert!(text.contains("plays sound \"Animal.Cat\""), "{text}");
    let out = dir.run(&["replay", path(&capture), "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let last = json_lines(&stdout(&out)).pop().expect("a summary");
    assert!(last["y_cm"].as_f64().unwrap_or(0.0) > 30.0, "{last:?}");
    let png = dir.0.join("rec.png");
    let out = dir.run(&["plot", path(&capture), "-o", path(&png)]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(png.exists());
}
