//! What droidctl sends after every (re)connect (issue 4, "On connect"): wake, tripod for R2,
//! dome to 0, collision detection on, sensor streaming, battery notifications.

use crate::model::Model;
use crate::protocol::v2::sensor::StreamingConfig;
use crate::protocol::v2::wire::{CollisionMethod, LegAction, Mask};
use crate::protocol::v2::{Command, cmd};
use crate::units::HeadAngle;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SetupOptions {
    /// Put R2 into tripod so it can roll.
    pub tripod: bool,
    /// Sensor streaming interval; 0 turns streaming off.
    pub streaming_interval_ms: u16,
}

impl Default for SetupOptions {
    fn default() -> Self {
        SetupOptions {
            tripod: true,
            streaming_interval_ms: 100,
        }
    }
}

/// The streaming masks droidctl asks for.
pub fn streaming(opts: &SetupOptions) -> StreamingConfig {
    StreamingConfig::full(opts.streaming_interval_ms)
}

/// The connect setup, in order.
pub fn connect_setup(model: Model, opts: &SetupOptions) -> Vec<Command> {
    let mut out = vec![cmd::wake()];
    if model.has_legs() && opts.tripod {
        out.push(cmd::perform_leg_action(LegAction::Tripod));
    }
    if model.has_dome() {
        out.push(cmd::set_head_position(HeadAngle::clamped(0.0)));
    }
    // Equal x and y values sidestep the disputed parameter order (`droid-facts.md` §2).
    out.push(cmd::configure_collision_detection(
        CollisionMethod::Accelerometer,
        100,
        100,
        100,
        100,
        10,
    ));
    out.push(cmd::enable_collision_detected_notify(true));
    if opts.streaming_interval_ms > 0 {
        // Reconfigure as the reference clients do: mask with interval 0, extended mask, then
        // the mask again with the real interval (`droid-facts.md` §2).
        let s = streaming(opts);
        out.push(cmd::set_sensor_streaming_mask(0, 0, Mask(s.mask)));
        out.push(cmd::set_extended_sensor_streaming_mask(Mask(s.ext_mask)));
        out.push(cmd::set_sensor_streaming_mask(
            s.interval_ms,
            0,
            Mask(s.mask),
        ));
    }
    out.push(cmd::enable_battery_state_changed_notify(true));
    out.push(cmd::enable_battery_voltage_state_change_notify(true));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn r2_setup_order() {
        let cmds = connect_setup(Model::R2D2, &SetupOptions::default());
        let names: Vec<String> = cmds
            .iter()
            .map(|c| c.def().map(|d| d.name.clone()).unwrap_or_default())
            .collect();
        assert_eq!(
            names,
            [
                "wake",
                "perform-leg-action",
                "set-head-position",
                "configure-collision-detection",
                "enable-collision-detected-notify",
                "set-sensor-streaming-mask",
                "set-extended-sensor-streaming-mask",
                "set-sensor-streaming-mask",
                "enable-battery-state-changed-notify",
                "enable-battery-voltage-state-change-notify",
            ]
        );
        // The first mask write has interval 0, the last the real one (100 ms).
        assert_eq!(&cmds[5].data[..2], &[0, 0]);
        assert_eq!(&cmds[7].data[..2], &[0, 100]);
    }

    #[test]
    fn bb9e_has_no_legs_or_dome() {
        let cmds = connect_setup(Model::BB9E, &SetupOptions::default());
        assert!(cmds.iter().all(|c| c.did != 0x17));
    }
}
