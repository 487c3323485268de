//! The session's I/O-free core (`src/session/core.rs`) under any sequence of events and
//! times: a droid's bytes, requests, slot writes, emergency stops, links up and down,
//! deadlines, in any order and at any instants. It must never panic; an emergency stop made
//! while connected is always the next write, urgent; no write is longer than the chunk size;
//! every request a caller waits for is answered exactly once by the time the session closes
//! (by the droid, a timeout, a lost link, a newer drive or the close).
//!
//! Input layout: the first byte picks the family (low 2 bits), the chunk size (next 3 bits,
//! 1 to 8 bytes, small so packets are cut) and the pacing (high 3 bits, 0 to 140 ms); the
//! rest is a list of operations, one byte each with its operands after it.

use super::Target;
use crate::family::Command;
use crate::model::Protocol;
use crate::session::SessionConfig;
use crate::session::core::SessionCore;
use crate::session::queue::{Reply, Slot};
use crate::units::Heading;
use std::collections::HashSet;
use std::time::{Duration, Instant};

pub const TARGET: Target = Target {
    name: "session_core",
    run: run_input,
    dictionary: &[
        &[0x8D, 0x09, 0x13, 0x00, 0x00, 0xD8],
        &[0xFF, 0xFF, 0x00, 0x00, 0x01, 0x01, 0xFD],
        &[0xFF, 0xFE],
        &[0x04, 0x04, 0x04],
        &[0x08, 0xFF],
        &[0x09, 0x09],
    ],
};

/// What one operation does, by its byte's value modulo the count.
const OPS: u8 = 12;

pub fn run_input(data: &[u8]) {
    let Some((&head, mut ops)) = data.split_first() else {
        return;
    };
    let family_of = [Protocol::SpheroV2, Protocol::SpheroV1, Protocol::Rsrcp];
    let protocol = family_of[(head & 0x03) as usize % family_of.len()];
    let chunk_size = ((head >> 2) & 0x07) as usize + 1;
    let pacing = Duration::from_millis(20 * u64::from(head >> 5));
    let family = crate::family::for_protocol(protocol);
    let cfg = SessionConfig {
        family: protocol,
        chunk_size,
        pacing,
        queue_capacity: 8,
        setup: family.wake().into_iter().collect(),
        ..SessionConfig::default()
    };
    let start = Instant::now();
    let mut now = start;
    let mut core = SessionCore::new(cfg, start);
    let mut issued: HashSet<Reply> = HashSet::new();
    let mut answered: HashSet<Reply> = HashSet::new();
    let mut connected = false;
    let take = |ops: &mut &[u8]| -> u8 {
        let (&b, rest) = ops.split_first().unwrap_or((&0, &[]));
        *ops = rest;
        b
    };
    while !ops.is_empty() {
        let op = take(&mut ops);
        let arg = take(&mut ops);
        match op % OPS {
            0 => now += Duration::from_millis(u64::from(arg) * 5),
            1 | 2 => {
                let cmd = command(family, arg);
                if let Ok(Some(id)) = core.handle_request(cmd, op % OPS == 1) {
                    assert!(issued.insert(id), "a reply id given twice");
                }
            }
            3 => core.handle_write(
                Slot::Drive,
                family.drive(arg, Heading::new(u16::from(arg)).unwrap_or_default(), false),
            ),
            4 => core.handle_write(Slot::Head, family.ping()),
            5 => {
                core.emergency_stop(family.stop_after(core.last_drive()));
                if connected {
                    let t = core.poll_transmit(now);
                    assert!(
                        t.as_ref().is_some_and(|t| t.urgent),
                        "an emergency stop was not the next write: {t:?}"
                    );
                    core.handle_written(now);
                }
            }
            6 => {
                let n = (arg as usize).min(ops.len());
                let (bytes, rest) = ops.split_at(n);
                core.handle_bytes(bytes, now);
                ops = rest;
            }
            7 => core.handle_timeout(now),
            8 => {
                while let Some(t) = core.poll_transmit(now) {
                    assert!(t.bytes.len() <= chunk_size, "a write longer than a chunk");
                    core.handle_written(now);
                    if !t.urgent {
                        break;
                    }
                }
            }
            9 if connected => {
                core.handle_link_lost();
                connected = false;
            }
            9 => {
                core.handle_connected(now, (arg & 1 == 1).then_some(Duration::from_secs(1)), true);
                connected = true;
            }
            10 => match arg % 3 {
                0 => core.redo_setup(),
                1 => core.set_setup(vec![command(family, arg)]),
                _ => core.log_wanted = !core.log_wanted,
            },
            _ => {
                if let Some(at) = core.poll_timeout() {
                    now = now.max(at);
                    core.handle_timeout(now);
                }
            }
        }
        drain(&mut core, &issued, &mut answered);
    }
    let _ = core.finish(vec![family.ping()], now);
    core.close();
    drain(&mut core, &issued, &mut answered);
    assert_eq!(issued, answered, "a waited request never answered");
}

/// A command of the family: a ping, the wake, a stop or a drive.
fn command(family: &dyn crate::family::Family, arg: u8) -> Command {
    match arg % 4 {
        0 => family.ping(),
        1 => family.wake().unwrap_or_else(|| family.ping()),
        2 => family.stop_after(None),
        _ => family.drive(arg, Heading::default(), false),
    }
}

/// Take everything the core has put out, checking each answer goes to a waiter once.
fn drain(core: &mut SessionCore, issued: &HashSet<Reply>, answered: &mut HashSet<Reply>) {
    while let Some((id, _)) = core.poll_answer() {
        assert!(issued.contains(&id), "an answer for no request");
        assert!(answered.insert(id), "a request answered twice");
    }
    while core.poll_event().is_some() {}
    while core.poll_log().is_some() {}
}

#[cfg(test)]
mod tests {
    use super::super::runner;
    use super::*;

    /// The seed corpus and a few thousand inputs the stable mutator makes of it, as
    /// `tests/fuzz_smoke.rs` runs the other targets (libFuzzer goes much further).
    #[test]
    fn random_events_and_times_keep_the_rules() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/session_core");
        let corpus = runner::load_corpus(&dir);
        assert!(
            !corpus.is_empty(),
            "fuzz/corpus/session_core holds no seeds"
        );
        let failures = std::env::temp_dir().join("droidctl-fuzz-failures");
        let stats = runner::run(
            &TARGET,
            &corpus,
            runner::Budget::Inputs(4000),
            0x5EED,
            &failures,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(stats.generated, 4000);
    }
}
