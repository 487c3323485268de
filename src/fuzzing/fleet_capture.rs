//! The reader of captures of several droids (version 2) and its split into one capture per
//! droid (issue 27 point 3): any bytes give the droids' captures or one error, never a
//! panic, and never more than the file holds. Nothing is copied per droid (the events of all
//! droids together are at most the file's lines); warnings stay summarised (a few kept, the
//! rest counted) for the file and for each droid; chunks are bounded; each droid's events are
//! in time order. The streaming reader line by line and the whole-file reader agree, and
//! each droid's capture replays as one droid's does ([`super::capture::check_replay`]).
//!
//! Input layout: the first byte: bit 0 set puts the version-2 magic line and a header of
//! as many droids as the second byte says (mod 70: some past the limit) in front; the first
//! byte is also the model pick of the replay check; the third and fourth the interval (ms);
//! the rest is the file.

use super::{Bytes, Target};
use crate::capture::fleet::{self, FleetLine, FleetReader};
use crate::capture::{Event, KEPT_WARNINGS, MAX_CHUNK};

pub const TARGET: Target = Target {
    name: "fleet_capture",
    run: run_input,
    dictionary: &[
        b"droidctl-capture 2\n",
        b"# droids: 2\n",
        b"# droid-1: r2d2 v2 D2-0001\n",
        b"# droid-2: bb8 v1 BB-0002\n",
        b"# droid-3: robi42 rsrcp Robi 42\n",
        b"# droid-64: r2d2 v2 X\n",
        b"# started: 2025-06-01T10:00:00.123Z\n",
        b"@1 ",
        b"@2 ",
        b"@99 ",
        b"@0 ",
        b"0.000 connect\n",
        b" in notify ",
        b" out api ",
        b" mark mission-start\n",
        b" mark step 2 drive 80 0 for 2s\n",
        b" end\n",
        b"8d0a130d00d5d8",
        b"8d8d8d8d8d8d8d8d",
    ],
};

pub fn run_input(data: &[u8]) {
    let mut b = Bytes::new(data);
    let pick = b.u8();
    let listed = b.u8() as usize % 70;
    let interval_ms = b.u16();
    let body = b.rest();
    let mut file = Vec::with_capacity(body.len() + 64 * listed);
    if pick & 1 == 1 {
        file.extend_from_slice(b"droidctl-capture 2\n");
        for k in 1..=listed {
            file.extend_from_slice(format!("# droid-{k}: r2d2 v2 D2-{k:04}\n").as_bytes());
        }
    }
    file.extend_from_slice(body);
    let text = String::from_utf8_lossy(&file);
    let lines = text.split_inclusive('\n').count();
    let split = match fleet::read(&text) {
        Ok(s) => s,
        Err(e) => {
            assert!(!e.is_empty());
            return;
        }
    };
    assert!(split.droids.len() <= fleet::MAX_DROIDS);
    assert!(
        split.warnings.len() <= KEPT_WARNINGS + 1,
        "{:?}",
        split.warnings
    );
    let events: usize = split.droids.iter().map(|c| c.events.len()).sum();
    let shared = fleet::MAX_SHARED * split.droids.len();
    assert!(
        events <= lines + shared,
        "{events} events from {lines} lines"
    );
    for c in &split.droids {
        // Kept and counted, plus the header's problems and the missing `end`.
        assert!(c.warnings.len() <= KEPT_WARNINGS + 8, "{:?}", c.warnings);
        assert!(c.events.windows(2).all(|w| w[0].at <= w[1].at));
        for t in &c.events {
            if let Event::In(v) | Event::Out(_, v) = &t.event {
                assert!(v.len() <= MAX_CHUNK, "a chunk of {} bytes", v.len());
            }
        }
    }
    // Line by line, the streaming reader sees the same events.
    let mut r = FleetReader::new();
    let mut per_droid = vec![0usize; split.droids.len()];
    for line in text.split_inclusive('\n') {
        if let Ok(FleetLine::Event(i, _)) = r.line(line.trim_end_matches(['\r', '\n'])) {
            per_droid[i] += 1;
        }
    }
    for (own, c) in per_droid.iter().zip(&split.droids) {
        assert!(*own <= c.events.len() && c.events.len() <= own + fleet::MAX_SHARED);
    }
    // Each droid replays as one droid's capture (a few of them: each costs its samples).
    for c in split.droids.iter().take(3) {
        super::capture::check_replay(c, pick >> 1, interval_ms);
    }
}
