//! The packet-log filter prompt: typed text that applies as it is typed; apply keeps it,
//! cancel goes back to the filter from before.

use super::{Around, Component, Do, Outcome, Overlay};
use crate::app::packet_log::LogFilter;
use crate::app::place::Place;
use crate::config::{Action, Context, Key, KeyCode, KeyMap};

/// The packet-log filter prompt.
pub struct Filter;

impl Component for Filter {
    const PLACE: Place = Place::Filter;

    fn on_key(o: &mut Overlay, around: &mut Around, key: Key, _new_press: bool) -> Outcome<Do> {
        let Overlay::Filter { input, before } = o else {
            return Outcome::Stay;
        };
        match on_key(input, before, around.keymap, key) {
            Prompted::Stay => Outcome::Stay,
            Prompted::Typed(f) => Outcome::Apply(Do::Filter(f)),
            Prompted::Applied => Outcome::Close,
            Prompted::Cancelled(before) => Outcome::Done(Do::Filter(before)),
        }
    }

    #[cfg(test)]
    fn sample() -> Overlay {
        Overlay::Filter {
            input: String::new(),
            before: Default::default(),
        }
    }
}

/// Longest log filter typed.
const FILTER_MAX: usize = 80;

/// What a key on the prompt did (the prompt's own outcome: it stays open while typing).
#[derive(Debug, Clone, PartialEq)]
pub enum Prompted {
    /// Nothing the log needs to know.
    Stay,
    /// The text changed: the log shows this filter now, and the prompt stays.
    Typed(LogFilter),
    /// Applied: the filter as typed stays, the prompt closes.
    Applied,
    /// Cancelled: the log goes back to the filter it had, the prompt closes.
    Cancelled(LogFilter),
}

/// A key on the prompt holding `input`, opened over the log's filter `before`.
pub fn on_key(input: &mut String, before: &mut LogFilter, km: &KeyMap, key: Key) -> Prompted {
    match km.action_in(Context::Filter, &key) {
        Some(Action::FilterCancel) => Prompted::Cancelled(std::mem::take(before)),
        Some(Action::FilterApply) => Prompted::Applied,
        // The rest is typing, and the log follows as it is typed.
        _ => {
            let was = input.clone();
            edit(input, key, FILTER_MAX, |_| true);
            if *input != was {
                Prompted::Typed(LogFilter::parse(input))
            } else {
                Prompted::Stay
            }
        }
    }
}

/// Typing into a prompt's `input`: Backspace, Space, and the characters `ok` takes, up to
/// `max` bytes (the filter, a packet's search and BOLT's matrix text are typed alike).
pub fn edit(input: &mut String, key: Key, max: usize, ok: impl Fn(char) -> bool) {
    match key.code {
        KeyCode::Backspace => {
            input.pop();
        }
        KeyCode::Char(c) if !key.ctrl && ok(c) && input.len() < max => input.push(c),
        KeyCode::Space if input.len() < max => input.push(' '),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_log_follows_the_typing_and_cancel_restores_the_filter_from_before() {
        let km = crate::config::Config::defaults().keymap;
        let old = LogFilter::parse("ack");
        let mut before = old.clone();
        let mut input = String::new();
        assert_eq!(
            on_key(&mut input, &mut before, &km, Key::ch('r')),
            Prompted::Typed(LogFilter::parse("r"))
        );
        // Ctrl+r is no text: nothing changes, nothing to tell the log.
        let ctrl_r = Key {
            code: KeyCode::Char('r'),
            ctrl: true,
        };
        assert_eq!(on_key(&mut input, &mut before, &km, ctrl_r), Prompted::Stay);
        assert_eq!(input, "r");
        let cancel = km.keys(Action::FilterCancel)[0];
        assert_eq!(
            on_key(&mut input, &mut before, &km, cancel),
            Prompted::Cancelled(old)
        );
        let apply = km.keys(Action::FilterApply)[0];
        assert_eq!(
            on_key(&mut input, &mut before, &km, apply),
            Prompted::Applied
        );
    }
}
