//! Sensor streaming as the user chooses it (issue 22 point 2): which sensor groups stream and
//! how many samples a second, resolved against what the droid's family offers and what its
//! Bluetooth link can carry, and turned into the family's own commands.
//!
//! A family says what it offers through [`crate::family::Family::stream_caps`] (the groups of
//! a model, the rates its clock allows, the link's budget) and
//! [`crate::family::Family::stream_sample_bytes`] (how long one sample's packet is); it builds
//! the commands in [`crate::family::Family::streaming`]. [`resolve`] caps a request to the
//! budget and says so; [`reconfigure`] always re-sends collision detection after a streaming
//! change, so changing the streaming never silences collisions.
//!
//! ## The budget
//! Sphero droids speak over BLE 4 with the default 23-byte ATT MTU: a notification carries at
//! most 20 bytes and a packet longer than that takes several. How many notifications a
//! connection event carries and how often events come depend on both ends; droidctl assumes
//! BlueZ's default connection interval range of 30-50 ms at its slow end (50 ms) and four
//! notifications per event (what common controllers deliver at that MTU): 80 notifications
//! per second. A quarter is kept for command responses, collisions and power notifications,
//! leaving [`BLE_SENSOR_NOTIFICATIONS_PER_S`] = 60 for sensor samples. A sample costs
//! `ceil(packet bytes / 20)` notifications; the rate is capped so that count × rate stays
//! within the 60. (No spec gives the droids' connection parameters: the figures are
//! assumptions, stated in README.)
//!
//! Sans-IO: plain values in, commands out.

use crate::model::Model;
pub use crate::tuning::{SensorGroup, SensorSet, StreamRequest};

/// Payload of one notification at the default ATT MTU of 23.
pub const ATT_PAYLOAD: usize = 20;

/// Sensor-sample notifications a second a BLE link is budgeted for (see the module docs).
pub const BLE_SENSOR_NOTIFICATIONS_PER_S: u32 = 60;

/// The rates the old SDKs offered, in samples per second.
pub const STANDARD_RATES: [u16; 5] = [1, 10, 20, 50, 100];

/// What a model can stream (from its family).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StreamCaps {
    /// The groups this model streams.
    pub groups: SensorSet,
    /// The rates its sample clock makes exactly, samples per second.
    pub rates: &'static [u16],
    /// Sample notifications a second its link is budgeted for.
    pub notifications_per_s: u32,
}

/// A request resolved: what is sent, and why it differs from what was asked, if it does.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StreamPlan {
    /// Sample interval in ms; 0: streaming off.
    pub interval_ms: u16,
    pub sensors: SensorSet,
    /// Shown to the user when the request was capped or groups were dropped.
    pub note: Option<String>,
}

impl StreamPlan {
    pub fn off() -> StreamPlan {
        StreamPlan {
            interval_ms: 0,
            sensors: SensorSet::EMPTY,
            note: None,
        }
    }

    /// `sensors` every `1/rate_hz` s (0: off).
    pub fn at_rate(rate_hz: u16, sensors: SensorSet) -> StreamPlan {
        if rate_hz == 0 || sensors.is_empty() {
            return StreamPlan::off();
        }
        StreamPlan {
            interval_ms: (1000 / rate_hz).max(1),
            sensors,
            note: None,
        }
    }

    pub fn is_on(&self) -> bool {
        self.interval_ms > 0 && !self.sensors.is_empty()
    }

    /// Samples per second (0 when off).
    pub fn rate_hz(&self) -> f32 {
        if self.is_on() {
            1000.0 / self.interval_ms as f32
        } else {
            0.0
        }
    }
}

/// Notifications one sample of `bytes` takes.
pub fn notifications_per_sample(bytes: usize) -> u32 {
    bytes.div_ceil(ATT_PAYLOAD).max(1) as u32
}

/// The fastest rate of `caps.rates` that fits the budget with samples of `bytes`.
pub fn max_rate(caps: &StreamCaps, bytes: usize) -> u16 {
    let per = notifications_per_sample(bytes);
    caps.rates
        .iter()
        .copied()
        .filter(|r| *r as u32 * per <= caps.notifications_per_s)
        .max()
        .unwrap_or(0)
}

/// Resolve `req` against `caps`: groups the model lacks are dropped, a rate is taken from the
/// model's rates (the nearest not above it), and capped to what the link carries with samples
/// of `sample_bytes(groups)` bytes. Each change is said in the plan's note.
pub fn resolve(
    caps: &StreamCaps,
    req: StreamRequest,
    sample_bytes: &dyn Fn(SensorSet) -> usize,
) -> StreamPlan {
    if req.rate_hz == 0 || req.sensors.is_empty() {
        return StreamPlan::off();
    }
    let mut notes = Vec::new();
    let sensors = req.sensors.intersect(caps.groups);
    if sensors != req.sensors {
        let dropped: Vec<&str> = req
            .sensors
            .iter()
            .filter(|g| !caps.groups.contains(*g))
            .map(SensorGroup::name)
            .collect();
        notes.push(format!("no {} on this droid", dropped.join(", ")));
    }
    if sensors.is_empty() {
        return StreamPlan {
            note: Some(notes.join("; ")),
            ..StreamPlan::off()
        };
    }
    let mut rate = caps
        .rates
        .iter()
        .copied()
        .filter(|r| *r <= req.rate_hz)
        .max()
        .or_else(|| caps.rates.iter().copied().min())
        .unwrap_or(0);
    if rate != req.rate_hz {
        let offered: Vec<String> = caps.rates.iter().map(u16::to_string).collect();
        notes.push(format!(
            "{}/s is not offered (this droid offers {}/s): {rate}/s",
            req.rate_hz,
            offered.join(", ")
        ));
    }
    let bytes = sample_bytes(sensors);
    let limit = max_rate(caps, bytes);
    if rate > limit {
        notes.push(format!(
            "{rate}/s × {bytes} B exceeds the BLE budget ({} notifications/s): capped at {limit}/s",
            caps.notifications_per_s
        ));
        rate = limit;
    }
    StreamPlan {
        note: (!notes.is_empty()).then(|| notes.join("; ")),
        ..StreamPlan::at_rate(rate, sensors)
    }
}

/// Resolve `req` for `model` through its family. `None` when the droid streams by itself at
/// its own rate (Robi 42's state frames).
pub fn plan_for(model: Model, req: StreamRequest) -> Option<StreamPlan> {
    let family = super::for_model(model);
    let caps = family.stream_caps(model)?;
    Some(resolve(&caps, req, &|s| family.stream_sample_bytes(s)))
}

/// Everything the model can stream.
pub fn all_groups(model: Model) -> SensorSet {
    let family = super::for_model(model);
    family
        .stream_caps(model)
        .map_or(SensorSet::EMPTY, |c| c.groups)
}

/// The commands that change the streaming to `plan`, then collision detection as `collision`
/// says: some clients lose collision events when they reconfigure streaming; droidctl always
/// sets collision detection again after it.
pub fn reconfigure(
    model: Model,
    plan: &StreamPlan,
    collision: &crate::tuning::CollisionConfig,
) -> Vec<super::Command> {
    let family = super::for_model(model);
    let mut out = family.streaming(model, plan);
    out.extend(family.collision_detection(collision));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    static CAPS: std::sync::LazyLock<StreamCaps> = std::sync::LazyLock::new(|| StreamCaps {
        groups: SensorSet::of(&[
            SensorGroup::Attitude,
            SensorGroup::Accelerometer,
            SensorGroup::Gyro,
            SensorGroup::Locator,
            SensorGroup::Velocity,
        ]),
        rates: &STANDARD_RATES,
        notifications_per_s: 60,
    });

    #[test]
    fn requests_are_capped_to_the_budget_and_say_so() {
        // 63 bytes: 4 notifications a sample, 15/s fit: 10/s is the fastest offered rate.
        let p = resolve(
            &CAPS,
            StreamRequest {
                rate_hz: 100,
                sensors: SensorSet::of(&[SensorGroup::Attitude]),
            },
            &|_| 63,
        );
        assert_eq!(p.interval_ms, 100);
        assert!(p.note.unwrap().contains("capped at 10/s"));
        // One notification a sample: 50/s fits, 100/s does not.
        let p = resolve(
            &CAPS,
            StreamRequest {
                rate_hz: 50,
                sensors: SensorSet::of(&[SensorGroup::Attitude]),
            },
            &|_| 19,
        );
        assert_eq!((p.interval_ms, p.note), (20, None));
        // A rate between the offered ones takes the one below it; missing groups are dropped.
        let p = resolve(
            &CAPS,
            StreamRequest {
                rate_hz: 30,
                sensors: SensorSet::of(&[SensorGroup::Gyro, SensorGroup::HeadAngle]),
            },
            &|_| 19,
        );
        assert_eq!(p.rate_hz(), 20.0);
        assert_eq!(p.sensors, SensorSet::of(&[SensorGroup::Gyro]));
        let note = p.note.unwrap();
        assert!(note.contains("no head") && note.contains("30/s"), "{note}");
        // Off is off.
        let p = resolve(
            &CAPS,
            StreamRequest {
                rate_hz: 0,
                sensors: CAPS.groups,
            },
            &|_| 19,
        );
        assert!(!p.is_on());
        assert_eq!(p.interval_ms, 0);
    }
}
