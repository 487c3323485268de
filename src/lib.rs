//! droidctl: drive Sphero's Star Wars droids and friends from the terminal.
//!
//! The crate is layered: [`protocol`] is sans-IO (bytes in, typed values out); everything that
//! touches a clock, a radio or a terminal sits at the edges.

pub mod cli;
pub mod hex;
pub mod protocol;
pub mod units;
pub mod link;
pub mod model;
pub mod session;
pub mod rng;
pub mod sim;
pub mod mission;
pub mod script;
pub mod setup;
pub mod telemetry;
pub mod logging;
pub mod app;
pub mod config;
pub mod teleop;
