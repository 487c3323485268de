//! The relay server as a whole (`droidctl serve --sim`): a client's byte stream, cut and
//! paced as the input says, against a server with three simulated droids (v2, v1, RSRCP), in
//! one process on paused time, no sockets. Whatever the stream: nothing panics; every
//! request is answered in order (OK or the data asked for) or refused (ERROR), until the
//! stream ends, the client says END, the stream cannot be followed (one ERROR, then the
//! server closes), the client queues more than the server takes (one ERROR, then it closes)
//! or a request takes longer than 10 s to arrive (closed; never a faster one); notifications only for characteristics subscribed; and when the stream ends,
//! every droid is released and stopped.
//!
//! Input layout: the first byte's low nibble counts chunk sizes (as the decoder target), its
//! high nibble is the pause between chunks in ms; the rest is the stream.

use super::{Target, feeds, split};
use crate::model::Model;
use crate::protocol::relay::{
    DecodeError, Expect, Limits, Reply, ReplyDecoder, Request, RequestDecoder,
};
use crate::relay::server::{EventSink, ServerConfig, ServerEvent, serve_stream};
use crate::relay::sim_backend::SimBackend;
use crate::sim::faults::GattFaults;
use crate::sync::lock;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::time::{Instant, sleep, timeout, timeout_at};

pub const TARGET: Target = Target {
    name: "relay_server",
    run: run_input,
    dictionary: &[
        // SCAN 0.5 s; INIT seq 1 of the three droids; END.
        &[0x00, 0x3F, 0x00, 0x00, 0x00],
        b"\x01\x01\x00\x115E:D0:00:00:00:01",
        b"\x01\x02\x00\x115E:D0:00:00:00:02",
        b"\x01\x03\x00\x115E:D0:00:00:00:03",
        b"\x04\x00\x07D2-0001\x00\x00\x00\x00",
        b"\x02\x04\x00\x2400010002-574f-4f20-5370-6865726f2121",
        b"\x03\x05\x00\x2400010002-574f-4f20-5370-6865726f2121\x00\x07",
        b"\x03\x06\x00\x2400020005-574f-4f20-5370-6865726f2121\x00\x12usetheforce...band",
        &[
            0x8D, 0x0A, 0x16, 0x07, 0x01, 0x80, 0x00, 0x5A, 0x00, 0x00, 0xD8,
        ],
        &[0xFF],
    ],
};

/// What a request (or a request the server cannot read) must be answered with.
#[derive(Debug, Clone)]
enum Wanted {
    Scan,
    Find(String),
    Seq(u8),
    /// An ERROR, with the seq when the broken request had one.
    Refusal(Option<u8>),
}

impl Wanted {
    fn expect(&self) -> Expect {
        match self {
            Wanted::Scan => Expect::Scan,
            Wanted::Find(_) => Expect::Find,
            Wanted::Seq(_) | Wanted::Refusal(Some(_)) => Expect::Seq,
            Wanted::Refusal(None) => Expect::Scan,
        }
    }

    /// Whether `r` answers this.
    fn answered_by(&self, r: &Reply, devices: &[(String, String, Model)]) -> bool {
        match (self, r) {
            (Wanted::Scan, Reply::Devices(list)) => {
                list.len() == devices.len()
                    && list
                        .iter()
                        .zip(devices)
                        .all(|(d, (n, a, _))| d.name == *n && d.address == *a)
            }
            (Wanted::Find(name), Reply::Found(d)) => d.name == *name,
            (Wanted::Scan | Wanted::Find(_), Reply::Error { seq: None, .. }) => true,
            (Wanted::Seq(s), Reply::Ok { seq }) => seq == s,
            (Wanted::Seq(s), Reply::Error { seq: Some(q), .. }) => q == s,
            (Wanted::Refusal(s), Reply::Error { seq, .. }) => seq == s,
            _ => false,
        }
    }
}

/// The answers the stream asks for, in order, as the server reads it: up to END or a
/// request it cannot follow.
fn wanted(stream: &[u8], limits: Limits) -> Vec<Wanted> {
    let mut d = RequestDecoder::new(limits);
    d.push(stream);
    let mut out = Vec::new();
    while let Some(r) = d.next() {
        match r {
            Ok(Request::End) => break,
            Ok(Request::Scan { .. }) => out.push(Wanted::Scan),
            Ok(Request::Find { name, .. }) => out.push(Wanted::Find(name)),
            Ok(r) => out.push(Wanted::Seq(r.seq().expect("INIT, SET_CALLBACK and WRITE"))),
            Err(e) => {
                out.push(Wanted::Refusal(e.seq()));
                if !e.recoverable() {
                    break;
                }
            }
        }
    }
    out
}

/// The longest any request (or the partial one the stream ends in) takes to arrive, with the
/// stream cut into `pieces` and `pause` after each: the server may close a client whose
/// request takes longer than its limit, and must not otherwise.
fn slowest_request(stream: &[u8], pieces: &[&[u8]], pause: Duration, limits: Limits) -> Duration {
    // When each byte is sent: after the pauses of the pieces before its own.
    let mut sent_at = Vec::with_capacity(stream.len());
    for (i, p) in pieces.iter().enumerate() {
        sent_at.extend(std::iter::repeat_n(pause * i as u32, p.len()));
    }
    let mut d = RequestDecoder::new(limits);
    let (mut start, mut slowest) = (0, Duration::ZERO);
    for (i, b) in stream.iter().enumerate() {
        d.push(std::slice::from_ref(b));
        let mut done = false;
        while d.next().is_some() {
            done = true;
        }
        if done {
            slowest = slowest.max(sent_at[i] - sent_at[start]);
            start = i + 1;
        }
    }
    if start < stream.len() {
        slowest = slowest.max(sent_at[stream.len() - 1] - sent_at[start]);
    }
    slowest
}

pub fn run_input(data: &[u8]) {
    let Some((pause, sizes, stream)) = split(data) else {
        return;
    };
    let cfg = ServerConfig::default();
    let limits = cfg.limits;
    let wanted = wanted(stream, limits);
    let pause_each = Duration::from_millis(pause as u64);
    let slow_client =
        slowest_request(stream, &feeds(sizes, stream), pause_each, limits) >= cfg.request_timeout;
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .start_paused(true)
        .build()
        .expect("a runtime");
    rt.block_on(async move {
        let backend = Arc::new(SimBackend::new(
            &[Model::R2D2, Model::BB8, Model::Robi42],
            GattFaults::default(),
        ));
        let devices = backend.devices();
        let events: Arc<Mutex<Vec<ServerEvent>>> = Arc::default();
        let sink: EventSink = {
            let events = events.clone();
            Arc::new(move |e: &ServerEvent| lock(&events).push(e.clone()))
        };
        let (client, server) = tokio::io::duplex(64 * 1024);
        let peer = "127.0.0.1:50004".parse().expect("an address");
        let served = tokio::spawn(serve_stream(server, peer, backend.clone(), cfg, sink));
        let (mut rd, mut wr) = tokio::io::split(client);

        // The client: the stream in its pieces, at its pace.
        let pieces: Vec<Vec<u8>> = feeds(sizes, stream).iter().map(|p| p.to_vec()).collect();
        // The whole exchange ends within a minute of the last piece.
        let deadline =
            Instant::now() + Duration::from_millis(pause as u64) * pieces.len() as u32 + Duration::from_secs(60);
        let writer = tokio::spawn(async move {
            for p in pieces {
                if wr.write_all(&p).await.is_err() {
                    break;
                }
                if pause > 0 {
                    sleep(Duration::from_millis(pause as u64)).await;
                }
            }
            wr
        });

        // Read the replies until every request is answered (then the stream ends: close our
        // side) or the server closes.
        let mut replies = ReplyDecoder::new(limits);
        for w in &wanted {
            replies.expect(w.expect());
        }
        let mut answers: Vec<Reply> = Vec::new();
        let mut subscribed_data = 0u64;
        let mut buf = vec![0u8; 4096];
        let mut writer = Some(writer);
        let mut closed_by_us = false;
        loop {
            // Every answer in: end the stream (after the writer is done).
            if answers.len() >= wanted.len() && !closed_by_us {
                if let Some(w) = writer.take() {
                    let mut wr = w.await.expect("the writer does not panic");
                    let _ = wr.shutdown().await;
                }
                closed_by_us = true;
            }
            let n = match timeout_at(deadline, rd.read(&mut buf)).await {
                Ok(Ok(n)) => n,
                Ok(Err(e)) => panic!("reading the server failed: {e}"),
                Err(_) => panic!(
                    "request {} of {} unanswered a minute after the stream: {:?} (answers {answers:?})",
                    answers.len() + 1,
                    wanted.len(),
                    wanted.get(answers.len())
                ),
            };
            if n == 0 {
                break;
            }
            replies.push(&buf[..n]);
            while let Some(r) = replies.next() {
                let r = r.unwrap_or_else(|e| panic!("the server sent what its client cannot read: {e}"));
                match r {
                    Reply::Data { data, .. } => {
                        assert!(data.len() <= 255);
                        subscribed_data += 1;
                    }
                    r => answers.push(r),
                }
            }
        }
        // The server closed: its task ends, without a panic.
        timeout(Duration::from_secs(30), served)
            .await
            .expect("the server ends when its client is gone")
            .expect("the server does not panic");
        let tail = replies.finish();
        let events = lock(&events).clone();
        check(&wanted, &answers, tail, &events, &devices, closed_by_us, slow_client);
        if subscribed_data > 0 {
            assert!(
                events.iter().any(|e| matches!(e, ServerEvent::DroidConnected { .. })),
                "notifications without a droid"
            );
        }
        // Every droid released and, a few seconds later, still.
        sleep(Duration::from_secs(5)).await;
        for (name, address, _) in &devices {
            assert!(!backend.connected(address), "{name} is still connected");
            let state = backend.state(address).expect("a simulated droid");
            assert!(
                state.velocity_cm_s.abs() < 1.0,
                "{name} still rolls at {} cm/s after its client went",
                state.velocity_cm_s
            );
        }
    });
}

/// The answers against the requests, and the server's reason to close.
fn check(
    wanted: &[Wanted],
    answers: &[Reply],
    tail: Option<Result<String, DecodeError>>,
    events: &[ServerEvent],
    devices: &[(String, String, Model)],
    closed_by_us: bool,
    slow_client: bool,
) {
    let closes: Vec<&String> = events
        .iter()
        .filter_map(|e| match e {
            ServerEvent::ClientClosed { reason, .. } => Some(reason),
            _ => None,
        })
        .collect();
    assert_eq!(closes.len(), 1, "{events:?}");
    assert!(matches!(
        events.last(),
        Some(ServerEvent::ClientClosed { .. })
    ));
    let reason = closes[0].as_str();
    for (i, (w, a)) in wanted.iter().zip(answers).enumerate() {
        assert!(
            w.answered_by(a, devices),
            "request {}: {w:?} answered by {a:?}",
            i + 1
        );
    }
    // A droid held is released (stopped unless it went by itself).
    let connected = events
        .iter()
        .filter(|e| matches!(e, ServerEvent::DroidConnected { .. }))
        .count();
    let released: Vec<bool> = events
        .iter()
        .filter_map(|e| match e {
            ServerEvent::DroidReleased { stopped, .. } => Some(*stopped),
            _ => None,
        })
        .collect();
    assert_eq!(connected, released.len(), "{events:?}");
    assert!(
        released.iter().all(|s| *s),
        "a droid released without its stop: {events:?}"
    );
    if reason.starts_with("more than") {
        // Refused for queueing too much: the answers so far, then the refusal.
        let refused = matches!(
            answers.last(),
            Some(Reply::Error { seq: None, message }) if message.starts_with("more than")
        ) || matches!(&tail, Some(Ok(m)) if m.starts_with("more than"));
        assert!(refused, "{reason}: answers {answers:?}, tail {tail:?}");
        return;
    }
    if reason == "incomplete request" {
        // Only a request that took longer than the limit to arrive is given up on (the
        // answers before it were checked above).
        assert!(
            slow_client,
            "closed as incomplete, though no request took 10 s"
        );
        return;
    }
    assert!(
        tail.is_none(),
        "{reason}: the replies end inside one: {tail:?}"
    );
    assert_eq!(
        answers.len(),
        wanted.len(),
        "{reason}: {} answers to {} requests ({answers:?})",
        answers.len(),
        wanted.len()
    );
    let fine = reason == "the client disconnected" && closed_by_us
        || reason == "the client ended the session"
        || reason.starts_with("protocol error: ");
    assert!(fine, "the server closed: {reason} ({events:?})");
}
