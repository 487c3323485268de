//! The scope's channel list and the streaming and collision settings: a titled list, the
//! selected row highlighted and kept in view, the keys in the bottom edge.

use super::super::layout::centered;
use super::super::text::width;
use super::super::theme;
use super::palette::offset;
use crate::app::state::AppState;
use crate::app::view::scope::{TuningDraft, TuningRow, tuning_rows};
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Clear, Paragraph};

/// A list box of `rows` with `selected` highlighted.
fn list(frame: &mut Frame, area: Rect, title: &str, keys: &str, rows: Vec<Line>, selected: usize) {
    // As wide as its title and keys (never cut where the screen has the room: issue 30).
    let want = 52.max(width(title) + 4).max(width(keys) + 4) as u16;
    let w = want.min(area.width.saturating_sub(2).max(1));
    let h = (rows.len() as u16 + 2).min(area.height.saturating_sub(2).max(1));
    let rect = centered(area, w, h);
    let block = theme::panel(Span::styled(format!(" {title} "), theme::bold()))
        .border_style(theme::label())
        .title_bottom(Line::from(Span::styled(format!(" {keys} "), theme::dim())).centered());
    let inner = block.inner(rect);
    frame.render_widget(Clear, rect);
    frame.render_widget(block, rect);
    let shown = inner.height as usize;
    let first = offset(selected, rows.len(), shown);
    let lines: Vec<Line> = rows
        .into_iter()
        .enumerate()
        .skip(first)
        .take(shown)
        .map(|(i, l)| {
            if i == selected {
                l.style(theme::selected())
            } else {
                l
            }
        })
        .collect();
    frame.render_widget(Paragraph::new(lines), inner);
}

fn check(on: bool) -> &'static str {
    if on { "[x] " } else { "[ ] " }
}

pub fn channels(frame: &mut Frame, area: Rect, s: &AppState, selected: usize) {
    // The channels the list offers, as its keys read them.
    let rows: Vec<Line> = crate::app::overlay::channels::offered(s.droid().model)
        .iter()
        .map(|c| {
            let on = s.droid().scope.channels.contains(c);
            Line::from(vec![Span::raw(check(on)), Span::raw(c.label())])
        })
        .collect();
    list(
        frame,
        area,
        "Scope channels",
        &s.borders.channels,
        rows,
        selected,
    );
}

pub fn tuning(frame: &mut Frame, area: Rect, s: &AppState, selected: usize, d: &TuningDraft) {
    let m = &s.droid().monitor;
    let c = &d.collision;
    let rows: Vec<Line> = tuning_rows(m)
        .into_iter()
        .map(|r| {
            let (name, value) = match r {
                TuningRow::Rate => (
                    "streaming rate".to_string(),
                    match d.rate_hz {
                        0 => "off".to_string(),
                        r => format!("{r}/s"),
                    },
                ),
                TuningRow::Group(g) => (
                    format!("  {}{}", check(d.sensors.contains(g)), g.name()),
                    String::new(),
                ),
                TuningRow::Collision => (
                    "collision detection".into(),
                    if c.enabled { "on" } else { "off" }.into(),
                ),
                TuningRow::XThreshold => ("  x threshold".into(), c.x_threshold.to_string()),
                TuningRow::YThreshold => ("  y threshold".into(), c.y_threshold.to_string()),
                TuningRow::XSpeed => ("  x speed term".into(), c.x_speed.to_string()),
                TuningRow::YSpeed => ("  y speed term".into(), c.y_speed.to_string()),
                TuningRow::DeadTime => ("  dead time".into(), format!("{} ms", c.dead_time_ms)),
            };
            Line::from(vec![
                Span::raw(format!("{name:<26}")),
                Span::styled(value, theme::commanded()),
            ])
        })
        .collect();
    let title = format!(
        "Streaming and collision · now {}",
        super::super::scope::rates(s)
    );
    list(frame, area, &title, &s.borders.tuning, rows, selected);
}
