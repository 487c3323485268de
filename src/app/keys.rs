//! Key dispatch: a key is read in the context that has the keyboard — an open overlay (any
//! registered in [`super::overlay`]: the registry hands it the key, and the app carries its
//! outcome out here), the focused packet log, a replay, or driving — and looked up in that
//! context's bindings from the key map. Nothing is hard-coded but Ctrl+C,
//! which always quits (the droid is stopped first).
//!
//! Held actions (drive, turn, dome, e-stop) track press and release through [`HeldKeys`]
//! (with emulated release where the terminal reports none); every other action fires once per
//! press.
//!
//! [`HeldKeys`]: crate::teleop::held::HeldKeys

use super::core::{App, ExitReason};
use super::input::{KeyKind, TermEvent};
use super::overlay::{self, Do, Outcome};
use super::place::Place;
use super::state::{Focus, Overlay};
use crate::config::{Action, Context, Key, KeyCode};
use crate::family::intent::Intent;

impl App {
    /// A terminal event; returns an exit reason when the app should stop.
    pub fn on_term(&mut self, e: TermEvent) -> Option<ExitReason> {
        self.touched();
        let r = match e {
            TermEvent::FocusLost => {
                // Focus loss lets go of every key: the deadman stops the droids now.
                self.clear_held();
                None
            }
            TermEvent::FocusGained | TermEvent::Resize => {
                self.dirty = true;
                None
            }
            TermEvent::Mouse { kind, col, row } => {
                self.dirty = true;
                self.on_mouse(kind, col, row);
                None
            }
            TermEvent::Key {
                key,
                kind: KeyKind::Release,
            } => {
                self.release(key);
                None
            }
            TermEvent::Key { key, kind } => {
                self.dirty = true;
                self.acknowledge_programs();
                self.on_key_event(key, kind)
            }
        };
        self.traced();
        r
    }

    /// A released key: let go of it (and of its other case: Shift may be let go first). A key
    /// that is not held (pressed in another place) changes nothing.
    fn release(&mut self, key: Key) {
        let mut any = self.held.release(key);
        if let KeyCode::Char(c) = key.code {
            for c in [c.to_ascii_lowercase(), c.to_ascii_uppercase()] {
                any |= self.held.release(Key {
                    code: KeyCode::Char(c),
                    ctrl: key.ctrl,
                });
            }
        }
        if any {
            self.control(false);
        }
    }

    /// A press or repeat: to the place on top, and only there. Keys are held (pressed and
    /// not yet released) only in driving, and only those bound to a held action there;
    /// everywhere else every press counts once and repeats are ignored for toggles. When the
    /// key changes the place on top, the droid or mirror mode, every held key is let go.
    fn on_key_event(&mut self, key: Key, kind: KeyKind) -> Option<ExitReason> {
        if key == Key::CTRL_C {
            return Some(ExitReason::Quit);
        }
        let before = (self.place(), self.chosen(), self.mirroring());
        let scope_key = before.0 == Place::Driving
            && self.state.droid().scope.visible
            && self.keymap.action_in(Context::Scope, &key).is_some();
        let held_action = before.0 == Place::Driving
            && !scope_key
            && self.keymap.action(&key).is_some_and(Action::is_held);
        let now = self.now();
        let new = match (held_action, kind) {
            // A repeat holds only a key pressed here (with reported releases, a key pressed in
            // another place keeps repeating after that place closed: it must not drive).
            (true, KeyKind::Repeat) => {
                self.held.repeat(key, now);
                false
            }
            (true, _) => self.held.press(key, now),
            (false, kind) => kind == KeyKind::Press,
        };
        // Forgetting asks first; any other key pressed meanwhile is a no.
        if kind == KeyKind::Press
            && !(before.0 == Place::Driving
                && self.keymap.action(&key) == Some(Action::ForgetSettings))
        {
            self.forget_asked = None;
        }
        let r = self.on_key(before.0, scope_key, key, new);
        if (self.place(), self.chosen(), self.mirroring()) != before {
            self.clear_held();
        }
        r
    }

    /// A key press (`new_press`) or repeat, to the place on top.
    fn on_key(
        &mut self,
        place: Place,
        scope_key: bool,
        key: Key,
        new_press: bool,
    ) -> Option<ExitReason> {
        // Ctrl+Space stops in every place: no place takes a Ctrl key as text, so it works in
        // the prompts too, where Space is typed.
        if key == Key::CTRL_SPACE {
            if new_press {
                self.estop();
            }
            return None;
        }
        // The emergency stop works over every overlay whose own table leaves its key free
        // (typing places take every printable key: there it is the Ctrl one above, or the
        // gamepad's).
        if place.lets_the_stop_through()
            && self
                .keymap
                .action_in(place.context(false, false), &key)
                .is_none()
            && self.keymap.action(&key) == Some(Action::EStop)
        {
            if new_press {
                self.estop();
            }
            return None;
        }
        match place {
            Place::Driving if scope_key => self.scope_key(key, new_press),
            Place::Log => return self.log_key(key, new_press),
            Place::Replay => return self.replay_key(key, new_press),
            Place::Driving => return self.drive_key(key, new_press),
            // Every other place is an open overlay's: the registry hands it the key.
            _ => {
                let (overlay, mut around) = self.overlay_around();
                let out = overlay.on_key(&mut around, key, new_press);
                self.carry_out(out);
            }
        }
        None
    }

    /// The open overlay, and what it reads beside its state ([`overlay::Around`]).
    pub(super) fn overlay_around(&mut self) -> (&mut Overlay, overlay::Around<'_>) {
        let s = &mut self.state;
        let d = &s.droids[s.chosen.min(s.droids.len() - 1)];
        let around = overlay::Around {
            keymap: &self.keymap,
            model: d.model,
            monitor: &d.monitor,
            animations: &s.animations,
            sounds: &s.sounds,
            help_page: &mut s.help_page,
            area: self.area,
        };
        (&mut s.overlay, around)
    }

    /// What an overlay's key or click asked for: close it, and do what reaches beyond it.
    pub(super) fn carry_out(&mut self, out: Outcome<Do>) {
        let todo = match out {
            Outcome::Stay => None,
            Outcome::Apply(d) => Some(d),
            Outcome::Close => {
                self.state.overlay = Overlay::None;
                None
            }
            Outcome::Done(d) => {
                self.state.overlay = Overlay::None;
                Some(d)
            }
        };
        match todo {
            None => {}
            Some(Do::Play { animation, index }) => {
                let list = if animation {
                    &self.state.animations
                } else {
                    &self.state.sounds
                };
                let chosen = self.chosen();
                if let (Some(e), Some(mut d)) = (list.get(index).cloned(), self.droid(chosen)) {
                    if animation {
                        d.play_animation(e.id, &e.name);
                    } else {
                        d.play_sound(e.id, &e.name);
                    }
                }
            }
            Some(Do::Filter(f)) => self.state.log.set_filter(f),
            Some(Do::ToggleChannel(c)) => self.state.droid_mut().scope.toggle(c),
            Some(Do::Tune(draft)) => {
                if let Some(mut d) = self.droid(self.chosen()) {
                    d.apply_tuning(draft);
                }
            }
            Some(Do::Matrix(shows)) => {
                self.state.droid_mut().matrix.shows = shows;
                self.draw_matrix();
            }
        }
    }

    fn open_help(&mut self) {
        self.state.help_page = 0;
        self.state.overlay = Overlay::Help;
    }

    /// The log's selected line, in full ([`overlay::packet`]).
    fn open_detail(&mut self) {
        let rows = self.log_rows();
        let Some(line) = self.state.log.selected(rows).cloned() else {
            return self.hint("no packet to show");
        };
        self.state.overlay = Overlay::Packet {
            line: Box::new(line),
            search: String::new(),
            typing: false,
            matched: 0,
            scroll: 0,
        };
    }

    /// The packet log has the keys: its own bindings first, then the drive table's quit,
    /// help, e-stop and log (back to driving).
    fn log_key(&mut self, key: Key, new_press: bool) -> Option<ExitReason> {
        let rows = self.log_rows();
        let log = &mut self.state.log;
        match self.keymap.action_in(Context::Log, &key) {
            Some(Action::LogUp) => log.cursor_up(rows),
            Some(Action::LogDown) => log.cursor_down(rows),
            Some(Action::LogPageUp) => log.scroll_up(rows.max(1)),
            Some(Action::LogPageDown) => log.scroll_down(rows.max(1)),
            Some(Action::LogTop) => log.cursor_top(rows),
            Some(Action::LogBottom) => log.cursor_bottom(),
            Some(Action::LogBack) => self.state.focus = Focus::Drive,
            // The toggles fire once per press.
            Some(_) if !new_press => {}
            Some(Action::LogPause) => log.toggle_pause(),
            Some(Action::LogDecoded) => log.decoded = !log.decoded,
            Some(Action::LogFilter) => {
                self.state.overlay = Overlay::Filter {
                    input: log.filter_input(),
                    before: Box::new(log.filter.clone()),
                }
            }
            Some(Action::LogClearFilter) => log.set_filter(Default::default()),
            Some(Action::LogOpen) => self.open_detail(),
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
        let Some(action) = self.keymap.action(&key) else {
            // Esc closes whatever is open; on the main screen there is nothing to close, and
            // one Esc too many must not end the session.
            if key == Key::plain(KeyCode::Esc) && new_press {
                let quit = self.keymap.shown(Action::Quit).unwrap_or_default();
                self.hint(format!("nothing to close — {quit} or Ctrl+c quits"));
            }
            return None;
        };
        if !new_press {
            return None;
        }
        match action {
            Action::Quit => return Some(ExitReason::Quit),
            Action::Help => self.open_help(),
            // The droid is held stopped while the log has the keys (the place changes: every
            // held key is let go).
            Action::Log => self.state.focus = Focus::Log,
            Action::EStop => self.estop(),
            Action::NextDroid => self.choose_next(true),
            Action::PreviousDroid => self.choose_next(false),
            Action::Mirror => self.toggle_mirror(),
            Action::Scope => self.toggle_scope(),
            Action::Tuning => self.open_tuning(),
            Action::ForgetSettings => self.ask_to_forget(),
            Action::Colour | Action::BackLight => {
                if let Some(mut d) = self.droid(self.chosen()) {
                    if action == Action::Colour {
                        d.cycle_colour();
                    } else {
                        d.toggle_back_light();
                    }
                }
            }
            Action::Animations | Action::Sounds => {
                let model = self.state.droid().model;
                // What the palette would play, asked of the droid's family as the play is.
                let can = |i: Intent| self.io[self.chosen()].family.lower(model, &i).is_ok();
                if action == Action::Animations && !can(Intent::Animation(0)) {
                    self.hint("this droid has no animations")
                } else if action == Action::Sounds && !can(Intent::Sound(0)) {
                    self.hint("this droid cannot play sounds")
                } else if action == Action::Animations {
                    self.state.overlay = Overlay::Animations { selected: 0 }
                } else {
                    self.state.overlay = Overlay::Sounds { selected: 0 }
                }
            }
            a if self.robot_action(a) => {}
            a => {
                self.press(a);
                if a.is_held() {
                    self.control(false);
                }
            }
        }
        None
    }
}
