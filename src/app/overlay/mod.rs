//! The overlays' keys as components, in the shape [`super::picker`] has: each overlay's file
//! holds its state's key handling, reads its own table of the key map and returns an
//! [`Outcome`]; the app loop carries the outcome out (closing, playing, filtering), so an
//! overlay never reaches into the app. Where each is registered: its variant of
//! [`super::state::Overlay`] (its state), its [`super::place::Place`] (`Place::of` and
//! `Place::context`, its key table), the dispatch in [`super::keys`], and its drawing in
//! `ui::overlay`.
//!
//! - [`palette`]: the animation and sound palettes;
//! - [`help`]: help's pages;
//! - [`filter`]: the packet-log filter prompt (its own outcome, [`filter::Prompted`]: it
//!   tells the log what to show as it is typed);
//! - `super::detail` (a packet in full), `super::monitor` (the channel list and the
//!   settings) and `super::matrix` (BOLT's matrix prompt) hold theirs beside the rest of
//!   their feature.

pub mod filter;
pub mod help;
pub mod palette;

/// What a key did in an overlay.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome<T = ()> {
    /// The overlay stays open (its state may have changed).
    Stay,
    /// The overlay closes, nothing else happens.
    Close,
    /// The overlay closes with what was chosen.
    Done(T),
}
