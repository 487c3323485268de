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
