//! What droidctl sends after every (re)connect (issue 4, "On connect"): wake, tripod for R2,
//! dome to 0, collision detection on, sensor streaming, battery notifications. The commands
//! themselves come from the model's protocol family (`crate::family`).

use super::Command;
use super::stream::SensorSet;
use crate::model::Model;
use crate::tuning::CollisionConfig;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SetupOptions {
    /// Put R2 into tripod so it can roll.
    pub tripod: bool,
    /// Sensor streaming interval; 0 turns streaming off.
    pub streaming_interval_ms: u16,
    /// The sensor groups streamed; `None`: everything the model streams.
    pub sensors: Option<SensorSet>,
    pub collision: CollisionConfig,
}

impl Default for SetupOptions {
    fn default() -> Self {
        SetupOptions {
            tripod: true,
            streaming_interval_ms: 100,
            sensors: None,
            collision: CollisionConfig::default(),
        }
    }
}

impl SetupOptions {
    /// The streaming this setup asks for, as a plan (the interval as given, not capped: the
    /// caller resolved it, [`super::stream::plan_for`]).
    pub fn stream_plan(&self, model: Model) -> super::stream::StreamPlan {
        let sensors = self
            .sensors
            .unwrap_or_else(|| super::stream::all_groups(model));
        if self.streaming_interval_ms == 0 || sensors.is_empty() {
            return super::stream::StreamPlan::off();
        }
        super::stream::StreamPlan {
            interval_ms: self.streaming_interval_ms,
            sensors,
            note: None,
        }
    }

    /// With a resolved plan's interval and groups.
    pub fn with_plan(self, plan: &super::stream::StreamPlan) -> SetupOptions {
        SetupOptions {
            streaming_interval_ms: plan.interval_ms,
            sensors: Some(plan.sensors),
            ..self
        }
    }
}

/// The connect setup, in order.
pub fn connect_setup(model: Model, opts: &SetupOptions) -> Vec<Command> {
    super::for_model(model).setup(model, opts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn r2_setup_order() {
        let cmds = connect_setup(Model::R2D2, &SetupOptions::default());
        let names: Vec<String> = cmds.iter().map(|c| c.name()).collect();
        assert_eq!(
            names,
            [
                "wake",
                "set-custom-control-system-timeout",
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
        assert_eq!(&cmds[6].data()[..2], &[0, 0]);
        assert_eq!(&cmds[8].data()[..2], &[0, 100]);
    }

    #[test]
    fn bb9e_has_no_legs_or_dome() {
        let cmds = connect_setup(Model::BB9E, &SetupOptions::default());
        assert!(cmds.iter().all(|c| c.did() != 0x17));
    }
}
