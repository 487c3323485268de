//! The `[streaming]` and `[collision]` tables (issue 22 points 2 and 3): which sensor groups
//! stream and how fast, and the collision detector's thresholds. Checked when the file loads;
//! the family caps the rate to what the droid's link carries when it connects.

use crate::tuning::{CollisionConfig, MAX_DEAD_TIME_MS, SensorSet};
use serde::Deserialize;

/// `[streaming]` as written.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Streaming {
    /// Samples per second; 0 turns streaming off.
    pub rate_hz: u16,
    /// Sensor group names (`attitude`, `accelerometer`, `gyro`, `locator`, `velocity`,
    /// `head`).
    pub sensors: Vec<String>,
}

impl Streaming {
    /// The groups named (checked at load, so this never fails on a loaded config).
    pub fn sensor_set(&self) -> SensorSet {
        SensorSet::parse(self.sensors.iter().map(String::as_str)).unwrap_or_default()
    }
}

/// Range checks: (section, key, message).
pub fn validate(s: &Streaming, c: &CollisionConfig) -> Result<(), (String, String, String)> {
    let bad = |sec: &str, k: &str, m: String| Err((sec.to_string(), k.to_string(), m));
    if s.rate_hz > 100 {
        return bad(
            "streaming",
            "rate_hz",
            format!(
                "{} is out of range 0..=100 (0 turns streaming off)",
                s.rate_hz
            ),
        );
    }
    if let Err(e) = SensorSet::parse(s.sensors.iter().map(String::as_str)) {
        return bad("streaming", "sensors", e);
    }
    if c.dead_time_ms > MAX_DEAD_TIME_MS {
        return bad(
            "collision",
            "dead_time_ms",
            format!("{} is out of range 0..={MAX_DEAD_TIME_MS}", c.dead_time_ms),
        );
    }
    Ok(())
}
