//! A packet in full ([`crate::app::detail`] makes its rows): the detail keys scroll it; a
//! search (`/`) is typed with the prompts' keys (as the log filter's) and marks the rows that
//! contain it; next and previous go from match to match. The wheel scrolls it.

use super::filter::edit;
use super::{Around, Component, Do, Outcome, Overlay};
use crate::app::detail::{matches, rows};
use crate::app::input::MouseKind;
use crate::app::place::Place;
use crate::config::{Action, Context, Key};
use ratatui::layout::Position;

/// Longest search typed.
const SEARCH_MAX: usize = 60;

/// Rows one wheel step scrolls.
const WHEEL_ROWS: usize = 3;

/// A packet in full.
pub struct Packet;

impl Component for Packet {
    const PLACE: Place = Place::Packet;

    /// Typing a search reads the prompts' keys; else the detail's.
    fn context(o: &Overlay) -> Context {
        let typing = matches!(o, Overlay::Packet { typing: true, .. });
        Self::PLACE.context(false, typing)
    }

    fn on_key(o: &mut Overlay, around: &mut Around, key: Key, new_press: bool) -> Outcome<Do> {
        let km = around.keymap;
        let action = km.action_in(Context::Detail, &key);
        let Overlay::Packet {
            line,
            search,
            typing,
            matched,
            scroll,
        } = o
        else {
            return Outcome::Stay;
        };
        let rows = rows(line);
        if *typing {
            // While typing, the prompts' keys (as the log filter's): the rest is text.
            match km.action_in(Context::Filter, &key) {
                Some(Action::FilterApply) => {
                    *typing = false;
                    *matched = 0;
                    if let Some(&i) = matches(&rows, search).first() {
                        *scroll = i;
                    }
                }
                Some(Action::FilterCancel) => {
                    *typing = false;
                    search.clear();
                }
                _ => edit(search, key, SEARCH_MAX, |_| true),
            }
            return Outcome::Stay;
        }
        let found = matches(&rows, search);
        match action {
            Some(Action::DetailUp) => *scroll = scroll.saturating_sub(1),
            Some(Action::DetailDown) => *scroll = (*scroll + 1).min(rows.len().saturating_sub(1)),
            Some(_) if !new_press => {}
            Some(Action::DetailSearch) => {
                *typing = true;
                search.clear();
            }
            Some(Action::DetailNext) | Some(Action::DetailPrevious) if !found.is_empty() => {
                let n = found.len();
                *matched = if action == Some(Action::DetailNext) {
                    (*matched + 1) % n
                } else {
                    (*matched + n - 1) % n
                };
                *scroll = found[*matched];
            }
            Some(Action::DetailClose) => return Outcome::Close,
            _ => {}
        }
        Outcome::Stay
    }

    fn on_mouse(o: &mut Overlay, _: &mut Around, kind: MouseKind, _: Position) -> Outcome<Do> {
        if let Overlay::Packet { scroll, line, .. } = o {
            let last = rows(line).len().saturating_sub(1);
            match kind {
                MouseKind::ScrollDown => *scroll = (*scroll + WHEEL_ROWS).min(last),
                MouseKind::ScrollUp => *scroll = scroll.saturating_sub(WHEEL_ROWS),
                MouseKind::Click => {}
            }
        }
        Outcome::Stay
    }

    #[cfg(test)]
    fn sample() -> Overlay {
        use crate::session::{Direction, LogEntry, LogItem};
        let drive = crate::protocol::v2::Packet::notification(0x16, 0x07, vec![100, 0, 90, 0]);
        let entry = LogEntry {
            at: std::time::Duration::from_millis(1125),
            dir: Direction::Out,
            item: LogItem::packet(drive),
        };
        Overlay::Packet {
            line: Box::new(crate::app::packet_log::LogLine::from_entry(&entry)),
            search: String::new(),
            typing: false,
            matched: 0,
            scroll: 0,
        }
    }
}
