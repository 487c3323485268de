//! The application: state, the packet log, palettes, and the event loop that owns them.

pub mod catalog;
pub mod packet_log;
pub mod state;

pub use state::AppState;
pub mod input;
pub mod picker;
pub mod replay;
pub mod run;
