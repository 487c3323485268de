//! The animation and sound palettes: a list of a droid's animations or sounds, moved through
//! with the `[keys.palette]` bindings; the play key chooses the selected entry.

use super::Outcome;
use crate::config::{Action, Context, Key, KeyMap};

/// How far the page keys move.
const PAGE: usize = 10;

/// A key on a palette of `len` entries with `selected` chosen: the selection moves, the
/// palette closes, or (a new press of the play key) the entry at the selection is played.
pub fn on_key(
    selected: &mut usize,
    len: usize,
    km: &KeyMap,
    key: Key,
    new_press: bool,
) -> Outcome<usize> {
    let last = len.saturating_sub(1);
    match km.action_in(Context::Palette, &key) {
        Some(Action::PaletteUp) => *selected = selected.saturating_sub(1),
        Some(Action::PaletteDown) => *selected = (*selected + 1).min(last),
        Some(Action::PalettePageUp) => *selected = selected.saturating_sub(PAGE),
        Some(Action::PalettePageDown) => *selected = (*selected + PAGE).min(last),
        Some(Action::PaletteClose) => return Outcome::Close,
        Some(Action::PalettePlay) if new_press => return Outcome::Done(*selected),
        _ => {}
    }
    Outcome::Stay
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::KeyCode;

    #[test]
    fn moves_within_the_list_plays_on_a_new_press_and_closes() {
        let km = crate::config::Config::defaults().keymap;
        let down = km.keys(Action::PaletteDown)[0];
        let play = km.keys(Action::PalettePlay)[0];
        let mut sel = 0;
        assert_eq!(on_key(&mut sel, 2, &km, down, true), Outcome::Stay);
        assert_eq!(on_key(&mut sel, 2, &km, down, true), Outcome::Stay);
        assert_eq!(sel, 1, "kept on the last entry");
        assert_eq!(on_key(&mut sel, 2, &km, play, false), Outcome::Stay);
        assert_eq!(on_key(&mut sel, 2, &km, play, true), Outcome::Done(1));
        let esc = Key::plain(KeyCode::Esc);
        assert_eq!(
            km.action_in(Context::Palette, &esc),
            Some(Action::PaletteClose)
        );
        assert_eq!(on_key(&mut sel, 2, &km, esc, true), Outcome::Close);
    }
}
