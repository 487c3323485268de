//! What a droid played last (issue 40 point 5, Home Assistant's animation and sound
//! selects): once the droid answered an `animation` or `sound` command, a `played` object
//! names it (id and catalogue name, [`crate::family::catalog`]), retained on MQTT's
//! `PREFIX/DROID/animation` and `…/sound`, so a select shows what was played, also after
//! Home Assistant restarts.

use super::Bridge;
use super::schema::{Cmd, Out};
use crate::family::catalog::Palette;

/// The MQTT topic leaves of what a droid played last (retained), as `played.what` says it.
pub const PLAYED_LEAVES: [&str; 2] = ["animation", "sound"];

/// The `played` object of `cmd` for droid `droid`, when it plays something.
fn played(droid: &str, cmd: &Cmd) -> Option<(usize, Out)> {
    let (slot, what, palette, id) = match *cmd {
        Cmd::Animation(id) => (0, PLAYED_LEAVES[0], Palette::Animations, id),
        Cmd::Sound(id) => (1, PLAYED_LEAVES[1], Palette::Sounds, id),
        _ => return None,
    };
    Some((
        slot,
        Out::Played {
            droid: droid.to_string(),
            what,
            id,
            name: palette.name_of(id),
        },
    ))
}

impl Bridge {
    /// Droid `i` answered `cmd`: what it played is kept and said.
    pub(super) fn said_played(&self, i: usize, cmd: &Cmd) {
        let (Some(m), Some(d)) = (self.fleet.member(i), self.droids.get(i)) else {
            return;
        };
        if let Some((slot, o)) = played(&m.name, cmd) {
            d.lock().played[slot] = Some(o.clone());
            self.emit(Some(i), o);
        }
    }

    /// Droid `i`'s last animation and sound played, for its retained topics.
    pub fn played_state(&self, i: usize) -> Vec<Out> {
        self.droids
            .get(i)
            .map(|d| d.lock().played.iter().flatten().cloned().collect())
            .unwrap_or_default()
    }
}
