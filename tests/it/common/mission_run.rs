//! `droidctl run --json` output, and the check that the same mission run two ways (through
//! the relay, through the virtual BlueZ) matches the run on `--sim`. Shared by `relay_e2e.rs`
//! and `sim_bluez.rs`.

#![allow(dead_code)]

use serde_json::Value;
use std::process::Output;
use std::time::Duration;

pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A mission's samples and its final summary.
pub struct Run {
    pub samples: Vec<Value>,
    pub summary: Value,
}

pub fn parse_run(out: &Output) -> Run {
    let stdout = text(&out.stdout);
    let mut values: Vec<Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect();
    let summary = values.pop().expect("a summary");
    assert_eq!(summary["done"], true, "{stdout}");
    Run {
        samples: values,
        summary,
    }
}

pub fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// `run` (which took `took` of real time) matches `reference` (the same mission on `--sim`):
/// duration, counters, final position, sample count, last heading and stance.
pub fn assert_matches(run: &Run, reference: &Run, took: Duration) {
    let (a, b) = (&run.summary, &reference.summary);
    let t_ms = f(&a["t_ms"]);
    assert!(
        (t_ms - f(&b["t_ms"])).abs() < 0.1 * f(&b["t_ms"]),
        "{a} vs {b}"
    );
    assert!(
        took.as_secs_f64() * 1000.0 >= t_ms * 0.9,
        "real time: {took:?}"
    );
    for key in ["collisions", "failed_steps", "errors", "timeouts"] {
        assert_eq!(a[key], b[key], "{key}: {a} vs {b}");
    }
    let moved = f(&b["x_cm"]).hypot(f(&b["y_cm"]));
    assert!(moved > 30.0, "the mission drives: {b}");
    let off = (f(&a["x_cm"]) - f(&b["x_cm"])).hypot(f(&a["y_cm"]) - f(&b["y_cm"]));
    assert!(off <= (0.1 * moved).max(6.0), "final position {a} vs {b}");
    let (n, m) = (run.samples.len() as f64, reference.samples.len() as f64);
    assert!((n - m).abs() <= 0.2 * m + 2.0, "samples: {n} vs {m}");
    let (last, last_ref) = (
        &run.samples[run.samples.len() - 1],
        &reference.samples[reference.samples.len() - 1],
    );
    assert_eq!(last["heading"], last_ref["heading"], "{last} vs {last_ref}");
    assert_eq!(last["stance"], last_ref["stance"], "{last} vs {last_ref}");
}
