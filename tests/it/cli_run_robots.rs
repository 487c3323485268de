//! Issue 19 point 2: `droidctl run` with the newer robots' mission lines — BOLT's matrix and
//! compass, RVR's tracks — on their simulators, and refused (before anything is sent) on
//! models without them.

use crate::common::scratch;
use scratch::{Scratch, json_lines, path, stderr};

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

#[test]
fn bolt_and_rvr_missions_run_on_their_simulators() {
    let dir = Scratch::new("cli-run-robots", "ok");
    let bolt = dir.file(
        "bolt.txt",
        "wake\nmatrix text \"HI\" 255 0 0\nmatrix char A\nmatrix fill 0 0 255\nmatrix pixel 3 4 255 255 0\n\
         matrix rotate 90\nmatrix clear\ncalibrate compass\nled back 0 0 255\ndrive 100 90 for 1s\nwait 0.3s\n",
    );
    let o = dir.run(&["run", path(&bolt), "--sim", "bolt", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let lines = json_lines(&scratch::stdout(&o));
    let done = lines.last().expect("summary");
    assert_eq!(done["errors"], 0, "{done:?}");
    assert_eq!(done["failed_steps"], 0, "{done:?}");
    assert!(f(&done["x_cm"]) > 30.0, "rolled east: {done:?}");
    let rvr = dir.file(
        "rvr.txt",
        "wake\nled front 255 255 255\ntank 200 200 for 1s\ntank -150 150 for 0.5s\nstop\nwait 0.3s\n",
    );
    let o = dir.run(&["run", path(&rvr), "--sim", "rvr", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let lines = json_lines(&scratch::stdout(&o));
    let done = lines.last().expect("summary");
    assert_eq!(done["errors"], 0, "{done:?}");
    assert!(f(&done["y_cm"]) > 40.0, "both tracks forward: {done:?}");
    let last = &lines[lines.len() - 2];
    // Streamed as a scaled 32-bit integer: zero within its resolution.
    assert!(f(&last["speed"]).abs() < 0.5, "stopped: {last:?}");
}

/// Issue 41: BOLT+ runs BOLT's mission lines on its simulator (its screen takes the matrix
/// lines, sphero-unsw's way), and a Sphero Edu program's `setDisplayImage`, which nothing public
/// describes, is refused in words that say what to use instead.
#[test]
fn boltplus_runs_bolts_lines_and_refuses_the_undescribed_screen_picture() {
    let dir = Scratch::new("cli-run-robots", "boltplus");
    let mission = dir.file(
        "bp.txt",
        "wake\nmatrix text \"HI\" 255 0 0\nmatrix char A\nmatrix fill 0 0 255\n\
         calibrate compass\nled back 0 0 255\ndrive 100 90 for 1s\nwait 0.3s\n",
    );
    let o = dir.run(&["run", path(&mission), "--sim", "boltplus", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let lines = json_lines(&scratch::stdout(&o));
    let done = lines.last().expect("summary");
    assert_eq!(done["errors"], 0, "{done:?}");
    assert_eq!(done["failed_steps"], 0, "{done:?}");
    assert!(f(&done["x_cm"]) > 30.0, "rolled east: {done:?}");
    let program = dir.file(
        "picture.js",
        "async function startProgram() {\n  setDisplayImage(\"smile\");\n}\n",
    );
    let o = dir.run(&["run", path(&program), "--sim", "boltplus"]);
    assert_ne!(o.status.code(), Some(0), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("setDisplayImage()") && err.contains("not described anywhere public"),
        "{err}"
    );
    assert!(err.contains("setMatrixCharacter"), "{err}");
}

#[test]
fn lines_a_model_lacks_are_refused_before_anything_is_sent() {
    let dir = Scratch::new("cli-run-robots", "refused");
    for (model, line, why) in [
        ("r2d2", "matrix char A", "R2-D2 has no LED matrix"),
        ("mini", "calibrate compass", "Sphero Mini has no compass"),
        ("bolt", "tank 100 100", "Sphero BOLT has no tracks"),
        ("rvr", "matrix text HI", "Sphero RVR has no LED matrix"),
        ("bb8", "tank 1 1 for 1s", "BB-8 has no tracks"),
    ] {
        let script = dir.file("bad.txt", &format!("wake\n{line}\n"));
        let o = dir.run(&["run", path(&script), "--sim", model]);
        assert_eq!(o.status.code(), Some(2), "{line}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(err.contains("bad.txt:2:") && err.contains(why), "{err}");
        assert!(err.contains("nothing was sent"), "{err}");
    }
}

/// BOLT, Mini and RVR have no speaker: a mission's animation and sound lines are refused
/// with the robot's name before anything is sent (spherov2 binds neither to them).
#[test]
fn animations_and_sounds_are_refused_on_the_newer_robots() {
    let dir = Scratch::new("cli-run-robots", "sounds");
    let script = dir.file("sounds.txt", "wake\nanimation 3\nsound 1915\n");
    for model in ["bolt", "mini", "rvr"] {
        let o = dir.run(&["run", path(&script), "--sim", model]);
        assert_eq!(o.status.code(), Some(2), "{model}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(
            err.contains("sounds.txt:2: ") && err.contains("has no animations"),
            "{model}: {err}"
        );
        assert!(err.contains("cannot play sounds"), "{model}: {err}");
    }
}
