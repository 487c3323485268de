//! Keys, actions and the configurable bindings between them. Keys are our own type so the
//! control logic is testable without a terminal; [`crate::app`] converts crossterm events.

use std::collections::{BTreeMap, HashMap};
use std::fmt;

/// A key, without the press/release distinction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum KeyCode {
    /// A printable character, case kept (upper case = with Shift).
    Char(char),
    Up,
    Down,
    Left,
    Right,
    Space,
    Esc,
    Enter,
    Tab,
    Backspace,
    PageUp,
    PageDown,
    Home,
    End,
    F(u8),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Key {
    pub code: KeyCode,
    pub ctrl: bool,
}

impl Key {
    pub const fn plain(code: KeyCode) -> Key {
        Key { code, ctrl: false }
    }

    pub const fn ch(c: char) -> Key {
        Key::plain(KeyCode::Char(c))
    }

    /// Parse a config name: "Up", "Space", "F1", "w", "+", "Ctrl+c".
    pub fn parse(name: &str) -> Option<Key> {
        let (ctrl, rest) = match name
            .strip_prefix("Ctrl+")
            .or_else(|| name.strip_prefix("ctrl+"))
        {
            Some(r) => (true, r),
            None => (false, name),
        };
        let code = match rest {
            "Up" => KeyCode::Up,
            "Down" => KeyCode::Down,
            "Left" => KeyCode::Left,
            "Right" => KeyCode::Right,
            "Space" => KeyCode::Space,
            "Esc" => KeyCode::Esc,
            "Enter" => KeyCode::Enter,
            "Tab" => KeyCode::Tab,
            "Backspace" => KeyCode::Backspace,
            "PageUp" => KeyCode::PageUp,
            "PageDown" => KeyCode::PageDown,
            "Home" => KeyCode::Home,
            "End" => KeyCode::End,
            f if f.len() >= 2 && f.starts_with('F') => {
                KeyCode::F(f[1..].parse().ok().filter(|n| (1..=12).contains(n))?)
            }
            s => {
                let mut chars = s.chars();
                let c = chars.next()?;
                if chars.next().is_some() || c.is_control() || c == ' ' {
                    return None;
                }
                KeyCode::Char(c)
            }
        };
        Some(Key { code, ctrl })
    }
}

impl fmt::Display for Key {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.ctrl {
            write!(f, "Ctrl+")?;
        }
        match self.code {
            KeyCode::Char(c) => write!(f, "{c}"),
            KeyCode::Up => write!(f, "↑"),
            KeyCode::Down => write!(f, "↓"),
            KeyCode::Left => write!(f, "←"),
            KeyCode::Right => write!(f, "→"),
            KeyCode::F(n) => write!(f, "F{n}"),
            other => write!(f, "{other:?}"),
        }
    }
}

/// What a key does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Action {
    Forward,
    Backward,
    Left,
    Right,
    Faster,
    Slower,
    DomeLeft,
    DomeRight,
    Tripod,
    Bipod,
    Waddle,
    StanceStop,
    EStop,
    Turbo,
    /// Aim mode for rolling droids (toggle).
    Aim,
    /// Cycle the main LED colour.
    Colour,
    /// Back (aiming) light on/off.
    BackLight,
    Animations,
    Sounds,
    Log,
    Help,
    Quit,
}

impl Action {
    pub const ALL: [Action; 22] = [
        Action::Forward,
        Action::Backward,
        Action::Left,
        Action::Right,
        Action::Faster,
        Action::Slower,
        Action::DomeLeft,
        Action::DomeRight,
        Action::Tripod,
        Action::Bipod,
        Action::Waddle,
        Action::StanceStop,
        Action::EStop,
        Action::Turbo,
        Action::Aim,
        Action::Colour,
        Action::BackLight,
        Action::Animations,
        Action::Sounds,
        Action::Log,
        Action::Help,
        Action::Quit,
    ];

    /// The name used in the config's `[keys]` table.
    pub fn config_name(self) -> &'static str {
        match self {
            Action::Forward => "forward",
            Action::Backward => "backward",
            Action::Left => "left",
            Action::Right => "right",
            Action::Faster => "faster",
            Action::Slower => "slower",
            Action::DomeLeft => "dome_left",
            Action::DomeRight => "dome_right",
            Action::Tripod => "tripod",
            Action::Bipod => "bipod",
            Action::Waddle => "waddle",
            Action::StanceStop => "stance_stop",
            Action::EStop => "estop",
            Action::Turbo => "turbo",
            Action::Aim => "aim",
            Action::Colour => "colour",
            Action::BackLight => "back_light",
            Action::Animations => "animations",
            Action::Sounds => "sounds",
            Action::Log => "log",
            Action::Help => "help",
            Action::Quit => "quit",
        }
    }

    /// For the help overlay.
    pub fn description(self) -> &'static str {
        match self {
            Action::Forward => "drive forward (hold)",
            Action::Backward => "reverse (hold)",
            Action::Left => "turn left (hold; also aims while stopped)",
            Action::Right => "turn right (hold; also aims while stopped)",
            Action::Faster => "cruise speed up",
            Action::Slower => "cruise speed down",
            Action::DomeLeft => "dome left (hold)",
            Action::DomeRight => "dome right (hold)",
            Action::Tripod => "stance: tripod (3 legs, can roll)",
            Action::Bipod => "stance: bipod (2 legs)",
            Action::Waddle => "stance: waddle",
            Action::StanceStop => "stance: stop",
            Action::EStop => "EMERGENCY STOP (latched while held)",
            Action::Turbo => "turbo on/off",
            Action::Aim => "aim mode (rolling droids)",
            Action::Colour => "main LED colour",
            Action::BackLight => "back light",
            Action::Animations => "animation palette",
            Action::Sounds => "sound palette",
            Action::Log => "focus the packet log",
            Action::Help => "this help",
            Action::Quit => "quit (stops the droid first)",
        }
    }

    /// Actions that last while the key is held (the rest fire once per press).
    pub fn is_held(self) -> bool {
        matches!(
            self,
            Action::Forward
                | Action::Backward
                | Action::Left
                | Action::Right
                | Action::DomeLeft
                | Action::DomeRight
                | Action::EStop
        )
    }

    pub fn from_config_name(name: &str) -> Option<Action> {
        Action::ALL.into_iter().find(|a| a.config_name() == name)
    }
}

/// Bindings from keys to actions.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyMap {
    map: HashMap<Key, Action>,
    by_action: BTreeMap<Action, Vec<Key>>,
}

impl KeyMap {
    /// Build from the config's `[keys]` table. Errors name the offending config key.
    pub fn from_config(keys: &BTreeMap<String, Vec<String>>) -> Result<KeyMap, (String, String)> {
        let mut map = HashMap::new();
        let mut by_action: BTreeMap<Action, Vec<Key>> = BTreeMap::new();
        for (name, names) in keys {
            let action = Action::from_config_name(name).ok_or_else(|| {
                let all: Vec<&str> = Action::ALL.iter().map(|a| a.config_name()).collect();
                (
                    name.clone(),
                    format!("unknown action; expected one of {}", all.join(", ")),
                )
            })?;
            for kn in names {
                let key = Key::parse(kn).ok_or_else(|| {
                    (
                        name.clone(),
                        format!("unknown key {kn:?} (e.g. \"Up\", \"Space\", \"w\", \"Ctrl+c\")"),
                    )
                })?;
                if let Some(other) = map.insert(key, action)
                    && other != action
                {
                    return Err((
                        name.clone(),
                        format!(
                            "key {kn:?} is bound to both {} and {name}",
                            other.config_name()
                        ),
                    ));
                }
                by_action.entry(action).or_default().push(key);
            }
        }
        for a in [Action::Quit, Action::EStop] {
            if by_action.get(&a).is_none_or(|k| k.is_empty()) {
                return Err((
                    a.config_name().to_string(),
                    "must have at least one key".into(),
                ));
            }
        }
        Ok(KeyMap { map, by_action })
    }

    pub fn action(&self, key: &Key) -> Option<Action> {
        self.map.get(key).copied()
    }

    pub fn keys(&self, a: Action) -> &[Key] {
        self.by_action.get(&a).map(Vec::as_slice).unwrap_or(&[])
    }

    /// Help lines in a stable order.
    pub fn help(&self) -> Vec<(String, &'static str)> {
        Action::ALL
            .iter()
            .filter(|a| !self.keys(**a).is_empty())
            .map(|a| {
                let keys: Vec<String> = self.keys(*a).iter().map(Key::to_string).collect();
                (keys.join(" / "), a.description())
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;

    #[test]
    fn parses_key_names() {
        assert_eq!(Key::parse("Up"), Some(Key::plain(KeyCode::Up)));
        assert_eq!(Key::parse("w"), Some(Key::ch('w')));
        assert_eq!(Key::parse("Q"), Some(Key::ch('Q')));
        assert_eq!(
            Key::parse("Ctrl+c"),
            Some(Key {
                code: KeyCode::Char('c'),
                ctrl: true
            })
        );
        assert_eq!(Key::parse("F12"), Some(Key::plain(KeyCode::F(12))));
        assert_eq!(Key::parse("F13"), None);
        assert_eq!(Key::parse("ww"), None);
        assert_eq!(Key::parse(""), None);
    }

    #[test]
    fn default_bindings() {
        let km = KeyMap::from_config(&Config::defaults().keys).unwrap();
        assert_eq!(km.action(&Key::plain(KeyCode::Up)), Some(Action::Forward));
        assert_eq!(km.action(&Key::ch('w')), Some(Action::Forward));
        assert_eq!(km.action(&Key::ch('q')), Some(Action::Quit));
        assert_eq!(km.action(&Key::ch('Q')), Some(Action::DomeLeft));
        assert_eq!(km.action(&Key::plain(KeyCode::Space)), Some(Action::EStop));
        assert_eq!(km.action(&Key::ch('?')), Some(Action::Help));
        let help = km.help();
        assert_eq!(help.len(), Action::ALL.len());
        assert_eq!(help[0].0, "↑ / w");
    }

    #[test]
    fn conflicts_and_unknowns_are_errors() {
        let mut keys = Config::defaults().keys;
        keys.insert("forward".into(), vec!["t".into()]);
        let (_, msg) = KeyMap::from_config(&keys).unwrap_err();
        assert!(msg.contains("forward") && msg.contains("turbo"), "{msg}");
        let mut keys = Config::defaults().keys;
        keys.insert("fly".into(), vec!["f".into()]);
        assert_eq!(KeyMap::from_config(&keys).unwrap_err().0, "fly");
        let mut keys = Config::defaults().keys;
        keys.insert("quit".into(), vec![]);
        assert_eq!(KeyMap::from_config(&keys).unwrap_err().0, "quit");
    }
}
