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

/// The setup the config file asks for on `model`: `[streaming]` resolved against what the
/// droid's link carries (the plan says when it was capped; `None` for a droid that streams by
/// itself), `[collision]`, tripod on.
pub fn from_config(
    model: Model,
    config: &crate::config::Config,
) -> (SetupOptions, Option<super::stream::StreamPlan>) {
    let plan = super::stream::plan_for(model, config.stream_request());
    let setup = SetupOptions {
        tripod: true,
        collision: config.collision,
        ..SetupOptions::default()
    };
    let setup = match &plan {
        Some(p) => setup.with_plan(p),
        None => setup,
    };
    (setup, plan)
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
    fn the_config_files_streaming_and_collision_reach_the_setup() {
        use crate::config::Config;
        let c = Config::parse_merged(
            None,
            "[streaming]\nrate_hz = 50\nsensors = [\"attitude\"]\n[collision]\nx_threshold = 180\n",
        )
        .unwrap();
        let (setup, plan) = from_config(Model::R2D2, &c);
        assert_eq!(plan.unwrap().note, None);
        let cmds = connect_setup(Model::R2D2, &setup);
        let mask = cmds
            .iter()
            .rfind(|c| c.name() == "set-sensor-streaming-mask")
            .unwrap();
        // 20 ms, attitude (0x00070000).
        assert_eq!(&mask.data()[..], &[0, 20, 0, 0, 7, 0, 0]);
        let coll = cmds
            .iter()
            .find(|c| c.name() == "configure-collision-detection")
            .unwrap();
        assert_eq!(coll.data()[1], 180);
        // Off: nothing streams; collision detection is still set.
        let c = Config::parse_merged(None, "[streaming]\nrate_hz = 0\n").unwrap();
        let (setup, _) = from_config(Model::BB8, &c);
        let names: Vec<String> = connect_setup(Model::BB8, &setup)
            .iter()
            .map(|c| c.name())
            .collect();
        assert!(!names.iter().any(|n| n.contains("streaming")), "{names:?}");
        assert!(names.iter().any(|n| n == "configure-collision-detection"));
        // More than the link carries is capped, and the plan says so.
        let c = Config::parse_merged(None, "[streaming]\nrate_hz = 100\n").unwrap();
        let (setup, plan) = from_config(Model::BB8, &c);
        assert_eq!(setup.streaming_interval_ms, 50, "20/s for every v1 sensor");
        assert!(plan.unwrap().note.unwrap().contains("capped at 20/s"));
    }

    #[test]
    fn bb9e_has_no_legs_or_dome() {
        let cmds = connect_setup(Model::BB9E, &SetupOptions::default());
        assert!(cmds.iter().all(|c| c.did() != 0x17));
    }
}
