//! droidctl: drive Sphero's Star Wars droids and friends from the terminal.
//!
//! The crate is layered: [`protocol`] is sans-IO (bytes in, typed values out); everything that
//! touches a clock, a radio or a terminal sits at the edges.

pub mod app;
pub mod bridge;
pub mod capture;
pub mod cli;
pub mod config;
pub mod edu;
pub mod examples;
pub mod family;
pub mod fleet;
#[doc(hidden)]
pub mod fuzzing;
pub mod gatt;
pub mod hex;
pub mod link;
pub mod logging;
pub mod mission;
pub mod model;
pub mod net;
pub mod output;
pub mod own_file;
pub mod plot;
pub mod printable;
pub mod protocol;
pub mod relay;
pub mod rng;
pub mod script;
pub mod session;
pub mod sim;
pub mod sync;
pub mod telemetry;
pub mod teleop;
pub mod text_file;
pub mod tuning;
pub mod ui;
pub mod units;
