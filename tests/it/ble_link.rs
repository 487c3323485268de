//! BleLink against the fake peripheral, all on tokio's paused clock: handshakes per model,
//! chunking, pacing, notifications as a byte stream, timeouts, and the session's reconnect path.

use droidctl::family::{v1::gatt as v1g, v2::gatt as v2g};
use droidctl::gatt::GattUuid;
use droidctl::link::backoff::Backoff;
use droidctl::link::ble::fake::{FakeCentral, FakeOp, FakePeripheral};
use droidctl::link::ble::{
    Advertisement, BleAddress, BleError, BleErrorKind, BleLink, DiscoveredChar,
};
use droidctl::link::{Connection, Link, LinkEvent};
use droidctl::model::Model;
use droidctl::protocol::v2::{Decoder, ErrorCode, Packet, cmd};
use droidctl::session::{self, LinkState, SessionConfig};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::watch;
use tokio::time::{Instant, sleep, timeout};

const ADDR: BleAddress = BleAddress([0xF1, 0x22, 0x33, 0x44, 0x55, 0x66]);

fn name_for(model: Model) -> String {
    match model.name_prefix() {
        Some(p) => format!("{p}1A2B"),
        None => "Robi 42".into(),
    }
}

/// An adapter holding one fake `model` droid; returns the adapter, the droid and its link.
fn setup(model: Model) -> (FakeCentral, FakePeripheral, BleLink) {
    let profile = droidctl::family::gatt_profile(model);
    let droid = FakePeripheral::for_profile(&profile);
    let central = FakeCentral::new();
    central.add_device(
        Advertisement {
            address: ADDR,
            name: Some(name_for(model)),
            rssi: Some(-50),
        },
        droid.clone(),
    );
    let link = BleLink::new(
        Arc::new(central.clone()),
        ADDR,
        name_for(model),
        model,
        droidctl::family::gatt_profile(model),
    );
    (central, droid, link)
}

async fn open(link: &mut BleLink) -> Connection {
    match link.open().await {
        Ok(c) => c,
        Err(e) => panic!("open failed: {e}"),
    }
}

fn write(ch: GattUuid, data: &[u8]) -> FakeOp {
    FakeOp::Write {
        ch,
        data: data.to_vec(),
    }
}

#[tokio::test(start_paused = true)]
async fn v2_handshake_is_unlock_then_subscribe() {
    let (_c, droid, mut link) = setup(Model::R2D2);
    let _conn = open(&mut link).await;
    assert_eq!(
        droid.ops(),
        [
            FakeOp::Connect,
            FakeOp::Discover,
            write(v2g::V2_ANTI_DOS, b"usetheforce...band"),
            FakeOp::Subscribe(v2g::V2_API),
        ]
    );
    assert_eq!(
        v2g::V2_API.to_string(),
        "00010002-574f-4f20-5370-6865726f2121"
    );
    assert_eq!(
        v2g::V2_ANTI_DOS.to_string(),
        "00020005-574f-4f20-5370-6865726f2121"
    );
    assert_eq!(link.describe(), "R2-D2 D2-1A2B (F1:22:33:44:55:66)");
}

#[tokio::test(start_paused = true)]
async fn v1_handshake_is_antidos_txpower_wake_then_subscribe() {
    for model in [Model::BB8, Model::SprkPlus, Model::Ollie] {
        let (_c, droid, mut link) = setup(model);
        let mut conn = open(&mut link).await;
        assert_eq!(
            droid.ops(),
            [
                FakeOp::Connect,
                FakeOp::Discover,
                write(v1g::V1_ANTI_DOS, b"011i3"),
                write(v1g::V1_TX_POWER, &[0x07]),
                write(v1g::V1_WAKE, &[0x01]),
                FakeOp::Subscribe(v1g::V1_RESPONSES),
            ],
            "{model:?}"
        );
        // Commands go to 2ba1.
        conn.writer.write(&[0xFF, 0xFF, 0x00, 0x01]).await.unwrap();
        assert_eq!(droid.writes_to(v1g::V1_COMMANDS).len(), 1);
        assert_eq!(
            v1g::V1_COMMANDS.to_string(),
            "22bb746f-2ba1-7554-2d6f-726568705327"
        );
    }
}

#[tokio::test(start_paused = true)]
async fn robi_handshake_reads_then_confirms_then_subscribes() {
    let (_c, droid, mut link) = setup(Model::Robi42);
    // Version 1, MSDT 10 ms (`droid-facts.md` §5).
    let handshake = vec![0x7E, 0x01, 0x00, 0x0A, 0x7F];
    droid.set_read(
        droidctl::family::robi::gatt::ROBI_HANDSHAKE,
        handshake.clone(),
    );
    let mut conn = open(&mut link).await;
    assert_eq!(
        droid.ops(),
        [
            FakeOp::Connect,
            FakeOp::Discover,
            FakeOp::Read(droidctl::family::robi::gatt::ROBI_HANDSHAKE),
            write(droidctl::family::robi::gatt::ROBI_START, &[0x01]),
            FakeOp::Subscribe(droidctl::family::robi::gatt::ROBI_FRAMES),
        ]
    );
    assert_eq!(
        droidctl::family::robi::gatt::ROBI_FRAMES.as_u16(),
        Some(0x8765)
    );
    // What the handshake read comes first, so the session learns the announced interval.
    assert_eq!(conn.events.recv().await, Some(LinkEvent::Data(handshake)));
    droid.notify(
        droidctl::family::robi::gatt::ROBI_FRAMES,
        &[0x7E, 0x01, 0x7F],
    );
    assert_eq!(
        conn.events.recv().await,
        Some(LinkEvent::Data(vec![0x7E, 0x01, 0x7F]))
    );
    // A write names its destination: the remote control's two characteristics.
    use droidctl::gatt::Endpoint;
    conn.writer
        .write_to(Endpoint::Velocity, &[200])
        .await
        .unwrap();
    conn.writer
        .write_to(Endpoint::Steering, &[128])
        .await
        .unwrap();
    assert_eq!(
        droid
            .writes_to(droidctl::family::robi::gatt::ROBI_VELOCITY)
            .into_iter()
            .map(|(_, d)| d)
            .collect::<Vec<_>>(),
        [vec![200]]
    );
    assert_eq!(
        droid
            .writes_to(droidctl::family::robi::gatt::ROBI_STEERING)
            .into_iter()
            .map(|(_, d)| d)
            .collect::<Vec<_>>(),
        [vec![128]]
    );
}

#[tokio::test(start_paused = true)]
async fn a_45_byte_write_is_three_chunks() {
    let (_c, droid, mut link) = setup(Model::R2D2);
    let mut conn = open(&mut link).await;
    let data: Vec<u8> = (0..45).collect();
    conn.writer.write(&data).await.unwrap();
    let writes = droid.writes_to(v2g::V2_API);
    let sizes: Vec<usize> = writes.iter().map(|(_, d)| d.len()).collect();
    assert_eq!(sizes, [20, 20, 5]);
    let joined: Vec<u8> = writes.into_iter().flat_map(|(_, d)| d).collect();
    assert_eq!(joined, data);
}

#[tokio::test(start_paused = true)]
async fn writes_are_paced_per_model_even_when_called_faster() {
    for (model, ms) in [(Model::R2D2, 120u64), (Model::BB8, 60)] {
        let (_c, droid, mut link) = setup(model);
        let mut conn = open(&mut link).await;
        let ch = link.profile().write.characteristic;
        let t0 = Instant::now();
        conn.writer.write(&[0u8; 45]).await.unwrap();
        conn.writer.write(&[1u8; 5]).await.unwrap();
        sleep(Duration::from_secs(1)).await;
        conn.writer.write(&[2u8; 3]).await.unwrap();
        let at: Vec<u64> = droid
            .writes_to(ch)
            .iter()
            .map(|(t, _)| t.duration_since(t0).as_millis() as u64)
            .collect();
        // Back-to-back chunks and calls wait out the pacing; a write after a pause does not.
        let last = 3 * ms + 1000;
        assert_eq!(at, [0, ms, 2 * ms, 3 * ms, last], "{model:?}");
    }
}

/// The emergency stop's write does not wait out the pacing slot; the pacing after it counts
/// from it.
#[tokio::test(start_paused = true)]
async fn an_urgent_write_skips_the_pacing_slot() {
    let (_c, droid, mut link) = setup(Model::R2D2);
    let mut conn = open(&mut link).await;
    let ch = link.profile().write.characteristic;
    let t0 = Instant::now();
    conn.writer.write(&[0u8; 5]).await.unwrap();
    sleep(Duration::from_millis(10)).await;
    conn.writer
        .write_urgent(droidctl::gatt::Endpoint::Api, &[1u8; 5])
        .await
        .unwrap();
    conn.writer.write(&[2u8; 5]).await.unwrap();
    let at: Vec<u64> = droid
        .writes_to(ch)
        .iter()
        .map(|(t, _)| t.duration_since(t0).as_millis() as u64)
        .collect();
    assert_eq!(
        at,
        [0, 10, 130],
        "the urgent write at once, the next one a slot after it"
    );
}

#[tokio::test(start_paused = true)]
async fn notifications_are_one_byte_stream() {
    let (_c, droid, mut link) = setup(Model::R2D2);
    let mut conn = open(&mut link).await;
    // A response split across three notifications, plus noise on another characteristic.
    let packet = Packet::response_to(&cmd::wake().to_packet(7), ErrorCode::Success, vec![]);
    let wire = packet.encode();
    droid.notify(v2g::V2_API, &wire[..3]);
    droid.notify(v2g::V2_ANTI_DOS, &[0xAA]);
    droid.notify(v2g::V2_API, &wire[3..5]);
    droid.notify(v2g::V2_API, &wire[5..]);
    let mut bytes = Vec::new();
    for _ in 0..3 {
        match conn.events.recv().await {
            Some(LinkEvent::Data(d)) => bytes.extend(d),
            other => panic!("unexpected {other:?}"),
        }
    }
    assert_eq!(bytes, wire);
    let decoded: Vec<Packet> = Decoder::new().feed(&bytes).flatten().collect();
    assert_eq!(decoded, [packet]);
}

#[tokio::test(start_paused = true)]
async fn a_disconnect_becomes_a_link_event() {
    let (_c, droid, mut link) = setup(Model::R2D2);
    let mut conn = open(&mut link).await;
    droid.drop_connection("supervision timeout");
    assert_eq!(
        conn.events.recv().await,
        Some(LinkEvent::Disconnected("supervision timeout".into()))
    );
    assert_eq!(conn.events.recv().await, None);
}

#[tokio::test(start_paused = true)]
async fn a_failed_write_is_an_error() {
    let (_c, droid, mut link) = setup(Model::R2D2);
    let mut conn = open(&mut link).await;
    droid.fail_next_write(BleError::from_dbus(
        Some("org.bluez.Error.Failed"),
        "Not connected",
    ));
    let e = conn.writer.write(&[1, 2, 3]).await.unwrap_err();
    assert!(!e.fatal, "{e}");
}

#[tokio::test(start_paused = true)]
async fn a_sleeping_droid_times_out_and_is_retryable() {
    let (_c, droid, mut link) = setup(Model::R2D2);
    droid.hang_connect(true);
    let t0 = Instant::now();
    let e = link.open().await.err().unwrap();
    assert_eq!(t0.elapsed(), Duration::from_secs(10));
    assert!(!e.fatal);
    assert!(
        e.message
            .starts_with("connecting to D2-1A2B timed out after 10 s"),
        "{e}"
    );
    // The pending connect is cancelled.
    assert_eq!(droid.ops(), [FakeOp::Connect, FakeOp::Disconnect]);
}

#[tokio::test(start_paused = true)]
async fn the_wrong_device_is_fatal() {
    // Something called D2-… without the anti-DoS characteristic.
    let droid = FakePeripheral::new(vec![DiscoveredChar {
        service: v2g::V2_SERVICE,
        characteristic: v2g::V2_API,
    }]);
    let central = FakeCentral::new();
    central.add_device(
        Advertisement {
            address: ADDR,
            name: Some("D2-FAKE".into()),
            rssi: None,
        },
        droid.clone(),
    );
    let mut link = BleLink::new(
        Arc::new(central),
        ADDR,
        "D2-FAKE",
        Model::R2D2,
        droidctl::family::gatt_profile(Model::R2D2),
    );
    let e = link.open().await.err().unwrap();
    assert!(e.fatal, "{e}");
    assert!(e.message.contains("does not look like a R2-D2"), "{e}");
    assert!(
        !droid.is_connected(),
        "disconnects after a failed handshake"
    );
}

#[tokio::test(start_paused = true)]
async fn a_forgotten_device_is_scanned_for_again() {
    let profile = droidctl::family::gatt_profile(Model::R2D2);
    let droid = FakePeripheral::for_profile(&profile);
    let central = FakeCentral::new();
    let mut link = BleLink::new(
        Arc::new(central.clone()),
        ADDR,
        "D2-1A2B",
        Model::R2D2,
        droidctl::family::gatt_profile(Model::R2D2),
    );
    // Not known at all: a bounded rescan, then a retryable error.
    let e = link.open().await.err().unwrap();
    assert!(!e.fatal);
    assert!(e.message.contains("is not advertising"), "{e}");
    // It wakes up two seconds into the next attempt's rescan.
    let c2 = central.clone();
    let d2 = droid.clone();
    tokio::spawn(async move {
        sleep(Duration::from_secs(2)).await;
        c2.add_device(
            Advertisement {
                address: ADDR,
                name: Some("D2-1A2B".into()),
                rssi: Some(-60),
            },
            d2,
        );
    });
    let _conn = open(&mut link).await;
    assert!(droid.is_connected());
    assert_eq!(central.scans(), 2);
}

/// Records every state the session goes through.
fn record(mut rx: watch::Receiver<LinkState>) -> Arc<Mutex<Vec<LinkState>>> {
    let seen = Arc::new(Mutex::new(vec![rx.borrow_and_update().clone()]));
    let out = seen.clone();
    tokio::spawn(async move {
        while rx.changed().await.is_ok() {
            let s = rx.borrow_and_update().clone();
            out.lock().unwrap().push(s);
        }
    });
    seen
}

async fn wait_for(rx: &mut watch::Receiver<LinkState>, want: impl Fn(&LinkState) -> bool) {
    timeout(Duration::from_secs(120), async {
        loop {
            if want(&rx.borrow_and_update()) {
                return;
            }
            rx.changed().await.unwrap();
        }
    })
    .await
    .expect("state not reached");
}

/// The wake commands the session wrote, decoded from the fake's write log.
fn wakes_written(droid: &FakePeripheral) -> usize {
    let bytes: Vec<u8> = droid
        .writes_to(v2g::V2_API)
        .into_iter()
        .flat_map(|(_, d)| d)
        .collect();
    let wake = cmd::wake();
    Decoder::new()
        .feed(&bytes)
        .flatten()
        .filter(|p| p.did == wake.did && p.cid == wake.cid)
        .count()
}

fn count(droid: &FakePeripheral, op: &FakeOp) -> usize {
    droid.ops().iter().filter(|o| *o == op).count()
}

#[tokio::test(start_paused = true)]
async fn session_reconnects_and_reruns_handshake_and_setup() {
    let (_c, droid, link) = setup(Model::R2D2);
    let cfg = SessionConfig {
        setup: vec![cmd::wake().into()],
        pacing: link.profile().pacing,
        chunk_size: link.profile().chunk_size,
        ..SessionConfig::default()
    };
    let s = session::start(Box::new(link), cfg);
    let mut rx = s.watch_state();
    let seen = record(s.watch_state());
    wait_for(&mut rx, |st| *st == LinkState::Connected).await;
    sleep(Duration::from_millis(500)).await;
    assert_eq!(wakes_written(&droid), 1);

    droid.drop_connection("droid went out of range");
    let lost = Instant::now();
    wait_for(&mut rx, |st| matches!(st, LinkState::Reconnecting { .. })).await;
    wait_for(&mut rx, |st| *st == LinkState::Connected).await;
    // The default backoff waits 500 ms before the first retry.
    assert_eq!(lost.elapsed(), Backoff::default().delay(1));
    sleep(Duration::from_millis(500)).await;

    assert_eq!(
        *seen.lock().unwrap(),
        [
            LinkState::Connecting,
            LinkState::Connected,
            LinkState::Reconnecting {
                attempt: 1,
                reason: "droid went out of range".into()
            },
            LinkState::Connected,
        ]
    );
    let unlock = write(v2g::V2_ANTI_DOS, b"usetheforce...band");
    assert_eq!(count(&droid, &FakeOp::Connect), 2);
    assert_eq!(count(&droid, &unlock), 2, "handshake re-run");
    assert_eq!(count(&droid, &FakeOp::Subscribe(v2g::V2_API)), 2);
    assert_eq!(wakes_written(&droid), 2, "setup commands written again");
    assert_eq!(s.stats().reconnects, 1);
    s.shutdown(vec![]).await;
    assert!(!droid.is_connected(), "shutdown disconnects");
}

#[tokio::test(start_paused = true)]
async fn failed_reconnects_follow_the_backoff_schedule() {
    let (_c, droid, link) = setup(Model::R2D2);
    let s = session::start(Box::new(link), SessionConfig::default());
    let mut rx = s.watch_state();
    wait_for(&mut rx, |st| *st == LinkState::Connected).await;
    droid.fail_connects(2);
    droid.clear_ops();
    let lost = Instant::now();
    droid.drop_connection("link loss");
    wait_for(&mut rx, |st| {
        matches!(st, LinkState::Reconnecting { attempt: 3, .. })
    })
    .await;
    wait_for(&mut rx, |st| *st == LinkState::Connected).await;
    let connects: Vec<u64> = droid
        .timed_ops()
        .into_iter()
        .filter(|(_, o)| *o == FakeOp::Connect)
        .map(|(t, _)| t.duration_since(lost).as_millis() as u64)
        .collect();
    // 500 ms, then 1 s, then 2 s between attempts (`Backoff::default()`).
    assert_eq!(connects, [500, 1500, 3500]);
    s.shutdown(vec![]).await;
}

#[tokio::test(start_paused = true)]
async fn a_fatal_open_error_closes_the_session() {
    let central = FakeCentral::new();
    central.fail_scan(BleError::no_adapter());
    // Unknown device → rescan → the adapter error, which retrying cannot fix.
    let link = BleLink::new(
        Arc::new(central),
        ADDR,
        "D2-1A2B",
        Model::R2D2,
        droidctl::family::gatt_profile(Model::R2D2),
    );
    let s = session::start(Box::new(link), SessionConfig::default());
    let mut rx = s.watch_state();
    wait_for(&mut rx, |st| matches!(st, LinkState::Closed { .. })).await;
    match s.state() {
        LinkState::Closed { reason: Some(r) } => {
            assert!(r.contains("no Bluetooth adapter found"), "{r}");
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(BleError::no_adapter().kind, BleErrorKind::NoAdapter);
}

/// The drive commands (speed, heading) written to the API characteristic since `from`.
fn drives_written(droid: &FakePeripheral, from: Instant) -> Vec<(u8, u16)> {
    let bytes: Vec<u8> = droid
        .writes_to(v2g::V2_API)
        .into_iter()
        .filter(|(t, _)| *t >= from)
        .flat_map(|(_, d)| d)
        .collect();
    Decoder::new()
        .feed(&bytes)
        .flatten()
        .filter(|p| (p.did, p.cid) == (0x16, 0x07))
        .map(|p| (p.data[0], u16::from_be_bytes([p.data[1], p.data[2]])))
        .collect()
}

/// The adapter switched off mid-session is not fatal: the link says it waits, and reconnects
/// as soon as the adapter is powered again (not after the backoff), resuming at speed 0 at
/// the last heading.
#[tokio::test(start_paused = true)]
async fn the_adapter_switched_off_mid_session_is_waited_for() {
    use droidctl::protocol::v2::wire::DriveFlags;
    use droidctl::session::Slot;
    use droidctl::units::Heading;
    let (central, droid, link) = setup(Model::R2D2);
    let cfg = SessionConfig {
        setup: vec![cmd::wake().into()],
        pacing: link.profile().pacing,
        chunk_size: link.profile().chunk_size,
        ..SessionConfig::default()
    };
    let s = session::start(Box::new(link), cfg);
    let mut rx = s.watch_state();
    wait_for(&mut rx, |st| *st == LinkState::Connected).await;
    let heading = Heading::new(90).unwrap();
    s.set(
        Slot::Drive,
        cmd::drive_with_heading(60, heading, DriveFlags::empty()),
    );
    sleep(Duration::from_millis(500)).await;
    central.set_powered(false);
    wait_for(&mut rx, |st| {
        matches!(st, LinkState::Reconnecting { reason, .. } if reason == droidctl::link::ADAPTER_OFF_WAITING)
    })
    .await;
    assert_eq!(s.state().label(), "Bluetooth adapter is off — waiting");
    // Long after the backoff's cap it still waits, never gives up.
    sleep(Duration::from_secs(60)).await;
    assert!(
        matches!(s.state(), LinkState::Reconnecting { .. }),
        "{:?}",
        s.state()
    );
    let on = Instant::now();
    central.set_powered(true);
    wait_for(&mut rx, |st| *st == LinkState::Connected).await;
    assert!(
        on.elapsed() <= Duration::from_millis(500),
        "reconnects once the adapter is on: {:?}",
        on.elapsed()
    );
    sleep(Duration::from_millis(500)).await;
    assert_eq!(
        drives_written(&droid, on).first(),
        Some(&(0, 90)),
        "resumes at speed 0 at the last heading"
    );
    s.shutdown(vec![]).await;
}

/// At the first open the adapter off is fatal, one line naming the fix.
#[tokio::test(start_paused = true)]
async fn the_adapter_off_at_the_first_open_is_fatal() {
    let (central, _droid, mut link) = setup(Model::R2D2);
    central.set_powered(false);
    let e = link.open().await.err().unwrap();
    assert!(e.fatal, "{e}");
    assert!(e.message.contains("bluetoothctl power on"), "{e}");
    assert!(!e.message.contains('\n'));
}

/// A characteristic missing on a reconnect (services half-resolved) is retried with the
/// backoff; on the first open it stays fatal (`the_wrong_device_is_fatal`).
#[tokio::test(start_paused = true)]
async fn a_characteristic_missing_on_a_reconnect_is_retried() {
    let (_central, droid, link) = setup(Model::R2D2);
    let s = session::start(Box::new(link), SessionConfig::default());
    let mut rx = s.watch_state();
    wait_for(&mut rx, |st| *st == LinkState::Connected).await;
    droid.set_chars(vec![DiscoveredChar {
        service: v2g::V2_SERVICE,
        characteristic: v2g::V2_API,
    }]);
    droid.drop_connection("link loss");
    wait_for(&mut rx, |st| {
        matches!(st, LinkState::Reconnecting { attempt: 3, reason } if reason.contains("has no characteristic"))
    })
    .await;
    droid.set_chars(
        droidctl::family::gatt_profile(Model::R2D2)
            .characteristics()
            .into_iter()
            .map(|c| DiscoveredChar {
                service: c.service.unwrap_or(v2g::V2_SERVICE),
                characteristic: c.characteristic,
            })
            .collect(),
    );
    wait_for(&mut rx, |st| *st == LinkState::Connected).await;
    s.shutdown(vec![]).await;
}

// ---------------------------------------------------------------------------------------------
// A v1 droid (BB-8) over BleLink: wake sequence, v1 setup on 2ba1, pacing, responses on 2ba6,
// and the reconnect path.
// ---------------------------------------------------------------------------------------------

mod v1_session {
    use super::*;
    use droidctl::family::setup::{SetupOptions, connect_setup};
    use droidctl::protocol::v1::{
        self, CommandPacket, Decoder as V1Decoder, Mrsp, Packet as V1Packet, Response, Source,
    };

    /// The wake sequence of `droid-facts.md` §4, then the subscription to 2ba6.
    fn wake_sequence() -> Vec<FakeOp> {
        vec![
            FakeOp::Connect,
            FakeOp::Discover,
            write(v1g::V1_ANTI_DOS, b"011i3"),
            write(v1g::V1_TX_POWER, &[0x07]),
            write(v1g::V1_WAKE, &[0x01]),
            FakeOp::Subscribe(v1g::V1_RESPONSES),
        ]
    }

    /// Every command written to 2ba1 so far, decoded as the droid reads them.
    fn commands_written(droid: &FakePeripheral) -> Vec<CommandPacket> {
        let bytes: Vec<u8> = droid
            .writes_to(v1g::V1_COMMANDS)
            .into_iter()
            .flat_map(|(_, d)| d)
            .collect();
        V1Decoder::new(Source::Host)
            .feed(&bytes)
            .map(|r| match r {
                Ok(V1Packet::Command(c)) => c,
                other => panic!("not a command on 2ba1: {other:?}"),
            })
            .collect()
    }

    fn ids(cmds: &[CommandPacket]) -> Vec<(u8, u8)> {
        cmds.iter().map(|c| (c.did, c.cid)).collect()
    }

    fn setup_ids() -> Vec<(u8, u8)> {
        connect_setup(Model::BB8, &SetupOptions::default())
            .iter()
            .map(|c| (c.did(), c.cid()))
            .collect()
    }

    /// Notify a v1 response on 2ba6, cut into notifications of at most `piece` bytes.
    fn answer(droid: &FakePeripheral, to: &CommandPacket, data: Vec<u8>, piece: usize) {
        let wire = V1Packet::Response(Response::to(to, Mrsp::Ok, data))
            .encode()
            .unwrap();
        for chunk in wire.chunks(piece) {
            droid.notify(v1g::V1_RESPONSES, chunk);
        }
    }

    /// Plays the droid's part: answers every command written to 2ba1 that asks for an answer
    /// (Get Power State with 3.87 V), split over two notifications.
    fn spawn_responder(droid: FakePeripheral) -> tokio::task::JoinHandle<()> {
        tokio::spawn(async move {
            let mut decoder = V1Decoder::new(Source::Host);
            let mut seen = 0;
            loop {
                sleep(Duration::from_millis(5)).await;
                let writes = droid.writes_to(v1g::V1_COMMANDS);
                for (_, w) in &writes[seen..] {
                    let cmds: Vec<_> = decoder.feed(w).collect();
                    for c in cmds {
                        let Ok(V1Packet::Command(c)) = c else {
                            panic!("not a command: {c:?}")
                        };
                        if !c.answer() {
                            continue;
                        }
                        let data = match (c.did, c.cid) {
                            // Record 1, state OK, 3.87 V, 5 charges, 60 s.
                            (0x00, 0x20) => vec![1, 2, 0x01, 0x83, 0, 5, 0, 60],
                            _ => vec![],
                        };
                        answer(&droid, &c, data, 4);
                    }
                }
                seen = writes.len();
            }
        })
    }

    fn bb8_config(link: &BleLink) -> SessionConfig {
        SessionConfig {
            family: Model::BB8.protocol(),
            setup: connect_setup(Model::BB8, &SetupOptions::default()),
            pacing: link.profile().pacing,
            chunk_size: link.profile().chunk_size,
            ..SessionConfig::default()
        }
    }

    #[tokio::test(start_paused = true)]
    async fn bb8_session_wakes_runs_the_v1_setup_paced_and_is_answered() {
        let (_c, droid, link) = setup(Model::BB8);
        assert_eq!(link.profile().pacing, Duration::from_millis(60));
        let cfg = bb8_config(&link);
        let s = session::start(Box::new(link), cfg);
        let responder = spawn_responder(droid.clone());
        let mut rx = s.watch_state();
        wait_for(&mut rx, |st| *st == LinkState::Connected).await;
        sleep(Duration::from_secs(1)).await;
        assert_eq!(droid.ops()[..6], wake_sequence()[..], "{:?}", droid.ops());
        // The v1 setup, in order, on 2ba1.
        let written = commands_written(&droid);
        assert_eq!(ids(&written), setup_ids());
        // Issue 15: the fail-safe (stop on disconnect) goes first.
        assert_eq!(
            written[0],
            v1::cmd::set_temporary_option_flags(1).to_packet(written[0].seq),
            "asks for an answer and resets the inactivity timeout (SOP2 FF)"
        );
        assert_eq!(
            written[1],
            v1::cmd::ping().to_packet(written[1].seq),
            "then the ping"
        );
        let streaming = written.iter().find(|c| c.cid == 0x11).unwrap();
        let cfg = v1::StreamingConfig::from_command_data(&streaming.data).unwrap();
        assert_eq!((cfg.n, cfg.m, cfg.pcnt), (40, 1, 0), "10 Hz, forever");
        // Each answered by SEQ: nothing timed out, nothing retried.
        let st = s.stats();
        assert_eq!((st.timeouts, st.retried, st.answered), (0, 0, 6), "{st:?}");

        // A request, answered through 2ba6 in pieces.
        let power = s
            .request(v1::cmd::get_power_state())
            .await
            .expect("answered");
        let family = droidctl::family::for_model(Model::BB8);
        assert_eq!(family.battery_volts(power.data()), Some(3.87));

        // Writes are paced at the model's 60 ms, also when queued back to back.
        for i in 0..4 {
            s.send(v1::cmd::set_rgb_led(i, 0, 0, false)).unwrap();
        }
        sleep(Duration::from_secs(1)).await;
        let times: Vec<Instant> = droid
            .writes_to(v1g::V1_COMMANDS)
            .into_iter()
            .map(|(t, _)| t)
            .collect();
        assert!(times.len() >= 10, "{}", times.len());
        for w in times.windows(2) {
            assert!(
                w[1] - w[0] >= Duration::from_millis(60),
                "{:?}",
                w[1] - w[0]
            );
        }
        assert_eq!(s.stats().timeouts, 0);
        responder.abort();
        s.shutdown(vec![]).await;
        assert!(!droid.is_connected());
    }

    #[tokio::test(start_paused = true)]
    async fn a_v1_response_injected_on_2ba6_answers_the_request_by_seq() {
        let (_c, droid, link) = setup(Model::BB8);
        let cfg = SessionConfig {
            setup: Vec::new(),
            ..bb8_config(&link)
        };
        let s = session::start(Box::new(link), cfg);
        let mut rx = s.watch_state();
        wait_for(&mut rx, |st| *st == LinkState::Connected).await;
        let req = {
            let s = s.clone();
            tokio::spawn(async move { s.request(v1::cmd::get_rgb_led()).await })
        };
        sleep(Duration::from_millis(100)).await;
        let written = commands_written(&droid);
        assert_eq!(ids(&written), [(0x02, 0x22)]);
        // A stale answer with another SEQ matches nothing.
        let other = v1::cmd::get_rgb_led().to_packet(written[0].seq.wrapping_add(7));
        answer(&droid, &other, vec![9, 9, 9], 20);
        // The real one, one byte per notification.
        answer(&droid, &written[0], vec![255, 64, 0], 1);
        let r = timeout(Duration::from_secs(1), req)
            .await
            .expect("answered in time")
            .unwrap()
            .expect("success");
        assert_eq!(r.data(), [255, 64, 0]);
        let st = s.stats();
        assert_eq!((st.answered, st.unmatched, st.errors), (1, 1, 0), "{st:?}");
        s.shutdown(vec![]).await;
    }

    #[tokio::test(start_paused = true)]
    async fn bb8_reconnect_reruns_the_wake_sequence_and_the_setup() {
        let (_c, droid, link) = setup(Model::BB8);
        let cfg = bb8_config(&link);
        let s = session::start(Box::new(link), cfg);
        let responder = spawn_responder(droid.clone());
        let mut rx = s.watch_state();
        let seen = record(s.watch_state());
        wait_for(&mut rx, |st| *st == LinkState::Connected).await;
        sleep(Duration::from_secs(1)).await;
        assert_eq!(ids(&commands_written(&droid)), setup_ids());
        // Drive, so the reconnect also ends with a stop at the last heading.
        let roll = v1::cmd::roll(
            80,
            droidctl::units::Heading::new(90).unwrap(),
            v1::RollState::Go,
        );
        s.set(droidctl::session::Slot::Drive, roll);
        sleep(Duration::from_millis(200)).await;

        droid.drop_connection("BB-8 went out of range");
        let lost = Instant::now();
        wait_for(&mut rx, |st| matches!(st, LinkState::Reconnecting { .. })).await;
        wait_for(&mut rx, |st| *st == LinkState::Connected).await;
        assert_eq!(lost.elapsed(), Backoff::default().delay(1));
        sleep(Duration::from_secs(1)).await;
        assert_eq!(
            *seen.lock().unwrap(),
            [
                LinkState::Connecting,
                LinkState::Connected,
                LinkState::Reconnecting {
                    attempt: 1,
                    reason: "BB-8 went out of range".into()
                },
                LinkState::Connected,
            ]
        );
        // The wake sequence again, in order, after the drop.
        let ops = droid.ops();
        let second = ops
            .iter()
            .rposition(|o| *o == FakeOp::Connect)
            .expect("reconnected");
        assert_eq!(ops[second..second + 6], wake_sequence()[..], "{ops:?}");
        assert_eq!(count(&droid, &FakeOp::Connect), 2);
        // Issue 15, stop first: after the reconnect a stop (Roll state 0) keeping the
        // heading, then the setup again.
        let written = commands_written(&droid);
        let setup = setup_ids();
        let mut expected = setup.clone();
        expected.push((0x02, 0x30));
        expected.push((0x02, 0x30));
        expected.extend(&setup);
        assert_eq!(ids(&written), expected);
        let stop = &written[setup.len() + 1];
        assert_eq!(stop.data, [0, 0, 90, 0], "speed 0, heading 90, state stop");
        assert_eq!(s.stats().reconnects, 1);
        assert_eq!(s.stats().timeouts, 0);
        responder.abort();
        s.shutdown(vec![]).await;
        assert!(!droid.is_connected(), "shutdown disconnects");
    }
}

/// Issue 15: quitting while a connect is still pending cancels that attempt too, so BlueZ is
/// not left connecting (which hides the droid from the phone app).
#[tokio::test(start_paused = true)]
async fn quitting_mid_connect_cancels_the_attempt() {
    let (_c, droid, link) = setup(Model::R2D2);
    droid.hang_connect(true);
    let s = session::start(Box::new(link), SessionConfig::default());
    sleep(Duration::from_secs(2)).await;
    assert_eq!(droid.ops(), [FakeOp::Connect], "still connecting");
    let t0 = Instant::now();
    s.shutdown(vec![]).await;
    assert!(t0.elapsed() <= Duration::from_secs(3), "{:?}", t0.elapsed());
    assert_eq!(
        droid.ops(),
        [FakeOp::Connect, FakeOp::Disconnect],
        "the pending connect was cancelled"
    );
}
