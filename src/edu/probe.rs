//! A program run for its calls alone, and the bounds every call's effect keeps: what the
//! tests of hostile programs (src/edu/hostile.rs, the sans-IO sweep in api_tests.rs) and the
//! fuzz target `edu` (src/fuzzing/edu.rs) share. No droid: each promise is resolved at once.

use super::api::{Act, MAX_SECONDS, MAX_STROBES, MAX_TEXT, Matrix, STEP, Wait};
use super::engine::{Failure, FromJs, Op, Readings, Status, ToJs};
use super::host::Calls;
use crate::model::Model;
use std::sync::mpsc;
use std::time::Duration;

/// Run `source` on `model`, each promise resolved at once, for at most `turns` turns: every
/// call it made, and where it stands. `Err`: the engine died or hung.
///
/// The engine's own loop ([`super::engine::js_thread`], what the engine's child process
/// runs) on a thread of this process, its calls played through droidctl's side
/// ([`Calls`]) as a run plays them: everything but the pipe, so the tests and the fuzz
/// target need no droidctl executable.
pub async fn run(source: &str, model: Model, turns: usize) -> Result<(Vec<Op>, Status), Failure> {
    let gone = |message: &str| Failure {
        line: None,
        message: message.to_string(),
    };
    let (tx, to_js) = mpsc::channel::<ToJs>();
    let (reply, from_js) = mpsc::channel::<FromJs>();
    let source = source.to_string();
    std::thread::Builder::new()
        .name("edu-probe".into())
        .stack_size(64 << 20)
        .spawn(move || super::engine::js_thread(source, "probe.js".into(), model, to_js, reply))
        .map_err(|e| gone(&format!("cannot start the engine: {e}")))?;
    let mut calls = Calls::new(model);
    let mut fired: Vec<u64> = Vec::new();
    let mut all = Vec::new();
    let mut from_js = Some(from_js);
    for _ in 0..turns {
        calls.fired(&fired);
        tx.send(ToJs::Turn {
            fired: std::mem::take(&mut fired),
            events: Vec::new(),
            readings: Readings::default(),
        })
        .map_err(|_| gone("the engine stopped"))?;
        let rx = from_js.take().ok_or_else(|| gone("the engine stopped"))?;
        let (rx, got) = tokio::task::spawn_blocking(move || {
            let got = rx.recv_timeout(Duration::from_secs(30));
            (rx, got)
        })
        .await
        .map_err(|_| gone("the engine stopped"))?;
        from_js = Some(rx);
        let FromJs::Done(out) = got.map_err(|_| gone("the engine stopped or hung"))?;
        let ops = calls.play(out.calls)?;
        fired = ops.iter().filter_map(|o| o.promise).collect();
        all.extend(ops);
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
