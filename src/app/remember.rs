//! Settings the app remembers per droid model between launches: cruise speed, the scope's
//! channels and window, the streaming rate, the packet log's filter and mirror mode. They
//! live in the state directory (`settings-<model>.toml`, beside the log file), never in the
//! configuration file, which stays the user's. The forget key (`R`) puts the droid's back
//! to the configuration's and deletes its file.
//!
//! The file is read as untrusted input: one that cannot be read, is too big, is not TOML
//! or holds values out of range is a visible warning (a hint) and the defaults, never a
//! panic; what is valid in it is still used. What is not a regular file (a FIFO, a symbolic
//! link) is not opened as one ([`crate::own_file`]): a warning too, and never a hang; at
//! exit the file is written anew in its place.

use crate::model::Model;
use crate::telemetry::history::Channel;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A settings file bigger than this is not read.
const MAX_BYTES: u64 = 64 * 1024;
/// The scope's windows there are ([`super::view::scope::WINDOWS`]).
const WINDOWS: usize = super::view::scope::WINDOWS.len();

/// What is remembered of one model; `None`: not remembered, the configuration's value.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Remembered {
    pub cruise: Option<u8>,
    pub scope_channels: Option<Vec<String>>,
    pub scope_window: Option<usize>,
    pub stream_rate_hz: Option<u16>,
    pub log_filter: Option<String>,
    pub mirror: Option<bool>,
}

/// The file of `model`'s settings in `dir`.
pub fn path(dir: &Path, model: Model) -> PathBuf {
    dir.join(format!("settings-{}.toml", model.id()))
}

/// The platform's state directory (`~/.local/state/droidctl` on Linux), or
/// `DROIDCTL_STATE_DIR`.
pub fn default_dir() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("DROIDCTL_STATE_DIR") {
        return Some(PathBuf::from(p));
    }
    directories::ProjectDirs::from("", "", "droidctl").map(|d| {
        d.state_dir()
            .unwrap_or_else(|| d.data_local_dir())
            .to_path_buf()
    })
}

impl Remembered {
    /// `model`'s settings in `dir`, and a warning to show when the file was there but not
    /// (all) usable.
    pub fn load(dir: &Path, model: Model) -> (Remembered, Option<String>) {
        let p = path(dir, model);
        let warn = |why: String| {
            Some(format!(
                "remembered settings {}: {why}; using the configuration's (R forgets them)",
                p.display()
            ))
        };
        // Not a FIFO (the app would hang before drawing) nor through a symbolic link.
        let file = match crate::own_file::open(
            &p,
            std::fs::OpenOptions::new().read(true),
            crate::own_file::Links::Refuse,
        ) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return (Remembered::default(), None);
            }
            Err(e) => return (Remembered::default(), warn(e.to_string())),
            Ok(f) => f,
        };
        match file.metadata() {
            Ok(m) if m.len() > MAX_BYTES => {
                return (
                    Remembered::default(),
                    warn(format!("{} bytes, more than {MAX_BYTES}", m.len())),
                );
            }
            _ => {}
        }
        let text = match crate::text_file::read_from(file, MAX_BYTES) {
            Ok(t) => t,
            Err(e) => return (Remembered::default(), warn(e.to_string())),
        };
        match toml::from_str::<Remembered>(&text) {
            Ok(r) => {
                let (r, bad) = r.checked();
                (r, bad.map(|b| warn(b).unwrap_or_default()))
            }
            Err(e) => (
                Remembered::default(),
                warn(format!("not readable ({})", e.message())),
            ),
        }
    }

    /// Only the values in range; the first one that was not, in words.
    fn checked(mut self) -> (Remembered, Option<String>) {
        let mut bad = None;
        if let Some(names) = &self.scope_channels {
            let known: Vec<String> = names
                .iter()
                .filter(|n| Channel::ALL.iter().any(|c| c.name() == n.as_str()))
                .take(Channel::ALL.len())
                .cloned()
                .collect();
            if known.len() != names.len() {
                bad = Some("unknown scope channels left out".to_string());
            }
            self.scope_channels = Some(known);
        }
        if self.scope_window.is_some_and(|w| w >= WINDOWS) {
            self.scope_window = None;
            bad = Some("scope_window out of range".into());
        }
        if self.stream_rate_hz.is_some_and(|r| r > 1000) {
            self.stream_rate_hz = None;
            bad = Some("stream_rate_hz out of range".into());
        }
        if self.log_filter.as_ref().is_some_and(|f| f.len() > 80) {
            self.log_filter = None;
            bad = Some("log_filter too long".into());
        }
        (self, bad)
    }

    /// What of this beats the configuration, in words (`cruise 145 (config 60)`): said on
    /// screen at start, so a remembered value never silently wins over the file. `cruise` and
    /// `rate` are the configuration's.
    pub fn over_config(&self, cruise: u8, rate: u16) -> Vec<String> {
        let mut said = Vec::new();
        if let Some(c) = self.cruise.filter(|c| *c != cruise) {
            said.push(format!("cruise {c} (config {cruise})"));
        }
        if let Some(r) = self.stream_rate_hz.filter(|r| *r != rate) {
            said.push(format!("rate {r}/s (config {rate}/s)"));
        }
        if let Some(f) = self.log_filter.as_deref().filter(|f| !f.is_empty()) {
            said.push(format!("log filter \"{f}\""));
        }
        said
    }

    /// The scope's channels, as channels.
    pub fn channels(&self) -> Option<Vec<Channel>> {
        self.scope_channels.as_ref().map(|names| {
            Channel::ALL
                .iter()
                .copied()
                .filter(|c| names.iter().any(|n| n == c.name()))
                .collect()
        })
    }

    /// Write `model`'s settings to `dir` (created when missing), whole or not at all, and
    /// over whatever is at the file's path (a symbolic link is replaced, its target kept).
    pub fn save(&self, dir: &Path, model: Model) -> std::io::Result<()> {
        std::fs::create_dir_all(dir)?;
        let mut text = String::from(
            "# What droidctl remembers of this droid model between launches (not your\n\
             # configuration). Delete this file, or press R in the app, to forget it.\n",
        );
        text.push_str(&toml::to_string(self).map_err(std::io::Error::other)?);
        crate::own_file::write_atomic(&path(dir, model), text.as_bytes())
    }

    /// Forget `model`'s settings (no file is fine).
    pub fn forget(dir: &Path, model: Model) -> std::io::Result<()> {
        match std::fs::remove_file(path(dir, model)) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(e),
            _ => Ok(()),
        }
    }
}

impl super::core::App {
    /// Remember every live droid's settings for its model (at exit). A file that cannot be
    /// written is logged: the app is closing, the screen is gone.
    pub(super) fn save_remembered(&self) {
        let Some(dir) = &self.remember else {
            return;
        };
        let filter = self.state.log.filter_input();
        for (view, io) in self.state.droids.iter().zip(&self.io) {
            if io.session.is_none() {
                continue;
            }
            let r = Remembered {
                cruise: Some(view.control.cruise),
                scope_channels: Some(
                    view.scope
                        .channels
                        .iter()
                        .map(|c| c.name().to_string())
                        .collect(),
                ),
                scope_window: Some(view.scope.window),
                stream_rate_hz: Some(io.pending_rate.unwrap_or(view.monitor.request.rate_hz)),
                log_filter: (!filter.is_empty()).then(|| filter.clone()),
                mirror: (self.state.droids.len() > 1).then_some(self.state.mirror),
            };
            if let Err(e) = r.save(dir, view.model) {
                tracing::warn!("remembering settings in {}: {e}", dir.display());
            }
        }
    }

    /// The forget key asks first: the first press says what would be forgotten, a second
    /// press while that is on screen (and before any other key) forgets it.
    pub(super) fn ask_to_forget(&mut self) {
        let now = self.now();
        if self
            .forget_asked
            .is_some_and(|at| now.saturating_sub(at) < super::state::HINT_TIME)
        {
            self.forget_asked = None;
            return self.forget_settings();
        }
        self.forget_asked = Some(now);
        let key = self
            .keymap
            .shown(crate::config::Action::ForgetSettings)
            .unwrap_or_default();
        let model = self.state.droid().model;
        self.hint(format!(
            "forget {}'s remembered settings? {key} again: yes · other keys: no",
            model.display_name()
        ));
    }

    /// Forgetting: the chosen droid's model goes back to the configuration's settings
    /// (cruise, scope, streaming rate) and the log filter is cleared; its file is deleted.
    fn forget_settings(&mut self) {
        let i = self.chosen();
        let model = self.state.droid().model;
        let cruise = self.default_cruise;
        let rate = self.default_rate;
        if let Some(mut d) = self.droid(i) {
            d.io.controller.set_cruise(cruise);
            d.view.control.cruise = cruise;
            d.view.scope = super::view::scope::ScopeView::for_model(model);
            d.io.pending_rate = None;
            let m = &d.view.monitor;
            if m.live && m.caps.is_some() && m.request.rate_hz != rate {
                let draft = super::view::scope::TuningDraft {
                    rate_hz: rate,
                    sensors: m.request.sensors,
                    collision: m.collision,
                };
                d.apply_tuning(draft);
            }
        }
        self.state.log.set_filter(Default::default());
        let text = match self
            .remember
            .as_deref()
            .map(|dir| Remembered::forget(dir, model))
        {
            Some(Err(e)) => format!("settings reset; the remembered file stays: {e}"),
            _ => format!(
                "{} settings back to the configuration's",
                model.display_name()
            ),
        };
        self.hint(text);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("droidctl-remember-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    #[test]
    fn round_trip_and_forget() {
        let d = dir("trip");
        let r = Remembered {
            cruise: Some(140),
            scope_channels: Some(vec!["pitch".into(), "speed".into()]),
            scope_window: Some(3),
            stream_rate_hz: Some(20),
            log_filter: Some("in dev:sensor".into()),
            mirror: Some(true),
        };
        r.save(&d, Model::R2D2).unwrap();
        assert_eq!(Remembered::load(&d, Model::R2D2), (r.clone(), None));
        // Per model: BB-8 has none.
        assert_eq!(
            Remembered::load(&d, Model::BB8),
            (Remembered::default(), None)
        );
        Remembered::forget(&d, Model::R2D2).unwrap();
        Remembered::forget(&d, Model::R2D2).unwrap();
        assert_eq!(Remembered::load(&d, Model::R2D2).0, Remembered::default());
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn a_hostile_file_is_a_warning_never_a_panic() {
        let d = dir("hostile");
        std::fs::create_dir_all(&d).unwrap();
        let p = path(&d, Model::R2D2);
        for text in [
            "cruise = 999\n",
            "cruise = \"fast\"\n",
            "\u{0}\u{1}garbage[[[",
            "scope_window = 99\ncruise = 50\n",
            "scope_channels = [\"pitch\", \"nonsense\"]\n",
            "stream_rate_hz = 65535\n",
        ] {
            std::fs::write(&p, text).unwrap();
            let (r, warning) = Remembered::load(&d, Model::R2D2);
            let w = warning.unwrap_or_else(|| panic!("no warning for {text:?}"));
            assert!(w.contains("settings-r2d2.toml"), "{w}");
            if text.starts_with("scope_window") {
                // What is valid is kept.
                assert_eq!((r.cruise, r.scope_window), (Some(50), None));
            }
            if text.starts_with("scope_channels") {
                assert_eq!(r.channels(), Some(vec![Channel::Pitch]));
            }
        }
        std::fs::write(&p, vec![b'#'; 100_000]).unwrap();
        assert!(Remembered::load(&d, Model::R2D2).1.is_some());
        let _ = std::fs::remove_dir_all(&d);
    }

    /// Issue 37 point 13: a FIFO in the file's place gave a start that never drew.
    #[cfg(unix)]
    #[test]
    fn a_fifo_in_place_is_a_warning_at_once_and_saving_replaces_it() {
        let d = dir("fifo");
        std::fs::create_dir_all(&d).unwrap();
        let p = path(&d, Model::R2D2);
        let at = d.clone();
        let (r, warning) = crate::own_file::testing::with_fifo(&p, "loading", move || {
            Remembered::load(&at, Model::R2D2)
        });
        assert_eq!(r, Remembered::default());
        let w = warning.expect("a warning");
        assert!(
            w.contains("settings-r2d2.toml") && w.contains("FIFO"),
            "{w}"
        );
        let mine = Remembered {
            cruise: Some(90),
            ..Default::default()
        };
        mine.save(&d, Model::R2D2).unwrap();
        assert_eq!(Remembered::load(&d, Model::R2D2), (mine, None));
        let _ = std::fs::remove_dir_all(&d);
    }

    /// Issue 37 point 13: a symbolic link in the file's place had its target overwritten.
    #[cfg(unix)]
    #[test]
    fn a_link_in_place_is_not_followed_and_its_target_is_kept() {
        let d = dir("link");
        std::fs::create_dir_all(&d).unwrap();
        let target = d.join("precious.toml");
        std::fs::write(&target, "cruise = 10\n").unwrap();
        let p = path(&d, Model::R2D2);
        std::os::unix::fs::symlink(&target, &p).unwrap();
        let (r, warning) = Remembered::load(&d, Model::R2D2);
        assert_eq!(r, Remembered::default(), "not read through the link");
        let w = warning.expect("a warning");
        assert!(w.contains("symbolic link"), "{w}");
        let mine = Remembered {
            cruise: Some(90),
            ..Default::default()
        };
        mine.save(&d, Model::R2D2).unwrap();
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "cruise = 10\n");
        assert!(std::fs::symlink_metadata(&p).unwrap().is_file());
        assert_eq!(Remembered::load(&d, Model::R2D2), (mine, None));
        let _ = std::fs::remove_dir_all(&d);
    }
}
