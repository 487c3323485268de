//! Terminal input as the app sees it, converted from crossterm at the edge so the event loop
//! can be driven by synthetic events in tests.

use crate::config::{Key, KeyCode};
use crossterm::event::{
    Event, KeyCode as CtCode, KeyEvent, KeyEventKind, KeyModifiers, MouseButton, MouseEventKind,
};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeyKind {
    Press,
    Repeat,
    Release,
}

/// What the mouse did (the wheel, or a left click); it never drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MouseKind {
    ScrollUp,
    ScrollDown,
    Click,
}

/// An input event from the terminal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TermEvent {
    Key {
        key: Key,
        kind: KeyKind,
    },
    /// At column `col`, row `row` of the terminal.
    Mouse {
        kind: MouseKind,
        col: u16,
        row: u16,
    },
    FocusLost,
    FocusGained,
    Resize,
}

/// Convert a crossterm key event (None for keys droidctl does not use).
pub fn key_from_crossterm(k: &KeyEvent) -> Option<(Key, KeyKind)> {
    let code = match k.code {
        CtCode::Char(' ') => KeyCode::Space,
        CtCode::Char(c) => {
            // Shift+letter may arrive as the lower-case letter with SHIFT (kitty protocol):
            // bindings write it upper case.
            if k.modifiers.contains(KeyModifiers::SHIFT) && c.is_ascii_lowercase() {
                KeyCode::Char(c.to_ascii_uppercase())
            } else {
                KeyCode::Char(c)
            }
        }
        CtCode::Up => KeyCode::Up,
        CtCode::Down => KeyCode::Down,
        CtCode::Left => KeyCode::Left,
        CtCode::Right => KeyCode::Right,
        CtCode::Esc => KeyCode::Esc,
        CtCode::Enter => KeyCode::Enter,
        CtCode::Tab => KeyCode::Tab,
        CtCode::Backspace => KeyCode::Backspace,
        CtCode::PageUp => KeyCode::PageUp,
        CtCode::PageDown => KeyCode::PageDown,
        CtCode::Home => KeyCode::Home,
        CtCode::End => KeyCode::End,
        CtCode::F(n) => KeyCode::F(n),
        _ => return None,
    };
    let kind = match k.kind {
        KeyEventKind::Press => KeyKind::Press,
        KeyEventKind::Repeat => KeyKind::Repeat,
        KeyEventKind::Release => KeyKind::Release,
    };
    let ctrl = k.modifiers.contains(KeyModifiers::CONTROL);
    Some((Key { code, ctrl }, kind))
}

pub fn from_crossterm(e: &Event) -> Option<TermEvent> {
    match e {
        Event::Key(k) => key_from_crossterm(k).map(|(key, kind)| TermEvent::Key { key, kind }),
        Event::FocusLost => Some(TermEvent::FocusLost),
        Event::FocusGained => Some(TermEvent::FocusGained),
        Event::Resize(..) => Some(TermEvent::Resize),
        Event::Mouse(m) => {
            let kind = match m.kind {
                MouseEventKind::ScrollUp => MouseKind::ScrollUp,
                MouseEventKind::ScrollDown => MouseKind::ScrollDown,
                MouseEventKind::Down(MouseButton::Left) => MouseKind::Click,
                _ => return None,
            };
            Some(TermEvent::Mouse {
                kind,
                col: m.column,
                row: m.row,
            })
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crossterm::event::KeyEventState;

    fn ev(code: CtCode, modifiers: KeyModifiers, kind: KeyEventKind) -> KeyEvent {
        KeyEvent {
            code,
            modifiers,
            kind,
            state: KeyEventState::empty(),
        }
    }

    #[test]
    fn converts_keys() {
        let k = key_from_crossterm(&ev(
            CtCode::Char('q'),
            KeyModifiers::SHIFT,
            KeyEventKind::Press,
        ));
        assert_eq!(k, Some((Key::ch('Q'), KeyKind::Press)));
        let k = key_from_crossterm(&ev(
            CtCode::Char(' '),
            KeyModifiers::NONE,
            KeyEventKind::Release,
        ));
        assert_eq!(k, Some((Key::plain(KeyCode::Space), KeyKind::Release)));
        let k = key_from_crossterm(&ev(
            CtCode::Char('c'),
            KeyModifiers::CONTROL,
            KeyEventKind::Press,
        ));
        assert_eq!(
            k,
            Some((
                Key {
                    code: KeyCode::Char('c'),
                    ctrl: true
                },
                KeyKind::Press
            ))
        );
        assert_eq!(
            key_from_crossterm(&ev(CtCode::Insert, KeyModifiers::NONE, KeyEventKind::Press)),
            None
        );
        assert_eq!(
            from_crossterm(&Event::FocusLost),
            Some(TermEvent::FocusLost)
        );
        let mouse = |kind| {
            from_crossterm(&Event::Mouse(crossterm::event::MouseEvent {
                kind,
                column: 7,
                row: 3,
                modifiers: KeyModifiers::NONE,
            }))
        };
        assert_eq!(
            mouse(MouseEventKind::ScrollDown),
            Some(TermEvent::Mouse {
                kind: MouseKind::ScrollDown,
                col: 7,
                row: 3
            })
        );
        assert_eq!(
            mouse(MouseEventKind::Down(MouseButton::Left)).map(|e| matches!(
                e,
                TermEvent::Mouse {
                    kind: MouseKind::Click,
                    ..
                }
            )),
            Some(true)
        );
        assert_eq!(mouse(MouseEventKind::Moved), None);
    }
}
