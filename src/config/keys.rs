//! Keys, the actions they do in each part of the app, and the configured bindings between
//! them, parsed and checked when the configuration loads. Keys are our own type so the
//! control logic is testable without a terminal (`app::input` converts crossterm's events).
//!
//! Bindings live in contexts: driving (the `[keys]` table itself), the packet log
//! (`[keys.packet_log]`), the animation and sound palettes (`[keys.palette]`), the help
//! overlay (`[keys.help_overlay]`), the log filter being typed (`[keys.filter]`), replay
//! (`[keys.replay]`) and the droid picker (`[keys.picker]`).
//! A key means one thing per context; the same key may mean different things in different
//! contexts (`c` is the colour while driving and "clear the filter" in the log).

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

    /// Ctrl+C: always quits (the droid is stopped first), whatever the bindings say.
    pub const CTRL_C: Key = Key {
        code: KeyCode::Char('c'),
        ctrl: true,
    };

    /// Ctrl+Space (a terminal sends it as NUL): always the emergency stop, in every place,
    /// text prompts included (no place takes a Ctrl key as text, while Space is typed there),
    /// whatever the bindings say.
    pub const CTRL_SPACE: Key = Key {
        code: KeyCode::Space,
        ctrl: true,
    };

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
            KeyCode::PageUp => write!(f, "PgUp"),
            KeyCode::PageDown => write!(f, "PgDn"),
            KeyCode::F(n) => write!(f, "F{n}"),
            other => write!(f, "{other:?}"),
        }
    }
}

/// Where a key is read: which part of the app has the keyboard.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Context {
    /// Driving: the `[keys]` table itself.
    Drive,
    /// The packet log has the focus.
    Log,
    /// The animation or sound palette is open.
    Palette,
    /// The help overlay is open.
    Help,
    /// The log filter is being typed.
    Filter,
    /// A capture is played back.
    Replay,
    /// Choosing a droid among those a scan found.
    Picker,
    /// The scope is on screen (keys it does not bind still drive).
    Scope,
    /// A settings list is open: the scope's channels, streaming and collision detection.
    Settings,
    /// A packet in full (`Enter` on a log line).
    Detail,
}

impl Context {
    pub const ALL: [Context; 10] = [
        Context::Drive,
        Context::Log,
        Context::Palette,
        Context::Help,
        Context::Filter,
        Context::Replay,
        Context::Picker,
        Context::Scope,
        Context::Settings,
        Context::Detail,
    ];

    /// The sub-table of `[keys]` (`None`: the `[keys]` table itself).
    pub fn table(self) -> Option<&'static str> {
        match self {
            Context::Drive => None,
            Context::Log => Some("packet_log"),
            Context::Palette => Some("palette"),
            Context::Help => Some("help_overlay"),
            Context::Filter => Some("filter"),
            Context::Replay => Some("replay"),
            Context::Picker => Some("picker"),
            Context::Scope => Some("scope_view"),
            Context::Settings => Some("settings"),
            Context::Detail => Some("packet_detail"),
        }
    }

    /// The help overlay's heading.
    pub fn title(self) -> &'static str {
        match self {
            Context::Drive => "Keyboard",
            Context::Log => "Packet log",
            Context::Palette => "Palettes",
            Context::Help => "Help",
            Context::Filter => "Log filter",
            Context::Replay => "Replay",
            Context::Picker => "Choosing a droid",
            Context::Scope => "Scope (other keys drive)",
            Context::Settings => "Channels, streaming and collision",
            Context::Detail => "A packet in full",
        }
    }
}

/// What a droid must have (or the session must be) for a key to apply: help and the footer
/// leave out what does not apply to the chosen droid (R2's help lists no BOLT keys).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Needs {
    /// Every droid.
    All,
    /// Several droids are driven (a fleet).
    Fleet,
    /// R2's rotating dome.
    Dome,
    /// R2's legs (stances).
    Legs,
    /// A turbo (every Sphero droid; Robi has none).
    Turbo,
    /// An aim mode (rolling droids).
    Aim,
    /// Lights droidctl can set (the Sphero droids).
    Lights,
    /// Animations and sounds (the Star Wars droids).
    Animations,
    /// Two tracks (RVR).
    Tracks,
    /// An LED matrix (BOLT).
    Matrix,
    /// A compass (BOLT).
    Compass,
}

impl Needs {
    /// Whether a key needing this applies to `model` (`fleet`: several droids are driven).
    pub fn applies(self, model: crate::model::Model, fleet: bool) -> bool {
        match (self, self.caps()) {
            (Needs::Fleet, _) => fleet,
            (_, Some(caps)) => model.has(caps),
            (_, None) => true,
        }
    }

    /// The capabilities of the model table a key needing this asks for (`None`: every droid,
    /// or not a droid's capability at all: [`Needs::Fleet`]).
    pub fn caps(self) -> Option<crate::model::Caps> {
        use crate::model::Caps;
        Some(match self {
            Needs::All | Needs::Fleet => return None,
            Needs::Dome => Caps::DOME,
            Needs::Legs => Caps::LEGS,
            // A turbo and settable lights: every Sphero droid (Robi has neither).
            Needs::Turbo => Caps::HEADING,
            Needs::Lights => Caps::LIGHTS,
            Needs::Aim => Caps::AIM,
            Needs::Animations => Caps::ANIMATIONS,
            Needs::Tracks => Caps::TRACKS,
            Needs::Matrix => Caps::MATRIX,
            Needs::Compass => Caps::COMPASS,
        })
    }
}

/// One key definition: the single table the key map, the help overlay, the context footer and
/// the man page's KEYS section are built from ([`KEY_TABLE`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KeyDef {
    pub action: Action,
    /// Where the key is read.
    pub context: Context,
    /// The name in its table of the config (`forward`, `packet_log.pause` is `pause` here).
    pub name: &'static str,
    /// Lasts while the key is held (the rest fire once per press).
    pub held: bool,
    /// What must apply for the key to be listed (help, footer).
    pub needs: Needs,
    /// The footer's word for it; empty: help only.
    pub short: &'static str,
    /// For help and the man page.
    pub description: &'static str,
}

macro_rules! actions {
    ($( $ctx:ident { $( $v:ident $name:literal $held:literal $needs:ident $short:literal $desc:literal; )* } )*) => {
        /// What a key does, in its context.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Action { $( $( $v, )* )* }

        /// Every key definition, context by context, in help's order. The default keys are in
        /// `assets/default-config.toml` (`Config::defaults().keymap.shown(action)`).
        pub const KEY_TABLE: &[KeyDef] = &[ $( $( KeyDef {
            action: Action::$v,
            context: Context::$ctx,
            name: $name,
            held: $held,
            needs: Needs::$needs,
            short: $short,
            description: $desc,
        }, )* )* ];

        impl Action {
            pub const ALL: &'static [Action] = &[ $( $( Action::$v, )* )* ];
        }
    };
}

impl Action {
    /// Its row of [`KEY_TABLE`].
    pub fn def(self) -> &'static KeyDef {
        // The table lists the actions in declaration order.
        &KEY_TABLE[self as usize]
    }

    pub fn context(self) -> Context {
        self.def().context
    }

    /// The name in its table of the config.
    pub fn config_name(self) -> &'static str {
        self.def().name
    }

    /// For the help overlay.
    pub fn description(self) -> &'static str {
        self.def().description
    }

    /// Actions that last while the key is held (the rest fire once per press).
    pub fn is_held(self) -> bool {
        self.def().held
    }

    /// What must apply for the key to be listed.
    pub fn needs(self) -> Needs {
        self.def().needs
    }

    /// The footer's word for it (empty: help only).
    pub fn short(self) -> &'static str {
        self.def().short
    }
}

actions! {
    Drive {
        Forward "forward" true All "" "drive forward (hold)";
        Backward "backward" true All "" "reverse (hold)";
        Left "left" true All "" "turn left (hold; also aims while stopped)";
        Right "right" true All "" "turn right (hold; also aims while stopped)";
        Faster "faster" false All "faster" "cruise speed up";
        Slower "slower" false All "slower" "cruise speed down";
        DomeLeft "dome_left" true Dome "" "dome left (hold)";
        DomeRight "dome_right" true Dome "" "dome right (hold)";
        Tripod "tripod" false Legs "tripod" "stance: tripod (3 legs, can roll)";
        Bipod "bipod" false Legs "" "stance: bipod (2 legs)";
        Waddle "waddle" false Legs "" "stance: waddle";
        StanceStop "stance_stop" false Legs "" "stance: stop";
        EStop "estop" true All "stop" "EMERGENCY STOP (latched while held)";
        Turbo "turbo" false Turbo "turbo" "turbo on/off";
        Aim "aim" false Aim "aim" "aim mode (rolling droids)";
        Colour "colour" false Lights "" "main LED colour";
        BackLight "back_light" false Lights "" "back light";
        Animations "animations" false Animations "animations" "animation palette";
        Sounds "sounds" false Animations "" "sound palette";
        NextDroid "next_droid" false Fleet "next droid" "fleet: drive the next droid";
        PreviousDroid "previous_droid" false Fleet "" "fleet: drive the previous droid";
        Mirror "mirror" false Fleet "mirror" "fleet: mirror mode (the same control to every droid)";
        Tank "tank" false Tracks "tank" "tank mode: a track per stick (RVR)";
        Matrix "matrix" false Matrix "matrix" "type on the matrix (BOLT)";
        MatrixColour "matrix_colour" false Matrix "" "next matrix colour (BOLT)";
        Calibrate "calibrate" false Compass "calibrate" "calibrate the compass (BOLT)";
        Log "log" false All "log" "the packet log has the keys (and back)";
        Scope "scope" false All "scope" "the scope: chosen channels against time (and back)";
        Tuning "tuning" false All "settings" "streaming (rate, sensors) and collision detection";
        ForgetSettings "forget_settings" false All "" "forget this model's remembered settings (cruise, scope, rate, filter)";
        Help "help" false All "more keys" "this help";
        Quit "quit" false All "quit" "quit (stops the droid first)";
    }
    Log {
        LogUp "up" false All "" "scroll up";
        LogDown "down" false All "" "scroll down";
        LogPageUp "page_up" false All "" "scroll up a page";
        LogPageDown "page_down" false All "" "scroll down a page";
        LogTop "top" false All "" "to the oldest line";
        LogBottom "bottom" false All "" "to the newest line (follow)";
        LogPause "pause" false All "pause" "pause / resume";
        LogDecoded "decoded" false All "hex" "decoded / hex";
        LogFilter "filter" false All "filter" "filter (in|out dev:NAME droid:NAME text)";
        LogClearFilter "clear_filter" false All "" "clear the filter";
        LogBack "back" false All "back" "back to driving";
        LogOpen "open" false All "detail" "the selected line in full (fields, frame, hex)";
    }
    Palette {
        PaletteUp "up" false All "" "previous entry";
        PaletteDown "down" false All "" "next entry";
        PalettePageUp "page_up" false All "" "ten entries back";
        PalettePageDown "page_down" false All "" "ten entries on";
        PalettePlay "play" false All "play" "play it and close";
        PaletteClose "close" false All "close" "close";
    }
    Help {
        HelpNext "next_page" false All "next page" "next page";
        HelpPrevious "previous_page" false All "previous page" "previous page (any other key closes)";
    }
    Filter {
        FilterApply "apply" false All "apply" "apply the filter";
        FilterCancel "cancel" false All "cancel" "leave it as it was";
    }
    Replay {
        ReplayPause "pause" false All "pause" "pause / play";
        ReplayFaster "faster" false All "faster" "faster (up to 16×)";
        ReplaySlower "slower" false All "slower" "slower (down to 0.25×)";
        ReplayForward "forward" false All "+5 s" "seek forward 5 s";
        ReplayBack "back" false All "-5 s" "seek back 5 s";
        ReplayForwardLong "forward_long" false All "" "seek forward 60 s";
        ReplayBackLong "back_long" false All "" "seek back 60 s";
        ReplayStart "start" false All "" "to the start";
        ReplayEnd "end" false All "" "to the end";
        ReplayStep "step" false All "step" "single step: pause, then the next event";
    }
    Picker {
        PickerUp "up" false All "" "previous droid";
        PickerDown "down" false All "" "next droid";
        PickerFirst "first" false All "" "the first droid";
        PickerLast "last" false All "" "the last droid";
        PickerChoose "choose" false All "connect" "connect to it (to the marked ones, if any)";
        PickerMark "mark" false All "mark" "mark / unmark it (several marked: drive them all at once)";
        PickerCancel "cancel" false All "cancel" "cancel";
    }
    Scope {
        ScopePause "pause" false All "pause" "pause / follow (the droid still streams)";
        ScopeZoomIn "zoom_in" false All "zoom in" "shorter window (down to 10 s)";
        ScopeZoomOut "zoom_out" false All "zoom out" "longer window (up to 2 min)";
        ScopeAutoscale "autoscale" false All "" "autoscaled / fixed axes";
        ScopeChannels "channels" false All "channels" "choose the channels";
    }
    Settings {
        SettingsUp "up" false All "" "previous row";
        SettingsDown "down" false All "" "next row";
        SettingsLess "less" false All "" "value down / previous rate";
        SettingsMore "more" false All "" "value up / next rate";
        SettingsToggle "toggle" false All "on/off" "switch a channel, sensor or collision detection on/off";
        SettingsApply "apply" false All "apply" "apply to the droid and close (channels: switch)";
        SettingsClose "close" false All "close" "close (nothing sent)";
    }
    Detail {
        DetailUp "up" false All "" "scroll up";
        DetailDown "down" false All "" "scroll down";
        DetailSearch "search" false All "search" "search (Enter: to the first match)";
        DetailNext "next" false All "next" "next match";
        DetailPrevious "previous" false All "previous" "previous match";
        DetailClose "close" false All "close" "close";
    }
}

impl Action {
    /// The action named `name` in `ctx`'s table.
    pub fn from_config_name(ctx: Context, name: &str) -> Option<Action> {
        Action::ALL
            .iter()
            .copied()
            .find(|a| a.context() == ctx && a.config_name() == name)
    }

    /// The config key, `table.name` for a sub-table: for messages.
    pub fn config_key(self) -> String {
        match self.context().table() {
            None => self.config_name().to_string(),
            Some(t) => format!("{t}.{}", self.config_name()),
        }
    }
}

/// The `[keys]` table as written: drive actions at the top, contexts as sub-tables.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(untagged)]
pub enum KeyEntry {
    Keys(Vec<String>),
    Table(BTreeMap<String, Vec<String>>),
}

/// Bindings from keys to actions, per context.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct KeyMap {
    map: HashMap<(Context, Key), Action>,
    by_action: BTreeMap<Action, Vec<Key>>,
}

impl KeyMap {
    /// Build from the config's `[keys]` table. Errors name the offending config key
    /// (`forward`, `log.pause`).
    pub fn from_config(keys: &BTreeMap<String, KeyEntry>) -> Result<KeyMap, (String, String)> {
        KeyMap::from_config_with(keys, &|_| false)
    }

    /// [`KeyMap::from_config`], the bindings the user wrote (`touched("forward")`,
    /// `touched("packet_log.pause")`) bound last: a key bound twice is reported on the binding
    /// the user touched, not on the default it ran into (issue 27 point 7).
    pub fn from_config_with(
        keys: &BTreeMap<String, KeyEntry>,
        touched: &dyn Fn(&str) -> bool,
    ) -> Result<KeyMap, (String, String)> {
        let mut km = KeyMap::default();
        for users in [false, true] {
            for (name, entry) in keys {
                match entry {
                    KeyEntry::Keys(names) => {
                        if touched(name) == users {
                            km.bind(Context::Drive, name, name, names)?;
                        }
                    }
                    KeyEntry::Table(table) => {
                        let ctx = Context::ALL
                            .into_iter()
                            .find(|c| c.table() == Some(name.as_str()))
                            .ok_or_else(|| unknown_action(name, Context::Drive))?;
                        for (action, names) in table {
                            let key = format!("{name}.{action}");
                            if touched(&key) == users {
                                km.bind(ctx, &key, action, names)?;
                            }
                        }
                    }
                }
            }
        }
        for a in [Action::Quit, Action::EStop] {
            if km.keys(a).is_empty() {
                return Err((a.config_key(), "must have at least one key".into()));
            }
        }
        // The scope is on screen while driving: a key means one thing there, so a scope key
        // may not be a drive key too (Tab was "next droid" and "channels" at once).
        let mut scope: Vec<(&Key, &Action)> = km
            .map
            .iter()
            .filter(|((c, _), _)| *c == Context::Scope)
            .map(|((_, k), a)| (k, a))
            .collect();
        scope.sort();
        for (k, a) in scope {
            if let Some(d) = km.action(k) {
                return Err((
                    a.config_key(),
                    format!(
                        "key \"{k}\" is bound to both {} and {} (the scope is on screen while \
                         driving: a key means one thing there)",
                        d.config_key(),
                        a.config_key()
                    ),
                ));
            }
        }
        // Esc closes overlays and gives the log's keys back: pressed once too many, it would
        // end the session and stop the droid abruptly.
        if km.keys(Action::Quit).contains(&Key::plain(KeyCode::Esc)) {
            return Err((
                Action::Quit.config_key(),
                "Esc closes panels and cannot quit (one Esc too many would end the session); \
                 bind quit to another key, e.g. [\"q\"]"
                    .into(),
            ));
        }
        Ok(km)
    }

    /// Bind `names` to the action `action` of `ctx`; `key` is the config key for messages.
    fn bind(
        &mut self,
        ctx: Context,
        key: &str,
        action: &str,
        names: &[String],
    ) -> Result<(), (String, String)> {
        let a = Action::from_config_name(ctx, action).ok_or_else(|| unknown_action(key, ctx))?;
        for kn in names {
            let k = Key::parse(kn).ok_or_else(|| {
                (
                    key.to_string(),
                    format!("unknown key {kn:?} (e.g. \"Up\", \"Space\", \"w\", \"Ctrl+c\")"),
                )
            })?;
            if k == Key::CTRL_C {
                return Err((
                    key.to_string(),
                    "Ctrl+c always quits; bind another key".into(),
                ));
            }
            if k == Key::CTRL_SPACE {
                return Err((
                    key.to_string(),
                    "Ctrl+Space is always the emergency stop; bind another key".into(),
                ));
            }
            if let Some(other) = self.map.insert((ctx, k), a)
                && other != a
            {
                return Err((
                    key.to_string(),
                    format!(
                        "key {kn:?} is bound to both {} and {}",
                        other.config_key(),
                        a.config_key()
                    ),
                ));
            }
            let keys = self.by_action.entry(a).or_default();
            if !keys.contains(&k) {
                keys.push(k);
            }
        }
        Ok(())
    }

    /// What `key` does in `ctx`.
    pub fn action_in(&self, ctx: Context, key: &Key) -> Option<Action> {
        self.map.get(&(ctx, *key)).copied()
    }

    /// What `key` does while driving.
    pub fn action(&self, key: &Key) -> Option<Action> {
        self.action_in(Context::Drive, key)
    }

    pub fn keys(&self, a: Action) -> &[Key] {
        self.by_action.get(&a).map(Vec::as_slice).unwrap_or(&[])
    }

    /// The keys of `a` as shown in help (`↑ / w`); `None` when it has none.
    pub fn shown(&self, a: Action) -> Option<String> {
        let keys: Vec<String> = self.keys(a).iter().map(Key::to_string).collect();
        (!keys.is_empty()).then(|| keys.join(" / "))
    }

    /// Help lines of a context, in the table's order: (keys, the action).
    pub fn help(&self, ctx: Context) -> Vec<(String, Action)> {
        Action::ALL
            .iter()
            .filter(|a| a.context() == ctx)
            .filter_map(|a| self.shown(*a).map(|k| (k, *a)))
            .collect()
    }
}

fn unknown_action(key: &str, ctx: Context) -> (String, String) {
    let mut all: Vec<String> = Action::ALL
        .iter()
        .filter(|a| a.context() == ctx)
        .map(|a| a.config_name().to_string())
        .collect();
    if ctx == Context::Drive {
        all.extend(
            Context::ALL
                .iter()
                .filter_map(|c| c.table())
                .map(|t| format!("[keys.{t}]")),
        );
    }
    (
        key.to_string(),
        format!("unknown action; expected one of {}", all.join(", ")),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;

    /// `Needs` reads the model table; this is what it spelled out before, so a row that
    /// changes which keys apply shows here.
    #[test]
    fn needs_agree_with_the_model_table() {
        use crate::model::{Model, Protocol};
        for m in Model::ALL {
            let sphero = m.protocol() != Protocol::Rsrcp;
            let r2 = matches!(m, Model::R2D2 | Model::R2Q5);
            let spelled = [
                (Needs::All, true),
                (Needs::Dome, r2),
                (Needs::Legs, r2),
                (Needs::Turbo, sphero),
                (Needs::Lights, sphero),
                (Needs::Aim, sphero && !r2),
                (
                    Needs::Animations,
                    matches!(m, Model::R2D2 | Model::R2Q5 | Model::BB9E),
                ),
                (Needs::Tracks, m == Model::Rvr),
                (Needs::Matrix, matches!(m, Model::Bolt | Model::BoltPlus)),
                (Needs::Compass, matches!(m, Model::Bolt | Model::BoltPlus)),
            ];
            for (needs, applies) in spelled {
                assert_eq!(needs.applies(m, false), applies, "{needs:?} on {m:?}");
            }
            assert!(Needs::Fleet.applies(m, true) && !Needs::Fleet.applies(m, false));
        }
    }

    #[test]
    fn parses_key_names() {
        assert_eq!(Key::parse("Up"), Some(Key::plain(KeyCode::Up)));
        assert_eq!(Key::parse("w"), Some(Key::ch('w')));
        assert_eq!(Key::parse("Q"), Some(Key::ch('Q')));
        assert_eq!(Key::parse("Ctrl+c"), Some(Key::CTRL_C));
        assert_eq!(Key::parse("F12"), Some(Key::plain(KeyCode::F(12))));
        assert_eq!(Key::parse("F13"), None);
        assert_eq!(Key::parse("ww"), None);
        assert_eq!(Key::parse(""), None);
    }

    #[test]
    fn the_table_is_in_declaration_order_and_has_footer_words() {
        for (i, d) in KEY_TABLE.iter().enumerate() {
            assert_eq!(d.action as usize, i);
            assert_eq!(d.action.context(), d.context);
        }
        assert_eq!(Action::Tank.needs(), Needs::Tracks);
        assert!(!Needs::Tracks.applies(crate::model::Model::R2D2, false));
        assert!(Needs::Fleet.applies(crate::model::Model::R2D2, true));
        assert_eq!(Action::EStop.short(), "stop");
    }

    #[test]
    fn a_scope_key_cannot_be_a_drive_key() {
        let mut scope = BTreeMap::new();
        scope.insert("channels".to_string(), list(&["Tab"]));
        let keys = with(&[("scope_view", KeyEntry::Table(scope))]);
        let (k, msg) = KeyMap::from_config(&keys).unwrap_err();
        assert_eq!(k, "scope_view.channels");
        assert!(msg.contains("next_droid"), "{msg}");
    }

    #[test]
    fn default_bindings() {
        let km = Config::defaults().keymap;
        assert_eq!(km.action(&Key::plain(KeyCode::Up)), Some(Action::Forward));
        assert_eq!(km.action(&Key::ch('w')), Some(Action::Forward));
        assert_eq!(km.action(&Key::ch('q')), Some(Action::Quit));
        assert_eq!(km.action(&Key::ch('Q')), Some(Action::DomeLeft));
        assert_eq!(km.action(&Key::plain(KeyCode::Space)), Some(Action::EStop));
        assert_eq!(km.action(&Key::ch('?')), Some(Action::Help));
        // The same key means other things elsewhere.
        assert_eq!(km.action(&Key::ch('c')), Some(Action::Colour));
        assert_eq!(
            km.action_in(Context::Log, &Key::ch('c')),
            Some(Action::LogClearFilter)
        );
        assert_eq!(
            km.action_in(Context::Replay, &Key::plain(KeyCode::Space)),
            Some(Action::ReplayPause)
        );
        // Every action has a default key, and its help line.
        for a in Action::ALL {
            assert!(
                !km.keys(*a).is_empty(),
                "{} has no default key",
                a.config_key()
            );
        }
        let help = km.help(Context::Drive);
        assert_eq!(help[0].0, "↑ / w");
        let n: usize = Context::ALL.iter().map(|c| km.help(*c).len()).sum();
        assert_eq!(n, Action::ALL.len());
    }

    fn with(extra: &[(&str, KeyEntry)]) -> BTreeMap<String, KeyEntry> {
        let mut keys = Config::defaults().keys;
        for (k, v) in extra {
            keys.insert((*k).to_string(), v.clone());
        }
        keys
    }

    fn list(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn conflicts_and_unknowns_are_errors() {
        let keys = with(&[("forward", KeyEntry::Keys(list(&["t"])))]);
        let (_, msg) = KeyMap::from_config(&keys).unwrap_err();
        assert!(msg.contains("forward") && msg.contains("turbo"), "{msg}");
        let keys = with(&[("fly", KeyEntry::Keys(list(&["f"])))]);
        assert_eq!(KeyMap::from_config(&keys).unwrap_err().0, "fly");
        let keys = with(&[("quit", KeyEntry::Keys(vec![]))]);
        assert_eq!(KeyMap::from_config(&keys).unwrap_err().0, "quit");
        let keys = with(&[("quit", KeyEntry::Keys(list(&["q", "Esc"])))]);
        let (k, msg) = KeyMap::from_config(&keys).unwrap_err();
        assert_eq!(k, "quit");
        assert!(msg.contains("Esc closes panels"), "{msg}");
        let keys = with(&[("quit", KeyEntry::Keys(list(&["Ctrl+c"])))]);
        assert!(
            KeyMap::from_config(&keys)
                .unwrap_err()
                .1
                .contains("always quits")
        );
        // Within a context, too.
        let Some(KeyEntry::Table(mut log)) = Config::defaults().keys.remove("packet_log") else {
            panic!("the defaults have a packet_log table")
        };
        log.insert("pause".to_string(), list(&["d"]));
        let keys = with(&[("packet_log", KeyEntry::Table(log))]);
        let (k, msg) = KeyMap::from_config(&keys).unwrap_err();
        assert_eq!(k, "packet_log.pause");
        assert!(msg.contains("packet_log.decoded"), "{msg}");
        let mut log = BTreeMap::new();
        log.insert("zoom".to_string(), list(&["z"]));
        let keys = with(&[("packet_log", KeyEntry::Table(log))]);
        assert_eq!(KeyMap::from_config(&keys).unwrap_err().0, "packet_log.zoom");
    }
}
