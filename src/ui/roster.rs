//! The roster strip of a fleet: one row naming every droid with its state, battery and link
//! rate; the driven droid is highlighted, and `MIRROR` says when every droid gets the same
//! control. Entries shrink to fit the width (at 80 columns four droids keep name, state and
//! battery).

use super::text::{clean, truncate};
use super::theme;
use crate::app::roster::{Roster, RosterEntry};
use crate::session::LinkState;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::Modifier;
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;

/// One entry at full length: `▶2 D2-0001 conn 3.9V 12/9/s`.
/// `chosen`: the keys' droid; `driven`: it or, in mirror mode, every droid.
fn entry(i: usize, e: &RosterEntry, chosen: bool, driven: bool, room: usize) -> Vec<Span<'static>> {
    let state = match &e.link {
        LinkState::Connected if e.moving => "moving".to_string(),
        LinkState::Connected => "ok".to_string(),
        LinkState::Connecting => "connecting".to_string(),
        LinkState::Reconnecting { attempt, .. } => format!("retry {attempt}"),
        LinkState::Closed { .. } => "closed".to_string(),
    };
    let state_style = match &e.link {
        LinkState::Connected => theme::reported(),
        LinkState::Closed { .. } => theme::alarm(),
        _ => theme::attention(),
    };
    let battery = e.battery_v.map(|v| format!(" {v:.1}V")).unwrap_or_default();
    let rate = format!(" {:.0}/{:.0}/s", e.rate_in, e.rate_out);
    let marker = match (chosen, driven) {
        (true, _) => "▶",
        (false, true) => "»",
        _ => " ",
    };
    let head = format!("{marker}{} ", i + 1);
    // Drop the rate, then the battery, then shorten the name, to fit.
    let fixed = head.chars().count() + state.chars().count() + 1;
    let mut extra = format!("{battery}{rate}");
    if fixed + 4 + extra.chars().count() > room {
        extra = battery.clone();
    }
    if fixed + 4 + extra.chars().count() > room {
        extra.clear();
    }
    let name_room = room.saturating_sub(fixed + extra.chars().count()).max(3);
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
        Span::styled(truncate(&clean(&e.name), name_room), name_style),
        Span::raw(" "),
        Span::styled(state, state_style),
        Span::styled(extra, theme::dim()),
    ]
}

pub fn render(frame: &mut Frame, area: Rect, roster: &Roster) {
    let n = roster.droids.len().max(1);
    let tag = if roster.mirror { "MIRROR " } else { "" };
    let room = (area.width as usize).saturating_sub(tag.len()) / n;
    let mut spans = Vec::new();
    if !tag.is_empty() {
        spans.push(Span::styled(tag, theme::attention()));
    }
    for (i, e) in roster.droids.iter().enumerate() {
        let chosen = i == roster.chosen;
        spans.extend(entry(
            i,
            e,
            chosen,
            chosen || roster.mirror,
            room.saturating_sub(1),
        ));
        spans.push(Span::raw(" "));
    }
    frame.render_widget(Paragraph::new(Line::from(spans)), area);
}
