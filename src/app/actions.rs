//! What reaches the droid: the control loop's outputs (drive and dome through the session's
//! latest-wins slots, stance and aim as commands), and the one-shot actions — lights,
//! animations, sounds. Each is built by the droid's family; a family without the capability
//! gets a hint instead of a command. Nothing is sent in replay.

use super::core::App;
use super::state::{Focus, MAIN_LED_CYCLE, Overlay};
use crate::config::Action;
use crate::family::Command;
use crate::protocol::wire::LegAction;
use crate::script::{Action as ScriptAction, LedGroup};
use crate::session::Slot;
use crate::teleop::control::{Inputs, Out};
use std::time::Duration;
use tokio::time::Instant;

impl App {
    /// Carry out the control loop's outputs.
    pub fn apply(&mut self, outs: Vec<Out>) {
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
        // loop ticks without drawing. In replay the screen shows the capture's commands
        // instead (`super::replay`).
        let view = self.controller.view();
        if self.player.is_none() && *view != self.state.control {
            self.state.control = view.clone();
            self.dirty = true;
        }
    }

    /// Set a continuous control's latest value (nothing in replay).
    pub fn set(&self, slot: Slot, c: Command) {
        if let Some(s) = &self.session {
            s.set(slot, c);
        }
    }

    /// Send a one-shot command; a failure is a hint naming `what`.
    pub fn send(&mut self, c: Command, what: &str) {
        let Some(session) = &self.session else {
            return;
        };
        if let Err(e) = session.send(c) {
            self.hint(format!("{what} not sent: {e}"));
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
    pub fn cycle_colour(&mut self) {
        let next = match self.state.leds.main {
            Some(c) => MAIN_LED_CYCLE
                .iter()
                .position(|x| *x == c)
                .map_or(0, |i| (i + 1) % MAIN_LED_CYCLE.len()),
            None => 0,
        };
        let rgb = MAIN_LED_CYCLE[next];
        let action = ScriptAction::LedRgb(LedGroup::Front, rgb);
        match self.family.led(self.state.model, &action) {
            Some(c) => {
                self.send(c, "colour");
                self.state.leds.main = Some(rgb);
            }
            None => self.hint("this droid has no main LED"),
        }
    }

    pub fn toggle_back_light(&mut self) {
        let b = if self.state.leds.back.unwrap_or(0) > 0 {
            0
        } else {
            255
        };
        let action = ScriptAction::LedBrightness(LedGroup::Back, b);
        match self.family.led(self.state.model, &action) {
            Some(c) => {
                self.send(c, "back light");
                self.state.leds.back = Some(b);
            }
            None => self.hint("this droid has no back light to switch (R2: use the colour key)"),
        }
    }

    pub fn play_animation(&mut self, id: u16, name: &str) {
        let c = self.family.animation(self.state.model, id);
        self.play(c, "animation", id, name, "this droid has no animations");
    }

    pub fn play_sound(&mut self, id: u16, name: &str) {
        let c = self.family.sound(self.state.model, id);
        self.play(c, "sound", id, name, "this droid cannot play sounds");
    }

    /// Send an animation or sound and say which, or say the droid has none.
    fn play(&mut self, c: Option<Command>, what: &str, id: u16, name: &str, none: &str) {
        match c {
            Some(c) => {
                self.send(c, what);
                self.hint(format!("{what} {name} ({id})"));
            }
            None => self.hint(none),
        }
    }

    /// The emergency stop: latched now (not at the next tick) and written to every droid at
    /// once, ahead of pacing — idle ones too: a droid the app believes idle may be coasting,
    /// pushed, or driven by something the app never saw.
    pub fn estop(&mut self) {
        self.trace.estops += 1;
        self.estop_one();
        self.each_other(App::estop_one);
    }

    fn estop_one(&mut self) {
        let Out::Drive(stop) = self.controller.estop_now() else {
            return;
        };
        if let Some(s) = &self.session {
            s.emergency_stop(stop);
        }
        self.apply(Vec::new());
    }

    /// The driving input right now, from held keys and the pad. Nothing drives while the log
    /// has focus or an overlay is open, nor in replay.
    fn inputs(&self) -> Inputs {
        let mut inp = Inputs::default();
        if self.player.is_some() {
            return inp;
        }
        let pad_estop = self.pad.estop_held();
        if self.state.focus != Focus::Drive || self.state.overlay != Overlay::None {
            inp.estop = pad_estop;
            return inp;
        }
        if !self.driven {
            // A parked droid outside mirror mode: only the e-stop reaches it.
            inp.estop = pad_estop
                || self
                    .held
                    .keys()
                    .any(|k| self.keymap.action(k) == Some(Action::EStop));
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
        inp.pad_tracks = self.pad.tracks();
        inp
    }

    /// The fixed-rate control tick (`heartbeat`), or an immediate update after input stopped:
    /// the driven droid's, then every other droid's of a fleet (each its own deadman).
    pub fn control(&mut self, heartbeat: bool) {
        // Every droid's tick measures from the same last tick.
        let last = self.last_tick;
        self.control_one(heartbeat);
        if self.fleet.is_some() {
            let now = self.last_tick;
            self.each_other(|a| {
                a.last_tick = last;
                a.control_one(heartbeat);
                a.last_tick = now;
            });
        }
    }

    fn control_one(&mut self, heartbeat: bool) {
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
}
