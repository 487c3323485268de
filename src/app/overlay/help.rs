//! Help's pages: the page keys turn them; any other key pressed closes help. The wheel turns
//! them too, and a click closes help.

use super::{Around, Component, Do, Outcome, Overlay};
use crate::app::input::MouseKind;
use crate::app::place::Place;
use crate::config::{Action, Context, Key, KeyMap};
use ratatui::layout::Position;

/// The help overlay (its page is the app's [`crate::app::state::AppState::help_page`]).
pub struct Help;

impl Component for Help {
    const PLACE: Place = Place::Help;

    fn on_key(_: &mut Overlay, around: &mut Around, key: Key, new_press: bool) -> Outcome<Do> {
        match on_key(around.help_page, around.keymap, key, new_press) {
            Outcome::Stay => Outcome::Stay,
            _ => Outcome::Close,
        }
    }

    fn on_mouse(_: &mut Overlay, around: &mut Around, kind: MouseKind, _: Position) -> Outcome<Do> {
        let page = &mut *around.help_page;
        match kind {
            MouseKind::ScrollDown => *page += 1,
            MouseKind::ScrollUp => *page = page.saturating_sub(1),
            MouseKind::Click => return Outcome::Close,
        }
        Outcome::Stay
    }

    #[cfg(test)]
    fn sample() -> Overlay {
        Overlay::Help
    }
}

/// A key on help showing `page` (the UI clamps it to the last page).
pub fn on_key(page: &mut usize, km: &KeyMap, key: Key, new_press: bool) -> Outcome {
    match km.action_in(Context::Help, &key) {
        Some(Action::HelpNext) => *page += 1,
        Some(Action::HelpPrevious) => *page = page.saturating_sub(1),
        // Any other key closes help.
        _ if new_press => return Outcome::Close,
        _ => {}
    }
    Outcome::Stay
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn page_keys_turn_pages_and_any_other_press_closes() {
        let km = crate::config::Config::defaults().keymap;
        let next = km.keys(Action::HelpNext)[0];
        let prev = km.keys(Action::HelpPrevious)[0];
        let mut page = 0;
        assert_eq!(on_key(&mut page, &km, next, true), Outcome::Stay);
        assert_eq!(on_key(&mut page, &km, next, false), Outcome::Stay);
        assert_eq!(page, 2, "a repeat turns a page too");
        assert_eq!(on_key(&mut page, &km, prev, true), Outcome::Stay);
        assert_eq!(page, 1);
        let other = Key::ch('x');
        assert_eq!(on_key(&mut page, &km, other, false), Outcome::Stay);
        assert_eq!(on_key(&mut page, &km, other, true), Outcome::Close);
    }
}
