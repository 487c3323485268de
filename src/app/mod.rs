//! The application: state, the packet log, palettes, and the event loop that owns them.
//! Imports point down and close no circle (`tests/circles.rs`): [`view`] and [`state`] know
//! nothing of [`core`]'s `App`; the handlers (`impl App` in keys, mouse, pad, actions, fleet,
//! matrix, monitor, remember, replay) sit above it, `build` and [`run`] on top.
//!
//! - [`run`]: the event loop and its wiring (inputs in, frames out);
//! - `build`: the app set up for its droids, and [`run::AppOptions`];
//! - `core`: what the loop owns, why it ended ([`run::ExitReason`]), the events every
//!   source shares;
//! - [`state`]: what the screen shows ([`AppState`]), [`place`]: where keys are read;
//! - [`view`]: view state below everything that changes it (the matrix as drawn, the scope
//!   and the monitoring settings);
//! - [`keys`], [`pad`]: key dispatch by place and gamepad events; [`overlay`]: the
//!   overlays as components (own state, own keys and mouse, an outcome the app carries
//!   out) and their registry, one list that makes [`state::Overlay`] and its place, key
//!   context, key and mouse dispatch. To add an overlay: its component file in
//!   [`overlay`], its line in the registry, its drawing in `ui::overlay`;
//! - [`actions`]: what reaches the droid (control outputs, lights, animations, sounds);
//! - [`replay`], [`player`]: the app on a capture;
//! - [`program_status`]: the Sphero Edu program running beside it (`--program`);
//! - [`help`]: the help overlay's text and the footer, generated from the bindings;
//!   [`borders`]: the overlays' and panels' key hints, worded once from them;
//! - [`monitor`]: the keys of the scope, opening its channel list and the settings palette,
//!   and sending the settings; [`detail`]: a packet in full's rows;
//! - [`pacing`], [`rates`]: frame pacing and per-second rates, small state machines without IO;
//! - [`battery`]: the battery poller;
//! - `fleet`, [`roster`]: several droids (every droid held alike in fleet order, the chosen
//!   one an index; choosing, mirror) and the roster strip's view of them.
//! - [`layout`]: where each part of the screen goes (the UI draws there, the mouse hits
//!   there); `mouse`: wheel and clicks;
//! - [`remember`]: settings remembered per droid model between launches;
//! - [`matrix`]: BOLT's LED matrix: opening its prompt, drawing it, colour and compass keys.

mod actions;
pub mod battery;
pub mod borders;
mod build;
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
pub mod overlay;
pub mod pacing;
pub mod packet_log;
mod pad;
pub mod picker;
pub mod place;
pub mod player;
pub mod program_status;
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
