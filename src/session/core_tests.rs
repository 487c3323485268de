//! The session's timing rules on plain time values: no runtime, no link, no clock. Each test
//! drives a [`SessionCore`] with made-up instants and reads what it would write.

use super::*;
use crate::protocol::v2::wire::DriveFlags;
use crate::protocol::v2::{Decoder, ErrorCode, Packet as V2, cmd};
use crate::units::Heading;

const PACE: Duration = Duration::from_millis(120);
const TIMEOUT: Duration = Duration::from_secs(2);

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

fn drive(speed: u8) -> Command {
    cmd::drive_with_heading(speed, Heading::new(90).unwrap(), DriveFlags::empty()).into()
}

fn volume(v: u8) -> Command {
    cmd::set_audio_volume(v).into()
}

/// A core connected at the returned instant.
fn connected(cfg: SessionConfig) -> (SessionCore, Instant) {
    let t = Instant::now();
    let mut core = SessionCore::new(cfg, t);
    core.handle_connected(t, None, false);
    (core, t)
}

/// The one packet in a write.
fn packet(t: &Transmit) -> V2 {
    let mut found = Decoder::new().decode_all(&t.bytes);
    assert_eq!(found.len(), 1, "{t:?}");
    found.remove(0).unwrap()
}

/// The next write due at `now`, reported written at `now`.
fn write(core: &mut SessionCore, now: Instant) -> Option<Transmit> {
    let t = core.poll_transmit(now)?;
    core.handle_written(now);
    Some(t)
}

/// The next whole packet, one write per pacing slot from `now` on; and when it ended.
fn next_packet(core: &mut SessionCore, mut now: Instant) -> (V2, Instant) {
    let mut decoder = Decoder::new();
    loop {
        let t = write(core, now).expect("a write is due");
        if let Some(p) = decoder.decode_all(&t.bytes).pop() {
            return (p.unwrap(), now);
        }
        now += PACE;
    }
}

fn respond(core: &mut SessionCore, request: &V2, now: Instant) {
    core.handle_bytes(
        &V2::response_to(request, ErrorCode::Success, vec![]).encode(),
        now,
    );
}

#[test]
fn the_urgent_stop_goes_ahead_of_pacing_and_of_queued_commands() {
    let (mut core, t) = connected(SessionConfig::default());
    for v in 1..=3 {
        core.handle_request(volume(v), false).unwrap();
    }
    core.handle_write(Slot::Drive, drive(50));
    let first = packet(&write(&mut core, t).unwrap());
    assert_eq!(first.data[0], 50);
    // Pacing holds the next write back...
    assert!(core.poll_transmit(t + ms(10)).is_none());
    assert_eq!(core.poll_timeout(), Some(t + PACE));
    // ...but not the emergency stop, which also passes the three waiting volumes.
    core.emergency_stop(drive(0));
    let stop = write(&mut core, t + ms(10)).unwrap();
    assert!(stop.urgent);
    assert_eq!(packet(&stop).data[0], 0);
    assert!(core.poll_transmit(t + ms(10)).is_none());
    // One pacing slot after the stop, the stop again (through the drive slot), then the rest.
    assert!(core.poll_transmit(t + ms(10) + PACE - ms(1)).is_none());
    let again = write(&mut core, t + ms(10) + PACE).unwrap();
    assert!(!again.urgent);
    assert_eq!(packet(&again).data[0], 0);
    let mut now = t + ms(10) + PACE;
    let mut volumes = Vec::new();
    while core.queued() > 0 {
        now += PACE;
        volumes.push(packet(&write(&mut core, now).unwrap()).data[0]);
    }
    assert_eq!(volumes, [1, 2, 3]);
}

#[test]
fn the_urgent_stop_finishes_the_packet_it_cuts_in_on() {
    let (mut core, t) = connected(SessionConfig {
        chunk_size: 4,
        ..SessionConfig::default()
    });
    core.handle_request(volume(7), false).unwrap();
    let half = write(&mut core, t).unwrap();
    assert_eq!(half.bytes.len(), 4);
    core.emergency_stop(drive(0));
    let mut wire = half.bytes;
    let now = t + ms(1);
    while let Some(w) = core.poll_transmit(now) {
        assert!(w.urgent);
        wire.extend(w.bytes);
        core.handle_written(now);
    }
    // Whole framing: the volume, then the stop, and nothing broken between them.
    let found: Vec<V2> = Decoder::new()
        .decode_all(&wire)
        .into_iter()
        .map(|p| p.unwrap())
        .collect();
    assert_eq!(found.len(), 2);
    assert_eq!(found[0].data, [7]);
    assert_eq!(found[1].data[0], 0);
}

#[test]
fn the_urgent_stop_waits_for_a_connection_and_then_goes_first() {
    let t = Instant::now();
    let mut core = SessionCore::new(
        SessionConfig {
            setup: vec![cmd::wake().into(), cmd::ping().into()],
            ..SessionConfig::default()
        },
        t,
    );
    core.emergency_stop(drive(0));
    assert!(core.poll_transmit(t).is_none());
    assert_eq!(core.poll_timeout(), None);
    core.handle_connected(t + ms(500), None, false);
    let stop = write(&mut core, t + ms(500)).unwrap();
    assert!(stop.urgent);
    assert_eq!(packet(&stop).data[0], 0);
    // Then the setup, its wake first.
    let (wake, _) = next_packet(&mut core, t + ms(500) + PACE);
    assert_eq!(wake.cid, cmd::wake().cid);
}

#[test]
fn a_slot_keeps_only_its_latest_value() {
    let (mut core, t) = connected(SessionConfig::default());
    for s in 1..=100 {
        core.handle_write(Slot::Drive, drive(s));
    }
    assert_eq!(core.queued(), 1);
    assert_eq!(core.stats().coalesced, 99);
    assert_eq!(packet(&write(&mut core, t).unwrap()).data[0], 100);
    assert!(core.poll_transmit(t + PACE).is_none());
    // A drive supersedes a request's drive still waiting, and its waiter is told.
    let waiter = core.handle_request(drive(30), true).unwrap().unwrap();
    core.handle_write(Slot::Drive, drive(0));
    assert_eq!(
        core.poll_answer(),
        Some((waiter, Err(RequestError::Superseded)))
    );
}

#[test]
fn sequence_numbers_count_up_and_skip_one_still_pending() {
    let (mut core, t) = connected(SessionConfig {
        queue_capacity: 8,
        ..SessionConfig::default()
    });
    // Request 0 stays unanswered; 1..=254 are answered.
    core.handle_request(volume(0), false).unwrap();
    let (first, mut now) = next_packet(&mut core, t);
    assert_eq!(first.seq, 0);
    for want in 1..=254u8 {
        core.handle_request(volume(1), false).unwrap();
        now += PACE;
        let (p, at) = next_packet(&mut core, now);
        assert_eq!(p.seq, want);
        respond(&mut core, &p, at);
    }
    // The count wraps to 0, whose key is still waiting for an answer: 1 instead.
    core.handle_request(volume(2), false).unwrap();
    let (p, _) = next_packet(&mut core, now + PACE);
    assert_eq!(p.seq, 1);
    assert_eq!(core.stats().answered, 254);
}

#[test]
fn an_answer_goes_to_its_waiter() {
    let (mut core, t) = connected(SessionConfig::default());
    let waiter = core.handle_request(volume(3), true).unwrap().unwrap();
    let (p, at) = next_packet(&mut core, t);
    respond(&mut core, &p, at + ms(30));
    let (who, answer) = core.poll_answer().unwrap();
    assert_eq!(who, waiter);
    assert!(answer.is_ok());
    assert_eq!(core.poll_timeout(), None);
}

#[test]
fn an_unanswered_request_expires_at_its_deadline() {
    let (mut core, t) = connected(SessionConfig::default());
    let waiter = core.handle_request(volume(3), true).unwrap().unwrap();
    next_packet(&mut core, t);
    assert_eq!(core.poll_timeout(), Some(t + TIMEOUT));
    core.handle_timeout(t + TIMEOUT - ms(1));
    assert_eq!(core.poll_answer(), None);
    core.handle_timeout(t + TIMEOUT);
    assert_eq!(
        core.poll_answer(),
        Some((waiter, Err(RequestError::Timeout)))
    );
    assert_eq!(core.stats().timeouts, 1);
    // Nothing is left to wait for.
    assert_eq!(core.poll_timeout(), None);
}

#[test]
fn setup_commands_are_retried_twice_then_given_up() {
    let (mut core, t) = connected(SessionConfig {
        setup: vec![cmd::ping().into()],
        ..SessionConfig::default()
    });
    let mut now = t;
    let mut pings = 0;
    loop {
        let (p, at) = next_packet(&mut core, now);
        assert_eq!(p.cid, cmd::ping().cid);
        pings += 1;
        let deadline = core.poll_timeout().unwrap();
        assert_eq!(deadline, at + TIMEOUT);
        core.handle_timeout(deadline);
        now = deadline;
        if core.queued() == 0 {
            break;
        }
    }
    assert_eq!(pings, 3);
    assert_eq!(core.stats().retried, 2);
    assert_eq!(core.stats().timeouts, 3);
}

#[test]
fn the_link_lost_fails_every_waiter() {
    let (mut core, t) = connected(SessionConfig::default());
    let written = core.handle_request(volume(1), true).unwrap().unwrap();
    next_packet(&mut core, t);
    let queued = core.handle_request(volume(2), true).unwrap().unwrap();
    core.handle_link_lost();
    let answers: Vec<_> = std::iter::from_fn(|| core.poll_answer()).collect();
    assert_eq!(answers.len(), 2);
    assert!(answers.contains(&(written, Err(RequestError::LinkLost))));
    assert!(answers.contains(&(queued, Err(RequestError::LinkLost))));
    assert_eq!(core.stats().link_lost, 2);
    assert!(core.poll_transmit(t + PACE).is_none());
    core.close();
    assert_eq!(
        core.handle_request(volume(3), true),
        Err(RequestError::Closed)
    );
}

#[test]
fn a_quiet_link_gets_a_keepalive_in_time() {
    let t = Instant::now();
    let mut core = SessionCore::new(SessionConfig::default(), t);
    let every = Duration::from_secs(5);
    core.handle_connected(t, Some(every), false);
    assert_eq!(core.poll_timeout(), Some(t + every));
    core.handle_timeout(t + every - ms(1));
    assert_eq!(core.queued(), 0);
    core.handle_timeout(t + every);
    let (p, at) = next_packet(&mut core, t + every);
    respond(&mut core, &p, at);
    // Quiet time counts from the last write.
    assert_eq!(core.poll_timeout(), Some(at + every));
    // While there is work, the next deadline is the next paced write, not the keep-alive.
    core.handle_request(volume(1), false).unwrap();
    assert_eq!(core.poll_timeout(), Some(at + PACE));
}

#[test]
fn a_long_packet_goes_in_chunks_one_pacing_slot_apart() {
    let (mut core, t) = connected(SessionConfig {
        chunk_size: 3,
        ..SessionConfig::default()
    });
    core.handle_request(volume(9), false).unwrap();
    let mut wire = Vec::new();
    let mut writes = Vec::new();
    let mut now = t;
    while let Some(w) = write(&mut core, now) {
        assert!(w.bytes.len() <= 3);
        writes.push(now);
        wire.extend(w.bytes);
        assert!(core.poll_transmit(now + PACE - ms(1)).is_none());
        now += PACE;
    }
    let chunks = wire.len().div_ceil(3);
    assert_eq!(writes.len(), chunks);
    let found = Decoder::new().decode_all(&wire);
    assert_eq!(found.len(), 1);
    assert_eq!(found[0].as_ref().unwrap().data, [9]);
    // The response's deadline counts from the first chunk, plus the time the rest took.
    let extra = PACE * (chunks as u32 - 1);
    assert_eq!(core.poll_timeout(), Some(t + TIMEOUT + extra));
}

/// A Sphero Edu `spin` makes its next step once its last one is answered (src/edu/run/paced.rs):
/// a marked drive awaits while queued and while written but unanswered, and no longer once
/// the droid answers it; a marked request the same.
#[test]
fn a_marked_command_awaits_until_it_is_written_and_answered() {
    let (mut core, t) = connected(SessionConfig::default());
    let drive_mark = core
        .handle_write_marked(Slot::Drive, drive(50), true)
        .unwrap();
    assert!(core.awaits(drive_mark));
    let (written, at) = next_packet(&mut core, t);
    assert!(!core.holds(drive_mark) && core.awaits(drive_mark));
    respond(&mut core, &written, at + ms(5));
    assert!(!core.awaits(drive_mark));
    let (_, volume_mark) = core.handle_request_marked(volume(3), false, None).unwrap();
    let (written, at) = next_packet(&mut core, at + PACE);
    assert!(core.awaits(volume_mark));
    respond(&mut core, &written, at);
    assert!(!core.awaits(volume_mark));
}
