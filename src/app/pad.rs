//! Gamepad events: status for the status bar, sticks folded into the pad state (read by the
//! control loop), buttons to their configured actions. An unplugged pad or a stick back in its
//! deadzone stops the droid at once, not at the next tick.

use super::core::App;
use super::place::Place;
use super::state::{GamepadStatus, Overlay};
use crate::config::{Action, PadAction};
use crate::teleop::gamepad::{PadCommand, PadEvent};

impl App {
    pub fn on_pad(&mut self, e: PadEvent) {
        if self.replaying() {
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
        let before = self.place();
        match self.pad.apply(&e) {
            Some(PadCommand::Action(a)) => self.on_pad_action(a),
            Some(PadCommand::Sound(id)) => {
                if let Some(mut d) = self.droid(self.chosen()) {
                    d.play_sound(id, "from the D-pad");
                }
            }
            None => {}
        }
        // The help button opens or closes a place: held keys are let go, as for a key.
        if self.place() != before {
            self.clear_held();
        }
        // Stick back in its deadzone, pad unplugged, or a pad plugged in (its sticks at
        // rest): stop at once.
        if matches!(
            e,
            PadEvent::Disconnected | PadEvent::Connected(_) | PadEvent::Axis(..)
        ) {
            self.control(false);
        }
        self.dirty = true;
        self.traced();
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
            // As their keys: only where the keyboard drives. Over help, a palette, the log or
            // a prompt, the pad's stance and aim buttons do nothing (R2 would change stance
            // behind the help page); the stop and help buttons work everywhere.
            if self.place() == Place::Driving {
                self.press(action);
            }
            return;
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
                let chosen = self.chosen();
                if let (Some(a), Some(mut d)) =
                    (self.state.animations.get(sel).cloned(), self.droid(chosen))
                {
                    d.play_animation(a.id, &a.name);
                }
            }
        }
    }
}
