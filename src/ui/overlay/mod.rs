//! Overlays drawn over the main screen: help, the animation and sound palettes, and the
//! packet-log filter prompt. Each clears its own rect first so the panels below never bleed
//! through.

mod filter;
mod help;
mod packet;
mod palette;
mod settings;

use crate::app::state::{AppState, Overlay};
use ratatui::Frame;

pub fn render(frame: &mut Frame, s: &AppState) {
    let area = frame.area();
    match &s.overlay {
        Overlay::None => {}
        Overlay::Help => {
            // Only what applies to the chosen droid (R2's help lists no BOLT keys).
            let (model, fleet) = (s.droid().model, s.droids.len() > 1);
            let shown: Vec<_> = s
                .help
                .iter()
                .map(|h| h.applying(model, fleet))
                .filter(|h| !h.lines.is_empty())
                .collect();
            help::render(frame, area, &shown, &s.help_nav, s.help_page)
        }
        Overlay::Animations { selected } => {
            palette::render(frame, area, "Animations", &s.animations, *selected)
        }
        Overlay::Sounds { selected } => {
            palette::render(frame, area, "Sounds", &s.sounds, *selected)
        }
        Overlay::Filter { input } => filter::render(frame, area, input, &s.log.filter),
        Overlay::Matrix { input } => filter::matrix(frame, area, input),
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
            },
        ),
    }
}
