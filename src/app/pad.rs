//! Gamepad events: status for the status bar, sticks folded into the pad state (read by the
//! control loop), buttons to their configured actions. An unplugged pad or a stick back in its
//! deadzone stops the droid at once, not at the next tick.

use super::core::App;
use super::state::{GamepadStatus, Overlay};
use crate::config::{Action, PadAction};
use crate::teleop::gamepad::{PadCommand, PadEvent};

impl App {
    pub fn on_pad(&mut self, e: PadEvent) {
        if self.player.is_some() {
            return;
        }
        self.touched();
        match &e {
            PadEvent::Unavailable(why) => {
                // Said in full once (the pad field truncates it); the keyboard drives as ever.
                self.hint(why.clone());
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
        match self.pad.apply(&e) {
            Some(PadCommand::Action(a)) => self.on_pad_action(a),
            Some(PadCommand::Sound(id)) => self.play_sound(id, "from the D-pad"),
            None => {}
        }
        // Stick back in its deadzone or pad unplugged: stop at once.
        if matches!(e, PadEvent::Disconnected | PadEvent::Axis(..)) {
            self.control(false);
        }
        self.dirty = true;
    }

    fn on_pad_action(&mut self, a: PadAction) {
        // The stance and aim buttons do what their keys do.
        let key_action = match a {
            PadAction::Tripod => Some(Action::Tripod),
            PadAction::Bipod => Some(Action::Bipod),
            PadAction::Aim => Some(Action::Aim),
            _ => None,
        };
        if let Some(action) = key_action {
            let view = self.droid_view();
            let outs = self.controller.on_press(action, &view);
            return self.apply(outs);
        }
        match a {
            PadAction::Tripod | PadAction::Bipod | PadAction::Aim => {}
            PadAction::EStop => self.estop(),
            PadAction::Help => {
                self.state.overlay = if self.state.overlay == Overlay::Help {
                    Overlay::None
                } else {
                    Overlay::Help
                };
            }
            PadAction::Animation => {
                let sel = match self.state.overlay {
                    Overlay::Animations { selected } => selected,
                    _ => 0,
                };
                if let Some(a) = self.state.animations.get(sel).cloned() {
                    self.play_animation(a.id, &a.name);
                }
            }
        }
    }
}
