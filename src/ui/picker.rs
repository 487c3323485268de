//! The droid picker shown before the app when several droids answer the scan.

use super::layout::centered;
use super::text::{clean, truncate};
use super::theme;
use crate::app::picker::Picker;
use ratatui::Frame;
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;

pub fn draw(frame: &mut Frame, picker: &Picker) {
    let area = frame.area();
    let rows = picker.entries.len() as u16 + 6;
    let box_area = centered(area, 72, rows.max(7));
    let block = theme::panel(" Several droids are in range ");
    let inner = block.inner(box_area);
    frame.render_widget(block, box_area);
    let width = inner.width as usize;
    let mut lines = vec![Line::from(Span::styled(
        truncate(
            &format!(
                "     {:<14}{:<10}{:<19}{}",
                "name", "model", "address", "signal"
            ),
            width,
        ),
        theme::label(),
    ))];
    for (i, e) in picker.entries.iter().enumerate() {
        let marked = picker.marked.get(i).copied().unwrap_or(false);
        let text = format!(
            "{}{}{}. {:<13} {:<9} {}  {}",
            if i == picker.selected { "▶" } else { " " },
            if marked { "✓" } else { " " },
            i + 1,
            clean(e.name.as_deref().unwrap_or("?")),
            e.model.map(|m| m.display_name()).unwrap_or("?"),
            clean(&e.id.to_string()),
            e.rssi
                .map(|r| format!("{r} dBm"))
                .unwrap_or_else(|| "-".into())
        );
        let style = if i == picker.selected || marked {
            theme::selected()
        } else {
            theme::reported()
        };
        lines.push(Line::from(Span::styled(truncate(&text, width), style)));
    }
    lines.push(Line::from(""));
    lines.push(Line::from(Span::styled(
        truncate(&picker.footer(), width),
        theme::dim(),
    )));
    frame.render_widget(Paragraph::new(lines), inner);
}
