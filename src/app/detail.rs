//! A packet in full (issue 30 point 3): `Enter` in the packet log opens its newest line shown
//! with every field, the frame's parts (start, flags, device, command, seq, data, checksum,
//! end) and hex, its time, direction and droid. A search (`/`) marks the rows that contain
//! the text; `n` and `N` go to the next and previous match. The rows are made here, once,
//! for the screen and the search alike.

use super::core::App;
use super::overlay::filter::edit;
use super::packet_log::LogLine;
use super::state::Overlay;
use crate::config::{Action, Context, Key};

/// Longest search typed.
const SEARCH_MAX: usize = 60;

/// One row of the detail: a label and its value (never cut: the screen wraps it).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Row {
    pub label: String,
    pub value: String,
    /// A heading ("Fields", "Frame"): no value.
    pub heading: bool,
}

fn row(label: impl Into<String>, value: impl Into<String>) -> Row {
    Row {
        label: label.into(),
        value: value.into(),
        heading: false,
    }
}

fn heading(label: &str) -> Row {
    Row {
        label: label.into(),
        value: String::new(),
        heading: true,
    }
}

/// The rows of `l`'s detail.
pub fn rows(l: &LogLine) -> Vec<Row> {
    let mut v = vec![
        row("time", format!("{:.3} s", l.at.as_secs_f64())),
        row(
            "direction",
            format!(
                "{} {}",
                l.dir.arrow(),
                if l.dir == crate::session::Direction::In {
                    "from the droid"
                } else {
                    "to the droid"
                }
            ),
        ),
    ];
    if let Some(d) = &l.droid {
        v.push(row("droid", d.to_string()));
    }
    v.push(row("packet", l.name.clone()));
    if let Some(s) = l.seq {
        v.push(row("seq", s.to_string()));
    }
    if let Some(e) = l.err {
        v.push(row("error", format!("{} — {}", e.name(), e.message())));
    }
    v.push(heading("Fields"));
    if l.fields.is_empty() {
        let text = if l.decoded.is_empty() {
            "none"
        } else {
            &l.decoded
        };
        v.push(row("", text));
    }
    v.extend(l.fields.iter().map(|(n, val)| row(*n, val.clone())));
    v.push(heading("Frame"));
    v.extend(l.parts.iter().map(|(n, val)| row(*n, val.clone())));
    v.push(row("hex", l.hex.clone()));
    v
}

/// The rows of `rows` that contain `search` (case-insensitive); none for an empty search.
pub fn matches(rows: &[Row], search: &str) -> Vec<usize> {
    let s = search.trim().to_lowercase();
    if s.is_empty() {
        return Vec::new();
    }
    rows.iter()
        .enumerate()
        .filter(|(_, r)| r.label.to_lowercase().contains(&s) || r.value.to_lowercase().contains(&s))
        .map(|(i, _)| i)
        .collect()
}

impl App {
    /// The log's selected line, in full.
    pub(super) fn open_detail(&mut self) {
        let rows = self.log_rows();
        let Some(line) = self.state.log.selected(rows).cloned() else {
            return self.hint("no packet to show");
        };
        self.state.overlay = Overlay::Packet {
            line: Box::new(line),
            search: String::new(),
            typing: false,
            matched: 0,
            scroll: 0,
        };
    }

    pub(super) fn detail_scroll(&mut self, n: usize, down: bool) {
        if let Overlay::Packet { scroll, line, .. } = &mut self.state.overlay {
            let last = rows(line).len().saturating_sub(1);
            *scroll = if down {
                (*scroll + n).min(last)
            } else {
                scroll.saturating_sub(n)
            };
        }
    }

    pub(super) fn detail_key(&mut self, key: Key, new_press: bool) {
        let action = self.keymap.action_in(Context::Detail, &key);
        let Overlay::Packet {
            line,
            search,
            typing,
            matched,
            scroll,
        } = &mut self.state.overlay
        else {
            return;
        };
        let rows = rows(line);
        if *typing {
            // While typing, the prompts' keys (as the log filter's): the rest is text.
            match self.keymap.action_in(Context::Filter, &key) {
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
            return;
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
            Some(Action::DetailClose) => self.state.overlay = Overlay::None,
            _ => {}
        }
    }
}
