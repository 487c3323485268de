//! The droidctl capture text format and replay: any bytes read as a capture (as `droidctl
//! replay FILE` reads them) give a capture or one error, never a panic. A capture read
//! writes back as text that reads to the same capture (the writer's output is a fixed
//! point), and replays: `replay --json`'s sampling makes its samples in time order, a
//! number bounded by the events (silences are jumped over, never sampled every interval),
//! and ends with the summary's time; the app's replay steps through every event and ends.
//!
//! Input layout: the first byte picks the model (`--model`, or the capture's) and the second
//! and third the sample interval (`--interval`, ms); the rest is the file.

use super::{Bytes, Target};
use crate::capture::replay::{MAX_GAP, Replay, samples};
use crate::capture::{Capture, Event};
use crate::model::Model;
use std::time::Duration;

pub const TARGET: Target = Target {
    name: "capture",
    run: run_input,
    dictionary: &[
        b"droidctl-capture 1\n",
        b"# model: ",
        b"# family: ",
        b"r2d2",
        b"robi42",
        b"bb8",
        b"rsrcp",
        b" connect\n",
        b" out api ",
        b" out velocity ",
        b" in notify ",
        b" mark mission-start\n",
        b" mark mission-end\n",
        b" mark step 3 drive 80 90 for 2s\n",
        b" mark step 4 wait 1e20s\n",
        b" disconnect ",
        b" close\n",
        b" end\n",
        b"599999.999",
        b"600001.000",
        b"604800000.000",
        b"8d0a130d00d5d8",
    ],
};

/// `--model` as the harness's first byte picks it (or none: the capture's).
fn model_arg(pick: u8) -> Option<&'static str> {
    match pick % 5 {
        0 | 1 => None,
        2 => Some("r2d2"),
        3 => Some("bb8"),
        _ => Some("robi42"),
    }
}

pub fn run_input(data: &[u8]) {
    let mut b = Bytes::new(data);
    let pick = b.u8();
    let interval_ms = b.u16();
    let file = b.rest();
    match Capture::from_bytes(file, &[], "the input") {
        Ok(c) => {
            round_trip(&c);
            check_replay(&c, pick, interval_ms);
        }
        Err(e) => assert!(!e.is_empty()),
    }
}

/// What droidctl writes reads back to the same capture (the writer keeps every value on one
/// line: a carriage return read inside a value is written as a space, so what it writes is a
/// fixed point rather than the text read).
fn round_trip(c: &Capture) {
    let text = c.to_text();
    let again = Capture::from_text(&text)
        .unwrap_or_else(|e| panic!("a capture as written does not read: {e}\n{text}"));
    assert_eq!(again.events.len(), c.events.len(), "{text}");
    for (a, b) in again.events.iter().zip(&c.events) {
        assert_eq!(a.at, b.at, "{text}");
    }
    assert_eq!(again.to_text(), text);
}

/// How many samples `samples` may make of `c` at `interval`: every interval from the start,
/// but never more than a silence's worth (`MAX_GAP`) around each event.
fn sample_bound(c: &Capture, interval: Duration) -> u128 {
    let span = c.duration().as_nanos();
    let per_gap = MAX_GAP.as_nanos() / interval.as_nanos() + 2;
    let by_span = span / interval.as_nanos() + 2;
    by_span.min((c.events.len() as u128 + 1) * per_gap + 1)
}

/// Replay a capture as `replay --json` and the app do (btsnoop logs come here too).
pub fn check_replay(c: &Capture, pick: u8, interval_ms: u16) {
    // The checks `replay` makes before it plays (a damaged span, a step mark that does not
    // parse, the wrong model) are messages.
    let model: Model = match crate::cli::replay::checked_model(c, model_arg(pick), "the input") {
        Ok(m) => m,
        Err(e) => {
            assert!(!e.message.is_empty());
            return;
        }
    };
    // Each input costs at most about 300,000 samples: a long capture at a short interval is
    // sampled at a longer one.
    let mut interval = Duration::from_millis(interval_ms.max(1) as u64);
    let bound = sample_bound(c, interval);
    if bound > 300_000 {
        interval *= (bound / 300_000 + 1).min(u32::MAX as u128) as u32;
    }
    let bound = sample_bound(c, interval);
    let mut count = 0u128;
    let mut last = 0u64;
    let mut gaps = 0u64;
    let summary = samples(
        c,
        model,
        interval,
        &mut |s| {
            assert!(s.t_ms >= last, "sample at {} ms after {last} ms", s.t_ms);
            last = s.t_ms;
            count += 1;
            assert!(count <= bound, "more than {bound} samples at {interval:?}");
            Ok(())
        },
        &mut |from, to| {
            assert!(to > from, "a gap from {from:?} to {to:?}");
            gaps += 1;
        },
    )
    .expect("sampling into memory cannot fail");
    assert!(count >= 1, "the final sample is always made");
    assert_eq!(
        summary.t_ms, last,
        "the summary's time is the last sample's"
    );
    let traffic = c
        .events
        .iter()
        .filter(|t| matches!(t.event, Event::Out(..) | Event::In(_)))
        .map(|t| match &t.event {
            Event::Out(_, b) | Event::In(b) => b.len() as u64,
            _ => 0,
        })
        .sum::<u64>();
    assert!(summary.sent + summary.received <= traffic, "{summary:?}");
    assert!(gaps <= c.events.len() as u64 + 1);

    // The app's replay: step by step to the end, then all at once after a rewind.
    let mut r = Replay::new(c.clone(), model);
    let mut out = Vec::new();
    let mut steps = 0;
    while r.step(&mut out) {
        steps += 1;
        assert!(steps <= c.events.len(), "a step applies at least one event");
    }
    assert!(r.at_end());
    assert_eq!(r.position(), r.duration());
    let stepped = out.len();
    out.clear();
    r.rewind();
    r.advance_to(Duration::MAX, &mut out);
    assert!(r.at_end());
    assert_eq!(
        out.len(),
        stepped,
        "stepping and playing through give the same outputs"
    );
}
