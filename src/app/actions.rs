//! What reaches the droids: the driving input of the place on top turned into each droid's
//! control tick, the emergency stop to every droid, and the one-shot actions — lights,
//! animations, sounds — each said as an [`Intent`] and lowered by the droid's family (the
//! vocabulary missions, Edu programs, the bridge and fleets use too); a droid without the
//! capability gets a hint instead of a command. Nothing is sent in replay.

use super::core::App;
use super::droid::DroidMut;
use super::place::Place;
use super::view::matrix::MAIN_LED_CYCLE;
use crate::config::Action;
use crate::family::intent::Intent;
use crate::script::LedGroup;
use crate::teleop::control::Inputs;
use tokio::time::Instant;

impl DroidMut<'_> {
    /// The next colour of [`MAIN_LED_CYCLE`] on the main (R2: front) LED.
    pub fn cycle_colour(&mut self) {
        let next = match self.view.leds.main {
            Some(c) => MAIN_LED_CYCLE
                .iter()
                .position(|x| *x == c)
                .map_or(0, |i| (i + 1) % MAIN_LED_CYCLE.len()),
            None => 0,
        };
        let rgb = MAIN_LED_CYCLE[next];
        if self.act(&Intent::LedRgb(LedGroup::Front, rgb), "colour") {
            self.view.leds.main = Some(rgb);
        } else {
            self.hint("this droid has no main LED")
        }
    }

    pub fn toggle_back_light(&mut self) {
        let b = if self.view.leds.back.unwrap_or(0) > 0 {
            0
        } else {
            255
        };
        if self.act(&Intent::LedBrightness(LedGroup::Back, b), "back light") {
            self.view.leds.back = Some(b);
        } else {
            self.hint("this droid has no back light to switch (R2: use the colour key)")
        }
    }

    pub fn play_animation(&mut self, id: u16, name: &str) {
        let i = Intent::Animation(id);
        self.play(&i, "animation", id, name, "this droid has no animations");
    }

    pub fn play_sound(&mut self, id: u16, name: &str) {
        self.play(
            &Intent::Sound(id),
            "sound",
            id,
            name,
            "this droid cannot play sounds",
        );
    }

    /// Send an animation or sound and say which, or say the droid has none.
    fn play(&mut self, intent: &Intent, what: &str, id: u16, name: &str, none: &str) {
        if self.act(intent, what) {
            self.hint(format!("{what} {name} ({id})"));
        } else {
            self.hint(none)
        }
    }
}

impl App {
    /// The emergency stop: latched now (not at the next tick) and written to every droid at
    /// once, ahead of pacing — idle ones too: a droid the app believes idle may be coasting,
    /// pushed, or driven by something the app never saw.
    pub fn estop(&mut self) {
        self.trace.estops += 1;
        self.each(|d| d.estop());
    }

    /// The driving input for droid `i` right now, from held keys and the pad. Only the
    /// driving place drives, and only the droids the input goes to (the chosen one, or all
    /// mirrored); the e-stop held there, or on the pad, reaches every droid.
    fn inputs(&self, i: usize) -> Inputs {
        let mut inp = Inputs::default();
        if self.replaying() {
            return inp;
        }
        let pad_estop = self.pad.estop_held();
        let held_estop = self
            .held
            .keys()
            .any(|k| self.keymap.action(k) == Some(Action::EStop));
        inp.estop = pad_estop || held_estop;
        if self.place() != Place::Driving || !self.driven(i) {
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
                _ => {}
            }
        }
        inp.pad = self
            .pad
            .drive()
            .map(|d| (d, self.pad.speed(&d, self.turbo_speed)));
        inp.pad_dome_rate = self.pad.dome_rate();
        inp.pad_tracks = self.pad.tracks();
        inp
    }

    /// The fixed-rate control tick (`heartbeat`), or an immediate update after input
    /// changed: every droid's, each its own deadman, all measured from the same instant.
    pub fn control(&mut self, heartbeat: bool) {
        let now = Instant::now();
        for i in 0..self.len() {
            let inp = self.inputs(i);
            if let Some(mut d) = self.droid(i) {
                d.control(&inp, heartbeat, now);
            }
        }
    }

    /// A one-shot drive action pressed in driving: on the chosen droid, and on every droid
    /// in mirror mode (speed, turbo, stance and aim keys).
    pub fn press(&mut self, a: Action) {
        let chosen = self.chosen();
        for i in 0..self.len() {
            if (i == chosen || (self.mirroring() && !a.is_held()))
                && let Some(mut d) = self.droid(i)
            {
                d.press(a);
            }
        }
    }
}
