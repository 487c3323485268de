//! What the roster strip shows of a fleet: every droid with its state, battery and link
//! rate, which one the keys drive, and whether mirror mode sends the same control to all.
//! Plain data, made from [`super::AppState`] for drawing; `None` with one droid (the screen
//! is then as it always was).

use crate::model::Model;
use crate::session::LinkState;

#[derive(Debug, Clone, PartialEq, Default)]
pub struct Roster {
    pub droids: Vec<RosterEntry>,
    /// The droid the keys drive (and the gauges, map and scope show).
    pub chosen: usize,
    /// The same control goes to every droid.
    pub mirror: bool,
}

#[derive(Debug, Clone, PartialEq)]
pub struct RosterEntry {
    pub name: String,
    pub model: Model,
    pub link: LinkState,
    pub battery_v: Option<f32>,
    /// Packets per second in and out.
    pub rate_in: f32,
    pub rate_out: f32,
    /// Being driven (a drive command with speed above 0 is held).
    pub moving: bool,
    /// Where its locator puts it, cm, for the map of all droids.
    pub position: Option<(f32, f32)>,
    /// Where it started in the fleet's room, when known: the map draws `position` from there.
    pub room_origin: Option<(f32, f32)>,
}

impl Roster {
    /// Every droid of `state` as the strip shows it.
    pub fn of(state: &super::AppState) -> Roster {
        let droids = state
            .droids
            .iter()
            .map(|d| {
                let t = &d.telemetry;
                RosterEntry {
                    name: d.droid_name.clone(),
                    model: d.model,
                    link: d.link.clone(),
                    battery_v: t.battery_v,
                    rate_in: d.rate_in,
                    rate_out: d.rate_out,
                    moving: d.control.speed > 0 && !d.control.estop,
                    position: t.x_cm.zip(t.y_cm),
                    room_origin: d.room_origin,
                }
            })
            .collect();
        Roster {
            droids,
            chosen: state.chosen,
            mirror: state.mirror,
        }
    }
}
