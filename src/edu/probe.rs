//! A program run for its calls alone, and the bounds every call's effect keeps: what the
//! tests of hostile programs (src/edu/hostile.rs, the sans-IO sweep in api_tests.rs) and the
//! fuzz target `edu` (src/fuzzing/edu.rs) share. No droid: each promise is resolved at once.

use super::api::{Act, MAX_SECONDS, MAX_STROBES, MAX_TEXT, Matrix, STEP, Wait};
use super::engine::{Engine, Failure, Op, Readings, Status};
use crate::model::Model;
use std::time::Duration;

/// Run `source` on `model`, each promise resolved at once, for at most `turns` turns: every
/// call it made, and where it stands. `Err`: the engine died or hung.
pub async fn run(source: &str, model: Model, turns: usize) -> Result<(Vec<Op>, Status), Failure> {
    let mut engine =
        Engine::start(source.to_string(), "probe.js".into(), model).map_err(|message| Failure {
            line: None,
            message,
        })?;
    let mut fired = Vec::new();
    let mut all = Vec::new();
    for _ in 0..turns {
        let out = engine
            .turn(
                std::mem::take(&mut fired),
                Vec::new(),
                Readings::default(),
                Duration::from_secs(30),
            )
            .await?;
        fired = out.ops.iter().filter_map(|o| o.promise).collect();
        all.extend(out.ops);
        if out.status != Status::Running || fired.is_empty() {
            return Ok((all, out.status));
        }
    }
    Ok((all, Status::Running))
}

/// A call's effect is within droidctl's bounds.
pub fn check_effect(what: &str, now: &[Act], wait: Option<&Wait>) {
    match wait {
        Some(Wait::Timeline(t)) => {
            assert!(t.end.as_secs_f64() <= MAX_SECONDS, "{what}: {t:?}");
            let len = t.len();
            assert!(len as f64 <= 2.0 * MAX_STROBES.max(MAX_SECONDS / STEP.as_secs_f64()));
            for i in [0, len / 2, len.saturating_sub(1)] {
                if i < len {
                    assert!(t.at(i) <= t.end, "{what}: step {i} past the end: {t:?}");
                    check_effect(what, &t.acts(i), None);
                }
            }
        }
        Some(Wait::Distance { cm, then }) => {
            assert!(cm.is_finite() && *cm >= 0.0, "{what}: {cm}");
            check_effect(what, then, None);
        }
        Some(Wait::Stance | Wait::Compass) | None => {}
    }
    for a in now {
        match a {
            Act::Matrix(Matrix::Text { text, fps, .. }) => {
                assert!((1..=30).contains(fps) && text.len() <= 25, "{what}: {a:?}");
            }
            Act::Dome(d) => assert!(d.is_finite(), "{what}: {a:?}"),
            Act::Say(t) | Act::Sound(t) => assert!(t.len() <= MAX_TEXT, "{what}: {t:?}"),
            Act::Drive { heading, .. } => assert!(*heading < 360, "{what}: {a:?}"),
            _ => {}
        }
    }
}
