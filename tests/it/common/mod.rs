//! What several areas' tests share: the built binary run with arguments, scratch
//! directories, the app in a pseudo-terminal, brokers and bridges as processes.

pub mod app;
pub mod bridge_proc;
pub mod cli;
pub mod edu_run;
pub mod lines;
pub mod mission_run;
pub mod mosquitto;
pub mod pty;
pub mod python;
pub mod scratch;
pub mod serial_sim;
pub mod source;
