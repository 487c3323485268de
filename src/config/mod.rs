//! Configuration: a TOML file in the platform config directory, merged over the defaults
//! shipped in `assets/default-config.toml`. An invalid file is reported with its path, line
//! and key, and the app refuses to start rather than guess.
//!
//! Loading parses everything into types: key bindings into a [`KeyMap`] per context
//! ([`keys`]), gamepad buttons into [`PadBindings`] ([`pad`]). The layers above take those
//! types and never see a binding's name.

pub mod bridge;
pub mod keys;
pub mod monitor;
pub mod pad;
pub mod pad_mapping;

pub use keys::{Action, Context, KEY_TABLE, Key, KeyCode, KeyDef, KeyEntry, KeyMap, Needs};
pub use pad::{Button, PadAction, PadBindings};

use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The slowest write pacing `session.pacing_ms` may set.
pub const MAX_PACING_MS: u64 = 1000;

/// The bounds of `session.request_timeout_ms`: a droid answers within tens of ms; 0 made
/// every request fail at once, and a minute is already longer than anyone waits.
pub const MIN_REQUEST_TIMEOUT_MS: u64 = 100;
pub const MAX_REQUEST_TIMEOUT_MS: u64 = 60_000;

/// The shipped defaults (also what `droidctl config init` writes).
pub const DEFAULT_TOML: &str = include_str!("../../assets/default-config.toml");

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DriveMode {
    /// Drive while a key is held; letting go stops (deadman).
    Hold,
    /// Keys step the speed; Space stops.
    Latched,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Control {
    pub rate_hz: u32,
    pub cruise_speed: u8,
    pub speed_step: u8,
    pub turbo_speed: u8,
    pub turn_rate_deg_s: f32,
    pub dome_rate_deg_s: f32,
    pub mode: DriveMode,
    pub auto_tripod: bool,
    pub sleep_on_exit: bool,
    /// The older way to set the streaming rate (ms between samples; 0 off). When a file
    /// still sets it, it wins over `streaming.rate_hz`.
    #[serde(default)]
    pub streaming_interval_ms: Option<u16>,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Keyboard {
    pub release_first_ms: u64,
    pub release_repeat_ms: u64,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Session {
    pub request_timeout_ms: u64,
    pub pacing_ms: u64,
}

/// Several droids at once (`[fleet]`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FleetSettings {
    /// Droids connected through one Bluetooth adapter at most (1..=7): an adapter holds
    /// about six LE links of which about four stay stable.
    pub max_per_adapter: usize,
}

/// The `[gamepad]` table as written.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGamepad {
    enabled: bool,
    deadzone: f32,
    expo: f32,
    max_speed: u8,
    dome_rate_deg_s: f32,
    tripod: String,
    bipod: String,
    aim: String,
    estop: String,
    animation: String,
    help: String,
    sound_up: u16,
    sound_down: u16,
    sound_left: u16,
    sound_right: u16,
    mappings: Vec<String>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Gamepad {
    pub enabled: bool,
    pub deadzone: f32,
    pub expo: f32,
    pub max_speed: u8,
    pub dome_rate_deg_s: f32,
    /// Which button does what (tripod, bipod, aim, e-stop, animation, help).
    pub buttons: PadBindings,
    pub sound_up: u16,
    pub sound_down: u16,
    pub sound_left: u16,
    pub sound_right: u16,
    /// SDL controller-database lines for pads gilrs does not know, each checked when the
    /// configuration loads ([`pad_mapping::SdlMapping::parse`]); gilrs is given them.
    pub mappings: Vec<String>,
}

/// `[display]`: how the app looks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Display {
    pub theme: Theme,
}

/// The app's colours: for a dark terminal (the default), a light one, or none at all (also
/// what `NO_COLOR` asks for, <https://no-color.org>).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Theme {
    #[default]
    Dark,
    Light,
    None,
}

impl Theme {
    /// The theme to use: none when `NO_COLOR` is set to anything but the empty string (the
    /// convention's rule), else the configured one. The variable's value is passed in.
    pub fn effective(configured: Theme, no_color: Option<&std::ffi::OsStr>) -> Theme {
        match no_color {
            Some(v) if !v.is_empty() => Theme::None,
            _ => configured,
        }
    }
}

/// The file as written, before bindings are parsed.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConfig {
    control: Control,
    keyboard: Keyboard,
    session: Session,
    keys: BTreeMap<String, KeyEntry>,
    gamepad: RawGamepad,
    fleet: FleetSettings,
    streaming: monitor::Streaming,
    collision: crate::tuning::CollisionConfig,
    bridge: bridge::Bridge,
    display: Display,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    pub control: Control,
    pub keyboard: Keyboard,
    pub session: Session,
    /// The `[keys]` table as written: action name → key names, a sub-table per context.
    pub keys: BTreeMap<String, KeyEntry>,
    /// The key bindings parsed from [`Config::keys`].
    pub keymap: KeyMap,
    pub gamepad: Gamepad,
    pub fleet: FleetSettings,
    /// `[streaming]`: the sensor groups and rate asked for.
    pub streaming: monitor::Streaming,
    /// `[collision]`: collision detection's parameters.
    pub collision: crate::tuning::CollisionConfig,
    /// `[bridge]`: `droidctl bridge`'s command timeout, telemetry rate and MQTT settings.
    pub bridge: bridge::Bridge,
    /// `[display]`: the app's theme.
    pub display: Display,
}

/// Why a config could not be used: where and what.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfigError {
    pub path: Option<PathBuf>,
    pub line: Option<usize>,
    pub key: Option<String>,
    pub message: String,
}

impl std::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.path {
            Some(p) => write!(f, "{}", p.display())?,
            None => write!(f, "configuration")?,
        }
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
        }
        if let Some(k) = &self.key {
            write!(f, ": key `{k}`")?;
        }
        write!(f, ": {}", self.message)
    }
}

/// Where the user's config file lives.
pub fn config_path() -> PathBuf {
    match std::env::var_os("DROIDCTL_CONFIG") {
        Some(p) => PathBuf::from(p),
        None => default_config_path(),
    }
}

/// Where the config file lives on this system when `DROIDCTL_CONFIG` does not say.
pub fn default_config_path() -> PathBuf {
    directories::ProjectDirs::from("", "", "droidctl")
        .map(|d| d.config_dir().to_path_buf())
        .unwrap_or_else(|| PathBuf::from("."))
        .join("config.toml")
}

/// Whether `path` is the file DROIDCTL_CONFIG names.
fn explicit(path: &Path) -> bool {
    std::env::var_os("DROIDCTL_CONFIG").is_some_and(|p| Path::new(&p) == path)
}

/// The table and key whose value starts at `offset` of a TOML text (a line `key = value`
/// under a `[table]` header): where a type error is.
fn key_at(text: &str, offset: usize) -> Option<(String, String)> {
    let mut table = String::new();
    let mut at = 0;
    for line in text.split_inclusive('\n') {
        let end = at + line.len();
        let l = line.trim();
        if let Some(t) = l.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            table = t
                .trim()
                .trim_matches('[')
                .trim_matches(']')
                .trim()
                .to_string();
        } else if offset < end
            && let Some((k, _)) = l.split_once('=')
        {
            return Some((table, k.trim().trim_matches('"').to_string()));
        }
        if offset < end {
            return None;
        }
        at = end;
    }
    None
}

/// A type name of serde's as a person says it.
fn expected_in_words(t: &str) -> String {
    let range = |lo: &str, hi: &str| format!("a whole number from {lo} to {hi}");
    match t.trim() {
        "u8" => range("0", "255"),
        "u16" => range("0", "65535"),
        "u32" => range("0", "4294967295"),
        "u64" | "usize" => "a whole number, 0 or more".into(),
        "i8" | "i16" | "i32" | "i64" | "isize" => "a whole number".into(),
        "f32" | "f64" => "a number".into(),
        "a boolean" => "true or false".into(),
        "a string" | "a borrowed string" => "text in quotes".into(),
        "a sequence" => "a list in brackets, [ … ]".into(),
        t if t.starts_with("struct ") || t.starts_with("a map") || t.contains("map") => {
            "a table".into()
        }
        t => t.replace('`', ""),
    }
}

/// serde's messages in words (`invalid value: integer `300`, expected u8` becomes `300 is not
/// a whole number from 0 to 255`); `table` is where the key is, for an unknown one.
fn in_words(msg: &str, table: &str) -> String {
    let msg = msg.trim();
    let value_of = |what: &str| {
        let what = what.trim();
        let (kind, val) = what.split_once(' ').unwrap_or((what, ""));
        let val = val.trim().trim_matches('`');
        match kind {
            "string" => format!("{val} (text)"),
            "integer" | "floating" => val
                .trim_start_matches("point ")
                .trim_matches('`')
                .to_string(),
            "boolean" => val.to_string(),
            "sequence" => "a list".into(),
            "map" => "a table".into(),
            _ => what.replace('`', ""),
        }
    };
    if let Some(rest) = msg
        .strip_prefix("invalid value: ")
        .or_else(|| msg.strip_prefix("invalid type: "))
        && let Some((what, expected)) = rest.split_once(", expected ")
    {
        return format!("{} is not {}", value_of(what), expected_in_words(expected));
    }
    if let Some(rest) = msg.strip_prefix("unknown variant ")
        && let Some((v, expected)) = rest.split_once(", expected ")
    {
        let options = expected
            .trim_start_matches("one of ")
            .replace('`', "")
            .replace(" or ", ", ");
        return format!("{} is not one of: {options}", v.replace('`', "\""));
    }
    if let Some(rest) = msg.strip_prefix("unknown field ")
        && let Some((f, expected)) = rest.split_once(", expected ")
    {
        let options = expected
            .trim_start_matches("one of ")
            .replace('`', "")
            .replace(" or ", ", ");
        let place = if table.is_empty() {
            "the file".to_string()
        } else {
            format!("[{table}]")
        };
        return format!(
            "there is no setting {} in {place}; it has: {options}",
            f.replace('`', "")
        );
    }
    msg.replace('`', "")
}

/// Recursively merge `over` into `base` (tables merge, other values replace).
fn merge(base: &mut toml::Table, over: toml::Table) {
    for (k, v) in over {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

/// Find the line where `section.key` is set in the user's text (for semantic errors).
fn find_key_line(text: &str, section: &str, key: &str) -> Option<usize> {
    let mut current = String::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if let Some(s) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            current = s.trim().to_string();
            continue;
        }
        let k = line.split('=').next().unwrap_or("").trim();
        if current == section && k == key {
            return Some(i + 1);
        }
    }
    None
}

impl Config {
    /// The streaming asked for: `[streaming]`, or the older `control.streaming_interval_ms`
    /// when a file still sets it.
    pub fn stream_request(&self) -> crate::tuning::StreamRequest {
        let rate_hz = match self.control.streaming_interval_ms {
            Some(0) => 0,
            Some(ms) => (1000 / ms).max(1),
            None => self.streaming.rate_hz,
        };
        crate::tuning::StreamRequest {
            rate_hz,
            sensors: self.streaming.sensor_set(),
        }
    }

    /// The shipped defaults.
    pub fn defaults() -> Config {
        Config::parse_merged(None, "")
            .unwrap_or_else(|e| panic!("shipped defaults are invalid: {e}"))
    }

    /// Load the user's file if it exists, merged over the defaults. At the usual place only
    /// a regular file is read (a symbolic link to one too): a FIFO left there is an error,
    /// not a start that hangs. A file DROIDCTL_CONFIG names is read as it is (`/dev/null`,
    /// a shell's `<(…)`).
    pub fn load(path: &Path) -> Result<Config, ConfigError> {
        let read = if explicit(path) {
            crate::text_file::read(path, crate::text_file::MAX_CONFIG_BYTES)
        } else {
            crate::own_file::open(
                path,
                std::fs::OpenOptions::new().read(true),
                crate::own_file::Links::Follow,
            )
            .and_then(|f| crate::text_file::read_from(f, crate::text_file::MAX_CONFIG_BYTES))
        };
        match read {
            Ok(text) => Config::parse_merged(Some(path), &text),
            // A file named on purpose (DROIDCTL_CONFIG) that is not there is a mistake, not
            // a wish for the defaults (`/dev/null` asks for them).
            Err(e) if e.kind() == std::io::ErrorKind::NotFound && explicit(path) => {
                Err(ConfigError {
                    path: Some(path.to_path_buf()),
                    line: None,
                    key: None,
                    message: "no such file (DROIDCTL_CONFIG names it; unset it for the usual \
                              place, or name /dev/null for the defaults)"
                        .into(),
                })
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Config::defaults()),
            Err(e) => Err(ConfigError {
                path: Some(path.to_path_buf()),
                line: None,
                key: None,
                message: format!("cannot read: {e}"),
            }),
        }
    }

    /// Parse user text merged over the defaults, then validate.
    pub fn parse_merged(path: Option<&Path>, text: &str) -> Result<Config, ConfigError> {
        let err = |line, key: Option<String>, message: String| ConfigError {
            path: path.map(Path::to_path_buf),
            line,
            key,
            message,
        };
        let user: toml::Table = toml::from_str(text).map_err(|e: toml::de::Error| {
            err(
                e.span().map(|s| line_of(text, s.start)),
                None,
                e.message().to_string(),
            )
        })?;
        let mut base: toml::Table = toml::from_str(DEFAULT_TOML)
            .map_err(|e| err(None, None, format!("shipped defaults: {e}")))?;
        let user_keys = user
            .get("keys")
            .and_then(toml::Value::as_table)
            .cloned()
            .unwrap_or_default();
        // Key bindings replace per action, so one action can be rebound without repeating
        // the whole table; other sections merge key by key.
        merge(&mut base, user);
        let merged = toml::to_string(&base).map_err(|e| err(None, None, e.to_string()))?;
        let raw: RawConfig = toml::from_str(&merged).map_err(|e: toml::de::Error| {
            // The merged text's lines are not the user's: find the key the error is about
            // in the merged text, then that key's line in the user's file.
            let msg = e.message().to_string();
            let (table, name) = e
                .span()
                .and_then(|sp| key_at(&merged, sp.start))
                .unwrap_or_default();
            let unknown = msg
                .split('`')
                .nth(1)
                .filter(|_| msg.starts_with("unknown field"))
                .map(str::to_string);
            let name = unknown.unwrap_or(name);
            let line = find_key_line(text, &table, &name).or_else(|| {
                text.lines()
                    .position(|l| l.trim_start().starts_with(name.as_str()) && l.contains('='))
                    .map(|i| i + 1)
                    .filter(|_| !name.is_empty())
            });
            let key = match (table.is_empty(), name.is_empty()) {
                (_, true) => None,
                (true, false) => Some(name.clone()),
                (false, false) => Some(format!("{table}.{name}")),
            };
            err(line, key, in_words(&msg, &table))
        })?;
        // The bindings the user wrote (`forward`, `log.pause`): a conflict names the one they
        // touched, not the default it ran into.
        let touched = |key: &str| match key.split_once('.') {
            Some((table, name)) => user_keys
                .get(table)
                .and_then(toml::Value::as_table)
                .is_some_and(|t| t.contains_key(name)),
            None => user_keys.contains_key(key),
        };
        Config::from_raw(raw, &touched).map_err(|(section, key, message)| {
            // A context's binding (`log.pause`) sits in its own table (`[keys.packet_log]`).
            let (table, name) = match key.rsplit_once('.') {
                Some((sub, name)) => (format!("{section}.{sub}"), name.to_string()),
                None => (section.clone(), key.clone()),
            };
            err(
                find_key_line(text, &table, &name),
                Some(format!("{section}.{key}")),
                message,
            )
        })
    }

    /// Parse the bindings and check ranges: (section, key, message) on error.
    fn from_raw(
        raw: RawConfig,
        touched: &dyn Fn(&str) -> bool,
    ) -> Result<Config, (String, String, String)> {
        let keymap = KeyMap::from_config_with(&raw.keys, touched)
            .map_err(|(key, msg)| ("keys".to_string(), key, msg))?;
        let g = raw.gamepad;
        let buttons =
            PadBindings::parse([&g.tripod, &g.bipod, &g.aim, &g.estop, &g.animation, &g.help])
                .map_err(|(key, msg)| ("gamepad".to_string(), key, msg))?;
        let cfg = Config {
            control: raw.control,
            keyboard: raw.keyboard,
            session: raw.session,
            keys: raw.keys,
            keymap,
            gamepad: Gamepad {
                enabled: g.enabled,
                deadzone: g.deadzone,
                expo: g.expo,
                max_speed: g.max_speed,
                dome_rate_deg_s: g.dome_rate_deg_s,
                buttons,
                sound_up: g.sound_up,
                sound_down: g.sound_down,
                sound_left: g.sound_left,
                sound_right: g.sound_right,
                mappings: pad_mapping::checked(g.mappings)
                    .map_err(|msg| ("gamepad".to_string(), "mappings".to_string(), msg))?,
            },
            fleet: raw.fleet,
            streaming: raw.streaming,
            collision: raw.collision,
            bridge: raw.bridge,
            display: raw.display,
        };
        cfg.validate()?;
        Ok(cfg)
    }

    /// Range and consistency checks: (section, key, message).
    fn validate(&self) -> Result<(), (String, String, String)> {
        let bad = |s: &str, k: &str, m: String| Err((s.to_string(), k.to_string(), m));
        if !(1..=7).contains(&self.fleet.max_per_adapter) {
            return bad(
                "fleet",
                "max_per_adapter",
                format!("{} is out of range 1..=7", self.fleet.max_per_adapter),
            );
        }
        if !(1..=50).contains(&self.control.rate_hz) {
            return bad(
                "control",
                "rate_hz",
                format!("{} is out of range 1..=50", self.control.rate_hz),
            );
        }
        if !(self.control.turn_rate_deg_s > 0.0 && self.control.turn_rate_deg_s <= 720.0) {
            return bad("control", "turn_rate_deg_s", "must be in 0..=720".into());
        }
        if !(self.control.dome_rate_deg_s > 0.0 && self.control.dome_rate_deg_s <= 720.0) {
            return bad("control", "dome_rate_deg_s", "must be in 0..=720".into());
        }
        if !(0.0..1.0).contains(&self.gamepad.deadzone) {
            return bad("gamepad", "deadzone", "must be in 0..1".into());
        }
        if !(0.2..=5.0).contains(&self.gamepad.expo) {
            return bad("gamepad", "expo", "must be in 0.2..=5".into());
        }
        if self.keyboard.release_first_ms < self.keyboard.release_repeat_ms {
            return bad(
                "keyboard",
                "release_first_ms",
                "must be at least release_repeat_ms (the first repeat comes later than the next ones)".into(),
            );
        }
        monitor::validate(&self.streaming, &self.collision)?;
        bridge::validate(&self.bridge)?;
        for (k, v) in [
            ("release_first_ms", self.keyboard.release_first_ms),
            ("release_repeat_ms", self.keyboard.release_repeat_ms),
        ] {
            if !(20..=5000).contains(&v) {
                return bad("keyboard", k, format!("{v} is out of range 20..=5000"));
            }
        }
        // 0 passed the check and then every request failed at once (issue 27 point 7).
        if !(MIN_REQUEST_TIMEOUT_MS..=MAX_REQUEST_TIMEOUT_MS)
            .contains(&self.session.request_timeout_ms)
        {
            return bad(
                "session",
                "request_timeout_ms",
                format!(
                    "{} is out of range {MIN_REQUEST_TIMEOUT_MS}..={MAX_REQUEST_TIMEOUT_MS} (ms a droid has to answer a request)",
                    self.session.request_timeout_ms
                ),
            );
        }
        // Slower pacing would keep every command, the operator's stop included, waiting
        // that long (with a huge value, forever: found by the config fuzz target).
        if self.session.pacing_ms > MAX_PACING_MS {
            return bad(
                "session",
                "pacing_ms",
                format!(
                    "{} is out of range 0..={MAX_PACING_MS} (0: the model's own)",
                    self.session.pacing_ms
                ),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_parse() {
        let c = Config::defaults();
        assert_eq!(c.control.rate_hz, 10);
        assert_eq!(c.control.mode, DriveMode::Hold);
        assert_eq!(c.keys["quit"], KeyEntry::Keys(vec!["q".into()]));
    }

    #[test]
    fn user_values_merge_over_defaults() {
        let c = Config::parse_merged(
            None,
            "[control]\nrate_hz = 20\nmode = \"latched\"\n[keys]\nquit = [\"Ctrl+q\"]\n",
        )
        .unwrap();
        assert_eq!(c.control.rate_hz, 20);
        assert_eq!(c.control.mode, DriveMode::Latched);
        assert_eq!(c.control.cruise_speed, 100);
        assert_eq!(c.keymap.action(&Key::ch('q')), None);
        let ctrl_q = Key::parse("Ctrl+q").unwrap();
        assert_eq!(c.keymap.action(&ctrl_q), Some(Action::Quit));
        assert_eq!(c.keymap.action(&Key::ch('w')), Some(Action::Forward));
        // A context's table merges binding by binding too.
        let c = Config::parse_merged(None, "[keys.packet_log]\npause = [\"P\"]\n").unwrap();
        assert_eq!(
            c.keymap.action_in(Context::Log, &Key::ch('P')),
            Some(Action::LogPause)
        );
        assert_eq!(
            c.keymap.action_in(Context::Log, &Key::ch('d')),
            Some(Action::LogDecoded)
        );
    }

    #[test]
    fn errors_name_path_line_and_key() {
        let p = Path::new("/home/u/.config/droidctl/config.toml");
        let e = Config::parse_merged(Some(p), "[control]\n\nrate_hz = 99\n").unwrap_err();
        assert_eq!(e.line, Some(3));
        assert_eq!(e.key.as_deref(), Some("control.rate_hz"));
        assert!(
            e.to_string()
                .starts_with("/home/u/.config/droidctl/config.toml:3: key `control.rate_hz`"),
            "{e}"
        );

        let e = Config::parse_merged(Some(p), "[control]\nrate_hz = \"fast\"\n").unwrap_err();
        assert!(e.message.contains("is not a whole number"), "{e}");

        let e = Config::parse_merged(Some(p), "[control]\nwarp = 9\n").unwrap_err();
        assert_eq!(e.key.as_deref(), Some("control.warp"));
        assert_eq!(e.line, Some(2));

        let e = Config::parse_merged(Some(p), "[control\nrate_hz = 1").unwrap_err();
        assert_eq!(e.line, Some(1));

        let e = Config::parse_merged(Some(p), "[keys]\nforward = [\"Hyper+w\"]\n").unwrap_err();
        assert_eq!(e.key.as_deref(), Some("keys.forward"));
        assert_eq!(e.line, Some(2));

        let e = Config::parse_merged(Some(p), "[keys]\nforward = [\"t\"]\n").unwrap_err();
        assert!(
            e.message.contains("turbo") && e.message.contains("forward"),
            "{e}"
        );
        // Named on the binding the user touched, with its line.
        assert_eq!(e.key.as_deref(), Some("keys.forward"), "{e}");
        assert_eq!(e.line, Some(2));

        let e = Config::parse_merged(Some(p), "[gamepad]\ntripod = \"Z\"\n").unwrap_err();
        assert_eq!(e.key.as_deref(), Some("gamepad.tripod"));
        // Every button is checked, `aim` included, with its line.
        let e =
            Config::parse_merged(Some(p), "[gamepad]\nenabled = true\naim = \"RB\"\n").unwrap_err();
        assert_eq!(e.key.as_deref(), Some("gamepad.aim"));
        assert_eq!(e.line, Some(3));
        // A context's binding is found in its own table.
        let e = Config::parse_merged(Some(p), "[keys]\n[keys.packet_log]\npause = [\"d\"]\n")
            .unwrap_err();
        assert_eq!(e.key.as_deref(), Some("keys.packet_log.pause"));
        assert_eq!(e.line, Some(3));
        // A pacing that would keep the stop waiting for ever.
        let e = Config::parse_merged(Some(p), "[session]\npacing_ms = 9223372036854775807\n")
            .unwrap_err();
        assert_eq!(e.key.as_deref(), Some("session.pacing_ms"));
        assert!(e.message.contains("0..=1000"), "{e}");
        assert!(Config::parse_merged(Some(p), "[session]\npacing_ms = 1000\n").is_ok());
    }

    #[test]
    fn type_and_range_errors_name_line_and_key_in_words() {
        let p = Path::new("c.toml");
        let cases: &[(&str, &str, usize, &str)] = &[
            (
                "[control]\n\ncruise_speed = 300\n",
                "control.cruise_speed",
                3,
                "300 is not a whole number from 0 to 255",
            ),
            (
                "[control]\nrate_hz = \"fast\"\n",
                "control.rate_hz",
                2,
                "is not a whole number",
            ),
            (
                "[control]\nmode = \"fast\"\n",
                "control.mode",
                2,
                "is not one of: hold, latched",
            ),
            (
                "# mine\n[gamepad]\nenabled = 1\n",
                "gamepad.enabled",
                3,
                "1 is not true or false",
            ),
            (
                "[gamepad]\ndeadzone = \"x\"\n",
                "gamepad.deadzone",
                2,
                "is not a number",
            ),
            (
                "[keyboard]\nrelease_first_ms = -5\n",
                "keyboard.release_first_ms",
                2,
                "-5 is not a whole number",
            ),
            (
                "[session]\nrequest_timeout_ms = 0\n",
                "session.request_timeout_ms",
                2,
                "0 is out of range 100..=60000",
            ),
            (
                "[control]\nwarp = 9\n",
                "control.warp",
                2,
                "there is no setting warp in [control]",
            ),
        ];
        for (text, key, line, words) in cases {
            let e = Config::parse_merged(Some(p), text).unwrap_err();
            assert_eq!(e.key.as_deref(), Some(*key), "{text:?}: {e}");
            assert_eq!(e.line, Some(*line), "{text:?}: {e}");
            assert!(e.message.contains(words), "{text:?}: {e}");
            let shown = e.to_string();
            assert!(
                shown.starts_with(&format!("c.toml:{line}: key `{key}`: ")),
                "{shown}"
            );
            for serde in ["invalid value", "invalid type", "expected u8", "`"] {
                assert!(!e.message.contains(serde), "in words: {shown}");
            }
        }
        assert!(Config::parse_merged(Some(p), "[session]\nrequest_timeout_ms = 100\n").is_ok());
    }

    #[test]
    fn streaming_and_collision_tables() {
        use crate::tuning::{SensorGroup, SensorSet};
        let c = Config::defaults();
        let r = c.stream_request();
        assert_eq!(r.rate_hz, 10);
        assert!(
            r.sensors.contains(SensorGroup::Gyro) && r.sensors.contains(SensorGroup::HeadAngle)
        );
        assert_eq!(c.collision, crate::tuning::CollisionConfig::default());
        let c = Config::parse_merged(
            None,
            "[streaming]\nrate_hz = 50\nsensors = [\"attitude\"]\n[collision]\nx_threshold = 200\ndead_time_ms = 500\n",
        )
        .unwrap();
        let r = c.stream_request();
        assert_eq!(
            (r.rate_hz, r.sensors),
            (50, SensorSet::of(&[SensorGroup::Attitude]))
        );
        assert_eq!(c.collision.x_threshold, 200);
        assert_eq!(c.collision.dead_time_units(), 50);
        // The older key still works, and wins.
        let c = Config::parse_merged(None, "[control]\nstreaming_interval_ms = 0\n").unwrap();
        assert_eq!(c.stream_request().rate_hz, 0);
        let p = Path::new("c.toml");
        let e = Config::parse_merged(Some(p), "[streaming]\nsensors = [\"sonar\"]\n").unwrap_err();
        assert_eq!(e.key.as_deref(), Some("streaming.sensors"));
        assert_eq!(e.line, Some(2));
        let e = Config::parse_merged(Some(p), "[streaming]\nrate_hz = 400\n").unwrap_err();
        assert_eq!(e.key.as_deref(), Some("streaming.rate_hz"));
        let e = Config::parse_merged(Some(p), "[collision]\ndead_time_ms = 9000\n").unwrap_err();
        assert_eq!(e.key.as_deref(), Some("collision.dead_time_ms"));
    }

    #[test]
    fn missing_file_means_defaults() {
        let c = Config::load(Path::new("/nonexistent/droidctl/config.toml")).unwrap();
        assert_eq!(c, Config::defaults());
    }

    /// Issue 37 point 13: a FIFO at the usual place is an error at once, not a hang; a
    /// symbolic link to a file (a dotfile manager's) is read.
    #[cfg(unix)]
    #[test]
    fn a_fifo_at_the_usual_place_is_refused_and_a_link_followed() {
        let dir = std::env::temp_dir().join(format!("droidctl-config-fifo-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let fifo = dir.join("config.toml");
        let at = fifo.clone();
        let e = crate::own_file::testing::with_fifo(&fifo, "loading", move || {
            Config::load(&at).map_err(|e| e.to_string())
        })
        .unwrap_err();
        assert!(e.contains("FIFO"), "{e}");
        let real = dir.join("dotfiles.toml");
        std::fs::write(&real, "[control]\ncruise_speed = 77\n").unwrap();
        let link = dir.join("linked.toml");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        assert_eq!(Config::load(&link).unwrap().control.cruise_speed, 77);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
