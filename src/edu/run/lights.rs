//! A program's lights and infrared: each light's newest state replaces its unwritten older one
//! (a light loop never floods the queue and always ends on its last colour, issue 38 point 4).

use super::super::api::{Act, Ir, RvrLight};
use super::Player;
use crate::family::intent::Intent;
use crate::script::LedGroup;
use tokio::time::Instant;

/// RVR's lights' keys start here (each light's bits: its own key, beside the others').
const RVR_KEYS: u64 = 100;

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
            self.held.retain(|h| h.1 != key);
            self.held.push((line, key, intent));
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

    /// The lights held for a stop ([`Self::light`]), sent once no stop is that close (or the
    /// program ended). After the stop they wait for the program's next call, so its drive
    /// (`roll` after `roll`) does not wait a slot behind them either: spherov2 sends the next
    /// roll one round trip after the stop.
    pub(super) async fn release_lights(&mut self, ended: bool) {
        if self.held.is_empty() || (!ended && self.stop_due_within_a_slot()) {
            return;
        }
        for (line, key, intent) in std::mem::take(&mut self.held) {
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
