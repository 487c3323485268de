//! Configuration: a TOML file in the platform config directory, merged over the defaults
//! shipped in `assets/default-config.toml`. An invalid file is reported with its path, line
//! and key, and the app refuses to start rather than guess.

use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The slowest write pacing `session.pacing_ms` may set.
pub const MAX_PACING_MS: u64 = 1000;

/// The shipped defaults (also what `droidctl config init` writes).
pub const DEFAULT_TOML: &str = include_str!("../assets/default-config.toml");

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
    pub streaming_interval_ms: u16,
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

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gamepad {
    pub enabled: bool,
    pub deadzone: f32,
    pub expo: f32,
    pub max_speed: u8,
    pub dome_rate_deg_s: f32,
    pub tripod: String,
    pub bipod: String,
    /// Aim mode on rolling droids (BB-8, SPRK+, Ollie, BB-9E).
    pub aim: String,
    pub estop: String,
    pub animation: String,
    pub help: String,
    pub sound_up: u16,
    pub sound_down: u16,
    pub sound_left: u16,
    pub sound_right: u16,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    pub control: Control,
    pub keyboard: Keyboard,
    pub session: Session,
    /// Action name → key names.
    pub keys: BTreeMap<String, Vec<String>>,
    pub gamepad: Gamepad,
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
    if let Some(p) = std::env::var_os("DROIDCTL_CONFIG") {
        return PathBuf::from(p);
    }
    directories::ProjectDirs::from("", "", "droidctl")
        .map(|d| d.config_dir().to_path_buf())
        .unwrap_or_else(|| PathBuf::from("."))
        .join("config.toml")
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
    /// The shipped defaults.
    pub fn defaults() -> Config {
        Config::parse_merged(None, "")
            .unwrap_or_else(|e| panic!("shipped defaults are invalid: {e}"))
    }

    /// Load the user's file if it exists, merged over the defaults.
    pub fn load(path: &Path) -> Result<Config, ConfigError> {
        match std::fs::read_to_string(path) {
            Ok(text) => Config::parse_merged(Some(path), &text),
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
        // Key bindings replace per action, so one action can be rebound without repeating
        // the whole table; other sections merge key by key.
        merge(&mut base, user);
        let merged = toml::to_string(&base).map_err(|e| err(None, None, e.to_string()))?;
        let cfg: Config = toml::from_str(&merged).map_err(|e: toml::de::Error| {
            // The merged text's lines are not the user's: point at the key in the user's file.
            let msg = e.message().to_string();
            let key = msg
                .split('`')
                .nth(1)
                .map(str::to_string)
                .filter(|_| msg.contains("unknown field"));
            let line = key.as_deref().and_then(|k| {
                text.lines()
                    .position(|l| l.trim_start().starts_with(k) && l.contains('='))
                    .map(|i| i + 1)
            });
            err(line, key, msg)
        })?;
        cfg.validate().map_err(|(section, key, message)| {
            err(
                find_key_line(text, &section, &key),
                Some(format!("{section}.{key}")),
                message,
            )
        })?;
        Ok(cfg)
    }

    /// Range and consistency checks: (section, key, message).
    fn validate(&self) -> Result<(), (String, String, String)> {
        let bad = |s: &str, k: &str, m: String| Err((s.to_string(), k.to_string(), m));
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
        for (k, v) in [
            ("release_first_ms", self.keyboard.release_first_ms),
            ("release_repeat_ms", self.keyboard.release_repeat_ms),
        ] {
            if !(20..=5000).contains(&v) {
                return bad("keyboard", k, format!("{v} is out of range 20..=5000"));
            }
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
        if let Err((key, msg)) = crate::teleop::keymap::KeyMap::from_config(&self.keys) {
            return bad("keys", &key, msg);
        }
        for (k, name) in [
            ("tripod", &self.gamepad.tripod),
            ("bipod", &self.gamepad.bipod),
            ("aim", &self.gamepad.aim),
            ("estop", &self.gamepad.estop),
            ("animation", &self.gamepad.animation),
            ("help", &self.gamepad.help),
        ] {
            if crate::teleop::gamepad::Button::parse(name).is_none() {
                return bad(
                    "gamepad",
                    k,
                    format!(
                        "unknown button {name:?} (use South, East, North, West, Start, Select, LeftBumper, RightBumper)"
                    ),
                );
            }
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
        assert_eq!(c.keys["quit"], vec!["q", "Esc"]);
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
        assert_eq!(c.keys["quit"], vec!["Ctrl+q"]);
        assert_eq!(c.keys["forward"], vec!["Up", "w"]);
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
        assert!(
            e.message.contains("integer") || e.message.contains("invalid type"),
            "{e}"
        );

        let e = Config::parse_merged(Some(p), "[control]\nwarp = 9\n").unwrap_err();
        assert_eq!(e.key.as_deref(), Some("warp"));
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

        let e = Config::parse_merged(Some(p), "[gamepad]\ntripod = \"Z\"\n").unwrap_err();
        assert_eq!(e.key.as_deref(), Some("gamepad.tripod"));
        // Every button is checked (the aim button was accepted whatever it named, and then
        // never worked; found by the config fuzz target).
        let e = Config::parse_merged(Some(p), "[gamepad]\naim = \"Z\"\n").unwrap_err();
        assert_eq!(e.key.as_deref(), Some("gamepad.aim"));
        assert_eq!(e.line, Some(2));
        // A pacing that would keep the stop waiting for ever.
        let e = Config::parse_merged(Some(p), "[session]\npacing_ms = 9223372036854775807\n")
            .unwrap_err();
        assert_eq!(e.key.as_deref(), Some("session.pacing_ms"));
        assert!(e.message.contains("0..=1000"), "{e}");
        assert!(Config::parse_merged(Some(p), "[session]\npacing_ms = 1000\n").is_ok());
    }

    #[test]
    fn missing_file_means_defaults() {
        let c = Config::load(Path::new("/nonexistent/droidctl/config.toml")).unwrap();
        assert_eq!(c, Config::defaults());
    }
}
