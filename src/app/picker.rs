//! Choosing a droid when several answer the scan: a small full-screen list before the app.
//! State and keys only (the `[keys.picker]` bindings, and digits 1-9 to choose directly);
//! [`crate::ui::picker`] draws it. Marking several and choosing drives them all at once (a
//! fleet).

use crate::config::{Action, Context, Key, KeyCode, KeyMap};
use crate::link::ble::ScanEntry;

#[derive(Debug, Clone, PartialEq)]
pub struct Picker {
    /// Droids that can be driven, strongest first.
    pub entries: Vec<ScanEntry>,
    pub selected: usize,
    /// Marked entries (by index), to drive together.
    pub marked: Vec<bool>,
    keys: KeyMap,
}

/// What a key did.
#[derive(Debug, Clone, PartialEq)]
pub enum Picked {
    /// Still choosing.
    Pending,
    Chosen(ScanEntry),
    /// Several marked: drive them all, in the list's order.
    Several(Vec<ScanEntry>),
    Cancelled,
}

impl Picker {
    pub fn new(entries: Vec<ScanEntry>, keys: KeyMap) -> Self {
        Picker {
            marked: vec![false; entries.len()],
            entries,
            selected: 0,
            keys,
        }
    }

    pub fn on_key(&mut self, key: Key) -> Picked {
        let last = self.entries.len().saturating_sub(1);
        if key == Key::CTRL_C {
            return Picked::Cancelled;
        }
        match self.keys.action_in(Context::Picker, &key) {
            Some(Action::PickerUp) => self.selected = self.selected.saturating_sub(1),
            Some(Action::PickerDown) => self.selected = (self.selected + 1).min(last),
            Some(Action::PickerFirst) => self.selected = 0,
            Some(Action::PickerLast) => self.selected = last,
            Some(Action::PickerMark) => {
                if let Some(m) = self.marked.get_mut(self.selected) {
                    *m = !*m;
                }
            }
            Some(Action::PickerChoose) => {
                let marked: Vec<ScanEntry> = self
                    .entries
                    .iter()
                    .zip(&self.marked)
                    .filter(|(_, m)| **m)
                    .map(|(e, _)| e.clone())
                    .collect();
                return match (marked.len(), self.entries.get(self.selected)) {
                    (0, Some(e)) => Picked::Chosen(e.clone()),
                    (1, _) => Picked::Chosen(marked[0].clone()),
                    (n, _) if n > 1 => Picked::Several(marked),
                    _ => Picked::Cancelled,
                };
            }
            Some(Action::PickerCancel) => return Picked::Cancelled,
            _ => {
                if let KeyCode::Char(c @ '1'..='9') = key.code {
                    let i = c as usize - '1' as usize;
                    if let Some(e) = self.entries.get(i) {
                        return Picked::Chosen(e.clone());
                    }
                }
            }
        }
        Picked::Pending
    }

    /// The keys line under the list, as bound (each action's first key).
    pub fn footer(&self) -> String {
        let shown = |a| {
            self.keys
                .keys(a)
                .first()
                .map_or_else(|| "-".into(), ToString::to_string)
        };
        format!(
            "{} {} choose · {} mark several · {} or 1-9 connect · {} cancel",
            shown(Action::PickerUp),
            shown(Action::PickerDown),
            shown(Action::PickerMark),
            shown(Action::PickerChoose),
            shown(Action::PickerCancel)
        )
    }
}

/// The list's columns, as headed.
pub const HEADINGS: [&str; 4] = ["name", "model", "address", "signal"];

/// A name wider than this is cut (with `…`) so the other columns stay in view at 80 columns.
pub const NAME_MAX: usize = 24;

/// One entry's cells, in [`HEADINGS`] order: exactly what the list shows (a name is as heard;
/// the screen cleans control characters out of it, and cuts it at [`NAME_MAX`]).
pub fn cells(e: &ScanEntry) -> [String; 4] {
    [
        // Cleaned here: the numbered prompt on stderr prints these cells as they are.
        e.name
            .as_deref()
            .map_or_else(|| "?".into(), crate::printable::clean),
        e.model
            .map(crate::model::Model::display_name)
            .unwrap_or("?")
            .to_string(),
        e.id.to_string(),
        e.rssi
            .map(|r| format!("{r} dBm"))
            .unwrap_or_else(|| "-".into()),
    ]
}

/// Each column as wide as its widest cell or heading, in terminal columns: from the content,
/// so a model name ("Sphero BOLT") or a long name never runs into the next column.
pub fn widths(rows: &[[String; 4]]) -> [usize; 4] {
    let mut w = HEADINGS.map(str::len);
    for row in rows {
        for (w, cell) in w.iter_mut().zip(row) {
            *w = (*w).max(ratatui::text::Span::raw(cell.as_str()).width());
        }
    }
    w
}

/// `cells` laid out in columns of `widths`, two spaces apart (the last one not padded).
pub fn line(cells: &[String; 4], widths: &[usize; 4]) -> String {
    let mut out = String::new();
    for (i, (cell, w)) in cells.iter().zip(widths).enumerate() {
        out.push_str(cell);
        if i + 1 < cells.len() {
            let pad = w.saturating_sub(ratatui::text::Span::raw(cell.as_str()).width());
            out.extend(std::iter::repeat_n(' ', pad + 2));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::ble::BleAddress;
    use crate::model::Model;

    fn keys() -> KeyMap {
        crate::config::Config::defaults().keymap
    }

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
    fn a_hostile_name_becomes_a_printable_cell() {
        // The numbered prompt (`droidctl` with several droids in range, no terminal for the
        // full-screen list) writes these cells to stderr as they are.
        let [name, ..] = cells(&entry("D2-\u{1b}]0;owned\u{7}", -40));
        assert_eq!(name, "D2-·]0;owned·");
    }

    #[test]
    fn arrows_enter_digits_escape() {
        let mut p = Picker::new(
            vec![
                entry("D2-AAAA", -40),
                entry("Q5-BBBB", -60),
                entry("GB-CCCC", -70),
            ],
            keys(),
        );
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
            Picker::new(vec![], keys()).on_key(Key::plain(KeyCode::Enter)),
            Picked::Cancelled
        );
    }

    #[test]
    fn keys_are_the_configured_ones() {
        let c = crate::config::Config::parse_merged(
            None,
            "[keys.picker]\ndown = [\"n\"]\nchoose = [\"Tab\"]\n",
        )
        .unwrap();
        let mut p = Picker::new(vec![entry("D2-AAAA", -40), entry("Q5-BBBB", -60)], c.keymap);
        p.on_key(Key::ch('n'));
        assert_eq!(p.selected, 1);
        assert_eq!(
            p.on_key(Key::plain(KeyCode::Tab)),
            Picked::Chosen(entry("Q5-BBBB", -60))
        );
        assert_eq!(
            p.footer(),
            "↑ n choose · x mark several · Tab or 1-9 connect · Esc cancel"
        );
    }

    #[test]
    fn marking_several_chooses_them_all() {
        let all = [
            entry("D2-AAAA", -40),
            entry("Q5-BBBB", -60),
            entry("GB-CCCC", -70),
        ];
        let mut p = Picker::new(all.to_vec(), keys());
        p.on_key(Key::ch('x'));
        p.on_key(Key::plain(KeyCode::Down));
        p.on_key(Key::plain(KeyCode::Down));
        p.on_key(Key::ch('x'));
        assert_eq!(p.marked, [true, false, true]);
        assert_eq!(
            p.clone().on_key(Key::plain(KeyCode::Enter)),
            Picked::Several(vec![all[0].clone(), all[2].clone()])
        );
        // Unmarking down to one chooses that one.
        p.on_key(Key::ch('x'));
        assert_eq!(
            p.on_key(Key::plain(KeyCode::Enter)),
            Picked::Chosen(all[0].clone())
        );
    }
}
