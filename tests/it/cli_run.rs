//! `droidctl run SCRIPT --sim [MODEL] [--json] [--interval MS]` end to end, as a user runs it.

use serde_json::Value;
use std::time::Duration;

use crate::common::scratch;
use scratch::{Scratch, json_lines, path, stderr, stdout};

/// About a minute of mission: 2 s stance, 5 + 5 + 8 + 3 s of driving, 10 + 25 s of waiting.
const MINUTE: &str = "\
# a one-minute patrol
wake
stance tripod
head 45
drive 150 90 for 5s
led front 255 0 0
sound 1915
drive 100 180 for 5s
animation 7
wait 10s
drive 200 270 for 8s
stop
head -30
led logic 200
wait 25s
drive 80 0 for 3s
";

#[test]
fn a_minute_long_mission_runs_in_simulated_time_and_is_deterministic() {
    let dir = Scratch::new("cli-run", "minute");
    let script = dir.file("mission.txt", MINUTE);
    let (a, wall_a) = dir.run_timed(&["run", path(&script), "--sim", "--json"]);
    assert_eq!(a.status.code(), Some(0), "stderr: {}", stderr(&a));
    let (b, wall_b) = dir.run_timed(&["run", path(&script), "--sim", "--json"]);
    assert_eq!(b.status.code(), Some(0), "stderr: {}", stderr(&b));
    eprintln!("wall: {wall_a:?}, {wall_b:?}");
    assert!(
        wall_a < Duration::from_secs(5),
        "a 60 s mission took {wall_a:?} of wall time"
    );
    assert!(wall_b < Duration::from_secs(5), "{wall_b:?}");

    let la = json_lines(&stdout(&a));
    let lb = json_lines(&stdout(&b));
    let (sa, sb) = (la.last().unwrap(), lb.last().unwrap());
    assert_eq!(sa["done"], Value::Bool(true));
    let t_ms = sa["t_ms"].as_u64().unwrap();
    assert!((55_000..70_000).contains(&t_ms), "mission length {t_ms} ms");
    let pos = |s: &serde_json::Map<String, Value>| {
        (s["x_cm"].as_f64().unwrap(), s["y_cm"].as_f64().unwrap())
    };
    assert_eq!(pos(sa), pos(sb), "same script, same final position");
    // The droid really went somewhere: east, south, west, north.
    let (x, y) = pos(sa);
    assert!(x.abs() > 1.0 || y.abs() > 1.0, "({x}, {y})");
    assert_eq!(sa["failed_steps"], Value::from(0));
    // Everything is deterministic, sample by sample.
    assert_eq!(stdout(&a), stdout(&b));

    // The human-readable run ends at the same place.
    let (h, _) = dir.run_timed(&["run", path(&script), "--sim"]);
    assert_eq!(h.status.code(), Some(0));
    let text = stdout(&h);
    let last = text.lines().last().unwrap();
    assert!(last.starts_with("done in"), "{last}");
    assert!(
        last.contains(&format!("final position ({x:.1}, {y:.1}) cm")),
        "{last} vs ({x:.1}, {y:.1})"
    );
    assert!(text.contains("line 5: drive 150 90 for 5s"), "{text}");
    // The log went where DROIDCTL_LOG_FILE said.
    let log = std::fs::read_to_string(dir.log()).expect("log file");
    assert!(log.contains("connected"), "{log}");
}

#[test]
fn json_prints_one_sample_per_interval_then_a_summary() {
    let dir = Scratch::new("cli-run", "json");
    let script = dir.file(
        "m.txt",
        "wake\nstance tripod\ndrive 120 90 for 3s\nhead 30\nwait 2s\n",
    );
    let (o, _) = dir.run_timed(&["run", path(&script), "--sim", "--json", "--interval", "250"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let lines = json_lines(&stdout(&o));
    let (summary, samples) = lines.split_last().unwrap();
    assert!(samples.len() > 20, "{} samples", samples.len());
    let keys = [
        "t_ms",
        "x_cm",
        "y_cm",
        "speed",
        "heading",
        "head_deg",
        "stance",
        "stance_to",
        "battery_v",
        "collisions",
        "pitch_deg",
        "roll_deg",
        "yaw_deg",
        "accel_g",
        "gyro_deg_s",
        "velocity_cm_s",
    ];
    for s in samples {
        let got: Vec<&str> = s.keys().map(String::as_str).collect();
        assert_eq!(got, keys, "{s:?}");
    }
    // At the --interval spacing, from 0; the last sample is the final state after the stop.
    let times: Vec<u64> = samples
        .iter()
        .map(|s| s["t_ms"].as_u64().unwrap())
        .collect();
    let (last_t, regular) = times.split_last().unwrap();
    assert_eq!(regular[0], 0);
    for w in regular.windows(2) {
        assert_eq!(w[1] - w[0], 250, "{times:?}");
    }
    assert!(*last_t >= *regular.last().unwrap());
    // Samples carry real telemetry once streaming runs.
    let late = &samples[samples.len() - 2];
    assert!(late["x_cm"].as_f64().unwrap() > 50.0, "{late:?}");
    assert_eq!(late["stance"], Value::from("tripod"));
    // Plain values only: a stance's name or null, never display text ("→ tripod").
    let plain = |v: &Value, extra: &[&str]| {
        v.is_null()
            || ["tripod", "bipod", "waddle"]
                .iter()
                .chain(extra)
                .any(|n| v == &Value::from(*n))
    };
    for s in samples {
        assert!(plain(&s["stance"], &[]), "{s:?}");
        assert!(plain(&s["stance_to"], &["unknown"]), "{s:?}");
    }
    // The stand-up at the start is seen as a change under way, then as the stance.
    assert!(
        samples
            .iter()
            .any(|s| s["stance"].is_null() && s["stance_to"] == "tripod"),
        "{samples:?}"
    );
    assert!(
        (late["head_deg"].as_f64().unwrap() - 30.0).abs() < 0.5,
        "{late:?}"
    );
    assert!(late["battery_v"].as_f64().unwrap() > 3.5);
    // The summary.
    assert_eq!(summary["done"], Value::Bool(true));
    for k in ["sent", "received", "errors", "timeouts"] {
        assert!(summary[k].is_u64(), "{k} in {summary:?}");
    }
    assert!(summary["sent"].as_u64().unwrap() > 10);
    assert!(summary["received"].as_u64().unwrap() > 10);
    assert_eq!(summary["timeouts"], Value::from(0));
    assert_eq!(summary["errors"], Value::from(0));
}

#[test]
fn malformed_script_exits_2_naming_the_line_and_sends_nothing() {
    let dir = Scratch::new("cli-run", "malformed");
    let script = dir.file("bad.txt", "wake\n# fine\ndrive 300 90\nfly away\nwait 1s\n");
    let (o, _) = dir.run_timed(&["run", path(&script), "--sim", "--json"]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(
        err.contains("bad.txt:3:") && err.contains("speed 300 is out of range"),
        "{err}"
    );
    assert!(
        err.contains("bad.txt:4:") && err.contains("unknown command \"fly\""),
        "{err}"
    );
    assert!(err.contains("nothing was sent"), "{err}");
    assert_eq!(stdout(&o), "", "no JSON, no samples");
    // No session was started: nothing connected, nothing logged as sent.
    let log = std::fs::read_to_string(dir.log()).unwrap_or_default();
    assert!(!log.contains("connected"), "{log}");
}

#[test]
fn a_duration_beyond_the_limit_exits_2_naming_the_line_not_a_panic() {
    // `Duration::from_secs_f64` panicked on these before the limit was checked (exit 101).
    let dir = Scratch::new("cli-run", "huge");
    for (i, line) in ["wait 1e20s", "drive 1 1 for 1e20s", "wait 1e23ms"]
        .iter()
        .enumerate()
    {
        let script = dir.file(&format!("huge{i}.txt"), &format!("wake\n{line}\n"));
        let (o, _) = dir.run_timed(&["run", path(&script), "--sim"]);
        assert_eq!(o.status.code(), Some(2), "{line}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(
            err.contains(&format!("huge{i}.txt:2:")) && err.contains("the limit is 86400s"),
            "{line}: {err}"
        );
    }
}

#[test]
fn missing_script_exits_2() {
    let dir = Scratch::new("cli-run", "missing");
    let (o, _) = dir.run_timed(&["run", "no-such-mission.txt", "--sim"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("no-such-mission.txt"), "{}", stderr(&o));
    assert_eq!(stdout(&o), "");
    // No script at all is a usage error too.
    let (o, _) = dir.run_timed(&["run", "--sim"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

#[test]
fn bb9e_rejects_a_stance_line() {
    let dir = Scratch::new("cli-run", "bb9e");
    let script = dir.file("legs.txt", "wake\nstance tripod\ndrive 100 0 for 1s\n");
    let (o, _) = dir.run_timed(&["run", path(&script), "--sim", "bb9e", "--json"]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(
        err.contains("legs.txt:2:") && err.contains("no legs"),
        "{err}"
    );
    assert_eq!(stdout(&o), "");
    // The same script without the stance runs on BB-9E, whose samples have no stance
    // (null, not "unknown").
    let ok = dir.file("ok.txt", "wake\ndrive 100 0 for 1s\n");
    let (o, _) = dir.run_timed(&["run", path(&ok), "--sim", "bb9e", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let lines = json_lines(&stdout(&o));
    let samples: Vec<_> = lines.iter().filter(|s| s.get("done").is_none()).collect();
    assert!(!samples.is_empty());
    for s in samples {
        assert_eq!(s.get("stance"), Some(&Value::Null), "{s:?}");
        assert_eq!(s.get("stance_to"), Some(&Value::Null), "{s:?}");
    }
    // A model droidctl does not know is a usage error.
    let (o, _) = dir.run_timed(&["run", path(&ok), "--sim", "c3po"]);
    assert_eq!(o.status.code(), Some(2));
    // Robi 42 takes only drive, stop and wait: the wake line is refused before anything runs.
    let (o, _) = dir.run_timed(&["run", path(&ok), "--sim", "robi"]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(
        err.contains("ok.txt:1:")
            && err.contains("Robi 42")
            && err.contains("drive, stop and wait"),
        "{err}"
    );
}

#[test]
fn script_may_follow_a_bare_sim_flag() {
    let dir = Scratch::new("cli-run", "order");
    dir.file("mission.txt", "wake\nstance tripod\ndrive 100 90 for 1s\n");
    let (o, _) = dir.run_timed(&["run", "--sim", "mission.txt"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.lines().last().unwrap().starts_with("done in"), "{out}");
    assert!(out.contains("line 3: drive 100 90 for 1s"));
    // And with the model named explicitly, before or after the script.
    let (o, _) = dir.run_timed(&["run", "--sim", "r2q5", "mission.txt"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let (o, _) = dir.run_timed(&["run", "mission.txt", "--sim", "r2d2", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(
        json_lines(&stdout(&o)).last().unwrap()["done"],
        Value::Bool(true)
    );
}

/// The stop `run` writes when it closes the session must not turn the droid: a stop at
/// heading 0 after a mission that ended facing 90 would spin a real R2-D2 round.
#[tokio::test(start_paused = true)]
async fn final_stop_keeps_the_last_heading() {
    use droidctl::mission::MissionOptions;
    use droidctl::model::Model;
    use droidctl::sim::{Faults, SimConfig, SimLink};
    let link = SimLink::new(Model::R2D2, SimConfig::default(), Faults::none());
    let probe = link.probe();
    let steps = droidctl::script::parse("wake\nstance tripod\ndrive 100 90 for 2s\n").unwrap();
    let summary = droidctl::cli::run::run_on(
        Box::new(link),
        Model::R2D2,
        &steps,
        MissionOptions::default(),
        true,
    )
    .await
    .unwrap();
    assert!(summary.done);
    assert!(!probe.connected());
    tokio::time::sleep(Duration::from_secs(3)).await;
    let st = probe.state();
    assert_eq!(st.velocity_cm_s, 0.0);
    assert!(
        (st.yaw_deg - 90.0).abs() < 0.5,
        "the droid turned after the mission: yaw {}",
        st.yaw_deg
    );
}

#[test]
fn telemetry_keeps_flowing_after_sleep_and_wake() {
    // Sleeping turns streaming off in the droid; the wake line must set it up again, or the
    // position stays where the droid fell asleep.
    let dir = Scratch::new("cli-run", "sleepwake");
    let script = dir.file(
        "m.txt",
        "wake\ndrive 80 0 for 1s\nsleep\nwait 1s\nwake\ndrive 120 0 for 2s\n",
    );
    let (o, _) = dir.run_timed(&["run", path(&script), "--sim", "bb9e", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let lines = json_lines(&stdout(&o));
    let y = |l: &serde_json::Map<String, Value>| l.get("y_cm").and_then(Value::as_f64);
    let at_sleep = lines
        .iter()
        .filter(|l| {
            l.get("t_ms")
                .and_then(Value::as_u64)
                .is_some_and(|t| t <= 1500)
        })
        .filter_map(y)
        .next_back()
        .expect("position before sleeping");
    let end = lines
        .iter()
        .rev()
        .find_map(|l| l.get("done").is_none().then(|| y(l)).flatten())
        .expect("a final position");
    assert!(
        end > at_sleep + 50.0,
        "the drive after waking shows in the telemetry: {at_sleep} → {end}"
    );
}
