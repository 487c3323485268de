//! The droid picker shown when several droids answer the scan.

use droidctl::app::picker::{Picked, Picker};
use droidctl::config::{Key, KeyCode};
use droidctl::link::ble::{BleAddress, ScanEntry};
use droidctl::model::Model;
use ratatui::{Terminal, backend::TestBackend};

fn entry(name: &str, addr: u8, rssi: i16) -> ScanEntry {
    let address = BleAddress([0xF1, 0x22, 0x33, 0x44, 0x55, addr]);
    ScanEntry {
        name: Some(name.into()),
        model: Model::from_advertised_name(name),
        id: address.into(),
        address,
        rssi: Some(rssi),
        heard: true,
    }
}

fn picker() -> Picker {
    Picker::new(
        vec![
            entry("D2-1A2B", 0x66, -48),
            entry("Q5-77C0", 0x67, -63),
            entry("GB-0042", 0x68, -80),
        ],
        droidctl::config::Config::defaults().keymap,
    )
}

#[test]
fn picker_screen_80x24() {
    let mut p = picker();
    p.on_key(Key::plain(KeyCode::Down));
    let mut term = Terminal::new(TestBackend::new(80, 24)).unwrap();
    term.draw(|f| droidctl::ui::picker::draw(f, &p)).unwrap();
    insta::assert_snapshot!("picker_80x24", term.backend());
}

/// Issue 39 point 13: the model column overflowed with "Sphero BOLT" (a fixed 9 cells). The
/// columns are as wide as their content, at 80×24 and 120×40: every row's cells start where
/// their headings do, and the box holds them whole.
#[test]
fn picker_columns_fit_their_content_at_80x24_and_120x40() {
    let mut p = Picker::new(
        vec![
            entry("SB-5A1C", 0x61, -41),
            entry("RV-8E21", 0x62, -55),
            entry("D2-1A2B", 0x66, -48),
            entry("Robi 42", 0x69, -70),
        ],
        droidctl::config::Config::defaults().keymap,
    );
    p.on_key(Key::plain(KeyCode::Down));
    for (w, h) in [(80, 24), (120, 40)] {
        let mut term = Terminal::new(TestBackend::new(w, h)).unwrap();
        term.draw(|f| droidctl::ui::picker::draw(f, &p)).unwrap();
        let rows: Vec<String> = (0..h)
            .map(|y| {
                (0..w)
                    .map(|x| term.backend().buffer()[(x, y)].symbol())
                    .collect()
            })
            .collect();
        let all = rows.join("\n");
        let head = rows
            .iter()
            .find(|r| r.contains("address"))
            .expect("headings");
        let col = |r: &str, what: &str| r.find(what).map(|i| r[..i].chars().count());
        let (model_at, address_at, signal_at) = (
            col(head, "model").unwrap(),
            col(head, "address").unwrap(),
            col(head, "signal").unwrap(),
        );
        for (model, addr) in [
            ("Sphero BOLT", "F1:22:33:44:55:61"),
            ("Sphero RVR", "F1:22:33:44:55:62"),
            ("R2-D2", "F1:22:33:44:55:66"),
            ("Robi 42", "F1:22:33:44:55:69"),
        ] {
            let row = rows
                .iter()
                .find(|r| r.contains(addr))
                .unwrap_or_else(|| panic!("{addr} listed:\n{all}"));
            let from = |c: usize| -> String { row.chars().skip(c).collect() };
            assert!(from(model_at).starts_with(model), "{model}:\n{all}");
            assert!(from(address_at).starts_with(addr), "{addr}:\n{all}");
            assert_eq!(
                col(row, " dBm").map(|c| c >= signal_at),
                Some(true),
                "{all}"
            );
            assert!(!row.contains('…'), "nothing cut:\n{all}");
        }
        insta::assert_snapshot!(format!("picker_columns_{w}x{h}"), term.backend());
    }
}

#[test]
fn picker_never_panics_when_tiny_or_empty() {
    for (w, h) in [(1, 1), (20, 5), (80, 3)] {
        let mut term = Terminal::new(TestBackend::new(w, h)).unwrap();
        term.draw(|f| droidctl::ui::picker::draw(f, &picker()))
            .unwrap();
        term.draw(|f| {
            droidctl::ui::picker::draw(
                f,
                &Picker::new(vec![], droidctl::config::Config::defaults().keymap),
            )
        })
        .unwrap();
    }
}

#[test]
fn choosing_returns_the_address() {
    let mut p = picker();
    p.on_key(Key::plain(KeyCode::Down));
    let Picked::Chosen(e) = p.on_key(Key::plain(KeyCode::Enter)) else {
        panic!()
    };
    assert_eq!(e.address.to_string(), "F1:22:33:44:55:67");
}
