//! What the roster strip shows of a fleet: every droid with its state, battery and link
//! rate, which one the keys drive, and whether mirror mode sends the same control to all.
//! Plain data, made by the event loop before each frame; `None` in [`super::AppState`] with
//! one droid (the screen is then as it always was).

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
}
