//! The animation and sound palettes: a list of a droid's animations or sounds, moved through
//! with the `[keys.palette]` bindings; the play key chooses the selected entry. The wheel
//! moves the selection, a click on an entry plays it (as the play key does), a click outside
//! closes the palette.

use super::{Around, Component, Do, Outcome, Overlay};
use crate::app::input::MouseKind;
use crate::app::layout;
use crate::app::place::Place;
use crate::config::{Action, Context, Key, KeyMap};
use crate::family::catalog::Entry;
use ratatui::layout::{Position, Rect};

/// How far the page keys move.
const PAGE: usize = 10;

/// A palette: of animations (`ANIMATIONS`), or of sounds. One component for both: they
/// differ only in the list they show and what playing sends.
pub struct Palette<const ANIMATIONS: bool>;

/// The animation palette.
pub type Animations = Palette<true>;

/// The sound palette.
pub type Sounds = Palette<false>;

impl<const ANIMATIONS: bool> Component for Palette<ANIMATIONS> {
    const PLACE: Place = Place::Palette;

    fn on_key(o: &mut Overlay, around: &mut Around, key: Key, new_press: bool) -> Outcome<Do> {
        palette_key(o, around, key, new_press)
    }

    fn on_mouse(
        o: &mut Overlay,
        around: &mut Around,
        kind: MouseKind,
        at: Position,
    ) -> Outcome<Do> {
        palette_mouse(o, around, kind, at)
    }

    #[cfg(test)]
    fn sample() -> Overlay {
        if ANIMATIONS {
            Overlay::Animations { selected: 0 }
        } else {
            Overlay::Sounds { selected: 0 }
        }
    }
}

/// The open palette's selection and whether it lists animations.
fn open(o: &mut Overlay) -> Option<(&mut usize, bool)> {
    match o {
        Overlay::Animations { selected } => Some((selected, true)),
        Overlay::Sounds { selected } => Some((selected, false)),
        _ => None,
    }
}

/// The entries a palette lists.
fn entries<'a>(around: &Around<'a>, animation: bool) -> &'a [Entry] {
    if animation {
        around.animations
    } else {
        around.sounds
    }
}

/// A key on either palette; playing closes it.
fn palette_key(o: &mut Overlay, around: &mut Around, key: Key, new_press: bool) -> Outcome<Do> {
    let Some((selected, animation)) = open(o) else {
        return Outcome::Stay;
    };
    let list = entries(around, animation);
    match on_key(selected, list.len(), around.keymap, key, new_press) {
        Outcome::Done(index) => Outcome::Done(Do::Play { animation, index }),
        Outcome::Stay | Outcome::Apply(_) => Outcome::Stay,
        Outcome::Close => Outcome::Close,
    }
}

/// The mouse on either palette.
fn palette_mouse(
    o: &mut Overlay,
    around: &mut Around,
    kind: MouseKind,
    at: Position,
) -> Outcome<Do> {
    let Some((selected, animation)) = open(o) else {
        return Outcome::Stay;
    };
    let entries = entries(around, animation);
    let len = entries.len();
    let rect = layout::palette_rect(
        around.area,
        entries
            .iter()
            .map(|e| ratatui::text::Span::raw(e.name.as_str()).width()),
        len,
    );
    let inner = Rect {
        x: rect.x + 1,
        y: rect.y + 1,
        width: rect.width.saturating_sub(2),
        height: rect.height.saturating_sub(2),
    };
    *selected = match kind {
        MouseKind::ScrollUp => selected.saturating_sub(1),
        MouseKind::ScrollDown => (*selected + 1).min(len.saturating_sub(1)),
        MouseKind::Click if inner.contains(at) => {
            let first = layout::list_offset(*selected, len, inner.height as usize);
            let i = first + (at.y - inner.y) as usize;
            if i >= len {
                return Outcome::Stay;
            }
            i
        }
        MouseKind::Click => return Outcome::Close,
    };
    match around.keymap.keys(Action::PalettePlay).first().copied() {
        // The same path as the play key.
        Some(play) if kind == MouseKind::Click => palette_key(o, around, play, true),
        _ => Outcome::Stay,
    }
}

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
