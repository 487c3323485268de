//! The cruise speed (issue 40 point 5, Home Assistant's Speed number): a `drive` alone is
//! stopped by the command timeout 600 ms after it, so a speed that Home Assistant sets
//! once cannot be a drive. It is instead the speed of a `drive` that gives none
//! (`{"v":1,"cmd":"drive","heading":90}`, as the Heading number sends it): set with
//! `{"v":1,"cmd":"cruise","speed":N}`, it moves nothing by itself, a held droid keeps it
//! (a hold refuses the drives that would use it), and each change is said with a `cruise`
//! object (retained on MQTT's `PREFIX/DROID/cruise`, which the Speed number reads).

use super::Bridge;
use super::schema::Out;

/// The cruise speed's MQTT topic leaf (retained).
pub const CRUISE_LEAF: &str = "cruise";

impl Bridge {
    /// Droid `i`'s cruise speed (0 until set: a drive without a speed turns in place).
    pub fn cruise(&self, i: usize) -> u8 {
        self.droids.get(i).map_or(0, |d| d.lock().cruise)
    }

    /// Droid `i`'s `cruise` object.
    pub fn cruise_state(&self, i: usize) -> Option<Out> {
        Some(Out::Cruise {
            droid: self.fleet.member(i)?.name.clone(),
            speed: self.cruise(i),
        })
    }

    /// Set droid `i`'s cruise speed, said at a change.
    pub(super) fn set_cruise(&self, i: usize, speed: u8) {
        let Some(d) = self.droids.get(i) else {
            return;
        };
        let was = std::mem::replace(&mut d.lock().cruise, speed);
        if was != speed
            && let Some(o) = self.cruise_state(i)
        {
            self.emit(Some(i), o);
        }
    }
}
