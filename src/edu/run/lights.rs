//! A program's lights and infrared: each light's newest state replaces its unwritten older one
//! (a light loop never floods the queue and always ends on its last colour, issue 38 point 4).

use super::super::api::{Act, Ir, RvrLight};
use super::Player;
use crate::family::intent::Intent;
use crate::script::LedGroup;
use std::time::Duration;
use tokio::time::Instant;

/// RVR's lights' keys start here (each light's bits: its own key, beside the others').
const RVR_KEYS: u64 = 100;

/// Lights held back while a stop is due within a pacing slot ([`Player::light`]): one state
/// per light, so at most a few, and since when the first of them waits.
#[derive(Debug, Default)]
pub(super) struct Held {
    /// (line, light, state).
    lights: Vec<(u32, u64, Intent)>,
    since: Option<Instant>,
}

impl Held {
    /// Hold `intent` for light `key` at `now`, in place of that light's older held state.
    fn hold(&mut self, line: u32, key: u64, intent: Intent, now: Instant) {
        self.lights.retain(|h| h.1 != key);
        self.lights.push((line, key, intent));
        self.since.get_or_insert(now);
    }

    fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    /// When the held lights go at the latest: one pacing slot after the first was held, by
    /// when the stop they wait for has gone. Without it a program that then waits only on
    /// an event, with no timer pending, kept them held until the next call, for good maybe.
    pub(super) fn due_by(&self, pacing: Duration) -> Option<Instant> {
        self.since.map(|t| t + pacing)
    }

    /// Whether the held lights are past [`Self::due_by`] at `now`.
    fn overdue(&self, now: Instant, pacing: Duration) -> bool {
        self.due_by(pacing).is_some_and(|by| now >= by)
    }

    /// The held lights, in the order held; none held after.
    fn take(&mut self) -> Vec<(u32, u64, Intent)> {
        self.since = None;
        std::mem::take(&mut self.lights)
    }
}

impl Player {
    /// A light's state: each light (and brightness) has its own key, so a newer state of one
    /// light replaces its unwritten older one and no other light's.
    pub(super) async fn light(&mut self, line: u32, a: &Act) {
        let (key, intent) = match a {
            Act::Main(rgb) => (1, Intent::MainLight(*rgb)),
            Act::Front(rgb) => (2, Intent::LedRgb(LedGroup::Front, *rgb)),
            Act::Back(rgb) => (3, Intent::LedRgb(LedGroup::Back, *rgb)),
            Act::BackBrightness(b) => (4, Intent::LedBrightness(LedGroup::Back, *b)),
            Act::Holo(b) => (5, Intent::LedBrightness(LedGroup::Holo, *b)),
            Act::Logic(b) => (6, Intent::LedBrightness(LedGroup::Logic, *b)),
            // BB-9E's dome light, 0..15 scaled to 0..255 as spherov2 does.
            Act::DomeLeds(b) => (
                5,
                Intent::LedBrightness(LedGroup::Holo, (*b as u16 * 255 / 15) as u8),
            ),
            _ => return,
        };
        if self.stop_due_within_a_slot() {
            self.held.hold(line, key, intent, Instant::now());
            return;
        }
        self.release_lights(false).await;
        self.intend_as(line, intent, "light", Some(key)).await;
    }

    /// Whether a `roll`'s or `rawMotor`'s stop is due before a light written now would free
    /// the link: the stop would then leave a pacing slot late and the robot roll on (Mini's
    /// 120 ms slot: 10 cm, `unawaited.js` in tests/it/edu_twins.rs). spherov2 never meets
    /// this by design, only by its threads' timing; a light held one slot is not seen late,
    /// a stop is.
    fn stop_due_within_a_slot(&self) -> bool {
        let slot = Instant::now() + self.session.pacing();
        self.timed.next_stop().is_some_and(|at| at <= slot)
    }

    /// The lights held for a stop ([`Self::light`]), sent once no stop is that close, or a
    /// pacing slot after they were first held ([`Held::due_by`]), or when the program ended. After the stop they wait for the program's next call, so its drive
    /// (`roll` after `roll`) does not wait a slot behind them either: spherov2 sends the next
    /// roll one round trip after the stop.
    pub(super) async fn release_lights(&mut self, ended: bool) {
        let overdue = self.held.overdue(Instant::now(), self.session.pacing());
        if self.held.is_empty() || (!ended && !overdue && self.stop_due_within_a_slot()) {
            return;
        }
        for (line, key, intent) in self.held.take() {
            self.intend_as(line, intent, "light", Some(key)).await;
        }
    }

    /// Robot-to-robot infrared: the robot's own commands ([`super::infrared`]).
    pub(super) async fn infrared(&mut self, line: u32, ir: &Ir) {
        self.ir_running.note(ir);
        self.intend(line, Intent::Ir(ir.clone()), "infrared").await;
    }

    /// One of RVR's lights (a headlight, a side light): its own key too.
    pub(super) async fn rvr_light(&mut self, line: u32, light: RvrLight, rgb: [u8; 3]) {
        let c = crate::family::v2::robots::rvr_leds(light.mask(), rgb);
        let key = RVR_KEYS + u64::from(light.mask().trailing_zeros());
        self.send(line, Some(c), "light", Some(crate::session::Latest(key)))
            .await;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A held light goes one pacing slot after it was first held at the latest: lights held
    /// later, or a light held again, do not push that back.
    #[test]
    fn held_lights_are_due_one_pacing_slot_after_the_first_was_held() {
        let ms = Duration::from_millis;
        let pacing = ms(120);
        let t0 = Instant::now();
        let mut held = Held::default();
        assert_eq!(held.due_by(pacing), None);
        assert!(!held.overdue(t0 + ms(10_000), pacing));
        held.hold(3, 1, Intent::MainLight([255, 0, 0]), t0);
        held.hold(4, 2, Intent::MainLight([0, 255, 0]), t0 + ms(50));
        held.hold(5, 1, Intent::MainLight([0, 0, 255]), t0 + ms(100));
        assert_eq!(held.due_by(pacing), Some(t0 + pacing));
        assert!(!held.overdue(t0 + ms(119), pacing));
        assert!(held.overdue(t0 + pacing, pacing));
        // One state per light, in the order held; none held after.
        let lights: Vec<(u32, u64)> = held.take().into_iter().map(|h| (h.0, h.1)).collect();
        assert_eq!(lights, vec![(4, 2), (5, 1)]);
        assert!(held.is_empty());
        assert_eq!(held.due_by(pacing), None);
        // Held again later: counted from then.
        held.hold(6, 1, Intent::MainLight([1, 2, 3]), t0 + ms(500));
        assert_eq!(held.due_by(pacing), Some(t0 + ms(620)));
    }
}
