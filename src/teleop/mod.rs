//! Teleoperation: keys and gamepad in, drive/dome/stance commands out. The mapping and the
//! control loop are sans-IO (explicit time), so deadman, e-stop and emulated key release are
//! tested deterministically.

pub mod control;
pub mod gamepad;
pub mod gamepad_map;
pub mod held;
pub mod tank;
