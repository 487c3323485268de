//! Tank mode (RVR): each track driven on its own, as its raw motors take it. On a gamepad
//! each stick's Y is a track; with keys ↑/↓ drive both tracks and ←/→ pivot, mixed when held
//! together. Sans-IO and under the control loop's safety rules: no input, focus loss, a
//! lost link, aim mode or the e-stop give both tracks 0 (the deadman).

use super::control::{Inputs, Out};

/// Tank mode's state in the control loop.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TankMode {
    /// The robot has tracks.
    pub available: bool,
    pub on: bool,
    /// The tracks last sent, −255..=255 each.
    last: Option<(i16, i16)>,
}

/// Keys: forward/backward both tracks, left/right pivot; `cruise` is full key speed (the
/// sticks carry their own, the gamepad's top speed).
pub fn mix_keys(inp: &Inputs, cruise: u8) -> (i16, i16) {
    let drive = (inp.forward as i16 - inp.backward as i16) as f32;
    let turn = (inp.right as i16 - inp.left as i16) as f32;
    let (l, r) = if drive == 0.0 {
        (turn, -turn)
    } else {
        // Held with a drive key, a turn key slows the inner track to half.
        (
            drive * if turn < 0.0 { 0.5 } else { 1.0 },
            drive * if turn > 0.0 { 0.5 } else { 1.0 },
        )
    };
    let scale = |v: f32| (v * cruise as f32).round().clamp(-255.0, 255.0) as i16;
    (scale(l), scale(r))
}

impl TankMode {
    /// The tank key: on or off, and what to say.
    pub fn toggle(&mut self) -> Vec<Out> {
        if !self.available {
            return vec![Out::Hint("this robot has no tracks".into())];
        }
        self.on = !self.on;
        self.last = None;
        vec![Out::Hint(if self.on {
            "tank mode: a track per stick, or ↑↓ both tracks and ←→ pivot".into()
        } else {
            "tank mode off: drive by heading".into()
        })]
    }

    pub fn moving(&self) -> bool {
        self.last.is_some_and(|(l, r)| l != 0 || r != 0)
    }

    /// One tick: the tracks to send (as [`crate::family::intent::Intent::RawMotors`], which
    /// the droid's family lowers) when they changed, or on the heartbeat while moving. `live`
    /// is false while the e-stop, aim mode or a lost link hold it still.
    pub fn tick(
        &mut self,
        inp: &Inputs,
        live: bool,
        cruise: u8,
        heartbeat: bool,
        connected: bool,
    ) -> Option<(i16, i16)> {
        let tracks = match (live, inp.pad_tracks) {
            (false, _) => (0, 0),
            // The sticks carry their own scale (the gamepad's top speed).
            (true, Some((l, r))) => {
                let s = |v: f32| (v * 255.0).round().clamp(-255.0, 255.0) as i16;
                (s(l), s(r))
            }
            (true, None) => mix_keys(inp, cruise),
        };
        let moving = tracks != (0, 0);
        if !connected || (self.last == Some(tracks) && !(moving && heartbeat)) {
            return None;
        }
        self.last = Some(tracks);
        Some(tracks)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::family::intent::{Intent, lower};
    use crate::model::Model;

    /// RVR's raw-motor bytes (left mode, left power, right mode, right power) of `tracks`.
    fn rvr_bytes((left, right): (i16, i16)) -> (u8, u8, u8, u8) {
        let c = lower(Model::Rvr, &Intent::RawMotors { left, right })
            .unwrap()
            .remove(0);
        let d = c.data();
        (d[0], d[1], d[2], d[3])
    }

    #[test]
    fn keys_mix_into_tracks() {
        let i = |f: bool, b: bool, l: bool, r: bool| Inputs {
            forward: f,
            backward: b,
            left: l,
            right: r,
            ..Inputs::default()
        };
        assert_eq!(mix_keys(&i(true, false, false, false), 100), (100, 100));
        assert_eq!(mix_keys(&i(false, true, false, false), 100), (-100, -100));
        assert_eq!(mix_keys(&i(false, false, true, false), 100), (-100, 100));
        assert_eq!(mix_keys(&i(true, false, false, true), 100), (100, 50));
        assert_eq!(mix_keys(&i(false, false, false, false), 100), (0, 0));
    }

    #[test]
    fn deadman_and_heartbeat() {
        let mut t = TankMode {
            available: true,
            on: true,
            last: None,
        };
        let sticks = Inputs {
            pad_tracks: Some((1.0, -0.5)),
            ..Inputs::default()
        };
        let tracks = t.tick(&sticks, true, 200, true, true).unwrap();
        assert_eq!(tracks, (255, -128));
        // Raw motors: left forward 255, right reverse 128.
        assert_eq!(rvr_bytes(tracks), (1, 255, 2, 128));
        // Unchanged: only on the heartbeat.
        assert!(t.tick(&sticks, true, 200, false, true).is_none());
        assert!(t.tick(&sticks, true, 200, true, true).is_some());
        // Sticks let go: both tracks stop, once.
        let tracks = t.tick(&Inputs::default(), true, 200, true, true).unwrap();
        assert_eq!((tracks, rvr_bytes(tracks)), ((0, 0), (0, 0, 0, 0)));
        assert!(t.tick(&Inputs::default(), true, 200, true, true).is_none());
        // The e-stop (not live) holds it still whatever the sticks say.
        let tracks = t.tick(&sticks, true, 200, true, true).unwrap();
        assert_eq!(tracks, (255, -128));
        let tracks = t.tick(&sticks, false, 200, true, true).unwrap();
        assert_eq!(tracks, (0, 0));
        // A lost link sends nothing.
        assert!(t.tick(&sticks, true, 200, true, false).is_none());
        let mut none = TankMode::default();
        assert!(matches!(&none.toggle()[..], [Out::Hint(h)] if h.contains("no tracks")));
    }
}
