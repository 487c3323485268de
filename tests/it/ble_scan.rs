//! Scanning and choosing a droid over the fake adapter: model detection from advertised names,
//! sorting, early stop, and what `connect_link_with` hands back.

use droidctl::link::ble::fake::{FakeCentral, FakePeripheral};
use droidctl::link::ble::scan::{self, summarize};
use droidctl::link::ble::{
    Advertisement, BleAddress, BleErrorKind, DeviceId, DeviceSelector, connect_link_with,
};
use droidctl::link::{Link, LinkEvent};
use droidctl::model::Model;
use std::sync::Arc;
use std::time::Duration;
use tokio::time::Instant;

fn ad(name: &str, last: u8, rssi: i16) -> Advertisement {
    Advertisement {
        address: BleAddress([0xE0, 0, 0, 0, 0, last]),
        name: Some(name.into()),
        rssi: Some(rssi),
    }
}

#[test]
fn models_from_advertised_names() {
    let cases = [
        ("D2-1A2B", Some(Model::R2D2)),
        ("Q5-77C1", Some(Model::R2Q5)),
        ("GB-0E9F", Some(Model::BB9E)),
        ("BB-8C3D", Some(Model::BB8)),
        ("SK-1234", Some(Model::SprkPlus)),
        ("2B-5678", Some(Model::Ollie)),
        ("Robi 42", Some(Model::Robi42)),
        ("d2-1a2b", None),
        ("R2-D2", None),
        ("Bose QC35", None),
    ];
    let ads: Vec<Advertisement> = cases
        .iter()
        .enumerate()
        .map(|(i, (n, _))| ad(n, i as u8, -50 - i as i16))
        .collect();
    let got = summarize(&ads, true);
    for (name, want) in cases {
        let e = got
            .iter()
            .find(|e| e.name.as_deref() == Some(name))
            .unwrap();
        assert_eq!(e.model, want, "{name}");
    }
    assert_eq!(summarize(&ads, false).len(), 7);
}

fn central_with_droids() -> FakeCentral {
    let c = FakeCentral::new();
    for (name, last, rssi, model) in [
        ("D2-FAR0", 1, -80, Model::R2D2),
        ("BB-NEAR", 2, -45, Model::BB8),
        ("Q5-MID0", 3, -60, Model::R2Q5),
    ] {
        c.add_device(
            ad(name, last, rssi),
            FakePeripheral::for_profile(&droidctl::family::gatt_profile(model)),
        );
    }
    c.advertise(ad("Headphones", 9, -30), Duration::ZERO);
    c
}

#[tokio::test(start_paused = true)]
async fn strongest_supported_droid_by_default() {
    let c = central_with_droids();
    let t0 = Instant::now();
    let found = connect_link_with(
        Arc::new(c),
        &DeviceSelector::default(),
        droidctl::family::gatt_profile,
    )
    .await
    .unwrap();
    assert_eq!(t0.elapsed(), Duration::from_secs(5), "the full scan");
    assert_eq!(found.name, "BB-NEAR");
    assert_eq!(found.model, Model::BB8);
    assert_eq!(found.address, BleAddress([0xE0, 0, 0, 0, 0, 2]));
    let names: Vec<String> = found.candidates.iter().map(|e| e.label()).collect();
    assert_eq!(names, ["Headphones", "BB-NEAR", "Q5-MID0", "D2-FAR0"]);
    assert_eq!(found.link.model(), Model::BB8);
}

#[tokio::test(start_paused = true)]
async fn by_name_stops_the_scan_early_and_connects() {
    let c = central_with_droids();
    c.add_device(
        ad("D2-LATE", 7, -90),
        FakePeripheral::for_profile(&droidctl::family::gatt_profile(Model::R2D2)),
    );
    let sel = DeviceSelector {
        name: Some("d2-far0".into()),
        scan_timeout: Duration::from_secs(30),
        ..DeviceSelector::default()
    };
    let t0 = Instant::now();
    let found = connect_link_with(Arc::new(c.clone()), &sel, droidctl::family::gatt_profile)
        .await
        .unwrap();
    assert!(t0.elapsed() < Duration::from_secs(1), "{:?}", t0.elapsed());
    assert_eq!(found.name, "D2-FAR0");
    let mut link = found.link;
    let mut conn = link.open().await.unwrap();
    drop(c);
    conn.writer.write(&[1, 2, 3]).await.unwrap();
    conn.writer.close().await;
    assert!(matches!(
        conn.events.recv().await,
        Some(LinkEvent::Disconnected(_))
    ));
}

#[tokio::test(start_paused = true)]
async fn by_address_and_errors() {
    let c = central_with_droids();
    let sel = DeviceSelector {
        address: Some("E0:00:00:00:00:03".parse().unwrap()),
        ..DeviceSelector::default()
    };
    let found = connect_link_with(Arc::new(c.clone()), &sel, droidctl::family::gatt_profile)
        .await
        .unwrap();
    assert_eq!(found.model, Model::R2Q5);

    let sel = DeviceSelector {
        name: Some("Headphones".into()),
        ..DeviceSelector::default()
    };
    let e = connect_link_with(Arc::new(c.clone()), &sel, droidctl::family::gatt_profile)
        .await
        .err()
        .unwrap();
    assert_eq!(e.kind, BleErrorKind::Selection);
    assert!(e.fatal());

    let empty = FakeCentral::new();
    let e = connect_link_with(
        Arc::new(empty),
        &DeviceSelector::default(),
        droidctl::family::gatt_profile,
    )
    .await
    .err()
    .unwrap();
    assert_eq!(e.kind, BleErrorKind::NotFound);
    assert!(e.message.starts_with("no droid found in 5 s"), "{e}");
}

#[tokio::test(start_paused = true)]
async fn late_advertisers_are_heard_within_the_timeout() {
    let c = FakeCentral::new();
    c.advertise(ad("D2-SLOW", 1, -70), Duration::from_millis(1800));
    c.advertise(ad("D2-TOOLATE", 2, -40), Duration::from_millis(2500));
    let got = scan::scan(&c, Duration::from_secs(2), |_| false)
        .await
        .unwrap();
    let names: Vec<String> = got.iter().map(|e| e.label()).collect();
    assert_eq!(names, ["D2-SLOW"]);
}

/// CoreBluetooth reports the address 00:00:00:00:00:00 for every device: two droids with
/// that address are still two droids, told apart and chosen by their identifiers.
#[tokio::test(start_paused = true)]
async fn two_droids_with_one_address_are_two_droids() {
    let c = FakeCentral::new();
    let zero = Some(BleAddress::default());
    let near = FakePeripheral::for_profile(&droidctl::family::gatt_profile(Model::R2D2));
    let far = FakePeripheral::for_profile(&droidctl::family::gatt_profile(Model::R2D2));
    let near_id = DeviceId::new("8e5b5b4e-1234-4a6b-9c8d-0123456789ab", zero);
    let far_id = DeviceId::new("0f000000-5678-4a6b-9c8d-0123456789ab", zero);
    c.add_device_as(near_id.clone(), Some("D2-NEAR"), Some(-40), near.clone());
    c.add_device_as(far_id.clone(), Some("D2-FAR0"), Some(-80), far.clone());
    let got = scan::scan(&c, Duration::from_secs(1), |_| false)
        .await
        .unwrap();
    let names: Vec<String> = got.iter().map(|e| e.label()).collect();
    assert_eq!(names, ["D2-NEAR", "D2-FAR0"]);
    assert_eq!(got[1].id, far_id);
    assert_eq!(
        got[1].id.to_string(),
        "0f000000-5678-4a6b-9c8d-0123456789ab"
    );
    // --address takes the identifier (any case), and the link goes to that droid.
    let sel = DeviceSelector {
        address: Some("0F000000-5678-4A6B-9C8D-0123456789AB".into()),
        ..DeviceSelector::default()
    };
    let found = connect_link_with(Arc::new(c.clone()), &sel, droidctl::family::gatt_profile)
        .await
        .unwrap();
    assert_eq!(found.name, "D2-FAR0");
    assert_eq!(found.id, far_id);
    let mut link = found.link;
    let _conn = link.open().await.unwrap();
    assert!(far.is_connected() && !near.is_connected());
}

/// A droid the computer remembers but does not hear is neither listed nor picked; asked for
/// by name or address it fails once the scan is over, with one line, and no connection is
/// attempted.
#[tokio::test(start_paused = true)]
async fn remembered_droids_are_neither_listed_nor_picked() {
    let c = FakeCentral::new();
    let asleep = FakePeripheral::for_profile(&droidctl::family::gatt_profile(Model::R2D2));
    asleep.hang_connect(true);
    c.remember(ad("D2-GONE", 1, -30), Some(asleep.clone()));
    c.add_device(
        ad("BB-HERE", 2, -70),
        FakePeripheral::for_profile(&droidctl::family::gatt_profile(Model::BB8)),
    );
    let heard = scan::scan(&c, Duration::from_secs(1), |_| false)
        .await
        .unwrap();
    assert_eq!(heard.len(), 1, "{heard:?}");
    let found = connect_link_with(
        Arc::new(c.clone()),
        &DeviceSelector::default(),
        droidctl::family::gatt_profile,
    )
    .await
    .unwrap();
    assert_eq!(found.name, "BB-HERE");
    assert!(found.candidates.iter().all(|e| e.heard));
    for sel in [
        DeviceSelector {
            name: Some("D2-GONE".into()),
            ..DeviceSelector::default()
        },
        DeviceSelector {
            address: Some("E0:00:00:00:00:01".into()),
            ..DeviceSelector::default()
        },
    ] {
        let t0 = Instant::now();
        let e = connect_link_with(Arc::new(c.clone()), &sel, droidctl::family::gatt_profile)
            .await
            .err()
            .unwrap();
        assert_eq!(t0.elapsed(), Duration::from_secs(5), "after the scan");
        assert_eq!(e.kind, BleErrorKind::NotFound);
        assert!(!e.fatal());
        assert!(
            e.message.starts_with(
                "D2-GONE (E0:00:00:00:00:01) is known to this computer but not in range"
            ),
            "{e}"
        );
        assert!(e.message.contains("wake it"), "{e}");
    }
    assert!(
        asleep.ops().is_empty(),
        "never connected to: {:?}",
        asleep.ops()
    );
}
