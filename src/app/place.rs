//! The place that has the keyboard. Keys go to one place only, and each place reads its own
//! table of the key map; only [`Place::Driving`] turns keys into motion. Which place is on top
//! follows from what the screen shows (an overlay, the focused log, a replay), so there is no
//! second copy of it to fall out of step: `Place::of` (beside the state it reads, in
//! [`super::state`]) asks the overlay registry ([`super::overlay`]) for an open overlay's.
//!
//! The rule the safety promises rest on: whenever the place on top changes (an overlay opens
//! or closes, the log takes or gives back the keys), another droid is chosen, mirror mode is
//! switched or the terminal loses focus, every held key is let go and the droids' controllers
//! are told at once ([`super::core::App::clear_held`]). A key pressed anywhere but in driving
//! is never held, so it cannot drive once that place closes.

use crate::config::Context;

/// Where keys are read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Place {
    /// Keys drive the droid (or droids, mirrored). With the scope on screen its own keys go
    /// to the scope (and never drive); every other key drives as usual, so one can watch the
    /// scope while driving.
    Driving,
    /// A capture plays: the replay keys; nothing drives.
    Replay,
    /// The packet log has the keys (the droid is held stopped).
    Log,
    /// Typing a packet-log filter.
    Filter,
    /// Typing what BOLT's matrix shows.
    Matrix,
    /// The help overlay.
    Help,
    /// The animation or sound palette.
    Palette,
    /// The scope's channel list.
    Channels,
    /// The streaming and collision settings.
    Tuning,
    /// A packet in full.
    Packet,
}

impl Place {
    /// The table of keys read here: the one map from a place to its bindings, which the key
    /// dispatch, the stop's way through an overlay and the footer all read. `scope`: the
    /// scope is on screen (driving reads its own keys first); `typing`: a packet in full is
    /// taking a search (the prompts' keys, as in the filter).
    pub fn context(self, scope: bool, typing: bool) -> Context {
        match self {
            Place::Driving if scope => Context::Scope,
            Place::Driving => Context::Drive,
            Place::Replay => Context::Replay,
            Place::Log => Context::Log,
            Place::Filter | Place::Matrix => Context::Filter,
            Place::Help => Context::Help,
            Place::Palette => Context::Palette,
            Place::Channels | Place::Tuning => Context::Settings,
            Place::Packet if typing => Context::Filter,
            Place::Packet => Context::Detail,
        }
    }

    /// Whether the drive table's emergency stop works here when this place's own table
    /// leaves its key free: the overlays that take no text (a typing place takes every
    /// printable key: there the stop is the Ctrl one, or the gamepad's).
    pub fn lets_the_stop_through(self) -> bool {
        matches!(
            self,
            Place::Palette | Place::Help | Place::Channels | Place::Tuning
        )
    }

    /// Whether keys pressed here may drive.
    pub fn drives(self) -> bool {
        self == Place::Driving
    }

    /// A short name, for the status line and tests.
    pub fn name(self) -> &'static str {
        match self {
            Place::Driving => "driving",
            Place::Replay => "replay",
            Place::Log => "packet log",
            Place::Filter => "filter",
            Place::Matrix => "matrix",
            Place::Help => "help",
            Place::Palette => "palette",
            Place::Channels => "channels",
            Place::Tuning => "settings",
            Place::Packet => "packet",
        }
    }
}
