//! Typing what BOLT's matrix shows: one character is drawn, more scroll. The prompts' keys
//! (the filter table's apply and cancel); the rest is text, printable ASCII up to what the
//! matrix scrolls.

use super::filter::edit;
use super::{Around, Component, Do, Outcome, Overlay};
use crate::app::place::Place;
use crate::app::view::matrix::MatrixView;
use crate::config::{Action, Context, Key};
use crate::protocol::v2::types::SCROLL_TEXT_MAX;

/// The matrix prompt.
pub struct Matrix;

impl Component for Matrix {
    const PLACE: Place = Place::Matrix;

    fn on_key(o: &mut Overlay, around: &mut Around, key: Key, _new_press: bool) -> Outcome<Do> {
        let Overlay::Matrix { input } = o else {
            return Outcome::Stay;
        };
        match around.keymap.action_in(Context::Filter, &key) {
            Some(Action::FilterCancel) => Outcome::Close,
            Some(Action::FilterApply) => match MatrixView::typed(input) {
                Some(shows) => Outcome::Done(Do::Matrix(shows)),
                None => Outcome::Close,
            },
            _ => {
                edit(input, key, SCROLL_TEXT_MAX, |c| c.is_ascii_graphic());
                Outcome::Stay
            }
        }
    }

    #[cfg(test)]
    fn sample() -> Overlay {
        Overlay::Matrix {
            input: String::new(),
        }
    }
}
