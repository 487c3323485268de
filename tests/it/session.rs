//! Session behaviour (issue 3) against a scripted fake link, all under paused tokio time.
//!
//! The fake records every write with its `tokio::time::Instant`, decodes what the session
//! wrote into packets, lets the test inject arbitrary bytes in any order, scripts the outcome
//! of each `open()`, and can answer requests by itself.

use droidctl::link::backoff::Backoff;
use droidctl::link::{Connection, Link, LinkError, LinkEvent, LinkWriter};
use droidctl::protocol::v2::wire::{AudioMode, Bytes, DriveFlags, LegAction, Mask};
use droidctl::protocol::v2::{
    Command, Decoder, ErrorCode, ErrorKind, Flags, Notification, Packet, cmd,
};
use droidctl::session::{
    self, Direction, LinkState, LogItem, RequestError, SessionConfig, SessionEvent, SessionHandle,
    Slot,
};
use droidctl::units::{HeadAngle, Heading};
use futures_util::future::BoxFuture;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::{mpsc, watch};
use tokio::time::{Instant, sleep, timeout};

// ---------------------------------------------------------------------------------------------
// The fake link
// ---------------------------------------------------------------------------------------------

/// One chunk the session wrote.
#[derive(Debug, Clone)]
struct Write {
    at: Instant,
    bytes: Vec<u8>,
}

/// One complete packet the session wrote (decoded from the chunks).
#[derive(Debug, Clone)]
struct Sent {
    /// When its last chunk was written.
    at: Instant,
    conn: u32,
    packet: Packet,
}

#[derive(Default)]
struct FakeState {
    opens: Vec<Instant>,
    /// Outcome of the next `open()` calls; empty means success.
    open_script: VecDeque<Result<(), LinkError>>,
    conn: u32,
    events: Option<mpsc::Sender<LinkEvent>>,
    decoder: Decoder,
    writes: Vec<Write>,
    sent: Vec<Sent>,
    closes: Vec<(Instant, u32)>,
    /// Answer every request that asks for a response, with success and no data.
    auto_respond: bool,
    /// What the link says of its quiet time ([`Link::keepalive`]).
    keepalive: Option<Duration>,
}

#[derive(Clone)]
struct Fake {
    st: Arc<Mutex<FakeState>>,
    /// Number of packets written so far.
    count: Arc<watch::Sender<usize>>,
}

struct FakeLink(Fake);

struct FakeWriter {
    fake: Fake,
    conn: u32,
}

impl Fake {
    fn new() -> Self {
        Fake {
            st: Arc::new(Mutex::new(FakeState::default())),
            count: Arc::new(watch::channel(0).0),
        }
    }

    fn link(&self) -> Box<dyn Link> {
        Box::new(FakeLink(self.clone()))
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, FakeState> {
        self.st.lock().unwrap()
    }

    fn auto_respond(&self, on: bool) {
        self.lock().auto_respond = on;
    }

    fn script_opens(&self, outcomes: Vec<Result<(), LinkError>>) {
        self.lock().open_script.extend(outcomes);
    }

    /// Bytes from the droid, on the current connection.
    fn inject(&self, bytes: Vec<u8>) {
        let tx = self.lock().events.clone().expect("not connected");
        tx.try_send(LinkEvent::Data(bytes))
            .expect("event channel full");
    }

    fn respond(&self, request: &Packet, err: ErrorCode, data: Vec<u8>) {
        self.inject(Packet::response_to(request, err, data).encode());
    }

    fn disconnect(&self, reason: &str) {
        let tx = self.lock().events.take().expect("not connected");
        tx.try_send(LinkEvent::Disconnected(reason.into())).unwrap();
    }

    fn sent(&self) -> Vec<Sent> {
        self.lock().sent.clone()
    }

    fn packets(&self) -> Vec<Packet> {
        self.lock().sent.iter().map(|s| s.packet.clone()).collect()
    }

    fn writes(&self) -> Vec<Write> {
        self.lock().writes.clone()
    }

    fn opens(&self) -> Vec<Instant> {
        self.lock().opens.clone()
    }

    /// Wait until at least `n` packets have been written in total.
    async fn wait_packets(&self, n: usize) -> Vec<Packet> {
        let mut rx = self.count.subscribe();
        rx.wait_for(|c| *c >= n).await.unwrap();
        self.packets()
    }
}

impl Link for FakeLink {
    fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
        Box::pin(async move {
            let mut st = self.0.lock();
            st.opens.push(Instant::now());
            if let Some(Err(e)) = st.open_script.pop_front() {
                return Err(e);
            }
            st.conn += 1;
            st.decoder = Decoder::new();
            let (tx, rx) = mpsc::channel(4096);
            st.events = Some(tx);
            Ok(Connection {
                writer: Box::new(FakeWriter {
                    fake: self.0.clone(),
                    conn: st.conn,
                }),
                events: rx,
            })
        })
    }

    fn keepalive(&self) -> Option<Duration> {
        self.0.lock().keepalive
    }

    fn describe(&self) -> String {
        "fake".into()
    }
}

impl LinkWriter for FakeWriter {
    fn write<'a>(&'a mut self, chunk: &'a [u8]) -> BoxFuture<'a, Result<(), LinkError>> {
        Box::pin(async move {
            let now = Instant::now();
            let mut st = self.fake.lock();
            st.writes.push(Write {
                at: now,
                bytes: chunk.to_vec(),
            });
            let decoded: Vec<_> = st.decoder.feed(chunk).collect();
            for r in decoded {
                let p = r.expect("the session wrote a malformed packet");
                if st.auto_respond && p.flags.contains(Flags::REQUESTS_RESPONSE) {
                    let resp = Packet::response_to(&p, ErrorCode::Success, vec![]).encode();
                    if let Some(tx) = &st.events {
                        let _ = tx.try_send(LinkEvent::Data(resp));
                    }
                }
                st.sent.push(Sent {
                    at: now,
                    conn: self.conn,
                    packet: p,
                });
            }
            let n = st.sent.len();
            drop(st);
            self.fake.count.send_replace(n);
            Ok(())
        })
    }

    fn close(&mut self) -> BoxFuture<'_, ()> {
        let mut st = self.fake.lock();
        st.closes.push((Instant::now(), self.conn));
        Box::pin(async {})
    }
}

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

fn quick() -> SessionConfig {
    SessionConfig {
        pacing: ms(10),
        ..SessionConfig::default()
    }
}

fn drive(speed: u8, heading: u16) -> Command {
    cmd::drive_with_heading(speed, Heading::new(heading).unwrap(), DriveFlags::empty())
}

fn is_drive(p: &Packet) -> bool {
    (p.did, p.cid) == (0x16, 0x07)
}

/// Wait until the session reports `want`.
async fn wait_state(s: &SessionHandle, want: impl Fn(&LinkState) -> bool) {
    let mut rx = s.watch_state();
    rx.wait_for(|st| want(st)).await.unwrap();
}

async fn connected(fake: &Fake, config: SessionConfig) -> SessionHandle {
    let s = session::start(fake.link(), config);
    wait_state(&s, |st| *st == LinkState::Connected).await;
    s
}

// ---------------------------------------------------------------------------------------------
// Matching, timeouts, errors
// ---------------------------------------------------------------------------------------------

#[tokio::test(start_paused = true)]
async fn out_of_order_responses_reach_their_own_callers() {
    let fake = Fake::new();
    let s = connected(&fake, quick()).await;
    // Three requests with the same DID/CID: only the SEQ tells their responses apart.
    let mut calls = Vec::new();
    for volume in [10u8, 20, 30] {
        let s = s.clone();
        calls.push((
            volume,
            tokio::spawn(async move { s.request(cmd::set_audio_volume(volume)).await }),
        ));
    }
    let written = fake.wait_packets(3).await;
    assert_eq!(written.len(), 3);
    let seqs: Vec<u8> = written.iter().map(|p| p.seq).collect();
    assert_eq!(seqs, [0, 1, 2]);
    // Answer in reverse order, each response carrying the volume its request asked for and a
    // marker of the SEQ.
    for p in written.iter().rev() {
        fake.respond(p, ErrorCode::Success, vec![p.data[0], p.seq]);
    }
    for (volume, call) in calls {
        let resp = call.await.unwrap().expect("answered");
        let req = written.iter().find(|p| p.data == [volume]).unwrap();
        assert_eq!(resp.as_v2().unwrap().seq, req.seq, "volume {volume}");
        assert_eq!(
            resp.data(),
            [volume, req.seq],
            "volume {volume} got another's response"
        );
    }
    let st = s.stats();
    assert_eq!((st.answered, st.unmatched, st.timeouts), (3, 0, 0));
}

#[tokio::test(start_paused = true)]
async fn responses_match_on_did_cid_and_seq() {
    let fake = Fake::new();
    let s = connected(&fake, quick()).await;
    let a = {
        let s = s.clone();
        tokio::spawn(async move { s.request(cmd::get_battery_voltage()).await })
    };
    let written = fake.wait_packets(1).await;
    let req = &written[0];
    // Same SEQ, other CID: not this request's answer.
    fake.inject(
        Packet::response_to(
            &cmd::get_battery_state().to_packet(req.seq),
            ErrorCode::Success,
            vec![3],
        )
        .encode(),
    );
    fake.respond(req, ErrorCode::Success, vec![0x01, 0x9A]);
    let resp = a.await.unwrap().unwrap();
    assert_eq!(
        (resp.as_v2().unwrap().cid, resp.data()),
        (0x03, &[0x01, 0x9A][..])
    );
    assert_eq!(s.stats().unmatched, 1);
}

#[tokio::test(start_paused = true)]
async fn default_timeout_is_two_seconds() {
    let fake = Fake::new();
    let s = connected(&fake, SessionConfig::default()).await;
    assert_eq!(
        SessionConfig::default().request_timeout,
        Duration::from_secs(2)
    );
    let t0 = Instant::now();
    let call = s.request(cmd::ping());
    tokio::pin!(call);
    // Still waiting just before the deadline...
    assert!(
        timeout(ms(1990), &mut call).await.is_err(),
        "timed out early"
    );
    assert_eq!(s.stats().timeouts, 0);
    // ...and Timeout right at it.
    let r = call.await;
    let took = t0.elapsed();
    assert_eq!(r, Err(RequestError::Timeout));
    assert!(
        took >= ms(2000) && took <= ms(2005),
        "timed out after {took:?}"
    );
    assert_eq!(s.stats().timeouts, 1);
    // A late answer matches nothing.
    let p = fake.packets()[0].clone();
    fake.respond(&p, ErrorCode::Success, vec![]);
    sleep(ms(10)).await;
    assert_eq!(s.stats().unmatched, 1);
    assert_eq!(s.stats().answered, 0);
}

#[tokio::test(start_paused = true)]
async fn configured_timeout_counts_from_the_write() {
    let fake = Fake::new();
    let config = SessionConfig {
        request_timeout: ms(500),
        pacing: ms(120),
        ..SessionConfig::default()
    };
    let s = connected(&fake, config).await;
    let t0 = Instant::now();
    let first = {
        let s = s.clone();
        tokio::spawn(async move { (s.request(cmd::ping()).await, Instant::now()) })
    };
    let second = {
        let s = s.clone();
        tokio::spawn(async move { (s.request(cmd::get_battery_voltage()).await, Instant::now()) })
    };
    let (r1, at1) = first.await.unwrap();
    let (r2, at2) = second.await.unwrap();
    assert_eq!(r1, Err(RequestError::Timeout));
    assert_eq!(r2, Err(RequestError::Timeout));
    // The second was written one pacing interval later, and waited 500 ms from its write.
    let d1 = at1 - t0;
    let d2 = at2 - t0;
    assert!(d1 >= ms(500) && d1 <= ms(505), "{d1:?}");
    assert!(d2 >= ms(620) && d2 <= ms(625), "{d2:?}");
    assert_eq!(s.stats().timeouts, 2);
}

#[tokio::test(start_paused = true)]
async fn error_code_becomes_droid_error() {
    let fake = Fake::new();
    let s = connected(&fake, quick()).await;
    let call = {
        let s = s.clone();
        tokio::spawn(async move { s.request(drive(100, 90)).await })
    };
    let p = fake.wait_packets(1).await.remove(0);
    fake.respond(&p, ErrorCode::BadParameterValue, vec![]);
    assert_eq!(
        call.await.unwrap(),
        Err(RequestError::Droid(droidctl::family::DroidError::V2(
            ErrorCode::BadParameterValue
        )))
    );
    let st = s.stats();
    assert_eq!(
        (st.droid_errors, st.errors, st.answered, st.timeouts),
        (1, 1, 1, 0)
    );
}

#[tokio::test(start_paused = true)]
async fn target_unavailable_wakes_the_droid_and_resends_once() {
    // Issue 15: a drive that finds the droid in soft sleep is not lost: Wake, then the drive
    // again, once. A second target_unavailable is the caller's answer.
    let fake = Fake::new();
    let s = connected(&fake, quick()).await;
    let call = {
        let s = s.clone();
        tokio::spawn(async move { s.request(drive(100, 90)).await })
    };
    let first = fake.wait_packets(1).await.remove(0);
    fake.respond(&first, ErrorCode::TargetUnavailable, vec![]);
    let sent = fake.wait_packets(3).await;
    let (wake, again) = (&sent[1], &sent[2]);
    assert_eq!((wake.did, wake.cid), (0x13, 0x0D), "{sent:?}");
    assert_eq!(
        (again.did, again.cid, &again.data),
        (first.did, first.cid, &first.data)
    );
    fake.respond(wake, ErrorCode::Success, vec![]);
    fake.respond(again, ErrorCode::Success, vec![]);
    assert!(call.await.unwrap().is_ok());
    assert_eq!(s.stats().retried, 1);

    let call = {
        let s = s.clone();
        tokio::spawn(async move { s.request(drive(50, 90)).await })
    };
    let p = fake.wait_packets(4).await.remove(3);
    fake.respond(&p, ErrorCode::TargetUnavailable, vec![]);
    let sent = fake.wait_packets(6).await;
    fake.respond(&sent[4], ErrorCode::Success, vec![]);
    fake.respond(&sent[5], ErrorCode::TargetUnavailable, vec![]);
    assert_eq!(
        call.await.unwrap(),
        Err(RequestError::Droid(droidctl::family::DroidError::V2(
            ErrorCode::TargetUnavailable
        ))),
        "woken and re-sent once only"
    );
}

/// Issue 21: an emergency stop never waits behind, nor is overtaken by, a drive queued
/// before it. A drive that found the droid asleep is queued again behind a Wake; the operator
/// hits the e-stop meanwhile: the stop goes right after the Wake (one pacing slot), and the
/// older drive is dropped (its caller told it was superseded) instead of being written after
/// the stop and driving the droid again.
#[tokio::test(start_paused = true)]
async fn an_emergency_stop_is_not_overtaken_by_a_drive_queued_before_it() {
    let fake = Fake::new();
    let s = connected(&fake, quick()).await;
    let call = {
        let s = s.clone();
        tokio::spawn(async move { s.request(drive(100, 90)).await })
    };
    let first = fake.wait_packets(1).await.remove(0);
    fake.respond(&first, ErrorCode::TargetUnavailable, vec![]);
    // The Wake is written; the drive waits behind it.
    let wake = fake.wait_packets(2).await.remove(1);
    assert_eq!((wake.did, wake.cid), (0x13, 0x0D));
    let estop_at = Instant::now();
    s.set(Slot::Drive, drive(0, 90));
    sleep(ms(500)).await;
    let sent = fake.sent();
    let stop = sent
        .iter()
        .position(|w| is_drive(&w.packet) && w.packet.data[0] == 0)
        .expect("the stop was written");
    assert!(
        sent[stop].at - estop_at <= ms(10),
        "the stop waited {:?}",
        sent[stop].at - estop_at
    );
    let driven: Vec<_> = sent[stop..]
        .iter()
        .filter(|w| is_drive(&w.packet) && w.packet.data[0] > 0)
        .collect();
    assert!(driven.is_empty(), "driven after the e-stop: {driven:?}");
    assert_eq!(call.await.unwrap(), Err(RequestError::Superseded));
}

/// Issue 26, item 3: an emergency stop goes out at once, ahead of pacing and of everything
/// queued, and again one pacing slot later in case the droid dropped the first.
#[tokio::test(start_paused = true)]
async fn an_emergency_stop_is_written_at_once_and_again_one_slot_later() {
    let fake = Fake::new();
    fake.auto_respond(true);
    let pacing = ms(120);
    let s = connected(
        &fake,
        SessionConfig {
            pacing,
            ..SessionConfig::default()
        },
    )
    .await;
    // Driving, with requests queued behind: the next pacing slot is up to 120 ms away.
    s.set(Slot::Drive, drive(120, 45));
    for v in 0..5 {
        s.send(cmd::set_audio_volume(v)).unwrap();
    }
    fake.wait_packets(1).await;
    sleep(ms(30)).await;
    let at = Instant::now();
    s.emergency_stop(drive(0, 45));
    sleep(ms(400)).await;
    let stops: Vec<Sent> = fake
        .sent()
        .into_iter()
        .filter(|w| w.at >= at && is_drive(&w.packet) && w.packet.data[0] == 0)
        .collect();
    assert!(stops.len() >= 2, "written twice: {stops:?}");
    assert_eq!(
        stops[0].at,
        at,
        "the first stop waited {:?}",
        stops[0].at - at
    );
    let again = stops[1].at - stops[0].at;
    assert!(
        again >= pacing && again <= pacing + ms(5),
        "the second stop came {again:?} after the first"
    );
    let driven = fake
        .sent()
        .into_iter()
        .filter(|w| w.at >= at && is_drive(&w.packet) && w.packet.data[0] > 0)
        .count();
    assert_eq!(driven, 0, "nothing drives after the e-stop");
}

#[tokio::test(start_paused = true)]
async fn seq_runs_0_to_254_and_wraps_to_0() {
    let fake = Fake::new();
    fake.auto_respond(true);
    let s = connected(
        &fake,
        SessionConfig {
            pacing: ms(1),
            ..quick()
        },
    )
    .await;
    for _ in 0..300 {
        s.request(cmd::ping()).await.unwrap();
    }
    let seqs: Vec<u8> = fake.packets().iter().map(|p| p.seq).collect();
    assert_eq!(seqs.len(), 300);
    let expected: Vec<u8> = (0..300).map(|i| (i % 255) as u8).collect();
    assert_eq!(seqs, expected);
    assert!(!seqs.contains(&0xFF));
    assert_eq!(seqs[254], 254);
    assert_eq!(seqs[255], 0);
    assert_eq!(s.stats().answered, 300);
}

// ---------------------------------------------------------------------------------------------
// Pacing, chunking, coalescing, priorities
// ---------------------------------------------------------------------------------------------

#[tokio::test(start_paused = true)]
async fn writes_are_paced() {
    let fake = Fake::new();
    fake.auto_respond(true);
    let pacing = ms(120);
    let s = connected(
        &fake,
        SessionConfig {
            pacing,
            ..SessionConfig::default()
        },
    )
    .await;
    for v in 0..6 {
        s.send(cmd::set_audio_volume(v)).unwrap();
    }
    s.set(Slot::Drive, drive(50, 10));
    s.set(
        Slot::Head,
        cmd::set_head_position(HeadAngle::new(30.0).unwrap()),
    );
    fake.wait_packets(8).await;
    let writes = fake.writes();
    assert_eq!(writes.len(), 8);
    for w in writes.windows(2) {
        let gap = w[1].at - w[0].at;
        assert!(gap >= pacing, "writes {gap:?} apart");
    }
    // Not slower than needed either: back to back at exactly the pacing.
    assert!(writes[7].at - writes[0].at < pacing * 7 + ms(10));
}

#[tokio::test(start_paused = true)]
async fn long_packets_are_written_in_20_byte_chunks() {
    let fake = Fake::new();
    fake.auto_respond(true);
    let pacing = ms(50);
    let s = connected(
        &fake,
        SessionConfig {
            pacing,
            ..SessionConfig::default()
        },
    )
    .await;
    // 4 mask bytes + 40 values: a 51-byte packet.
    let long = cmd::set_all_leds_with_32_bit_mask(Mask(0xFF), Bytes((0..40).collect()));
    s.request(long.clone()).await.unwrap();
    let writes = fake.writes();
    let wire = long.to_packet(0).encode();
    assert!(wire.len() > 40, "{}", wire.len());
    assert_eq!(writes.len(), wire.len().div_ceil(20));
    assert!(
        writes
            .iter()
            .all(|w| !w.bytes.is_empty() && w.bytes.len() <= 20)
    );
    assert!(writes.len() >= 3);
    let joined: Vec<u8> = writes.iter().flat_map(|w| w.bytes.clone()).collect();
    assert_eq!(joined, wire);
    for w in writes.windows(2) {
        assert!(w[1].at - w[0].at >= pacing);
    }
    // A custom chunk size is honoured too.
    let fake = Fake::new();
    fake.auto_respond(true);
    let s = connected(
        &fake,
        SessionConfig {
            chunk_size: 8,
            ..quick()
        },
    )
    .await;
    s.request(long.clone()).await.unwrap();
    assert!(fake.writes().iter().all(|w| w.bytes.len() <= 8));
    assert_eq!(fake.writes().len(), wire.len().div_ceil(8));
}

/// A drive command that encodes its position in a storm of inputs.
fn storm_drive(i: u32) -> Command {
    let heading = (i % 360) as u16;
    let speed = 1 + ((i / 360) % 254) as u8;
    drive(speed, heading)
}

fn storm_index(p: &Packet) -> u32 {
    let heading = u16::from_be_bytes([p.data[1], p.data[2]]) as u32;
    (p.data[0] as u32 - 1) * 360 + heading
}

#[tokio::test(start_paused = true)]
async fn input_storm_is_coalesced_latest_wins() {
    let fake = Fake::new();
    fake.auto_respond(true);
    let s = connected(&fake, SessionConfig::default()).await;

    // A burst without yielding: at most one drive waits, whatever the rate.
    let mut sets = 0u64;
    for i in 0..10_000 {
        s.set(Slot::Drive, storm_drive(i));
        sets += 1;
        assert!(s.queued() <= 1, "queued {} after {i}", s.queued());
    }
    let first = fake.wait_packets(1).await;
    assert_eq!(
        storm_index(&first[0]),
        9_999,
        "the newest value goes out, not an old one"
    );
    assert_eq!(s.stats().coalesced, 9_999);

    // A storm interleaved with yields and time passing, on both slots.
    let mut max_queued = 0;
    let mut last_head = 0.0;
    for i in 10_000..20_000u32 {
        s.set(Slot::Drive, storm_drive(i));
        sets += 1;
        if i % 3 == 0 {
            last_head = (i % 180) as f32;
            s.set(
                Slot::Head,
                cmd::set_head_position(HeadAngle::new(last_head).unwrap()),
            );
            sets += 1;
        }
        max_queued = max_queued.max(s.queued());
        tokio::task::yield_now().await;
        if i % 10 == 0 {
            sleep(ms(1)).await;
        }
        max_queued = max_queued.max(s.queued());
    }
    assert!(max_queued <= 2, "queued up to {max_queued}");
    let storm_end = Instant::now();
    let during: Vec<&'static str> = fake
        .sent()
        .iter()
        .filter(|w| w.at < storm_end)
        .map(|w| if is_drive(&w.packet) { "drive" } else { "head" })
        .collect();
    // Both slots kept going out during the storm: the drive did not starve the dome.
    let heads_during = during.iter().filter(|k| **k == "head").count();
    let drives_during = during.len() - heads_during;
    assert!(heads_during >= 3 && drives_during >= 3, "{during:?}");
    // Let everything drain.
    sleep(ms(1000)).await;
    assert_eq!(s.queued(), 0);

    let drives: Vec<u32> = fake
        .packets()
        .iter()
        .filter(|p| is_drive(p))
        .map(storm_index)
        .collect();
    assert!(
        drives.len() < 50,
        "{} drive writes for 20 000 inputs",
        drives.len()
    );
    assert!(
        drives.windows(2).all(|w| w[0] < w[1]),
        "an older value was written after a newer one: {drives:?}"
    );
    assert_eq!(
        *drives.last().unwrap(),
        19_999,
        "the last value set is the last written"
    );
    let heads: Vec<Packet> = fake
        .packets()
        .into_iter()
        .filter(|p| p.cid == 0x0F)
        .collect();
    assert_eq!(
        f32::from_be_bytes(heads.last().unwrap().data[..4].try_into().unwrap()),
        last_head
    );
    // Every set either filled an empty slot (and was written) or replaced one.
    let written = fake.packets().len() as u64;
    assert_eq!(s.stats().coalesced, sets - written);
}

#[tokio::test(start_paused = true)]
async fn stop_jumps_ahead_of_queued_requests() {
    let fake = Fake::new();
    fake.auto_respond(true);
    let s = connected(&fake, SessionConfig::default()).await;
    for v in 1..=5 {
        s.send(cmd::set_audio_volume(v)).unwrap();
    }
    s.set(Slot::Drive, drive(50, 90));
    // Slots and the FIFO take turns: drive(50), then volume 1 would be next...
    let p = fake.wait_packets(1).await;
    assert!(is_drive(&p[0]) && p[0].data[0] == 50);
    // ...but a stop goes first.
    s.set(Slot::Drive, drive(0, 90));
    let p = fake.wait_packets(2).await;
    assert!(is_drive(&p[1]) && p[1].data[0] == 0, "{:?}", p[1]);
    // Control: a non-stop drive waits its turn behind volume 1.
    s.set(Slot::Drive, drive(60, 90));
    let p = fake.wait_packets(4).await;
    assert_eq!((p[2].cid, p[2].data.as_slice()), (0x08, &[1u8][..]));
    assert!(is_drive(&p[3]) && p[3].data[0] == 60);
    // A stop jumps ahead even when the FIFO's turn has come and several requests wait.
    s.set(Slot::Drive, drive(0, 45));
    let p = fake.wait_packets(5).await;
    assert!(is_drive(&p[4]) && p[4].data[0] == 0);
    let p = fake.wait_packets(9).await;
    let volumes: Vec<u8> = p[5..].iter().map(|p| p.data[0]).collect();
    assert_eq!(volumes, [2, 3, 4, 5]);
}

#[tokio::test(start_paused = true)]
async fn full_queue_rejects_with_queue_full() {
    let fake = Fake::new();
    let s = connected(
        &fake,
        SessionConfig {
            queue_capacity: 4,
            ..SessionConfig::default()
        },
    )
    .await;
    let results: Vec<_> = (0..6).map(|v| s.send(cmd::set_audio_volume(v))).collect();
    assert_eq!(results.iter().filter(|r| r.is_ok()).count(), 4);
    assert_eq!(results[5], Err(RequestError::QueueFull));
    assert_eq!(s.stats().rejected, 2);
}

// ---------------------------------------------------------------------------------------------
// Notifications and the packet log
// ---------------------------------------------------------------------------------------------

#[tokio::test(start_paused = true)]
async fn notifications_fan_out_to_every_subscriber() {
    let fake = Fake::new();
    let s = connected(&fake, quick()).await;
    let mut subs: Vec<_> = (0..3).map(|_| s.subscribe()).collect();
    let collision = vec![
        0x10, 0x00, 0xF8, 0x00, 0x00, 0x00, 0x03, 0x00, 0x64, 0xFF, 0xFB, 0x00, 0x07, 0x50, 0x00,
        0x01, 0x23, 0x45,
    ];
    let mut stream = Vec::new();
    for p in [
        Packet::notification(0x13, 0x19, vec![]),
        Packet::notification(0x18, 0x12, collision.clone()),
        Packet::notification(0x17, 0x26, vec![]),
    ] {
        p.encode_into(&mut stream);
    }
    // Delivered one byte at a time: notification boundaries are not packet boundaries.
    for b in stream {
        fake.inject(vec![b]);
    }
    for rx in &mut subs {
        let mut got = Vec::new();
        for _ in 0..3 {
            match timeout(ms(100), rx.recv())
                .await
                .expect("notification")
                .unwrap()
            {
                SessionEvent::Notification(n) => got.push(n),
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(got[0], Notification::WillSleep);
        assert!(
            matches!(&got[1], Notification::Collision(c) if c.speed == 80 && c.axis.x && c.axis.y)
        );
        assert_eq!(got[2], Notification::LegActionComplete);
    }
    // A known notification with a bad payload is reported, not dropped.
    fake.inject(Packet::notification(0x13, 0x06, vec![1, 2]).encode());
    for rx in &mut subs {
        let e = timeout(ms(100), rx.recv()).await.unwrap().unwrap();
        assert!(
            matches!(
                e,
                SessionEvent::BadNotification {
                    name: "battery-state-changed",
                    ..
                }
            ),
            "{e:?}"
        );
    }
}

#[tokio::test(start_paused = true)]
async fn packet_log_shows_every_packet_and_decode_error() {
    let fake = Fake::new();
    // Without the keep-awake ping the will-sleep below would trigger (tested in failsafe.rs).
    let s = session::start(
        fake.link(),
        SessionConfig {
            keep_awake: false,
            ..quick()
        },
    );
    let mut log = s.subscribe_log();
    wait_state(&s, |st| *st == LinkState::Connected).await;
    let call = {
        let s = s.clone();
        tokio::spawn(async move { s.request(cmd::get_battery_voltage()).await })
    };
    let req = fake.wait_packets(1).await.remove(0);
    fake.respond(&req, ErrorCode::Success, vec![0x01, 0x9A]);
    call.await.unwrap().unwrap();
    let note = Packet::notification(0x13, 0x19, vec![]);
    fake.inject(note.encode());
    // A corrupted packet: the checksum no longer matches.
    let mut bad = Packet::notification(0x13, 0x06, vec![3]).encode();
    bad[5] ^= 0x01;
    fake.inject(bad);
    s.send(cmd::ping()).unwrap();
    fake.wait_packets(2).await;

    let mut entries = Vec::new();
    while let Ok(Ok(e)) = timeout(ms(50), log.recv()).await {
        entries.push(e);
    }
    let outs: Vec<&Packet> = entries
        .iter()
        .filter(|e| e.dir == Direction::Out)
        .filter_map(|e| match &e.item {
            LogItem::Packet {
                packet: droidctl::family::Packet::V2(p),
                ..
            } => Some(p),
            _ => None,
        })
        .collect();
    let ins: Vec<&LogItem> = entries
        .iter()
        .filter(|e| e.dir == Direction::In)
        .map(|e| &e.item)
        .collect();
    assert_eq!(outs.len(), 2);
    assert_eq!(
        (outs[0].did, outs[0].cid, outs[0].seq),
        (0x13, 0x03, req.seq)
    );
    assert_eq!(outs[1].cid, 0x01);
    assert_eq!(ins.len(), 3, "{ins:?}");
    let v2 = |item: &LogItem| match item {
        LogItem::Packet {
            packet: droidctl::family::Packet::V2(p),
            ..
        } => Some(p.clone()),
        _ => None,
    };
    assert!(
        matches!(v2(ins[0]), Some(p) if p.is_response() && p.seq == req.seq && p.data == [0x01, 0x9A])
    );
    // The response is explained with its request: the battery voltage, by name.
    assert!(
        matches!(ins[0], LogItem::Packet { explained, .. } if explained.label == "get-battery-voltage")
    );
    assert_eq!(v2(ins[1]), Some(note));
    assert!(matches!(
        ins[2],
        LogItem::DecodeError(e) if e.kind == ErrorKind::BadChecksum
    ));
    // Times are since the session started and never go backwards.
    assert!(entries.windows(2).all(|w| w[0].at <= w[1].at));
    let st = s.stats();
    assert_eq!((st.decode_errors, st.sent, st.received), (1, 2, 2));
}

// ---------------------------------------------------------------------------------------------
// Reconnection, fatal errors, shutdown
// ---------------------------------------------------------------------------------------------

#[tokio::test(start_paused = true)]
async fn reconnects_with_backoff_setup_and_a_stop_at_the_last_heading() {
    let fake = Fake::new();
    let config = SessionConfig {
        setup: vec![
            cmd::wake().into(),
            cmd::perform_leg_action(LegAction::Tripod).into(),
        ],
        pacing: ms(120),
        ..SessionConfig::default()
    };
    assert_eq!(config.backoff, Backoff::default());
    let s = session::start(fake.link(), config.clone());

    // Record every state the session goes through.
    let states = Arc::new(Mutex::new(Vec::new()));
    {
        let mut rx = s.watch_state();
        let states = states.clone();
        tokio::spawn(async move {
            loop {
                let st = rx.borrow_and_update().clone();
                states.lock().unwrap().push((Instant::now(), st));
                if rx.changed().await.is_err() {
                    break;
                }
            }
        });
    }
    wait_state(&s, |st| *st == LinkState::Connected).await;
    fake.auto_respond(true);
    // Setup on the first connection.
    let p = fake.wait_packets(2).await;
    assert_eq!((p[0].did, p[0].cid), (0x13, 0x0D));
    assert_eq!((p[1].cid, p[1].data.as_slice()), (0x0D, &[1u8][..]));
    // Drive at heading 123, then leave a request unanswered.
    s.set(Slot::Drive, drive(120, 123));
    fake.wait_packets(3).await;
    fake.auto_respond(false);
    let pending = {
        let s = s.clone();
        tokio::spawn(async move { (s.request(cmd::get_battery_voltage()).await, Instant::now()) })
    };
    fake.wait_packets(4).await;

    // Drop the link; the next two opens fail, the third works.
    fake.script_opens(vec![
        Err(LinkError::transient("out of range")),
        Err(LinkError::transient("out of range")),
    ]);
    fake.auto_respond(true);
    let t_drop = Instant::now();
    fake.disconnect("radio silence");
    let (r, failed_at) = pending.await.unwrap();
    assert_eq!(r, Err(RequestError::LinkLost));
    assert!(
        failed_at - t_drop < ms(5),
        "pending request failed only after {:?}",
        failed_at - t_drop
    );

    wait_state(&s, |st| {
        matches!(st, LinkState::Reconnecting { attempt: 3, .. })
    })
    .await;
    wait_state(&s, |st| *st == LinkState::Connected).await;

    // Backoff::delay(1..=3): 0.5 s, 1 s, 2 s between the drop and the attempts.
    let opens = fake.opens();
    assert_eq!(opens.len(), 4, "first connect + three attempts");
    let gaps = [opens[1] - t_drop, opens[2] - opens[1], opens[3] - opens[2]];
    for (i, gap) in gaps.iter().enumerate() {
        let want = config.backoff.delay(i as u32 + 1);
        assert!(
            *gap >= want && *gap <= want + ms(5),
            "attempt {}: {gap:?}, want {want:?}",
            i + 1
        );
    }
    assert_eq!(gaps.map(|g| g.as_millis() / 10 * 10), [500, 1000, 2000]);

    // The state machine went Connected → Reconnecting{1,2,3} → Connected.
    // (The recorder may start after the first connect already happened.)
    let mut seen: Vec<LinkState> = states
        .lock()
        .unwrap()
        .iter()
        .map(|(_, s)| s.clone())
        .collect();
    if seen[0] == LinkState::Connecting {
        seen.remove(0);
    }
    let labels: Vec<String> = seen.iter().map(LinkState::label).collect();
    assert_eq!(
        labels,
        [
            "connected",
            "reconnecting (attempt 1)",
            "reconnecting (attempt 2)",
            "reconnecting (attempt 3)",
            "connected"
        ]
    );
    assert!(
        matches!(&seen[1], LinkState::Reconnecting { reason, .. } if reason == "radio silence")
    );

    // On the new connection: the wake, a stop at the last heading, then the setup again
    // (issue 15: stop first, then set up).
    fake.wait_packets(7).await;
    let after: Vec<Packet> = fake
        .sent()
        .into_iter()
        .filter(|s| s.conn == 2)
        .map(|s| s.packet)
        .collect();
    assert_eq!(after.len(), 3, "{after:?}");
    assert_eq!((after[0].did, after[0].cid), (0x13, 0x0D));
    assert!(is_drive(&after[1]));
    assert_eq!(after[1].data, [0, 0, 123, 0], "speed 0 at heading 123");
    assert_eq!(
        (after[2].did, after[2].cid, after[2].data.as_slice()),
        (0x17, 0x0D, &[1u8][..])
    );

    let st = s.stats();
    assert_eq!(st.reconnects, 1);
    assert!(st.link_lost >= 1);
    // The session works again.
    s.request(cmd::ping()).await.unwrap();
}

#[tokio::test(start_paused = true)]
async fn backoff_is_capped_and_applies_to_the_first_connect_too() {
    let fake = Fake::new();
    fake.script_opens((0..7).map(|_| Err(LinkError::transient("nope"))).collect());
    let config = SessionConfig {
        backoff: Backoff {
            initial: ms(500),
            max: ms(3000),
        },
        ..SessionConfig::default()
    };
    let t0 = Instant::now();
    let s = connected(&fake, config).await;
    let opens = fake.opens();
    assert_eq!(opens.len(), 8);
    let gaps: Vec<u128> = opens
        .windows(2)
        .map(|w| (w[1] - w[0]).as_millis())
        .collect();
    assert_eq!(gaps, [500, 1000, 2000, 3000, 3000, 3000, 3000]);
    assert_eq!(opens[0], t0);
    assert_eq!(s.stats().reconnects, 1);
}

#[tokio::test(start_paused = true)]
async fn fatal_link_error_closes_the_session() {
    let fake = Fake::new();
    let s = connected(&fake, quick()).await;
    let pending = {
        let s = s.clone();
        tokio::spawn(async move { s.request(cmd::ping()).await })
    };
    fake.wait_packets(1).await;
    fake.script_opens(vec![Err(LinkError::fatal("Bluetooth adapter removed"))]);
    fake.disconnect("gone");
    assert_eq!(pending.await.unwrap(), Err(RequestError::LinkLost));
    wait_state(&s, |st| matches!(st, LinkState::Closed { .. })).await;
    assert_eq!(
        s.state(),
        LinkState::Closed {
            reason: Some("Bluetooth adapter removed".into())
        }
    );
    assert!(s.is_closed());
    assert_eq!(s.request(cmd::ping()).await, Err(RequestError::Closed));
    assert_eq!(s.send(cmd::ping()), Err(RequestError::Closed));
    // No retry after a fatal error.
    sleep(Duration::from_secs(30)).await;
    assert_eq!(fake.opens().len(), 2);

    // Fatal on the very first open.
    let fake = Fake::new();
    fake.script_opens(vec![Err(LinkError::fatal("permission denied"))]);
    let s = session::start(fake.link(), quick());
    wait_state(&s, |st| matches!(st, LinkState::Closed { .. })).await;
    assert_eq!(s.state().label(), "closed: permission denied");
}

#[tokio::test(start_paused = true)]
async fn shutdown_writes_the_stop_before_closing() {
    let fake = Fake::new();
    fake.auto_respond(true);
    let s = connected(&fake, SessionConfig::default()).await;
    s.set(Slot::Drive, drive(200, 45));
    fake.wait_packets(1).await;
    // Something still queued, and a long packet in flight when shutdown comes.
    s.send(cmd::set_all_leds_with_32_bit_mask(
        Mask(0xFF),
        Bytes((0..40).collect()),
    ))
    .unwrap();
    sleep(ms(130)).await;
    let before = fake.writes().len();
    s.shutdown(vec![drive(0, 45).into()]).await;
    assert_eq!(s.state(), LinkState::Closed { reason: None });
    {
        let st = fake.lock();
        assert!(st.writes.len() > before);
        let last = &st.sent.last().unwrap().packet;
        assert!(
            is_drive(last) && last.data == [0, 0, 45, 0],
            "last written: {last:?}"
        );
        assert!(
            !last.flags.contains(Flags::REQUESTS_RESPONSE),
            "nobody waits for the shutdown stop's response"
        );
        // The LED packet that was in flight was finished, not cut (the decoder saw it whole).
        assert!(st.sent.iter().any(|s| s.packet.cid == 0x1A));
        let (closed_at, _) = *st.closes.last().expect("closed");
        assert!(closed_at >= st.writes.last().unwrap().at);
    }
    assert_eq!(s.request(cmd::ping()).await, Err(RequestError::Closed));
}

#[tokio::test(start_paused = true)]
async fn shutdown_while_reconnecting_ends_at_once() {
    let fake = Fake::new();
    let s = connected(&fake, quick()).await;
    fake.script_opens(
        (0..100)
            .map(|_| Err(LinkError::transient("nope")))
            .collect(),
    );
    fake.disconnect("gone");
    wait_state(&s, |st| {
        matches!(st, LinkState::Reconnecting { attempt: 2, .. })
    })
    .await;
    let t0 = Instant::now();
    s.shutdown(vec![drive(0, 0).into()]).await;
    assert!(t0.elapsed() < ms(5));
    assert_eq!(s.state(), LinkState::Closed { reason: None });
}

#[tokio::test(start_paused = true)]
async fn play_audio_request_roundtrip() {
    // A plain request/response with data, to pin the encoding the session writes.
    let fake = Fake::new();
    fake.auto_respond(true);
    let s = connected(&fake, quick()).await;
    s.request(cmd::play_audio_file(1915, AudioMode::IfIdle))
        .await
        .unwrap();
    let p = &fake.packets()[0];
    assert_eq!(
        (p.did, p.cid, p.data.as_slice()),
        (0x1A, 0x07, &[0x07, 0x7B, 1][..])
    );
    assert_eq!(p.flags, Flags::DEFAULT_COMMAND);
}

#[tokio::test(start_paused = true)]
async fn shutdown_stopped_stops_at_the_last_heading() {
    let fake = Fake::new();
    fake.auto_respond(true);
    let s = connected(&fake, SessionConfig::default()).await;
    s.set(Slot::Drive, drive(200, 135));
    fake.wait_packets(1).await;
    s.shutdown_stopped(vec![cmd::set_audio_volume(0).into()])
        .await;
    let sent = fake.packets();
    let n = sent.len();
    assert!(n >= 3);
    // The stop (speed 0 at 135, not at 0, which would turn the droid), then the extra command.
    assert!(
        is_drive(&sent[n - 2]) && sent[n - 2].data == [0, 0, 135, 0],
        "{:?}",
        sent[n - 2]
    );
    assert_eq!(
        (sent[n - 1].cid, sent[n - 1].data.as_slice()),
        (0x08, &[0u8][..])
    );
    assert_eq!(s.state(), LinkState::Closed { reason: None });
}

#[tokio::test(start_paused = true)]
async fn stop_now_keeps_the_last_heading() {
    // The panic hook's stop (issue 15): at the heading last written, never heading 0.
    let fake = Fake::new();
    let s = connected(&fake, quick()).await;
    s.set(Slot::Drive, drive(120, 123));
    fake.wait_packets(1).await;
    s.stop_now(droidctl::family::for_model(droidctl::model::Model::R2D2));
    let sent = fake.wait_packets(2).await;
    assert!(is_drive(&sent[1]));
    assert_eq!(sent[1].data, [0, 0, 123, 0], "speed 0 at heading 123");
}

/// A link that closes when quiet (a relay's idle timeout) is written to in time: an idle
/// session sends a harmless ping at least every keepalive period, and none on a link without
/// one.
#[tokio::test(start_paused = true)]
async fn a_quiet_link_that_needs_traffic_gets_a_ping_in_time() {
    let fake = Fake::new();
    fake.auto_respond(true);
    fake.lock().keepalive = Some(Duration::from_secs(20));
    let s = connected(&fake, quick()).await;
    s.send(drive(0, 90)).unwrap();
    sleep(Duration::from_secs(65)).await;
    let sent = fake.sent();
    let pings: Vec<&Sent> = sent
        .iter()
        .filter(|w| (w.packet.did, w.packet.cid) == (cmd::ping().did, cmd::ping().cid))
        .collect();
    assert!(pings.len() >= 3, "{} pings in 65 s", pings.len());
    let mut last = sent[0].at;
    for w in &sent {
        assert!(
            w.at - last <= Duration::from_secs(20) + ms(50),
            "a quiet stretch of {:?}",
            w.at - last
        );
        last = w.at;
    }

    let quiet = Fake::new();
    quiet.auto_respond(true);
    let s2 = connected(&quiet, quick()).await;
    sleep(Duration::from_secs(65)).await;
    assert!(
        quiet
            .packets()
            .iter()
            .all(|p| (p.did, p.cid) != (cmd::ping().did, cmd::ping().cid)),
        "no pings on a link that stays open however quiet"
    );
    drop((s, s2));
}
