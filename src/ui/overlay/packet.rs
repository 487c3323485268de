//! A packet in full: every row of [`crate::app::detail::rows`] wrapped to the width (never
//! cut), the search's matches marked, the one shown highlighted, and the keys at the bottom.

use super::super::text::{clean, width, wrap};
use super::super::theme;
use crate::app::detail::{matches, rows};
use crate::app::packet_log::LogLine;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::Modifier;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Clear, Paragraph};

/// How the detail is shown: the search, typed or done; the match shown; the first row.
pub struct View<'a> {
    pub search: &'a str,
    pub typing: bool,
    pub matched: usize,
    pub scroll: usize,
    /// The hints as bound, for the keys in the bottom edge.
    pub borders: &'a crate::app::borders::Borders,
}

const LABEL_W: usize = 10;

pub fn render(frame: &mut Frame, area: Rect, line: &LogLine, v: View<'_>) {
    let rect = Rect {
        x: area.x + 1,
        y: area.y + 1,
        width: area.width.saturating_sub(2),
        height: area.height.saturating_sub(2),
    };
    let rows = rows(line);
    let found = matches(&rows, v.search);
    let b = v.borders;
    let foot = if v.typing {
        format!(" /{}▏ {} ", clean(v.search), b.detail_typing)
    } else if v.search.is_empty() {
        format!(" {} ", b.detail)
    } else if found.is_empty() {
        format!(" no match for {:?} · {} ", clean(v.search), b.detail)
    } else {
        format!(
            " match {}/{} · {} ",
            v.matched % found.len() + 1,
            found.len(),
            b.detail_matches
        )
    };
    let block = theme::panel(Span::styled(
        format!(" Packet {} ", clean(&line.name)),
        theme::bold(),
    ))
    .border_style(theme::label())
    .title_bottom(Line::from(Span::styled(foot, theme::dim())).centered());
    let inner = block.inner(rect);
    frame.render_widget(Clear, rect);
    frame.render_widget(block, rect);
    let value_w = (inner.width as usize).saturating_sub(LABEL_W + 1).max(1);
    let shown = found.get(v.matched % found.len().max(1)).copied();
    let mut lines: Vec<Line> = Vec::new();
    for (i, r) in rows.iter().enumerate().skip(v.scroll) {
        if r.heading {
            lines.push(Line::from(Span::styled(
                r.label.clone(),
                theme::bold().add_modifier(Modifier::UNDERLINED),
            )));
            continue;
        }
        let style = if Some(i) == shown {
            theme::selected()
        } else if found.contains(&i) {
            theme::attention()
        } else {
            ratatui::style::Style::new()
        };
        let label = clean(&r.label);
        let pad = " ".repeat(LABEL_W.saturating_sub(width(&label)) + 1);
        for (k, part) in wrap(&clean(&r.value), value_w).into_iter().enumerate() {
            let lead = if k == 0 {
                Span::styled(format!("{label}{pad}"), theme::label())
            } else {
                Span::raw(" ".repeat(LABEL_W + 1))
            };
            lines.push(Line::from(vec![lead, Span::styled(part, style)]));
        }
        if lines.len() >= inner.height as usize {
            break;
        }
    }
    frame.render_widget(Paragraph::new(lines), inner);
}
