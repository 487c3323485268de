//! Overlays drawn over the main screen, one file each (help, the palettes, the prompts, the
//! settings lists, a packet in full), chosen by the open overlay of the app's registry
//! ([`crate::app::overlay`]): adding an overlay there asks for its arm in [`draw`] (the match
//! is exhaustive). Each clears its own rect first so the panels below never bleed through.

mod filter;
mod help;
mod packet;
mod palette;
mod settings;

use crate::app::state::{AppState, Overlay};
use ratatui::Frame;

pub fn render(frame: &mut Frame, s: &AppState) {
    let area = frame.area();
    draw(frame, s, area);
    // An overlay covers the status bar's E-STOP badge: the badge is drawn over it too, in
    // the top right corner, while any droid is stopped.
    if !matches!(s.overlay, Overlay::None) && s.droids.iter().any(|d| d.control.estop) {
        let badge = " E-STOP ";
        let w = badge.len() as u16;
        if area.width >= w && area.height > 0 {
            let at = ratatui::layout::Rect {
                x: area.right() - w,
                y: area.y,
                width: w,
                height: 1,
            };
            frame.render_widget(
                ratatui::widgets::Paragraph::new(ratatui::text::Span::styled(
                    badge,
                    super::theme::alarm(),
                )),
                at,
            );
        }
    }
}

fn draw(frame: &mut Frame, s: &AppState, area: ratatui::layout::Rect) {
    match &s.overlay {
        Overlay::None => {}
        Overlay::Help => {
            let shown = help_shown(s);
            let pages = &s.borders.help_pages;
            help::render(frame, area, &shown, (&s.help_nav, pages), s.help_page)
        }
        Overlay::Animations { selected } => {
            let keys = &s.borders.palette;
            palette::render(frame, area, "Animations", &s.animations, *selected, keys)
        }
        Overlay::Sounds { selected } => {
            let keys = &s.borders.palette;
            palette::render(frame, area, "Sounds", &s.sounds, *selected, keys)
        }
        Overlay::Filter { input, before } => {
            filter::render(frame, area, input, before, &s.borders.prompt)
        }
        Overlay::Matrix { input } => filter::matrix(frame, area, input, &s.borders.prompt),
        Overlay::Channels { selected } => settings::channels(frame, area, s, *selected),
        Overlay::Tuning { selected, draft } => settings::tuning(frame, area, s, *selected, draft),
        Overlay::Packet {
            line,
            search,
            typing,
            matched,
            scroll,
        } => packet::render(
            frame,
            area,
            line,
            packet::View {
                search,
                typing: *typing,
                matched: *matched,
                scroll: *scroll,
                borders: &s.borders,
            },
        ),
    }
}

/// Help's sections for the chosen droid: only what applies to it (R2's help lists no BOLT
/// keys).
fn help_shown(s: &AppState) -> Vec<crate::app::state::HelpSection> {
    let (model, fleet) = (s.droid().model, s.droids.len() > 1);
    s.help
        .iter()
        .map(|h| h.applying(model, fleet))
        .filter(|h| !h.lines.is_empty())
        .collect()
}

/// How many pages help takes on a screen of `area`.
pub fn help_pages(s: &AppState, area: ratatui::layout::Rect) -> usize {
    help::pages(area, &help_shown(s))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Model;
    use ratatui::{Terminal, backend::TestBackend};

    fn screen(s: &AppState) -> String {
        let Ok(mut t) = Terminal::new(TestBackend::new(80, 24));
        t.draw(|f| render(f, s)).expect("a test backend draws");
        let buf = t.backend().buffer();
        buf.content().iter().map(|c| c.symbol()).collect()
    }

    /// Every overlay of the app's registry is drawn: the screen under it changes.
    #[test]
    fn every_registered_overlay_is_drawn() {
        let mut s = AppState::new(Model::R2D2, "R2-D2".into());
        s.help = crate::app::help::live(&crate::config::Config::defaults());
        let bare = screen(&s);
        for o in Overlay::samples() {
            s.overlay = o.clone();
            assert_ne!(screen(&s), bare, "{:?} draws nothing", o.name());
        }
    }
}
