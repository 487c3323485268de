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

/// A prompt box low on the screen: its inner rect and the input as it fits.
fn prompt(frame: &mut Frame, area: Rect, title: &str, input: &str, keys: &str) -> (Rect, String) {
    let w = area.width.saturating_sub(4).clamp(1, 70).min(area.width);
    let h = 5.min(area.height);
    // Low on the screen, over the packet log.
    let rect = Rect {
        x: area.x + area.width.saturating_sub(w) / 2,
        y: area.y + area.height.saturating_sub(h + 1),
        width: w,
        height: h,
    };
    let block = theme::panel(Span::styled(format!(" {title} "), theme::bold()))
        .border_style(theme::commanded())
        .title_bottom(Line::from(Span::styled(format!(" {keys} "), theme::dim())).centered());
    let inner = block.inner(rect);
    frame.render_widget(Clear, rect);
    frame.render_widget(block, rect);
    let shown = truncate_left(&clean(input), (inner.width as usize).saturating_sub(3));
    (inner, shown)
}

/// The cursor after the typed text.
fn cursor(frame: &mut Frame, inner: Rect, shown: &str) {
    if inner.height > 0 && inner.width > 0 {
        let x = inner
            .x
            .saturating_add((2 + width(shown)) as u16)
            .min(inner.right().saturating_sub(1));
        frame.set_cursor_position(Position::new(x, inner.y));
    }
}

/// BOLT's matrix prompt: one character is drawn, more scroll (up to 25).
pub fn matrix(frame: &mut Frame, area: Rect, input: &str, keys: &str) {
    let (inner, shown) = prompt(frame, area, "On the matrix", input, keys);
    let what = match crate::app::view::matrix::MatrixView::typed(input) {
        None => "nothing yet".to_string(),
        Some(crate::app::view::matrix::MatrixShows::Char(c)) => format!("draws {c:?}"),
        Some(_) => format!("scrolls {} characters", input.trim().len()),
    };
    let lines = vec![
        Line::from(vec![
            Span::styled("> ", theme::commanded()),
            Span::raw(shown.clone()),
        ]),
        Line::from(vec![
            Span::styled("one character is drawn, more scroll ", theme::dim()),
            Span::styled("(up to 25)", theme::dim()),
        ]),
        Line::from(vec![
            Span::styled("now ", theme::label()),
            Span::styled(what, theme::commanded()),
        ]),
    ];
    frame.render_widget(Paragraph::new(lines), inner);
    cursor(frame, inner, &shown);
}

/// `before`: the filter Esc goes back to (what is typed already applies).
pub fn render(frame: &mut Frame, area: Rect, input: &str, before: &LogFilter, keys: &str) {
    let (inner, shown) = prompt(frame, area, "Filter packets", input, keys);
    let iw = inner.width as usize;
    let parsed = LogFilter::parse(input);
    let preview = if parsed.is_active() {
        parsed.describe()
    } else {
        "everything".into()
    };
    let now = if before.is_active() {
        before.describe()
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
                format!("  (was: {})", truncate(&clean(&now), iw / 3)),
                theme::dim(),
            ),
        ]),
    ];
    frame.render_widget(Paragraph::new(lines), inner);
    cursor(frame, inner, &shown);
}
