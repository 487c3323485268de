//! The event loop: one task owns the [`AppState`]; terminal input, gamepad events, session
//! notifications, the packet log, link-state changes and the control tick all arrive here over
//! bounded channels. Every outside input is a parameter, so tests drive it with fakes under
//! paused time and render into ratatui's `TestBackend`.

use super::input::{KeyKind, TermEvent};
use super::packet_log::{LogLine, PacketLog};
use super::replay::{Player, ReplayKey, replay_key};
use super::state::{
    AppState, Focus, GamepadStatus, HelpLine, KeyboardMode, MAIN_LED_CYCLE, Overlay,
};
use crate::capture::mirror::Output;
use crate::capture::replay::Replay;
use crate::config::Config;
use crate::family::{Command, Family};
use crate::model::Model;
use crate::protocol::notify::Notification;
use crate::protocol::wire::LegAction;
use crate::session::{LinkState, LogEntry, SessionEvent, SessionHandle, SessionStats, Slot};
use crate::teleop::control::{Controller, DroidView, Inputs, Out};
use crate::teleop::gamepad::{PadCommand, PadEvent, PadState};
use crate::teleop::held::{HeldKeys, ReleaseMode};
use crate::teleop::keymap::{Action, Key, KeyCode, KeyMap};
use ratatui::{Frame, Terminal, backend::Backend};
use std::path::PathBuf;
use std::time::Duration;
use tokio::sync::{broadcast, mpsc, watch};
use tokio::time::{Instant, MissedTickBehavior, interval, sleep_until};

/// How the app is set up.
pub struct AppOptions {
    pub config: Config,
    pub model: Model,
    pub droid_name: String,
    pub log_path: Option<PathBuf>,
    pub release: ReleaseMode,
    /// Whether the connect setup puts R2 into tripod.
    pub tripod_on_connect: bool,
}

/// Everything from outside the app.
pub struct AppInputs {
    pub term: mpsc::Receiver<TermEvent>,
    pub pad: mpsc::Receiver<PadEvent>,
    /// Signals (SIGTERM, SIGHUP, Ctrl-C from outside the terminal): the reason.
    pub quit: mpsc::Receiver<String>,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ExitReason {
    /// The operator quit.
    Quit,
    /// A signal.
    Signal(String),
    /// The terminal input ended.
    InputClosed,
}

/// How the loop ended, with the stop to send before restoring the terminal.
pub struct Exit {
    pub reason: ExitReason,
    pub state: AppState,
    /// Speed 0 at the last commanded heading.
    pub stop: Command,
}

pub type DrawFn = fn(&mut Frame, &AppState);

/// Where the app's droid comes from.
pub enum Source {
    /// A live session: the droid is driven.
    Live(SessionHandle),
    /// A capture played back: nothing is sent anywhere. The string names the file.
    Replay(Box<Replay>, String),
}

/// Frames are drawn only when something visible changed, at most this often while someone is
/// at the keys (or the droid is driven, or a replay plays)...
const RENDER_EVERY: Duration = Duration::from_millis(50);
/// ...and at most this often when nobody has touched anything for [`ACTIVE_FOR`]: an idle app
/// shows what the droid streams at a few frames per second.
const IDLE_RENDER_EVERY: Duration = Duration::from_millis(250);
const ACTIVE_FOR: Duration = Duration::from_secs(3);
const HINT_TIME: Duration = Duration::from_secs(4);
const BATTERY_EVERY: Duration = Duration::from_secs(10);

struct App {
    state: AppState,
    /// The live session; `None` in replay.
    session: Option<SessionHandle>,
    /// The capture played back, in replay.
    player: Option<Player>,
    controller: Controller,
    held: HeldKeys,
    pad: PadState,
    keymap: KeyMap,
    family: &'static dyn Family,
    turbo_speed: u8,
    start: Instant,
    last_tick: Instant,
    dirty: bool,
    /// Replay: what the last advance produced (kept to reuse its allocation).
    replayed: Vec<(Duration, Output)>,
    /// The operator touched something: frames come fast until then.
    active_until: Instant,
}

/// The help overlay's lines from the bindings as configured: keyboard, then gamepad.
pub fn help_lines(config: &Config, keymap: &KeyMap) -> (Vec<HelpLine>, Vec<HelpLine>) {
    let mut keys: Vec<HelpLine> = keymap
        .help()
        .into_iter()
        .map(|(k, a)| HelpLine {
            keys: k,
            action: a.to_string(),
        })
        .collect();
    keys.push(HelpLine {
        keys: "Ctrl+c".into(),
        action: "quit (stops the droid first)".into(),
    });
    for (k, a) in [
        ("↑ ↓ PgUp PgDn", "in the log: scroll"),
        ("p", "in the log: pause / resume"),
        ("d", "in the log: decoded / hex"),
        ("/", "in the log: filter (in|out dev:NAME text)"),
        ("c", "in the log: clear the filter"),
        ("↑ ↓ Enter Esc", "in a palette: choose, play, close"),
    ] {
        keys.push(HelpLine {
            keys: k.into(),
            action: a.into(),
        });
    }
    let g = &config.gamepad;
    let pad = vec![
        HelpLine {
            keys: "left stick".into(),
            action: "heading and speed (polar)".into(),
        },
        HelpLine {
            keys: "right stick X".into(),
            action: "turn the dome".into(),
        },
        HelpLine {
            keys: "right trigger".into(),
            action: "more speed, up to turbo".into(),
        },
        HelpLine {
            keys: g.tripod.clone(),
            action: "stance: tripod".into(),
        },
        HelpLine {
            keys: g.bipod.clone(),
            action: "stance: bipod".into(),
        },
        HelpLine {
            keys: g.aim.clone(),
            action: "aim mode on/off (rolling droids)".into(),
        },
        HelpLine {
            keys: g.estop.clone(),
            action: "EMERGENCY STOP (latched while held)".into(),
        },
        HelpLine {
            keys: g.animation.clone(),
            action: "play the selected animation".into(),
        },
        HelpLine {
            keys: g.help.clone(),
            action: "this help".into(),
        },
        HelpLine {
            keys: "D-pad".into(),
            action: format!(
                "sounds {} / {} / {} / {}",
                g.sound_up, g.sound_down, g.sound_left, g.sound_right
            ),
        },
    ];
    (keys, pad)
}

impl App {
    fn now(&self) -> Duration {
        Instant::now().duration_since(self.start)
    }

    fn droid_view(&self) -> DroidView {
        DroidView {
            connected: self.state.link == LinkState::Connected,
            has_legs: self.state.model.has_legs(),
            has_dome: self.state.model.has_dome(),
            can_aim: self.state.model.can_aim(),
            stance: self.state.telemetry.stance,
        }
    }

    fn hint(&mut self, text: impl Into<String>) {
        self.state.now = self.clock();
        self.state.show_hint(text, HINT_TIME);
        self.dirty = true;
    }

    fn apply(&mut self, outs: Vec<Out>) {
        for o in outs {
            match o {
                Out::Drive(c) => self.set(Slot::Drive, c),
                Out::Head(c) => self.set(Slot::Head, c),
                Out::Stance(a) => self.stance(a),
                Out::AimBegin => {
                    for c in self.family.aim_begin(self.state.model).unwrap_or_default() {
                        self.send(c, "aim");
                    }
                    self.state.leds.back = Some(255);
                }
                Out::AimEnd => {
                    for c in self.family.aim_end(self.state.model) {
                        self.send(c, "aim");
                    }
                    self.state.leds.back = Some(0);
                }
                Out::Hint(h) => self.hint(h),
            }
        }
        // Redraw only when what the screen shows of the control changed: an idle control
        // loop ticks without drawing.
        let view = self.controller.view();
        if *view != self.state.control {
            self.state.control = view.clone();
            self.dirty = true;
        }
    }

    /// Set a continuous control's latest value (nothing in replay).
    fn set(&self, slot: Slot, c: Command) {
        if let Some(s) = &self.session {
            s.set(slot, c);
        }
    }

    fn stance(&mut self, a: LegAction) {
        let Some(c) = self.family.stance(a) else {
            return self.hint("this droid has no legs");
        };
        let Some(session) = &self.session else {
            return;
        };
        match session.send(c) {
            Ok(()) => self.state.telemetry.stance_requested(a),
            Err(e) => self.hint(format!("stance not sent: {e}")),
        }
    }

    /// The next colour of [`MAIN_LED_CYCLE`] on the main (R2: front) LED.
    fn cycle_colour(&mut self) {
        let next = match self.state.leds.main {
            Some(c) => MAIN_LED_CYCLE
                .iter()
                .position(|x| *x == c)
                .map_or(0, |i| (i + 1) % MAIN_LED_CYCLE.len()),
            None => 0,
        };
        let rgb = MAIN_LED_CYCLE[next];
        let action = crate::script::Action::LedRgb(crate::script::LedGroup::Front, rgb);
        match self.family.led(self.state.model, &action) {
            Some(c) => {
                self.send(c, "colour");
                self.state.leds.main = Some(rgb);
            }
            None => self.hint("this droid has no main LED"),
        }
    }

    fn toggle_back_light(&mut self) {
        let b = if self.state.leds.back.unwrap_or(0) > 0 {
            0
        } else {
            255
        };
        let action = crate::script::Action::LedBrightness(crate::script::LedGroup::Back, b);
        match self.family.led(self.state.model, &action) {
            Some(c) => {
                self.send(c, "back light");
                self.state.leds.back = Some(b);
            }
            None => self.hint("this droid has no back light to switch (R2: use the colour key)"),
        }
    }

    fn play_animation(&mut self, id: u16, name: &str) {
        match self.family.animation(id) {
            Some(c) => {
                self.send(c, "animation");
                self.hint(format!("animation {name} ({id})"));
            }
            None => self.hint("this droid has no animations"),
        }
    }

    fn play_sound(&mut self, id: u16, name: &str) {
        match self.family.sound(id) {
            Some(c) => {
                self.send(c, "sound");
                self.hint(format!("sound {name} ({id})"));
            }
            None => self.hint("this droid cannot play sounds"),
        }
    }

    fn send(&mut self, c: Command, what: &str) {
        let Some(session) = &self.session else {
            return;
        };
        if let Err(e) = session.send(c) {
            self.hint(format!("{what} not sent: {e}"));
        }
    }

    /// The time telemetry and the screen run on: since the start live, capture time in
    /// replay (so the same capture always folds and draws the same).
    fn clock(&self) -> Duration {
        match &self.player {
            Some(p) => p.clock(Instant::now()),
            None => self.now(),
        }
    }

    /// A notification, from the session or the replay, received at `at`.
    fn on_notification(&mut self, n: &Notification, at: Duration) {
        self.state.telemetry.apply(n, at);
        self.dirty = true;
    }

    /// A packet-log entry, from the session or the replay.
    fn on_log(&mut self, entry: &LogEntry) {
        let line = LogLine::from_entry(entry);
        self.state.log.push(line);
        self.dirty = true;
    }

    /// What the replay produced, through the same paths as a live session's events.
    fn on_replayed(&mut self, outs: &mut Vec<(Duration, Output)>) {
        for (at, o) in outs.drain(..) {
            match o {
                Output::Log(entry) => self.on_log(&entry),
                Output::Notification(n) => self.on_notification(&n, at),
                Output::BadNotification { name, reason } => {
                    tracing::debug!(name, %reason, "malformed notification in the capture")
                }
                Output::Link(s) => self.on_link(s),
                Output::Battery(v) => {
                    self.state.telemetry.battery_v = Some(v);
                    self.dirty = true;
                }
                Output::StanceRequested(a) => self.state.telemetry.stance_requested(a),
                Output::StanceRead(s) => {
                    if self.state.telemetry.stance == crate::telemetry::Stance::Unknown {
                        self.state.telemetry.stance = crate::telemetry::Stance::from_state(s);
                    }
                }
                Output::Mark(_) => {}
            }
        }
        if let Some(p) = &self.player {
            let st = p.replay.mirror().stats();
            if st != self.state.stats {
                self.state.stats = st;
                self.dirty = true;
            }
        }
    }

    /// Replay: bring the capture up to the clock, and the status bar's position.
    fn replay_frame(&mut self) {
        let Some(p) = self.player.as_mut() else {
            return;
        };
        let mut outs = std::mem::take(&mut self.replayed);
        p.advance(Instant::now(), &mut outs);
        let view = p.view(Instant::now());
        self.on_replayed(&mut outs);
        self.replayed = outs;
        self.show_replay(view);
    }

    fn show_replay(&mut self, view: super::state::ReplayView) {
        // The position is shown to a tenth of a second: redraw when that changes.
        let shown = |v: &super::state::ReplayView| {
            (
                v.position.as_millis() / 100,
                v.paused,
                (v.speed * 100.0) as u64,
                v.events_done,
            )
        };
        if self.state.replay.as_ref().map(shown) != Some(shown(&view)) {
            self.dirty = true;
        }
        self.state.now = view.position;
        self.state.replay = Some(view);
    }

    /// A replay key.
    fn on_replay_key(&mut self, k: ReplayKey) {
        let now = Instant::now();
        let Some(p) = self.player.as_mut() else {
            return;
        };
        let mut outs = std::mem::take(&mut self.replayed);
        let mut restart = false;
        match k {
            ReplayKey::TogglePause => p.toggle_pause(now),
            ReplayKey::Faster => p.faster(now),
            ReplayKey::Slower => p.slower(now),
            ReplayKey::Step => p.step(now, &mut outs),
            ReplayKey::Forward(d) => restart = p.seek(p.clock(now) + d, now),
            ReplayKey::Back(d) => restart = p.seek(p.clock(now).saturating_sub(d), now),
            ReplayKey::Start => restart = p.seek(Duration::ZERO, now),
            ReplayKey::End => restart = p.seek(p.replay.duration(), now),
        }
        if restart {
            // Back in time: forget what the capture showed, then play it again up to there.
            p.replay_from_start();
            outs.clear();
            let log = &self.state.log;
            let mut fresh = PacketLog::with_capacity(log.capacity());
            fresh.decoded = log.decoded;
            fresh.filter = log.filter.clone();
            self.state.log = fresh;
            self.state.telemetry = Default::default();
            self.state.stats = SessionStats::default();
            self.state.link = LinkState::Connecting;
            self.state.rate_in = 0.0;
            self.state.rate_out = 0.0;
        }
        self.replayed = outs;
        self.replay_frame();
        self.dirty = true;
    }

    /// The driving input right now, from held keys and the pad. Nothing drives while the log
    /// has focus or an overlay is open.
    fn inputs(&self) -> Inputs {
        let mut inp = Inputs::default();
        if self.player.is_some() {
            // Nothing drives a replay.
            return inp;
        }
        let pad_estop = self.pad.estop_held();
        if self.state.focus != Focus::Drive || self.state.overlay != Overlay::None {
            inp.estop = pad_estop;
            return inp;
        }
        for k in self.held.keys() {
            match self.keymap.action(k) {
                Some(Action::Forward) => inp.forward = true,
                Some(Action::Backward) => inp.backward = true,
                Some(Action::Left) => inp.left = true,
                Some(Action::Right) => inp.right = true,
                Some(Action::DomeLeft) => inp.dome_left = true,
                Some(Action::DomeRight) => inp.dome_right = true,
                Some(Action::EStop) => inp.estop = true,
                _ => {}
            }
        }
        inp.estop |= pad_estop;
        inp.pad = self
            .pad
            .drive()
            .map(|d| (d, self.pad.speed(&d, self.turbo_speed)));
        inp.pad_dome_rate = self.pad.dome_rate();
        inp
    }

    /// The fixed-rate control tick (`heartbeat`), or an immediate update after input stopped.
    fn control(&mut self, heartbeat: bool) {
        let now = Instant::now();
        let dt = if heartbeat {
            now.duration_since(self.last_tick)
        } else {
            Duration::ZERO
        };
        if heartbeat {
            self.last_tick = now;
        }
        let inp = self.inputs();
        let view = self.droid_view();
        let outs = self.controller.tick(&inp, dt, &view, heartbeat);
        self.apply(outs);
    }

    /// Returns an exit reason when the app should stop.
    fn on_term(&mut self, e: TermEvent) -> Option<ExitReason> {
        self.active_until = Instant::now() + ACTIVE_FOR;
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
                    self.held.release(Key {
                        code: KeyCode::Char(c.to_ascii_lowercase()),
                        ctrl: key.ctrl,
                    });
                    self.held.release(Key {
                        code: KeyCode::Char(c.to_ascii_uppercase()),
                        ctrl: key.ctrl,
                    });
                }
                self.control(false);
            }
            TermEvent::Key { key, kind } => {
                if key
                    == (Key {
                        code: KeyCode::Char('c'),
                        ctrl: true,
                    })
                {
                    return Some(ExitReason::Quit);
                }
                // Only keys bound to held actions (drive, turn, dome, e-stop) track press and
                // release; for the others every press counts, so tapping `?` twice quickly
                // opens and closes help even when releases are only inferred.
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

    fn on_key(&mut self, key: Key, new_press: bool) -> Option<ExitReason> {
        // Overlays take the keys first.
        if let Overlay::Animations { selected } | Overlay::Sounds { selected } = self.state.overlay
        {
            let animations = matches!(self.state.overlay, Overlay::Animations { .. });
            let len = if animations {
                self.state.animations.len()
            } else {
                self.state.sounds.len()
            };
            let mut sel = selected;
            match key.code {
                KeyCode::Up => sel = sel.saturating_sub(1),
                KeyCode::Down => sel = (sel + 1).min(len.saturating_sub(1)),
                KeyCode::PageUp => sel = sel.saturating_sub(10),
                KeyCode::PageDown => sel = (sel + 10).min(len.saturating_sub(1)),
                KeyCode::Esc => {
                    self.state.overlay = Overlay::None;
                    return None;
                }
                KeyCode::Enter if new_press => {
                    if animations {
                        if let Some(e) = self.state.animations.get(sel).cloned() {
                            self.play_animation(e.id, &e.name);
                        }
                    } else if let Some(e) = self.state.sounds.get(sel).cloned() {
                        self.play_sound(e.id, &e.name);
                    }
                    self.state.overlay = Overlay::None;
                    return None;
                }
                _ => {}
            }
            self.state.overlay = if animations {
                Overlay::Animations { selected: sel }
            } else {
                Overlay::Sounds { selected: sel }
            };
            return None;
        }
        match &mut self.state.overlay {
            Overlay::Help => {
                match key.code {
                    // At 80×24 the bindings take two pages.
                    KeyCode::PageDown | KeyCode::Down | KeyCode::Right => self.state.help_page += 1,
                    KeyCode::PageUp | KeyCode::Up | KeyCode::Left => {
                        self.state.help_page = self.state.help_page.saturating_sub(1)
                    }
                    _ if new_press => self.state.overlay = Overlay::None,
                    _ => {}
                }
                return None;
            }
            Overlay::Filter { input } => {
                match key.code {
                    KeyCode::Esc => self.state.overlay = Overlay::None,
                    KeyCode::Enter => {
                        let f = super::packet_log::LogFilter::parse(input);
                        self.state.log.set_filter(f);
                        self.state.overlay = Overlay::None;
                    }
                    KeyCode::Backspace => {
                        input.pop();
                    }
                    KeyCode::Char(c) if input.len() < 80 => input.push(c),
                    KeyCode::Space if input.len() < 80 => input.push(' '),
                    _ => {}
                }
                return None;
            }
            Overlay::Animations { .. } | Overlay::Sounds { .. } => {}
            Overlay::None => {}
        }
        if self.state.focus == Focus::Log {
            let log = &mut self.state.log;
            match key.code {
                KeyCode::Up => log.scroll_up(1),
                KeyCode::Down => log.scroll_down(1),
                KeyCode::PageUp => log.scroll_up(10),
                KeyCode::PageDown => log.scroll_down(10),
                KeyCode::Home => log.scroll_up(usize::MAX / 2),
                KeyCode::End => log.scroll_down(usize::MAX / 2),
                KeyCode::Char('p') if new_press => log.toggle_pause(),
                KeyCode::Char('d') if new_press => log.decoded = !log.decoded,
                KeyCode::Char('/') | KeyCode::Char('f') if new_press => {
                    self.state.overlay = Overlay::Filter {
                        input: log.filter_input(),
                    }
                }
                KeyCode::Char('c') if new_press => log.set_filter(Default::default()),
                KeyCode::Esc => self.state.focus = Focus::Drive,
                _ => match self.keymap.action(&key) {
                    Some(Action::Log) if new_press => self.state.focus = Focus::Drive,
                    Some(Action::Quit) if new_press && key.code != KeyCode::Esc => {
                        return Some(ExitReason::Quit);
                    }
                    Some(Action::EStop) => {
                        let o = self.controller.estop_now();
                        self.apply(vec![o]);
                    }
                    Some(Action::Help) if new_press => {
                        self.state.help_page = 0;
                        self.state.overlay = Overlay::Help;
                    }
                    _ => {}
                },
            }
            return None;
        }
        if self.player.is_some() {
            // Replay: the quit, help and log keys as configured, then the replay keys;
            // nothing drives.
            if !new_press {
                return None;
            }
            match self.keymap.action(&key) {
                Some(Action::Quit) => return Some(ExitReason::Quit),
                Some(Action::Help) => {
                    self.state.help_page = 0;
                    self.state.overlay = Overlay::Help;
                }
                Some(Action::Log) => self.state.focus = Focus::Log,
                _ => {
                    if let Some(k) = replay_key(&key) {
                        self.on_replay_key(k);
                    }
                }
            }
            return None;
        }
        let action = self.keymap.action(&key)?;
        if !new_press {
            return None;
        }
        match action {
            Action::Quit => return Some(ExitReason::Quit),
            Action::Help => {
                self.state.help_page = 0;
                self.state.overlay = Overlay::Help;
            }
            Action::Log => {
                self.state.focus = Focus::Log;
                // The droid is held stopped while the log has the keys.
                self.held.release_all();
                self.control(false);
            }
            Action::Colour => self.cycle_colour(),
            Action::BackLight => self.toggle_back_light(),
            Action::Animations if self.family.animation(0).is_none() => {
                self.hint("this droid has no animations")
            }
            Action::Sounds if self.family.sound(0).is_none() => {
                self.hint("this droid cannot play sounds")
            }
            Action::Animations => self.state.overlay = Overlay::Animations { selected: 0 },
            Action::Sounds => self.state.overlay = Overlay::Sounds { selected: 0 },
            a => {
                let view = self.droid_view();
                let outs = self.controller.on_press(a, &view);
                self.apply(outs);
                if a.is_held() {
                    self.control(false);
                }
            }
        }
        None
    }

    fn on_pad(&mut self, e: PadEvent) {
        if self.player.is_some() {
            return;
        }
        self.active_until = Instant::now() + ACTIVE_FOR;
        match &e {
            PadEvent::Unavailable(why) => {
                self.state.gamepad = GamepadStatus::Unavailable(why.clone())
            }
            PadEvent::Connected(name) => {
                self.state.gamepad = GamepadStatus::Connected(name.clone())
            }
            PadEvent::Disconnected => {
                self.state.gamepad = GamepadStatus::NoPad;
                self.hint("gamepad unplugged — stopped");
            }
            _ => {}
        }
        let command = self.pad.apply(&e);
        let view = self.droid_view();
        match command {
            Some(PadCommand::Tripod) => {
                let o = self.controller.on_press(Action::Tripod, &view);
                self.apply(o);
            }
            Some(PadCommand::Bipod) => {
                let o = self.controller.on_press(Action::Bipod, &view);
                self.apply(o);
            }
            Some(PadCommand::Aim) => {
                let o = self.controller.on_press(Action::Aim, &view);
                self.apply(o);
            }
            Some(PadCommand::EStop) => {
                let o = self.controller.estop_now();
                self.apply(vec![o]);
            }
            Some(PadCommand::Help) => {
                self.state.overlay = if self.state.overlay == Overlay::Help {
                    Overlay::None
                } else {
                    Overlay::Help
                };
            }
            Some(PadCommand::Animation) => {
                let sel = match self.state.overlay {
                    Overlay::Animations { selected } => selected,
                    _ => 0,
                };
                if let Some(a) = self.state.animations.get(sel).cloned() {
                    self.play_animation(a.id, &a.name);
                }
            }
            Some(PadCommand::Sound(id)) => self.play_sound(id, "from the D-pad"),
            None => {}
        }
        // Stick back in its deadzone or pad unplugged: stop at once.
        if matches!(e, PadEvent::Disconnected | PadEvent::Axis(..)) {
            self.control(false);
        }
        self.dirty = true;
    }

    fn on_link(&mut self, s: LinkState) {
        if s != LinkState::Connected {
            self.controller.link_lost();
        } else if self.state.link != LinkState::Connected {
            // The connect setup asks for tripod.
            if self.state.model.has_legs() {
                self.state.telemetry.stance_requested(LegAction::Tripod);
            }
        }
        self.state.link = s;
        self.control(false);
        self.dirty = true;
    }
}

/// Run the app until the operator quits, a signal arrives, or input ends.
pub async fn run<B: Backend>(
    terminal: &mut Terminal<B>,
    session: SessionHandle,
    opts: AppOptions,
    inputs: AppInputs,
    draw: DrawFn,
) -> std::io::Result<Exit> {
    run_source(terminal, Source::Live(session), opts, inputs, draw).await
}

/// Run the app on a live session or a replay (the status bar says REPLAY; nothing is sent).
pub async fn run_source<B: Backend>(
    terminal: &mut Terminal<B>,
    source: Source,
    opts: AppOptions,
    mut inputs: AppInputs,
    draw: DrawFn,
) -> std::io::Result<Exit> {
    let keymap = KeyMap::from_config(&opts.config.keys).map_err(|(k, m)| {
        std::io::Error::new(std::io::ErrorKind::InvalidInput, format!("keys.{k}: {m}"))
    })?;
    let mut state = AppState::new(opts.model, opts.droid_name.clone());
    let (help_keys, help_gamepad) = help_lines(&opts.config, &keymap);
    state.help_keys = help_keys;
    state.help_gamepad = help_gamepad;
    state.log_path = opts.log_path.clone();
    state.keyboard = match opts.release {
        ReleaseMode::Reported => KeyboardMode::ReleaseEvents,
        ReleaseMode::Emulated { .. } => KeyboardMode::Emulated,
    };
    state.gamepad = if opts.config.gamepad.enabled {
        GamepadStatus::NoPad
    } else {
        GamepadStatus::Disabled
    };
    let _ = opts.tripod_on_connect;
    let start = Instant::now();
    let family = crate::family::for_model(opts.model);
    let (session, player) = match source {
        Source::Live(s) => (Some(s), None),
        Source::Replay(r, file) => {
            let quit = keymap.keys(Action::Quit).first().map(|k| k.to_string());
            let help = keymap.keys(Action::Help).first().map(|k| k.to_string());
            let log = keymap.keys(Action::Log).first().map(|k| k.to_string());
            state.help_gamepad = Vec::new();
            state.help_keys = super::replay::help_lines(
                quit.as_deref().unwrap_or("q"),
                help.as_deref().unwrap_or("?"),
                log.as_deref().unwrap_or("l"),
            );
            (None, Some(Player::new(*r, file, start)))
        }
    };
    let mut app = App {
        state,
        session: session.clone(),
        player,
        replayed: Vec::new(),
        active_until: start + ACTIVE_FOR,
        controller: Controller::with_family(opts.config.control.clone(), family),
        held: HeldKeys::new(opts.release),
        pad: PadState::new(opts.config.gamepad.clone()),
        keymap,
        family,
        turbo_speed: opts.config.control.turbo_speed,
        start,
        last_tick: start,
        dirty: true,
    };
    app.state.control = app.controller.view().clone();

    // A replay has no session: its channels are closed from the start.
    let (mut log_rx, mut events_rx, mut link_rx) = match &session {
        Some(s) => (s.subscribe_log(), s.subscribe(), s.watch_state()),
        None => (
            broadcast::channel(1).1,
            broadcast::channel(1).1,
            watch::channel(LinkState::Connecting).1,
        ),
    };
    // What the droid announced before we listened (Robi's handshake).
    for n in session.iter().flat_map(SessionHandle::greeting) {
        app.state.telemetry.apply(&n, Duration::ZERO);
    }
    let period = Duration::from_secs_f64(1.0 / opts.config.control.rate_hz.clamp(1, 50) as f64);
    let mut tick = interval(period);
    tick.set_missed_tick_behavior(MissedTickBehavior::Delay);
    // When the last frame was drawn.
    let mut last_frame = Instant::now()
        .checked_sub(IDLE_RENDER_EVERY)
        .unwrap_or_else(Instant::now);
    let mut second = interval(Duration::from_secs(1));
    second.set_missed_tick_behavior(MissedTickBehavior::Skip);
    let (battery_tx, mut battery_rx) = mpsc::channel::<f32>(4);
    let poller = {
        let session = session.clone();
        tokio::spawn(async move {
            let Some(session) = session else {
                return;
            };
            let Some(battery) = family.battery_request() else {
                return;
            };
            loop {
                let reading = match session.request(battery.clone()).await {
                    Ok(p) => family.battery_volts(p.data()),
                    Err(_) => None,
                };
                if let Some(v) = reading
                    && battery_tx.send(v).await.is_err()
                {
                    return;
                }
                tokio::time::sleep(BATTERY_EVERY).await;
            }
        })
    };
    let stats = |app: &App| match &app.session {
        Some(s) => s.stats(),
        None => app.state.stats,
    };
    let mut prev = stats(&app);
    let mut prev_at = Instant::now();
    let mut prev_clock = app.clock();
    let mut pad_open = true;
    // Closed channels would fire their select branch forever: disable them instead.
    let live = app.session.is_some();
    let (mut events_open, mut log_open, mut link_open, mut battery_open) = (live, live, live, true);

    // Test hook for the crash path (stop first, then restore the terminal): panic after this
    // many ms. Only read from the environment, never set by droidctl itself.
    let crash_at = std::env::var("DROIDCTL_TEST_PANIC_AFTER_MS")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
        .map(|ms| start + Duration::from_millis(ms));
    let reason = loop {
        let expiry = app.held.next_expiry().map(|d| start + d);
        // Something on screen ends by itself (a hint, the collision flash): redraw then. In
        // replay the screen's clock is capture time, which moves only while playing.
        let change = app.state.next_change().and_then(|t| match &app.player {
            None => Some(start + t),
            Some(p) if p.running() => {
                let ahead = t.saturating_sub(app.state.now).div_f64(p.speed());
                Some(Instant::now() + ahead)
            }
            Some(_) => None,
        });
        let playing = app.player.as_ref().is_some_and(Player::running);
        let active = playing || !app.state.control.deadman || Instant::now() < app.active_until;
        let frame_at = last_frame
            + if active {
                RENDER_EVERY
            } else {
                IDLE_RENDER_EVERY
            };
        tokio::select! {
            e = inputs.term.recv() => match e {
                Some(e) => {
                    if let Some(r) = app.on_term(e) {
                        break r;
                    }
                }
                None => break ExitReason::InputClosed,
            },
            e = inputs.pad.recv(), if pad_open => match e {
                Some(e) => app.on_pad(e),
                None => pad_open = false,
            },
            q = inputs.quit.recv() => {
                break ExitReason::Signal(q.unwrap_or_else(|| "quit".into()));
            }
            _ = sleep_until(expiry.unwrap_or_else(Instant::now)), if expiry.is_some() => {
                // Emulated release: the repeats stopped.
                let now = app.now();
                if !app.held.expire(now).is_empty() {
                    app.control(false);
                }
            }
            _ = tick.tick() => {
                app.control(true);
                if crash_at.is_some_and(|t| Instant::now() >= t) {
                    panic!("test panic requested by DROIDCTL_TEST_PANIC_AFTER_MS");
                }
            }
            e = events_rx.recv(), if events_open => match e {
                Ok(SessionEvent::Notification(n)) => {
                    let at = app.now();
                    app.on_notification(&n, at);
                }
                Ok(SessionEvent::BadNotification { name, reason }) => {
                    tracing::warn!(name, %reason, "malformed notification");
                }
                Err(broadcast::error::RecvError::Lagged(n)) => tracing::warn!(n, "notifications lagged"),
                Err(broadcast::error::RecvError::Closed) => events_open = false,
            },
            e = log_rx.recv(), if log_open => match e {
                Ok(entry) => app.on_log(&entry),
                Err(broadcast::error::RecvError::Lagged(n)) => app.state.log.dropped += n,
                Err(broadcast::error::RecvError::Closed) => log_open = false,
            },
            r = link_rx.changed(), if link_open => {
                if r.is_ok() {
                    let s = link_rx.borrow_and_update().clone();
                    app.on_link(s);
                } else {
                    link_open = false;
                    app.on_link(LinkState::Closed { reason: Some("the session ended".into()) });
                }
            }
            v = battery_rx.recv(), if battery_open => match v {
                Some(v) => {
                    app.state.telemetry.battery_v = Some(v);
                    app.dirty = true;
                }
                None => battery_open = false,
            },
            _ = second.tick() => {
                let st = stats(&app);
                // Rates per second of the session's time: capture time in replay.
                let secs = match &app.player {
                    Some(_) => app.clock().saturating_sub(prev_clock).as_secs_f32(),
                    None => prev_at.elapsed().as_secs_f32().max(1e-3),
                };
                if secs > 0.0 || st.received < prev.received {
                    let rate_in = st.received.saturating_sub(prev.received) as f32 / secs.max(1e-3);
                    let rate_out = st.sent.saturating_sub(prev.sent) as f32 / secs.max(1e-3);
                    if (rate_in, rate_out) != (app.state.rate_in, app.state.rate_out) {
                        app.state.rate_in = rate_in;
                        app.state.rate_out = rate_out;
                        app.dirty = true;
                    }
                    prev = st;
                    prev_at = Instant::now();
                    prev_clock = app.clock();
                }
                if st != app.state.stats {
                    app.state.stats = st;
                    app.dirty = true;
                }
            }
            _ = sleep_until(change.unwrap_or_else(Instant::now)), if change.is_some() && !app.dirty => {
                app.dirty = true;
            }
            _ = sleep_until(frame_at), if app.dirty || playing => {
                last_frame = Instant::now();
                app.replay_frame();
                if app.dirty {
                    app.state.now = app.clock();
                    app.state.stats = stats(&app);
                    terminal
                        .draw(|f| draw(f, &app.state))
                        .map_err(|e| std::io::Error::other(e.to_string()))?;
                    app.dirty = false;
                }
            }
        }
    };
    poller.abort();
    let stop = family.drive(0, app.controller.view().heading, false);
    // The operator sees the droid stopped even before the session writes it.
    app.set(Slot::Drive, stop.clone());
    Ok(Exit {
        reason,
        state: app.state,
        stop,
    })
}

/// The commands to send on exit after the session's stop at its last heading: the app's own
/// stop (its heading, which the operator saw), and sleep when configured (and the family
/// can).
pub fn exit_commands(
    model: Model,
    exit_stop: impl IntoIterator<Item = Command>,
    sleep_on_exit: bool,
) -> Vec<Command> {
    let mut v: Vec<Command> = exit_stop.into_iter().collect();
    if sleep_on_exit && let Some(sleep) = crate::family::for_model(model).sleep() {
        v.push(sleep);
    }
    v
}
