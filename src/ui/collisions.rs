//! Collisions: how many, and what the last one was like (axis, power, speed, impact
//! acceleration). While the collision flash is on the whole panel turns into an alarm, so a
//! bump is noticed even when the eye is on the packet log.

use super::theme;
use crate::app::state::AppState;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::Style;
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;

pub fn render(frame: &mut Frame, area: Rect, s: &AppState) {
    let t = &s.droid().telemetry;
    let block = if s.flashing() {
        theme::panel(Span::styled(
            format!(" COLLISION! #{} ", t.collisions),
            theme::alarm(),
        ))
        .border_style(Style::new().fg(theme::ALERT))
    } else {
        theme::panel(Line::from(vec![
            Span::raw(" Collisions "),
            Span::styled(format!("{} ", t.collisions), theme::bold()),
        ]))
    };
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let Some(seen) = t.last_collision else {
        frame.render_widget(
            Paragraph::new(Span::styled("none yet", theme::dim())),
            inner,
        );
        return;
    };
    let c = seen.collision;
    let ago = s.now.saturating_sub(seen.at).as_secs_f32();
    let axis = match (c.axis.x, c.axis.y) {
        (true, true) => "x+y",
        (true, false) => "x",
        (false, true) => "y",
        (false, false) => "none",
    };
    let [ax, ay, az] = c.accel.map(|a| a.g());
    let [px, py, pz] = c.power;
    let lines = vec![
        Line::from(vec![
            Span::styled("last ", theme::label()),
            Span::raw(format!("{ago:.1} s ago")),
            Span::styled("  axis ", theme::label()),
            Span::styled(axis, theme::bold()),
            Span::styled("  speed ", theme::label()),
            Span::raw(c.speed.to_string()),
        ]),
        Line::from(vec![
            Span::styled("power ", theme::label()),
            Span::raw(format!("x {px} y {py} z {pz}")),
        ]),
        Line::from(vec![
            Span::styled("accel ", theme::label()),
            Span::raw(format!("x {ax:.2} y {ay:.2} z {az:.2} g")),
        ]),
        Line::from(vec![
            Span::styled("droid clock ", theme::label()),
            Span::raw(format!("{} ms", c.time_ms)),
        ]),
    ];
    frame.render_widget(Paragraph::new(lines), inner);
}
