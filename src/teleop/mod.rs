//! Teleoperation: keys and gamepad in, what the droid should do out, as
//! [`crate::family::intent::Intent`]s (drive, steer, tracks, stop, dome, stance, aim) that the
//! droid's family lowers into its commands. The mapping and the control loop are sans-IO
//! (explicit time), so deadman, e-stop and emulated key release are tested
//! deterministically.

pub mod control;
pub mod gamepad;
pub mod gamepad_map;
pub mod held;
pub mod tank;
