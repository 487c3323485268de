//! The context footer: the few keys that matter in the place on top and for the chosen
//! droid, then `?` for the rest (as lazygit, bottom and htop keep one). Its keys come from
//! [`crate::app::help::footer_now`], built from the same key table as help, with the
//! per-place exceptions of [`crate::app::help::FOOTER_EXCEPTIONS`]. Entries are never
//! cut: the least important go whole when the row is too narrow, the kept ones (help, quit,
//! close) stay.

use super::text::{clean, width};
use super::theme;
use crate::app::state::{AppState, FooterKey};
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;

const GAP: usize = 2;

fn entry_width(k: &FooterKey) -> usize {
    width(&k.key) + 1 + width(&k.word)
}

/// The entries shown in `w` cells: every kept one, then the others in order while they fit.
pub fn fit<'a>(keys: &[&'a FooterKey], w: usize) -> Vec<&'a FooterKey> {
    let cost = |k: &FooterKey| entry_width(k) + GAP;
    let mut used: usize = keys.iter().filter(|k| k.keep).map(|k| cost(k)).sum();
    let mut shown = Vec::new();
    for k in keys {
        if k.keep {
            shown.push(*k);
        } else if used + cost(k) <= w {
            used += cost(k);
            shown.push(*k);
        }
    }
    shown
}

pub fn render(frame: &mut Frame, area: Rect, state: &AppState) {
    // Only help's own size is the screen's business: the rest is the footer table's.
    let help_paged = state.overlay == crate::app::state::Overlay::Help
        && super::overlay::help_pages(state, frame.area()) > 1;
    let keys = crate::app::help::footer_now(state, help_paged);
    let mut spans = vec![Span::raw(" ")];
    for (i, k) in fit(&keys, area.width as usize).into_iter().enumerate() {
        if i > 0 {
            spans.push(Span::raw(" ".repeat(GAP)));
        }
        spans.push(Span::styled(clean(&k.key), theme::commanded()));
        spans.push(Span::styled(format!(" {}", clean(&k.word)), theme::dim()));
    }
    frame.render_widget(Paragraph::new(Line::from(spans)), area);
}
