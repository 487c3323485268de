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

/// Redraw a finished screen in `theme`'s colours: the panels are drawn for a dark terminal,
/// and this one pass adapts every cell, so no panel can forget the theme.
/// - dark: as drawn;
/// - light: the colours that vanish on a light background (white, light grey, yellow, the
///   light variants) become their dark counterparts; a droid's own LED colours stay true;
/// - none (`NO_COLOR`): no colour at all; what had a background (the E-STOP badge, alarms,
///   the selected entry) is shown in reverse video, so it still stands out.
pub fn apply(buf: &mut ratatui::buffer::Buffer, theme: crate::config::Theme) {
    use crate::config::Theme;
    match theme {
        Theme::Dark => {}
        Theme::Light => {
            for cell in buf.content.iter_mut() {
                cell.fg = on_light(cell.fg);
                if cell.bg != Color::Reset {
                    cell.bg = on_light(cell.bg);
                }
            }
        }
        Theme::None => {
            for cell in buf.content.iter_mut() {
                if cell.bg != Color::Reset {
                    cell.modifier.insert(Modifier::REVERSED);
                }
                cell.fg = Color::Reset;
                cell.bg = Color::Reset;
            }
        }
    }
}

/// A dark theme's colour as it reads on a light background.
fn on_light(c: Color) -> Color {
    match c {
        Color::White => Color::Black,
        Color::Gray => Color::DarkGray,
        Color::DarkGray => Color::Gray,
        Color::Yellow => Color::Indexed(130),
        Color::Cyan => Color::Blue,
        Color::LightGreen | Color::Green => Color::Indexed(28),
        Color::LightRed => Color::Red,
        Color::LightBlue => Color::Blue,
        Color::LightCyan => Color::Indexed(30),
        Color::LightYellow => Color::Indexed(130),
        Color::LightMagenta => Color::Magenta,
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Theme;
    use ratatui::buffer::Buffer;
    use ratatui::layout::Rect;

    fn screen() -> Buffer {
        let mut buf = Buffer::empty(Rect::new(0, 0, 4, 1));
        buf[(0, 0)].set_symbol("E").set_style(alarm());
        buf[(1, 0)].set_symbol("y").set_style(commanded());
        buf[(2, 0)].set_symbol("w").set_fg(Color::White);
        buf[(3, 0)].set_symbol("█").set_fg(Color::Rgb(255, 255, 0));
        buf
    }

    #[test]
    fn no_colour_keeps_the_text_and_shows_alarms_reversed() {
        let mut buf = screen();
        apply(&mut buf, Theme::None);
        for cell in buf.content.iter() {
            assert_eq!((cell.fg, cell.bg), (Color::Reset, Color::Reset), "{cell:?}");
        }
        assert!(
            buf[(0, 0)]
                .modifier
                .contains(Modifier::REVERSED | Modifier::BOLD)
        );
        assert!(!buf[(1, 0)].modifier.contains(Modifier::REVERSED));
        assert_eq!(buf[(0, 0)].symbol(), "E");
    }

    #[test]
    fn light_turns_what_vanishes_on_white_dark_and_keeps_led_colours() {
        let mut buf = screen();
        apply(&mut buf, Theme::Light);
        assert_eq!(buf[(2, 0)].fg, Color::Black);
        assert_ne!(buf[(1, 0)].fg, Color::Yellow);
        assert_eq!(
            buf[(3, 0)].fg,
            Color::Rgb(255, 255, 0),
            "a LED's own colour"
        );
        assert_eq!(buf[(0, 0)].bg, ALERT, "the alarm stays red");
        let mut dark = screen();
        apply(&mut dark, Theme::Dark);
        assert_eq!(dark, screen());
    }

    #[test]
    fn no_color_set_to_anything_but_empty_means_none() {
        use std::ffi::OsStr;
        assert_eq!(Theme::effective(Theme::Light, None), Theme::Light);
        assert_eq!(
            Theme::effective(Theme::Dark, Some(OsStr::new(""))),
            Theme::Dark
        );
        assert_eq!(
            Theme::effective(Theme::Dark, Some(OsStr::new("1"))),
            Theme::None
        );
    }
}
