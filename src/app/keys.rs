//! Key dispatch: a key is read in the context that has the keyboard — an open overlay (a
//! palette, help, the filter prompt), the focused packet log, a replay, or driving — and
//! looked up in that context's bindings from the key map. Nothing is hard-coded but Ctrl+C,
//! which always quits (the droid is stopped first).
//!
//! Held actions (drive, turn, dome, e-stop) track press and release through [`HeldKeys`]
//! (with emulated release where the terminal reports none); every other action fires once per
//! press.
//!
//! [`HeldKeys`]: crate::teleop::held::HeldKeys

use super::core::App;
use super::input::{KeyKind, TermEvent};
use super::packet_log::LogFilter;
use super::run::ExitReason;
use super::state::{Focus, Overlay};
use crate::config::{Action, Context, Key, KeyCode};

/// Longest log filter typed.
const FILTER_MAX: usize = 80;

/// Typing into a prompt's `input`: Backspace, Space, and the characters `ok` takes, up to
/// `max` bytes.
pub(super) fn edit(input: &mut String, key: Key, max: usize, ok: impl Fn(char) -> bool) {
    match key.code {
        KeyCode::Backspace => {
            input.pop();
        }
        KeyCode::Char(c) if !key.ctrl && ok(c) && input.len() < max => input.push(c),
        KeyCode::Space if input.len() < max => input.push(' '),
        _ => {}
    }
}

impl App {
    /// A terminal event; returns an exit reason when the app should stop.
    pub fn on_term(&mut self, e: TermEvent) -> Option<ExitReason> {
        self.touched();
        let now = self.now();
        match e {
            TermEvent::FocusLost => {
                // Focus loss releases every key: the deadman stops the droid now.
                self.held.release_all();
                self.control(false);
            }
            TermEvent::FocusGained | TermEvent::Resize => self.dirty = true,
            TermEvent::Key {
                key,
                kind: KeyKind::Release,
            } => {
                self.held.release(key);
                if let KeyCode::Char(c) = key.code {
                    // Shift may be let go first: release both cases.
                    for c in [c.to_ascii_lowercase(), c.to_ascii_uppercase()] {
                        self.held.release(Key {
                            code: KeyCode::Char(c),
                            ctrl: key.ctrl,
                        });
                    }
                }
                self.control(false);
            }
            TermEvent::Key { key, kind } => {
                if key == Key::CTRL_C {
                    return Some(ExitReason::Quit);
                }
                // Only keys bound to held actions track press and release; for the others
                // every press counts, so tapping `?` twice quickly opens and closes help even
                // when releases are only inferred.
                let held_action = self.keymap.action(&key).is_some_and(Action::is_held);
                let new = match (held_action, kind) {
                    (true, KeyKind::Repeat) => {
                        self.held.repeat(key, now);
                        false
                    }
                    (true, _) => self.held.press(key, now),
                    (false, kind) => kind == KeyKind::Press,
                };
                self.dirty = true;
                return self.on_key(key, new);
            }
        }
        None
    }

    /// A key press (`new_press`) or repeat, to whatever has the keyboard.
    fn on_key(&mut self, key: Key, new_press: bool) -> Option<ExitReason> {
        match self.state.overlay {
            Overlay::Animations { .. } | Overlay::Sounds { .. } => {
                self.palette_key(key, new_press);
                None
            }
            Overlay::Help => {
                self.help_key(key, new_press);
                None
            }
            Overlay::Filter { .. } => {
                self.filter_key(key);
                None
            }
            Overlay::Matrix { .. } => {
                self.matrix_key(key);
                None
            }
            Overlay::Channels { .. } => {
                self.channels_key(key, new_press);
                None
            }
            Overlay::Tuning { .. } => {
                self.tuning_key(key, new_press);
                None
            }
            Overlay::None
                if self.state.scope.visible
                    && self.state.focus == Focus::Drive
                    && self.keymap.action_in(Context::Scope, &key).is_some() =>
            {
                self.scope_key(key, new_press);
                None
            }
            Overlay::None if self.state.focus == Focus::Log => self.log_key(key, new_press),
            Overlay::None if self.player.is_some() => self.replay_key(key, new_press),
            Overlay::None => self.drive_key(key, new_press),
        }
    }

    fn open_help(&mut self) {
        self.state.help_page = 0;
        self.state.overlay = Overlay::Help;
    }

    fn palette_key(&mut self, key: Key, new_press: bool) {
        let (selected, animations) = match self.state.overlay {
            Overlay::Animations { selected } => (selected, true),
            Overlay::Sounds { selected } => (selected, false),
            _ => return,
        };
        let len = if animations {
            self.state.animations.len()
        } else {
            self.state.sounds.len()
        };
        let last = len.saturating_sub(1);
        let sel = match self.keymap.action_in(Context::Palette, &key) {
            Some(Action::PaletteUp) => selected.saturating_sub(1),
            Some(Action::PaletteDown) => (selected + 1).min(last),
            Some(Action::PalettePageUp) => selected.saturating_sub(10),
            Some(Action::PalettePageDown) => (selected + 10).min(last),
            Some(Action::PaletteClose) => {
                self.state.overlay = Overlay::None;
                return;
            }
            Some(Action::PalettePlay) if new_press => {
                if animations {
                    if let Some(e) = self.state.animations.get(selected).cloned() {
                        self.play_animation(e.id, &e.name);
                    }
                } else if let Some(e) = self.state.sounds.get(selected).cloned() {
                    self.play_sound(e.id, &e.name);
                }
                self.state.overlay = Overlay::None;
                return;
            }
            _ => selected,
        };
        self.state.overlay = if animations {
            Overlay::Animations { selected: sel }
        } else {
            Overlay::Sounds { selected: sel }
        };
    }

    fn help_key(&mut self, key: Key, new_press: bool) {
        match self.keymap.action_in(Context::Help, &key) {
            Some(Action::HelpNext) => self.state.help_page += 1,
            Some(Action::HelpPrevious) => {
                self.state.help_page = self.state.help_page.saturating_sub(1)
            }
            // Any other key closes help.
            _ if new_press => self.state.overlay = Overlay::None,
            _ => {}
        }
    }

    fn filter_key(&mut self, key: Key) {
        let action = self.keymap.action_in(Context::Filter, &key);
        let Overlay::Filter { input } = &mut self.state.overlay else {
            return;
        };
        match action {
            Some(Action::FilterCancel) => self.state.overlay = Overlay::None,
            Some(Action::FilterApply) => {
                let f = LogFilter::parse(input);
                self.state.log.set_filter(f);
                self.state.overlay = Overlay::None;
            }
            // The rest is typing.
            _ => edit(input, key, FILTER_MAX, |_| true),
        }
    }

    /// The packet log has the keys: its own bindings first, then the drive table's quit,
    /// help, e-stop and log (back to driving).
    fn log_key(&mut self, key: Key, new_press: bool) -> Option<ExitReason> {
        let log = &mut self.state.log;
        match self.keymap.action_in(Context::Log, &key) {
            Some(Action::LogUp) => log.scroll_up(1),
            Some(Action::LogDown) => log.scroll_down(1),
            Some(Action::LogPageUp) => log.scroll_up(10),
            Some(Action::LogPageDown) => log.scroll_down(10),
            Some(Action::LogTop) => log.scroll_up(usize::MAX / 2),
            Some(Action::LogBottom) => log.scroll_down(usize::MAX / 2),
            Some(Action::LogBack) => self.state.focus = Focus::Drive,
            // The toggles fire once per press.
            Some(_) if !new_press => {}
            Some(Action::LogPause) => log.toggle_pause(),
            Some(Action::LogDecoded) => log.decoded = !log.decoded,
            Some(Action::LogFilter) => {
                self.state.overlay = Overlay::Filter {
                    input: log.filter_input(),
                }
            }
            Some(Action::LogClearFilter) => log.set_filter(Default::default()),
            Some(_) => {}
            None => match self.keymap.action(&key) {
                Some(Action::EStop) => self.estop(),
                Some(_) if !new_press => {}
                Some(Action::Log) => self.state.focus = Focus::Drive,
                Some(Action::Quit) => return Some(ExitReason::Quit),
                Some(Action::Help) => self.open_help(),
                _ => {}
            },
        }
        None
    }

    /// Replay: the replay bindings, then the drive table's quit, help and log keys; nothing
    /// drives.
    fn replay_key(&mut self, key: Key, new_press: bool) -> Option<ExitReason> {
        if !new_press {
            return None;
        }
        if let Some(a) = self.keymap.action_in(Context::Replay, &key) {
            // Every droid of a fleet's capture plays on the same clock.
            self.on_replay_action(a);
            self.each_other(|o| o.on_replay_action(a));
            return None;
        }
        match self.keymap.action(&key) {
            Some(Action::NextDroid) => {
                self.choose_next(true);
                return None;
            }
            Some(Action::PreviousDroid) => {
                self.choose_next(false);
                return None;
            }
            _ => {}
        }
        match self.keymap.action(&key) {
            Some(Action::Quit) => return Some(ExitReason::Quit),
            Some(Action::Help) => self.open_help(),
            Some(Action::Log) => self.state.focus = Focus::Log,
            Some(Action::Scope) => self.toggle_scope(),
            Some(Action::Tuning) => self.open_tuning(),
            _ => {}
        }
        None
    }

    /// Driving.
    fn drive_key(&mut self, key: Key, new_press: bool) -> Option<ExitReason> {
        let action = self.keymap.action(&key)?;
        if !new_press {
            return None;
        }
        match action {
            Action::Quit => return Some(ExitReason::Quit),
            Action::Help => self.open_help(),
            Action::Log => {
                self.state.focus = Focus::Log;
                // The droid is held stopped while the log has the keys.
                self.held.release_all();
                self.control(false);
            }
            Action::NextDroid => self.choose_next(true),
            Action::PreviousDroid => self.choose_next(false),
            Action::Mirror => self.toggle_mirror(),
            Action::Scope => self.toggle_scope(),
            Action::Tuning => self.open_tuning(),
            Action::Colour => self.cycle_colour(),
            Action::BackLight => self.toggle_back_light(),
            Action::Animations if self.family.animation(self.state.model, 0).is_none() => {
                self.hint("this droid has no animations")
            }
            Action::Sounds if self.family.sound(self.state.model, 0).is_none() => {
                self.hint("this droid cannot play sounds")
            }
            Action::Animations => self.state.overlay = Overlay::Animations { selected: 0 },
            Action::Sounds => self.state.overlay = Overlay::Sounds { selected: 0 },
            a if self.robot_action(a) => {}
            a => {
                let view = self.droid_view();
                let outs = self.controller.on_press(a, &view);
                self.apply(outs);
                // Mirror: speed, turbo, stance and aim keys act on every droid too.
                if self.mirroring() && !a.is_held() {
                    self.each_other(|o| {
                        let view = o.droid_view();
                        let outs = o.controller.on_press(a, &view);
                        o.apply(outs);
                    });
                }
                if a.is_held() {
                    self.control(false);
                }
            }
        }
        None
    }
}
