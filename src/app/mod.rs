//! The application: state, the packet log, palettes, and the event loop that owns them.
//!
//! - [`run`]: the event loop and its wiring (inputs in, frames out);
//! - [`core`]: what the loop owns, and the events every source shares;
//! - [`keys`], [`pad`]: key dispatch by context and gamepad events;
//! - [`actions`]: what reaches the droid (control outputs, lights, animations, sounds);
//! - [`replay`], [`player`]: the app on a capture;
//! - [`help`]: the help overlay's text, generated from the bindings;
//! - [`monitor`]: the scope's view, the streaming and collision settings and their keys;
//! - [`pacing`], [`rates`]: frame pacing and per-second rates, small state machines without IO;
//! - [`battery`]: the battery poller;
//! - `fleet`, [`roster`]: several droids (the parked ones, choosing, mirror) and the roster
//!   strip's view of them.
//! - [`layout`]: where each part of the screen goes (the UI draws there, the mouse hits
//!   there); `mouse`: wheel and clicks;
//! - [`remember`]: settings remembered per droid model between launches;
//! - [`matrix`]: BOLT's LED matrix as droidctl drew it, its prompt, colour and compass keys.

mod actions;
pub mod battery;
mod build;
pub mod catalog;
mod core;
pub mod detail;
mod droid;
mod fleet;
pub mod help;
pub mod input;
mod keys;
pub mod layout;
pub mod matrix;
pub mod monitor;
mod mouse;
pub mod pacing;
pub mod packet_log;
mod pad;
pub mod picker;
pub mod place;
pub mod player;
pub mod rates;
pub mod remember;
mod replay;
pub mod roster;
pub mod run;
pub mod state;
pub mod view;

pub use core::InputTrace;
pub use place::Place;
pub use state::AppState;
