//! Colours and styles, in one place so every panel agrees on what a colour means
//! (yellow = what we command, cyan = what the droid reports, red = trouble).

use ratatui::style::{Color, Modifier, Style};

/// What droidctl commands (heading, speed, dome target).
pub const COMMANDED: Color = Color::Yellow;
/// What the droid reports back.
pub const REPORTED: Color = Color::Cyan;
/// Errors, e-stop, critical battery, collisions.
pub const ALERT: Color = Color::Red;
/// Warnings: low battery, reconnecting, transitions.
pub const WARN: Color = Color::Yellow;
/// Healthy states.
pub const OK: Color = Color::Green;
/// Secondary text: labels, units, empty gauge cells.
pub const DIM: Color = Color::DarkGray;

pub fn dim() -> Style {
    Style::new().fg(DIM)
}

pub fn label() -> Style {
    Style::new().fg(Color::Gray)
}

pub fn bold() -> Style {
    Style::new().add_modifier(Modifier::BOLD)
}

pub fn commanded() -> Style {
    Style::new().fg(COMMANDED)
}

pub fn reported() -> Style {
    Style::new().fg(REPORTED)
}

/// A latched alarm: white on red, bold (E-STOP, COLLISION!).
pub fn alarm() -> Style {
    Style::new()
        .fg(Color::White)
        .bg(ALERT)
        .add_modifier(Modifier::BOLD)
}

/// Something to look at now but not an alarm (reconnecting).
pub fn attention() -> Style {
    Style::new()
        .fg(Color::Black)
        .bg(WARN)
        .add_modifier(Modifier::BOLD)
}

/// The selected entry of a list.
pub fn selected() -> Style {
    Style::new().add_modifier(Modifier::REVERSED | Modifier::BOLD)
}

/// The frame of a panel: rounded border, title on the top edge.
pub fn panel<'a>(title: impl Into<ratatui::text::Line<'a>>) -> ratatui::widgets::Block<'a> {
    ratatui::widgets::Block::bordered()
        .border_type(ratatui::widgets::BorderType::Rounded)
        .border_style(dim())
        .title(title)
}
