//! What the droid reports, aggregated from notifications: the live gauges of the TUI and the
//! samples of `droidctl run --json` both read this.

use crate::protocol::notify::{Collision, Notification};
use crate::protocol::wire::{LegAction, LegState};
use crate::units::Heading;
use std::collections::VecDeque;
use std::time::Duration;

/// The voltage in a Get Battery Voltage response (u16 volts×100, `droid-facts.md` §2).
pub fn battery_volts(response: &[u8]) -> Option<f32> {
    use crate::protocol::v2::wire::{CentiVolts, Reader, Wire};
    let mut r = Reader::new(response);
    let v = CentiVolts::get(&mut r, "voltage").ok()?;
    r.finish().ok()?;
    Some(v.0 as f32 / 100.0)
}

/// How many locator positions the track keeps.
pub const TRACK_LEN: usize = 600;

/// The droid's stance as far as we know.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stance {
    Unknown,
    Tripod,
    Bipod,
    Waddle,
    /// Changing to the given stance.
    Transitioning(LegState),
}

impl Stance {
    pub fn label(self) -> String {
        match self {
            Stance::Unknown => "unknown".into(),
            Stance::Tripod => "tripod".into(),
            Stance::Bipod => "bipod".into(),
            Stance::Waddle => "waddle".into(),
            Stance::Transitioning(to) => format!("→ {}", to.label()),
        }
    }

    pub fn from_state(s: LegState) -> Stance {
        match s {
            LegState::Tripod => Stance::Tripod,
            LegState::Bipod => Stance::Bipod,
            LegState::Waddle => Stance::Waddle,
            LegState::Transitioning => Stance::Transitioning(LegState::Unknown),
            LegState::Unknown => Stance::Unknown,
        }
    }
}

/// The last collision and when it happened.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CollisionSeen {
    pub at: Duration,
    pub collision: Collision,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Telemetry {
    pub pitch: Option<f32>,
    pub roll: Option<f32>,
    pub yaw: Option<f32>,
    pub accel: Option<[f32; 3]>,
    pub gyro: Option<[f32; 3]>,
    pub x_cm: Option<f32>,
    pub y_cm: Option<f32>,
    pub velocity_cm_s: Option<[f32; 2]>,
    pub head_deg: Option<f32>,
    pub battery_v: Option<f32>,
    /// Battery voltage state: 1 ok, 2 low, 3 critical (Power 0x1C).
    pub battery_voltage_state: Option<u8>,
    pub stance: Stance,
    pub collisions: u32,
    pub last_collision: Option<CollisionSeen>,
    /// Recent locator positions, oldest first, bounded by [`TRACK_LEN`].
    pub track: VecDeque<(f32, f32)>,
    pub samples: u64,
    pub will_sleep: bool,
    pub asleep: bool,
    pub animations_completed: u32,
}

impl Default for Telemetry {
    fn default() -> Self {
        Telemetry {
            pitch: None,
            roll: None,
            yaw: None,
            accel: None,
            gyro: None,
            x_cm: None,
            y_cm: None,
            velocity_cm_s: None,
            head_deg: None,
            battery_v: None,
            battery_voltage_state: None,
            stance: Stance::Unknown,
            collisions: 0,
            last_collision: None,
            track: VecDeque::with_capacity(TRACK_LEN),
            samples: 0,
            will_sleep: false,
            asleep: false,
            animations_completed: 0,
        }
    }
}

impl Telemetry {
    /// Fold in a notification received at `at` (time since the session started).
    pub fn apply(&mut self, n: &Notification, at: Duration) {
        match n {
            Notification::Sensors(s) => {
                self.samples += 1;
                self.asleep = false;
                let triple = |a: &str, b: &str, c: &str| Some([s.get(a)?, s.get(b)?, s.get(c)?]);
                self.pitch = s.get("pitch").or(self.pitch);
                self.roll = s.get("roll").or(self.roll);
                self.yaw = s.get("yaw").or(self.yaw);
                self.accel = triple("accel_x", "accel_y", "accel_z").or(self.accel);
                self.gyro = triple("gyro_x", "gyro_y", "gyro_z").or(self.gyro);
                self.head_deg = s.get("head_angle").or(self.head_deg);
                if let (Some(vx), Some(vy)) = (s.get("velocity_x"), s.get("velocity_y")) {
                    self.velocity_cm_s = Some([vx, vy]);
                }
                if let (Some(x), Some(y)) = (s.get("locator_x"), s.get("locator_y")) {
                    self.x_cm = Some(x);
                    self.y_cm = Some(y);
                    let moved = self
                        .track
                        .back()
                        .is_none_or(|(px, py)| (px - x).abs() > 0.5 || (py - y).abs() > 0.5);
                    if moved {
                        if self.track.len() >= TRACK_LEN {
                            self.track.pop_front();
                        }
                        self.track.push_back((x, y));
                    }
                }
            }
            Notification::Collision(c) => {
                self.collisions += 1;
                self.last_collision = Some(CollisionSeen { at, collision: *c });
            }
            Notification::LegActionComplete => {
                self.stance = match self.stance {
                    Stance::Transitioning(to) => Stance::from_state(to),
                    other => other,
                };
            }
            Notification::AnimationComplete => self.animations_completed += 1,
            Notification::BatteryVoltageStateChanged(s) => self.battery_voltage_state = Some(*s),
            // v1: 1 charging, 2 OK, 3 low, 4 critical → the v2 scale 1 ok, 2 low, 3 critical.
            Notification::PowerState(s @ 2..=4) => self.battery_voltage_state = Some(s - 1),
            Notification::PowerState(_) => {}
            Notification::WillSleep => self.will_sleep = true,
            Notification::DidSleep => {
                self.asleep = true;
                self.will_sleep = false;
            }
            _ => {}
        }
    }

    /// A stance change was requested.
    pub fn stance_requested(&mut self, a: LegAction) {
        let target = match a {
            LegAction::Tripod => LegState::Tripod,
            LegAction::Bipod => LegState::Bipod,
            LegAction::Waddle => LegState::Waddle,
            // Stop ends a waddle on two legs.
            LegAction::Stop => LegState::Bipod,
        };
        self.stance = Stance::Transitioning(target);
    }

    /// Activity seen: the droid is awake.
    pub fn woke(&mut self) {
        self.will_sleep = false;
        self.asleep = false;
    }

    /// Measured speed in cm/s.
    pub fn speed_cm_s(&self) -> Option<f32> {
        self.velocity_cm_s.map(|[x, y]| (x * x + y * y).sqrt())
    }

    /// Measured heading: the yaw as a compass heading, 0..=359.
    pub fn heading(&self) -> Option<Heading> {
        self.yaw.map(|y| Heading::wrapped(y as f64))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::notify::SensorSample;

    fn sample(values: &[(&'static str, f32)]) -> Notification {
        Notification::Sensors(SensorSample {
            values: values.to_vec(),
        })
    }

    #[test]
    fn sensors_fill_gauges_and_track() {
        let mut t = Telemetry::default();
        t.apply(
            &sample(&[
                ("yaw", -90.0),
                ("locator_x", 10.0),
                ("locator_y", 5.0),
                ("velocity_x", 3.0),
                ("velocity_y", 4.0),
            ]),
            Duration::ZERO,
        );
        assert_eq!(t.heading().map(Heading::degrees), Some(270));
        assert_eq!(t.speed_cm_s(), Some(5.0));
        assert_eq!(t.track.len(), 1);
        // A sample without locator keeps the position.
        t.apply(&sample(&[("pitch", 2.0)]), Duration::ZERO);
        assert_eq!(t.x_cm, Some(10.0));
        assert_eq!(t.yaw, Some(-90.0));
    }

    #[test]
    fn track_is_bounded() {
        let mut t = Telemetry::default();
        for i in 0..(TRACK_LEN * 3) {
            t.apply(
                &sample(&[("locator_x", i as f32), ("locator_y", 0.0)]),
                Duration::ZERO,
            );
        }
        assert_eq!(t.track.len(), TRACK_LEN);
        assert_eq!(t.track.back(), Some(&((TRACK_LEN * 3 - 1) as f32, 0.0)));
    }

    #[test]
    fn battery_response() {
        assert_eq!(battery_volts(&[0x01, 0x9A]), Some(4.10));
        assert_eq!(battery_volts(&[0x01]), None);
        assert_eq!(battery_volts(&[0x01, 0x9A, 0]), None);
    }

    #[test]
    fn stance_and_collisions() {
        let mut t = Telemetry::default();
        t.stance_requested(LegAction::Tripod);
        assert_eq!(t.stance.label(), "→ tripod");
        t.apply(&Notification::LegActionComplete, Duration::ZERO);
        assert_eq!(t.stance, Stance::Tripod);
        t.apply(
            &Notification::Collision(Collision::default()),
            Duration::from_secs(3),
        );
        assert_eq!(t.collisions, 1);
        assert_eq!(t.last_collision.unwrap().at, Duration::from_secs(3));
        t.apply(&Notification::WillSleep, Duration::ZERO);
        assert!(t.will_sleep);
        t.apply(&Notification::DidSleep, Duration::ZERO);
        assert!(t.asleep && !t.will_sleep);
        // A v1 power notification lands on the same battery-state scale.
        t.apply(&Notification::PowerState(3), Duration::ZERO);
        assert_eq!(t.battery_voltage_state, Some(2));
        t.apply(&Notification::PowerState(1), Duration::ZERO);
        assert_eq!(t.battery_voltage_state, Some(2));
    }
}
