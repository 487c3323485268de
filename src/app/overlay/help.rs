//! Help's pages: the page keys turn them; any other key pressed closes help.

use super::Outcome;
use crate::config::{Action, Context, Key, KeyMap};

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
