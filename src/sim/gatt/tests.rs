//! The GATT-level droid: tables, handshakes, notifications, faults and sleep.

use super::*;
use crate::family::robi::gatt::{ROBI_FRAMES, ROBI_HANDSHAKE, ROBI_START, ROBI_VELOCITY};
use crate::family::v1::gatt::{V1_ANTI_DOS, V1_COMMANDS, V1_TX_POWER, V1_WAKE};
use crate::family::v2::gatt::{V2_ANTI_DOS, V2_ANTI_DOS_SERVICE, V2_API, V2_UNLOCK};
use crate::protocol::v2::{Decoder, Packet, cmd};

const MS: Duration = Duration::from_millis(1);

fn ms(n: u64) -> Duration {
    MS * n as u32
}

fn droid(model: Model, faults: GattFaults) -> GattDroid {
    GattDroid::new(model, SimConfig::for_model(model), faults)
}

/// Connected, services resolved, subscribed to the profile's notifications.
fn ready(model: Model) -> GattDroid {
    let mut d = droid(model, GattFaults::none());
    d.connect(ms(0)).unwrap();
    assert_eq!(d.advance(ms(1)), [GattEvent::ServicesResolved]);
    for c in d.profile().notify.clone() {
        d.start_notify(c.characteristic, ms(1)).unwrap();
    }
    d
}

fn notifications(events: &[GattEvent]) -> Vec<Vec<u8>> {
    events
        .iter()
        .filter_map(|e| match e {
            GattEvent::Notification { value, .. } => Some(value.clone()),
            _ => None,
        })
        .collect()
}

fn ping_v2() -> Vec<u8> {
    cmd::ping().to_packet(1).encode()
}

fn v2_packets(bytes: &[u8]) -> Vec<Packet> {
    Decoder::new()
        .decode_all(bytes)
        .into_iter()
        .filter_map(Result::ok)
        .collect()
}

#[test]
fn tables_hold_every_profile_characteristic() {
    for model in Model::ALL {
        let table = gatt_table(model);
        let profile = crate::family::gatt_profile(model);
        for c in profile.characteristics() {
            assert!(
                table
                    .iter()
                    .any(|s| s.characteristics.iter().any(|d| c.matches(s.uuid, d.uuid))),
                "{model:?}: {c} missing"
            );
        }
        assert_eq!(
            table[0].uuid, profile.service,
            "{model:?}: main service first"
        );
    }
    let v2 = gatt_table(Model::R2D2);
    assert_eq!(v2.len(), 2);
    assert_eq!(v2[1].uuid, V2_ANTI_DOS_SERVICE);
    let api = &v2[0].characteristics[0];
    assert_eq!(api.uuid, V2_API);
    assert_eq!(
        api.flags.names(),
        ["write-without-response", "write", "notify"]
    );
    let robi = gatt_table(Model::Robi42);
    let handshake = robi
        .iter()
        .flat_map(|s| &s.characteristics)
        .find(|c| c.uuid == ROBI_HANDSHAKE)
        .unwrap();
    assert_eq!(handshake.flags, CharFlags::READ);
}

#[test]
fn v2_ignores_commands_until_unlocked() {
    let mut d = ready(Model::R2D2);
    d.write(V2_API, &ping_v2(), ms(10)).unwrap();
    assert!(notifications(&d.advance(ms(20))).is_empty(), "locked");
    assert_eq!(d.state().commands, 0);
    // A wrong unlock does nothing either.
    d.write(V2_ANTI_DOS, b"usetheforce", ms(30)).unwrap();
    d.write(V2_API, &ping_v2(), ms(40)).unwrap();
    assert!(notifications(&d.advance(ms(50))).is_empty());
    d.write(V2_ANTI_DOS, V2_UNLOCK, ms(60)).unwrap();
    assert!(d.status().unlocked);
    d.write(V2_API, &ping_v2(), ms(70)).unwrap();
    let bytes = notifications(&d.advance(ms(80))).concat();
    let answers = v2_packets(&bytes);
    assert_eq!(answers.len(), 1, "{bytes:02x?}");
    assert!(answers[0].is_response());
    // A new connection is locked again.
    d.disconnect(ms(90)).unwrap();
    d.connect(ms(100)).unwrap();
    d.advance(ms(101));
    d.start_notify(V2_API, ms(101)).unwrap();
    d.write(V2_API, &ping_v2(), ms(110)).unwrap();
    assert!(notifications(&d.advance(ms(120))).is_empty());
}

#[test]
fn v1_needs_the_whole_wake_sequence_in_order() {
    let roll = crate::protocol::v1::Packet::Command(crate::protocol::v1::CommandPacket::new(
        0x02,
        0x30,
        1,
        vec![80, 0, 0, 1],
    ))
    .encode()
    .unwrap();
    let mut d = ready(Model::BB8);
    let send = |d: &mut GattDroid, t: u64| {
        d.write(V1_COMMANDS, &roll, ms(t)).unwrap();
        notifications(&d.advance(ms(t + 5)))
    };
    assert!(send(&mut d, 10).is_empty(), "asleep");
    // Wake before the unlock: ignored.
    d.write(V1_WAKE, &[1], ms(20)).unwrap();
    d.write(V1_ANTI_DOS, b"011i3", ms(30)).unwrap();
    assert!(send(&mut d, 40).is_empty(), "unlocked but not awake");
    d.write(V1_TX_POWER, &[7], ms(50)).unwrap();
    d.write(V1_WAKE, &[1], ms(60)).unwrap();
    assert!(d.status().unlocked);
    let answer = send(&mut d, 70).concat();
    assert!(
        answer.starts_with(&[0xFF, 0xFF, 0x00, 0x01]),
        "{answer:02x?}"
    );
    assert_eq!(d.state().commands, 1);
}

#[test]
fn robi_reads_its_handshake_and_frames_flow_after_the_start() {
    let mut d = ready(Model::Robi42);
    assert_eq!(d.read(ROBI_HANDSHAKE, ms(5)).unwrap().len(), 5);
    assert!(
        notifications(&d.advance(ms(500))).is_empty(),
        "no frames yet"
    );
    assert_eq!(
        d.read(ROBI_FRAMES, ms(500)),
        Err(GattError::ReadNotPermitted)
    );
    d.write(ROBI_START, &[1], ms(500)).unwrap();
    let events = d.advance(ms(1000));
    let frames = notifications(&events);
    // One frame per notification, every 100 ms.
    assert!((5..=6).contains(&frames.len()), "{}", frames.len());
    assert!(
        frames
            .iter()
            .all(|f| f[0] == 0x7E && f.last() == Some(&0x7F))
    );
    assert!(events.iter().all(|e| matches!(
        e,
        GattEvent::Notification { characteristic, .. } if *characteristic == ROBI_FRAMES
    )));
    // The remote control drives it.
    d.write(ROBI_VELOCITY, &[255], ms(1000)).unwrap();
    d.advance(ms(3000));
    assert!(d.state().y_cm.abs() + d.state().x_cm.abs() > 10.0);
    // The host goes: the motors stop.
    d.disconnect(ms(3000)).unwrap();
    d.advance(ms(4000));
    assert!(d.state().velocity_cm_s.abs() < 1.0);
}

#[test]
fn notifications_are_cut_at_20_bytes() {
    let mut d = ready(Model::R2D2);
    d.write(V2_ANTI_DOS, V2_UNLOCK, ms(1)).unwrap();
    // The connect setup turns on sensor streaming, whose packets are longer than 20 bytes.
    let c = crate::family::setup::connect_setup(
        Model::R2D2,
        &crate::family::setup::SetupOptions::default(),
    );
    for (i, cmd) in c.iter().enumerate() {
        let family = crate::family::for_model(Model::R2D2);
        let mut codec = family.codec();
        let (writes, _) = codec.encode_writes(cmd, i as u8, true);
        for (_, w) in writes {
            for chunk in w.chunks(20) {
                d.write(V2_API, chunk, ms(10 + i as u64 * 120)).unwrap();
            }
        }
    }
    let events = d.advance(ms(5000));
    let values = notifications(&events);
    assert!(values.len() > 20);
    assert!(values.iter().all(|v| !v.is_empty() && v.len() <= 20));
    assert!(values.iter().any(|v| v.len() == 20), "long packets are cut");
    let packets = v2_packets(&values.concat());
    assert!(packets.iter().any(|p| p.did == 0x18 && p.cid == 0x02));
    // Unsubscribed: silence.
    d.stop_notify(V2_API, ms(5000)).unwrap();
    assert!(notifications(&d.advance(ms(6000))).is_empty());
    assert_eq!(
        d.stop_notify(V2_API, ms(6000)),
        Err(GattError::NotNotifying)
    );
}

#[test]
fn one_connection_at_a_time() {
    let mut d = droid(Model::R2D2, GattFaults::none());
    d.connect(ms(0)).unwrap();
    assert_eq!(d.connect(ms(1)), Err(GattError::AlreadyConnected));
    d.disconnect(ms(2)).unwrap();
    assert_eq!(d.disconnect(ms(3)), Err(GattError::NotConnected));
    d.connect(ms(4)).unwrap();
    assert_eq!(d.status().connects, 2);
}

#[test]
fn operations_need_a_resolved_connection() {
    let mut faults = GattFaults::none();
    faults.add("slow-resolve=1.5").unwrap();
    let mut d = droid(Model::R2D2, faults);
    assert_eq!(d.write(V2_API, &[1], ms(0)), Err(GattError::NotConnected));
    d.connect(ms(0)).unwrap();
    assert!(d.advance(ms(1000)).is_empty());
    assert_eq!(
        d.start_notify(V2_API, ms(1000)),
        Err(GattError::NotResolved)
    );
    assert_eq!(d.advance(ms(1500)), [GattEvent::ServicesResolved]);
    d.start_notify(V2_API, ms(1500)).unwrap();
    assert_eq!(
        d.start_notify(V2_ANTI_DOS, ms(1500)),
        Err(GattError::NotifyNotSupported)
    );
    let unknown = GattUuid::from_u16(0x1234);
    assert_eq!(
        d.write(unknown, &[1], ms(1500)),
        Err(GattError::UnknownCharacteristic(unknown))
    );
    assert_eq!(
        d.write(V2_API, &[0; 513], ms(1500)),
        Err(GattError::InvalidLength(513))
    );
}

#[test]
fn refused_connections_then_accepted() {
    let mut faults = GattFaults::none();
    faults.add("refuse-connect=2").unwrap();
    let mut d = droid(Model::BB8, faults);
    assert_eq!(d.connect(ms(0)), Err(GattError::Refused));
    assert_eq!(d.connect(ms(10)), Err(GattError::Refused));
    d.connect(ms(20)).unwrap();
    assert_eq!(d.status().refused, 2);
    let mut always = GattFaults::none();
    always.add("refuse-connect").unwrap();
    let mut d = droid(Model::BB8, always);
    assert!((0..50).all(|i| d.connect(ms(i)) == Err(GattError::Refused)));
    assert!(!d.status().connected);
}

#[test]
fn the_disconnect_fault_drops_the_first_connection_only() {
    let mut faults = GattFaults::none();
    faults.add("disconnect-after=1").unwrap();
    let mut d = droid(Model::R2D2, faults);
    d.connect(ms(100)).unwrap();
    d.advance(ms(500));
    assert!(d.status().connected);
    let events = d.advance(ms(1200));
    assert_eq!(
        events.last(),
        Some(&GattEvent::Dropped {
            after: Duration::from_secs(1)
        })
    );
    assert!(!d.status().connected);
    assert_eq!(
        d.write(V2_API, &[1], ms(1300)),
        Err(GattError::NotConnected)
    );
    // Still there: a new connection lasts.
    d.connect(ms(2000)).unwrap();
    let later = d.advance(ms(10_000));
    assert!(!later.iter().any(|e| matches!(e, GattEvent::Dropped { .. })));
    assert_eq!(d.status().dropped, 1);

    let mut every = GattFaults::none();
    every.add("disconnect-every=0.5").unwrap();
    let mut d = droid(Model::R2D2, every);
    for i in 0..3u64 {
        d.connect(ms(i * 1000)).unwrap();
        let ev = d.advance(ms(i * 1000 + 600));
        assert!(matches!(ev.last(), Some(GattEvent::Dropped { .. })), "{i}");
    }
}

#[test]
fn fault_syntax() {
    let mut f = GattFaults::none();
    for spec in ["disconnect-after=2.5", "refuse-connect=3", "slow-resolve=1"] {
        f.add(spec).unwrap();
    }
    assert_eq!(
        f.describe(),
        ["disconnect-after=2.5", "refuse-connect=3", "slow-resolve=1"]
    );
    for bad in [
        "explode",
        "disconnect-after",
        "disconnect-after=soon",
        "slow-resolve=-1",
        "slow-resolve=NaN",
        "refuse-connect=many",
        "disconnect-every=0",
    ] {
        assert!(GattFaults::none().add(bad).is_err(), "{bad}");
    }
}

#[test]
fn time_never_runs_backwards() {
    let mut d = ready(Model::R2D2);
    d.advance(ms(1000));
    // An older time is taken as the current one.
    d.write(V2_ANTI_DOS, V2_UNLOCK, ms(10)).unwrap();
    d.advance(ms(5));
    assert!(d.status().unlocked);
}

#[test]
fn an_idle_droid_warns_then_falls_asleep_for_good() {
    let secs = |n: u64| Duration::from_secs(n);
    let faults = GattFaults {
        idle_sleep: Some(secs(2)),
        ..GattFaults::none()
    };
    let mut d = droid(Model::R2D2, faults.clone());
    d.connect(ms(0)).unwrap();
    d.advance(ms(1));
    let api = d.profile().notify[0].characteristic;
    d.start_notify(api, ms(1)).unwrap();
    d.write(V2_ANTI_DOS, V2_UNLOCK, ms(2)).unwrap();
    assert!(notifications(&d.advance(ms(1900))).is_empty());
    // The warning at 2 s without a command, once.
    let warned = v2_packets(&notifications(&d.advance(ms(2100))).concat());
    assert_eq!(warned.len(), 1);
    assert_eq!((warned[0].did, warned[0].cid), (0x13, 0x19));
    assert!(notifications(&d.advance(ms(3000))).is_empty());
    // A command puts it off; then nothing more: asleep 5 s after the next warning.
    d.write(V2_API, &ping_v2(), ms(4000)).unwrap();
    let evs = d.advance(ms(6100));
    assert!(
        v2_packets(&notifications(&evs).concat())
            .iter()
            .any(|p| (p.did, p.cid) == (0x13, 0x19))
    );
    assert!(!d.status().asleep);
    let evs = d.advance(ms(11_100));
    assert_eq!(evs.last(), Some(&GattEvent::Dropped { after: ms(11_000) }));
    assert!(d.status().asleep && !d.status().connected);
    assert_eq!(d.connect(ms(12_000)), Err(GattError::Asleep));
    // Robi has no sleep timer.
    let mut robi = droid(Model::Robi42, faults);
    robi.connect(ms(0)).unwrap();
    robi.advance(secs(60));
    assert!(robi.status().connected && !robi.status().asleep);
}
