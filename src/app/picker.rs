//! Choosing a droid when several answer the scan: a small full-screen list before the app.
//! State and keys only; [`crate::ui::picker`] draws it.

use crate::link::ble::ScanEntry;
use crate::teleop::keymap::{Key, KeyCode};

#[derive(Debug, Clone, PartialEq)]
pub struct Picker {
    /// Droids that can be driven, strongest first.
    pub entries: Vec<ScanEntry>,
    pub selected: usize,
}

/// What a key did.
#[derive(Debug, Clone, PartialEq)]
pub enum Picked {
    /// Still choosing.
    Pending,
    Chosen(ScanEntry),
    Cancelled,
}

impl Picker {
    pub fn new(entries: Vec<ScanEntry>) -> Self {
        Picker {
            entries,
            selected: 0,
        }
    }

    pub fn on_key(&mut self, key: Key) -> Picked {
        let last = self.entries.len().saturating_sub(1);
        match key.code {
            KeyCode::Up | KeyCode::Char('k') => self.selected = self.selected.saturating_sub(1),
            KeyCode::Down | KeyCode::Char('j') => self.selected = (self.selected + 1).min(last),
            KeyCode::Home => self.selected = 0,
            KeyCode::End => self.selected = last,
            KeyCode::Enter | KeyCode::Space => {
                return match self.entries.get(self.selected) {
                    Some(e) => Picked::Chosen(e.clone()),
                    None => Picked::Cancelled,
                };
            }
            KeyCode::Char(c @ '1'..='9') => {
                let i = c as usize - '1' as usize;
                if let Some(e) = self.entries.get(i) {
                    return Picked::Chosen(e.clone());
                }
            }
            KeyCode::Esc | KeyCode::Char('q') => return Picked::Cancelled,
            KeyCode::Char('c') if key.ctrl => return Picked::Cancelled,
            _ => {}
        }
        Picked::Pending
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::ble::BleAddress;
    use crate::model::Model;

    fn entry(name: &str, rssi: i16) -> ScanEntry {
        let address = BleAddress([0, 0, 0, 0, 0, rssi.unsigned_abs() as u8]);
        ScanEntry {
            name: Some(name.into()),
            model: Model::from_advertised_name(name),
            id: address.into(),
            address,
            rssi: Some(rssi),
            heard: true,
        }
    }

    #[test]
    fn arrows_enter_digits_escape() {
        let mut p = Picker::new(vec![
            entry("D2-AAAA", -40),
            entry("Q5-BBBB", -60),
            entry("GB-CCCC", -70),
        ]);
        assert_eq!(p.on_key(Key::plain(KeyCode::Up)), Picked::Pending);
        assert_eq!(p.selected, 0);
        p.on_key(Key::plain(KeyCode::Down));
        p.on_key(Key::plain(KeyCode::Down));
        p.on_key(Key::plain(KeyCode::Down));
        assert_eq!(p.selected, 2);
        assert_eq!(
            p.on_key(Key::plain(KeyCode::Enter)),
            Picked::Chosen(entry("GB-CCCC", -70))
        );
        assert_eq!(
            p.on_key(Key::ch('2')),
            Picked::Chosen(entry("Q5-BBBB", -60))
        );
        assert_eq!(p.on_key(Key::ch('9')), Picked::Pending);
        assert_eq!(p.on_key(Key::plain(KeyCode::Esc)), Picked::Cancelled);
        assert_eq!(
            p.on_key(Key {
                code: KeyCode::Char('c'),
                ctrl: true
            }),
            Picked::Cancelled
        );
        assert_eq!(
            Picker::new(vec![]).on_key(Key::plain(KeyCode::Enter)),
            Picked::Cancelled
        );
    }
}
