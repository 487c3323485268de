//! The droid picker shown before the app when several droids answer the scan. Its columns
//! are as wide as their content ([`crate::app::picker::widths`]) and the box as wide as its
//! widest line, within the screen.

use super::layout::centered;
use super::text::{clean, truncate, width};
use super::theme;
use crate::app::picker::{HEADINGS, NAME_MAX, Picker, cells, line, widths};
use ratatui::Frame;
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;

const TITLE: &str = " Several droids are in range ";

/// The picker, in the colours of `theme` (the app's: `[display] theme`, `NO_COLOR`).
pub fn draw_themed(frame: &mut Frame, picker: &Picker, t: crate::config::Theme) {
    draw(frame, picker);
    theme::apply(frame.buffer_mut(), t);
}

pub fn draw(frame: &mut Frame, picker: &Picker) {
    let area = frame.area();
    let rows: Vec<[String; 4]> = picker
        .entries
        .iter()
        .map(|e| {
            let [name, model, id, rssi] = cells(e);
            [truncate(&clean(&name), NAME_MAX), model, clean(&id), rssi]
        })
        .collect();
    let w = widths(&rows);
    // The marks and the number: "▶✓12. ".
    let digits = picker.entries.len().max(1).to_string().len();
    let lead = 2 + digits + 2;
    let heading = format!(
        "{}{}",
        " ".repeat(lead),
        line(&HEADINGS.map(String::from), &w)
    );
    let body: Vec<String> = rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let marked = picker.marked.get(i).copied().unwrap_or(false);
            format!(
                "{}{}{:>digits$}. {}",
                if i == picker.selected { "▶" } else { " " },
                if marked { "✓" } else { " " },
                i + 1,
                line(r, &w)
            )
        })
        .collect();
    let footer = picker.footer();
    let widest = std::iter::once(&heading)
        .chain(&body)
        .chain(std::iter::once(&footer))
        .map(|l| width(l))
        .chain(std::iter::once(width(TITLE) + 2))
        .max()
        .unwrap_or(0);
    // A column of margin on the right, and the borders.
    let box_w = u16::try_from(widest + 3).unwrap_or(u16::MAX);
    let box_h = u16::try_from(picker.entries.len() + 6).unwrap_or(u16::MAX);
    let box_area = centered(area, box_w, box_h.max(7));
    let block = theme::panel(TITLE);
    let inner = block.inner(box_area);
    frame.render_widget(block, box_area);
    let room = inner.width as usize;
    let mut lines = vec![Line::from(Span::styled(
        truncate(&heading, room),
        theme::label(),
    ))];
    for (i, text) in body.iter().enumerate() {
        let marked = picker.marked.get(i).copied().unwrap_or(false);
        let style = if i == picker.selected || marked {
            theme::selected()
        } else {
            theme::reported()
        };
        lines.push(Line::from(Span::styled(truncate(text, room), style)));
    }
    lines.push(Line::from(""));
    lines.push(Line::from(Span::styled(
        truncate(&footer, room),
        theme::dim(),
    )));
    frame.render_widget(Paragraph::new(lines), inner);
}
