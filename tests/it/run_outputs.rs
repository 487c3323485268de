//! `droidctl run` when its outputs fail (issue 27 points 1 and 2), and a mission's drive on a
//! droid standing on two legs (issue 26 point 9), as a user runs them: a closed pipe ends the
//! mission quietly with the droid stopped; a full disk on stdout, `--csv` or `--record` is
//! exit 1 with one line, never a panic and never exit 0.

use droidctl::capture::Capture;
use droidctl::capture::mirror::{Mirror, Output};
use droidctl::model::Model;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

use crate::common::scratch;
use scratch::{Scratch, json_lines, path, stderr, stdout};

/// The drive speeds written over the link, in order, from a recorded capture.
fn drive_speeds(capture: &std::path::Path, model: Model) -> Vec<u8> {
    let c = Capture::load(capture).unwrap();
    let family = droidctl::family::for_model(model);
    let mut m = Mirror::new(model);
    let mut speeds = Vec::new();
    for t in &c.events {
        let mut out = Vec::new();
        m.event(t, &mut out);
        for o in out {
            if let Output::Command(cmd) = o
                && let Some(d) = family.read_drive(&cmd)
            {
                speeds.push(d.speed);
            }
        }
    }
    speeds
}

fn no_panic(err: &str) {
    assert!(
        !err.contains("panicked") && !err.contains("RUST_BACKTRACE"),
        "{err}"
    );
}

fn closed_pipe_ends_the_mission(name: &str, sims: &str) {
    let dir = Scratch::new("run-outputs", name);
    let script = dir.file("m.txt", "drive 100 0 for 600s\n");
    let capture = dir.0.join("cap.txt");
    let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["run", path(&script), "--sim", sims, "--json", "--record"])
        .arg(&capture)
        .current_dir(&dir.0)
        .env("DROIDCTL_LOG_FILE", dir.log())
        .env("DROIDCTL_CONFIG", "/dev/null")
        .env("RUST_BACKTRACE", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Read until every droid is moving (`| head`), then go away.
    let droids = sims.split(',').count();
    let mut moving = std::collections::BTreeSet::new();
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    for l in lines.by_ref().take(5000) {
        let v: serde_json::Value = serde_json::from_str(&l.unwrap()).unwrap();
        if v["speed"].as_f64().is_some_and(|s| s > 20.0) {
            moving.insert(v["droid"].as_str().unwrap_or("").to_string());
        }
        if moving.len() == droids {
            break;
        }
    }
    assert_eq!(moving.len(), droids, "every droid moved: {moving:?}");
    drop(lines);
    let o = child.wait_with_output().unwrap();
    let err = stderr(&o);
    no_panic(&err);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(!err.contains("error"), "quietly: {err}");
    // The mission ended there (not 600 s later), with a stop written, and the capture is whole.
    let text = std::fs::read_to_string(&capture).unwrap();
    assert!(text.lines().last().unwrap().ends_with(" end"), "{text}");
    let models: Vec<Model> = sims.split(',').filter_map(Model::from_id).collect();
    let captures = if models.len() > 1 {
        droidctl::capture::fleet::split(&text).unwrap()
    } else {
        vec![Capture::from_text(&text).unwrap()]
    };
    for (c, model) in captures.iter().zip(&models) {
        assert!(
            c.duration() < std::time::Duration::from_secs(300),
            "{model:?}: the mission went on for {:?}",
            c.duration()
        );
        let one = dir.0.join("one.txt");
        std::fs::write(&one, c.to_text()).unwrap();
        let speeds = drive_speeds(&one, *model);
        assert!(speeds.iter().any(|s| *s > 0), "{model:?}: {speeds:?}");
        assert_eq!(speeds.last(), Some(&0), "{model:?}: stopped at the end");
    }
}

#[test]
fn a_closed_pipe_ends_the_mission_quietly_with_the_droid_stopped() {
    closed_pipe_ends_the_mission("pipe", "r2d2");
}

#[test]
fn a_closed_pipe_ends_a_fleet_mission_quietly_with_every_droid_stopped() {
    closed_pipe_ends_the_mission("fleet-pipe", "r2d2,bb8");
}

/// Run with stdout going to `out`.
fn run_to(dir: &Scratch, args: &[&str], out: Stdio) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(args)
        .current_dir(&dir.0)
        .env("DROIDCTL_LOG_FILE", dir.log())
        .env("DROIDCTL_CONFIG", "/dev/null")
        .env("RUST_BACKTRACE", "1")
        .stdout(out)
        .stderr(Stdio::piped())
        .output()
        .unwrap()
}

fn full() -> Stdio {
    std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap()
        .into()
}

#[test]
fn a_full_disk_is_exit_1_with_one_line() {
    let dir = Scratch::new("run-outputs", "full");
    let script = dir.file("m.txt", "drive 100 0 for 3s\n");
    for sims in ["r2d2", "r2d2,bb8"] {
        for json in [true, false] {
            let mut args = vec!["run", path(&script), "--sim", sims];
            if json {
                args.push("--json");
            }
            let o = run_to(&dir, &args, full());
            let err = stderr(&o);
            no_panic(&err);
            assert_eq!(o.status.code(), Some(1), "{sims} {json}: {err}");
            let said: Vec<&str> = err.lines().filter(|l| l.contains("error")).collect();
            assert_eq!(said.len(), 1, "{err}");
            assert!(said[0].contains("No space left"), "{err}");
        }
    }
}

#[test]
fn an_output_file_not_written_fully_is_exit_1() {
    let dir = Scratch::new("run-outputs", "files");
    let script = dir.file("m.txt", "drive 100 0 for 20s\n");
    for sims in ["r2d2", "r2d2,bb8"] {
        let o = run_to(
            &dir,
            &["run", path(&script), "--sim", sims, "--csv", "/dev/full"],
            Stdio::null(),
        );
        let err = stderr(&o);
        no_panic(&err);
        assert_eq!(o.status.code(), Some(1), "{sims} --csv: {err}");
        assert!(
            err.contains("--csv") && err.contains("No space left"),
            "{err}"
        );

        let o = run_to(
            &dir,
            &[
                "run",
                path(&script),
                "--sim",
                sims,
                "--record",
                "/dev/full",
                "--force",
            ],
            Stdio::null(),
        );
        let err = stderr(&o);
        no_panic(&err);
        assert_eq!(o.status.code(), Some(1), "{sims} --record: {err}");
        assert!(err.contains("incomplete"), "{err}");
    }
}

#[test]
fn a_mission_drive_on_two_legs_puts_r2_in_tripod_first_and_says_so() {
    let dir = Scratch::new("run-outputs", "bipod");
    let script = dir.file("nb.txt", "wake\ndrive 80 0 for 2s\n");
    for model in ["r2d2", "r2q5"] {
        let o = run_to(
            &dir,
            &["run", path(&script), "--sim", model, "--json"],
            Stdio::piped(),
        );
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(0), "{model}: {err}");
        assert!(
            err.contains("line 2") && err.contains("tripod"),
            "{model}: said on stderr: {err}"
        );
        let last = json_lines(&stdout(&o)).pop().unwrap();
        let y = last["y_cm"].as_f64().unwrap();
        assert!(y > 50.0, "{model}: it drove forward: y {y} cm");
    }
    // Text output shows the step it added.
    let o = run_to(&dir, &["run", path(&script), "--sim"], Stdio::piped());
    assert!(
        stdout(&o).contains("line 2: stance tripod"),
        "{}",
        stdout(&o)
    );
    // Already in tripod: nothing added.
    let script = dir.file("t.txt", "wake\nstance tripod\ndrive 80 0 for 2s\n");
    let o = run_to(&dir, &["run", path(&script), "--sim"], Stdio::piped());
    assert_eq!(o.status.code(), Some(0));
    assert!(
        !stderr(&o).contains("putting it in tripod"),
        "{}",
        stderr(&o)
    );
}
