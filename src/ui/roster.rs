//! The roster strip of a fleet: one row naming every droid with its state, battery and link
//! rate; the driven droid is highlighted, and `MIRROR` says when every droid gets the same
//! control. Entries shrink to fit the width (at 80 columns four droids keep name, state and
//! battery).

use super::text::{clean, truncate, truncate_left};
use super::theme;
use crate::app::roster::{Roster, RosterEntry};
use crate::session::LinkState;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::Modifier;
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;

/// The widest state ("retry 9"), battery (" 3.9V") and rate (" 12/s in") an entry makes
/// room for.
const STATE_W: usize = 7;
const BATTERY_W: usize = 5;
const RATE_W: usize = 9;

/// One entry at full length: `▶2 D2-0001 conn 3.9V 12/s in` (packets in a second: whether the
/// droid is talking; the status bar has both directions for the chosen one).
/// `chosen`: the keys' droid; `driven`: it or, in mirror mode, every droid.
fn entry(i: usize, e: &RosterEntry, chosen: bool, driven: bool, room: usize) -> Vec<Span<'static>> {
    let state = match &e.link {
        LinkState::Connected if e.moving => "moving".to_string(),
        LinkState::Connected => "ok".to_string(),
        LinkState::Connecting => "conn".to_string(),
        LinkState::Reconnecting { attempt, .. } => truncate(&format!("retry {attempt}"), STATE_W),
        LinkState::Closed { .. } => "closed".to_string(),
    };
    let state_style = match &e.link {
        LinkState::Connected => theme::reported(),
        LinkState::Closed { .. } => theme::alarm(),
        _ => theme::attention(),
    };
    let battery = e.battery_v.map(|v| format!(" {v:.1}V")).unwrap_or_default();
    let rate = truncate(
        &format!(" {} in", super::text::per_second(e.rate_in)),
        RATE_W,
    );
    let marker = match (chosen, driven) {
        (true, _) => "▶",
        (false, true) => "»",
        _ => " ",
    };
    let head = format!("{marker}{} ", i + 1);
    // Drop the rate, then the battery, then shorten the name, to fit. What goes and where the
    // name is cut depend on the room only, never on this frame's state or numbers, so the
    // strip does not jitter as a droid starts moving or its rate changes.
    let fixed = head.chars().count() + STATE_W + 1;
    let (extra, extra_w) = if fixed + 4 + BATTERY_W + RATE_W <= room {
        (format!("{battery}{rate}"), BATTERY_W + RATE_W)
    } else if fixed + 4 + BATTERY_W <= room {
        (battery.clone(), BATTERY_W)
    } else {
        (String::new(), 0)
    };
    let name_room = room.saturating_sub(fixed + extra_w).max(3);
    let name_style = if chosen {
        theme::selected().add_modifier(Modifier::BOLD)
    } else {
        theme::bold()
    };
    vec![
        Span::styled(
            head,
            if driven {
                theme::selected()
            } else {
                theme::label()
            },
        ),
        // Cut from the left: the end of a name tells droids apart (D2-0001, D2-0002).
        Span::styled(truncate_left(&clean(&e.name), name_room), name_style),
        Span::raw(" "),
        Span::styled(state, state_style),
        Span::styled(extra, theme::dim()),
    ]
}

pub fn render(frame: &mut Frame, area: Rect, roster: &Roster) {
    let (_, room) = crate::app::layout::roster_room(area.width, roster.droids.len(), roster.mirror);
    let tag = if roster.mirror {
        crate::app::layout::ROSTER_MIRROR_TAG
    } else {
        ""
    };
    let mut spans = Vec::new();
    if !tag.is_empty() {
        spans.push(Span::styled(tag, theme::attention()));
    }
    for (i, e) in roster.droids.iter().enumerate() {
        let chosen = i == roster.chosen;
        let one = entry(
            i,
            e,
            chosen,
            chosen || roster.mirror,
            room.saturating_sub(1),
        );
        // Every entry takes its room whole: the next one starts at the same column each frame.
        let used: usize = one.iter().map(Span::width).sum();
        spans.extend(one);
        spans.push(Span::raw(" ".repeat(room.saturating_sub(used).max(1))));
    }
    frame.render_widget(Paragraph::new(Line::from(spans)), area);
}
