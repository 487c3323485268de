//! The lights panel, in the dome's place on droids without a dome (BB-8, SPRK+, Ollie,
//! BB-9E): the main LED's commanded colour as a swatch, the back (aiming) light, and whether
//! aim mode is on. Panels follow capabilities, not models: this one is for "no dome".

use super::theme;
use crate::app::state::AppState;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;

pub fn render(frame: &mut Frame, area: Rect, s: &AppState) {
    let title = if s.droid().control.aiming {
        Line::from(vec![
            Span::raw(" Lights "),
            Span::styled("AIMING ", theme::attention()),
        ])
    } else {
        Line::from(" Lights ")
    };
    let block = theme::panel(title);
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let main = match s.droid().leds.main {
        Some([r, g, b]) => vec![
            Span::styled("main ", theme::label()),
            Span::styled("███", Style::new().fg(Color::Rgb(r, g, b))),
            Span::raw(format!(" {r},{g},{b}")),
        ],
        None => vec![
            Span::styled("main ", theme::label()),
            Span::styled("not set", theme::dim()),
        ],
    };
    let back = match s.droid().leds.back {
        Some(0) => Span::raw("off"),
        Some(b) => Span::styled(
            format!("{b}/255"),
            Style::new().fg(Color::Rgb(90, 160, 255)),
        ),
        None => Span::styled("not set", theme::dim()),
    };
    let mut spans = main;
    spans.push(Span::styled("   back ", theme::label()));
    spans.push(back);
    let mut lines = vec![Line::from(spans)];
    if inner.height >= 2 {
        // The keys as bound, in words short enough for the panel (it was cut mid-word).
        let hint: std::borrow::Cow<str> = if s.droid().control.aiming {
            format!("turn to face forward, then {}", s.borders.aim_again).into()
        } else {
            s.borders.lights_panel.as_str().into()
        };
        // Whole hints over the lines there are (at 120×40 one line cut the last one
        // mid-word); only what still does not fit is cut, at the last line's end.
        let room = usize::from(inner.height - 1);
        let w = inner.width as usize;
        let mut wrapped = super::text::wrap_items(&hint, " · ", w);
        if wrapped.len() > room {
            let rest = wrapped.split_off(room - 1).join(" · ");
            wrapped.push(super::text::truncate(&rest, w));
        }
        lines.extend(
            wrapped
                .into_iter()
                .map(|l| Line::from(Span::styled(l, theme::dim()))),
        );
    }
    frame.render_widget(Paragraph::new(lines), inner);
}
