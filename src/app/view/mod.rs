//! View state the UI reads, below everything that changes it: what the app's keys, a droid's
//! events and the remembered settings write, and nothing that knows of [`super::core::App`].
//!
//! - [`matrix`]: BOLT's LED matrix as droidctl drew it, and the colour key's cycle;
//! - [`program`]: a Sphero Edu program beside the app, as the screen shows it;
//! - [`scope`]: the scope's window and channels, the streaming and collision settings and
//!   their palette's draft.

pub mod matrix;
pub mod program;
pub mod scope;
