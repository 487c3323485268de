//! The animation and sound palettes: id and name per row, the selected entry highlighted and
//! kept in view. The scroll offset is derived from the selection alone (selection near the
//! middle), so the palette needs no view state of its own.

use super::super::layout::palette_rect;
use super::super::text::{clean, truncate, width};
use super::super::theme;
use crate::family::catalog::Entry;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Clear, Paragraph};

pub use crate::app::layout::list_offset as offset;

/// `keys`: the border's hint ([`crate::app::help::PALETTE`] as bound).
pub fn render(
    frame: &mut Frame,
    area: Rect,
    title: &str,
    entries: &[Entry],
    selected: usize,
    keys: &str,
) {
    let rect = palette_rect(area, entries.iter().map(|e| width(&e.name)), entries.len());
    let sel = selected.min(entries.len().saturating_sub(1));
    let mut block = theme::panel(Line::from(vec![
        Span::styled(format!(" {title} "), theme::bold()),
        Span::styled(
            format!(
                "{}/{} ",
                sel + usize::from(!entries.is_empty()),
                entries.len()
            ),
            theme::dim(),
        ),
    ]))
    .border_style(theme::label());
    block =
        block.title_bottom(Line::from(Span::styled(format!(" {keys} "), theme::dim())).centered());
    let inner = block.inner(rect);
    frame.render_widget(Clear, rect);
    frame.render_widget(block, rect);
    if entries.is_empty() {
        frame.render_widget(
            Paragraph::new(Span::styled("no entries", theme::dim())),
            inner,
        );
        return;
    }
    let rows = inner.height as usize;
    let first = offset(sel, entries.len(), rows);
    let text_w = (inner.width as usize).saturating_sub(9);
    let lines: Vec<Line> = entries
        .iter()
        .enumerate()
        .skip(first)
        .take(rows)
        .map(|(i, e)| {
            let text = format!(
                "{} {:>5}  {}",
                if i == sel { "▶" } else { " " },
                e.id,
                truncate(&clean(&e.name), text_w)
            );
            if i == sel {
                // Pad so the highlight spans the whole row.
                let pad = (inner.width as usize).saturating_sub(width(&text));
                Line::from(Span::styled(
                    format!("{text}{}", " ".repeat(pad)),
                    theme::selected(),
                ))
            } else {
                Line::from(text)
            }
        })
        .collect();
    frame.render_widget(Paragraph::new(lines), inner);
}

#[cfg(test)]
mod tests {
    use super::offset;

    #[test]
    fn selection_stays_in_view() {
        assert_eq!(offset(0, 5, 10), 0);
        assert_eq!(offset(0, 50, 10), 0);
        assert_eq!(offset(20, 50, 10), 15);
        assert_eq!(offset(49, 50, 10), 40);
        assert_eq!(offset(999, 50, 10), 40);
        assert_eq!(offset(3, 50, 0), 0);
    }
}
