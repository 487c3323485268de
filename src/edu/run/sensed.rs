//! The events a program hears that the droid does not send as such: spherov2's free-fall and
//! landing detector, the colour sensor's `onColor` and the charger's `onCharging`, each
//! told from the droid's reports.

use super::super::engine::Event;
use super::Player;
use std::time::Duration;
use tokio::time::Instant;

/// What the events told from the droid's reports last saw: spherov2's fall detector
/// (`__process_falling`, on the acceleration's size), the gyroscope at its limit, the colour
/// sensor's index and the charger.
pub(super) struct Sensed {
    pub(super) v: f32,
    pub(super) since: Option<Instant>,
    pub(super) free: bool,
    pub(super) should_land: bool,
    pub(super) gyro_max: bool,
    /// The colour sensor's palette index last fired on (`onColor`).
    pub(super) colour: Option<u8>,
    /// On the charger, as the droid last said.
    pub(super) charging: Option<bool>,
}

impl Default for Sensed {
    /// At rest (1 g), nothing seen yet.
    fn default() -> Self {
        Sensed {
            v: 1.0,
            since: None,
            free: false,
            should_land: false,
            gyro_max: false,
            colour: None,
            charging: None,
        }
    }
}

impl Player {
    /// `onCharging` when the droid says it is on its charger, `onNotCharging` when it is taken
    /// off (not when the first report says it is off).
    pub(super) fn charging(&mut self, now: bool) -> Option<Event> {
        let was = self.sensed.charging.replace(now);
        match (was, now) {
            (Some(a), b) if a == b => None,
            (None, false) => None,
            (_, true) => Some(Event::Charging),
            (_, false) => Some(Event::NotCharging),
        }
    }

    /// `onColor` as spherov2 fires it: when the colour sensor's palette index changes (streamed
    /// or notified), is a colour (not 255) and is seen with confidence 0.71 or more.
    pub(super) fn colour(&mut self, reading: Option<([u8; 3], u8, f32)>) -> Option<Event> {
        let (rgb, index, confidence) = reading?;
        if Some(index) == self.sensed.colour || index == 255 || confidence < 0.71 {
            return None;
        }
        self.sensed.colour = Some(index);
        Some(Event::Color(rgb))
    }

    /// spherov2's free fall and landing, on the acceleration's size (1 g at rest, 0 falling).
    pub(super) fn fall(&mut self, a: [f32; 3]) -> Vec<Event> {
        let size = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        let f = &mut self.sensed;
        f.v = (f.v + size * 3.0) / 4.0;
        let now = Instant::now();
        let mut out = Vec::new();
        if f.v.abs() < 0.5 {
            let since = *f.since.get_or_insert(now);
            if now - since > Duration::from_millis(200) && !f.free {
                out.push(Event::Freefall);
                f.free = true;
                f.should_land = true;
            }
        } else {
            f.since = None;
            f.free = false;
        }
        if f.should_land && f.v > 1.1 {
            out.push(Event::Landing);
            f.should_land = false;
        }
        out
    }
}
