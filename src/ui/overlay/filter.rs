//! The packet-log filter prompt: what is typed, the syntax, and how the input parses right now,
//! so a typo shows before Enter rather than as an empty log after it.

use super::super::text::{clean, truncate, truncate_left, width};
use super::super::theme;
use crate::app::packet_log::LogFilter;
use ratatui::Frame;
use ratatui::layout::{Position, Rect};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Clear, Paragraph};

const SYNTAX: &str = "in|out dev:NAME text";

pub fn render(frame: &mut Frame, area: Rect, input: &str, current: &LogFilter) {
    let w = area.width.saturating_sub(4).clamp(1, 70).min(area.width);
    let h = 5.min(area.height);
    // Low on the screen, over the packet log it filters.
    let rect = Rect {
        x: area.x + area.width.saturating_sub(w) / 2,
        y: area.y + area.height.saturating_sub(h + 1),
        width: w,
        height: h,
    };
    let block = theme::panel(Span::styled(" Filter packets ", theme::bold()))
        .border_style(theme::commanded())
        .title_bottom(
            Line::from(Span::styled(" Enter apply · Esc cancel ", theme::dim())).centered(),
        );
    let inner = block.inner(rect);
    frame.render_widget(Clear, rect);
    frame.render_widget(block, rect);
    let iw = inner.width as usize;
    let shown = truncate_left(&clean(input), iw.saturating_sub(3));
    let parsed = LogFilter::parse(input);
    let preview = if parsed.is_active() {
        parsed.describe()
    } else {
        "everything".into()
    };
    let now = if current.is_active() {
        current.describe()
    } else {
        "none".into()
    };
    let lines = vec![
        Line::from(vec![
            Span::styled("> ", theme::commanded()),
            Span::raw(shown.clone()),
        ]),
        Line::from(vec![
            Span::styled("syntax ", theme::label()),
            Span::styled(SYNTAX, theme::dim()),
        ]),
        Line::from(vec![
            Span::styled("shows ", theme::label()),
            Span::styled(truncate(&clean(&preview), iw / 2), theme::commanded()),
            Span::styled(
                format!("  (now: {})", truncate(&clean(&now), iw / 3)),
                theme::dim(),
            ),
        ]),
    ];
    frame.render_widget(Paragraph::new(lines), inner);
    if inner.height > 0 && inner.width > 0 {
        let x = inner
            .x
            .saturating_add((2 + width(&shown)) as u16)
            .min(inner.right().saturating_sub(1));
        frame.set_cursor_position(Position::new(x, inner.y));
    }
}
