//! One droid's motion as the bridge holds it (sans-IO: the caller passes the time): the last
//! drive or twist, re-sent so the droid's own fail-safe never stops it while commands keep
//! coming, a twist's yaw rate integrated into a heading, and the command timeout — like ROS
//! drivers' `cmd_vel_timeout`, a droid that got no drive or twist for the timeout is stopped.
//!
//! The bridge's control task calls [`Motion::tick`] every [`TICK`] under `tokio::time`.

use std::time::Duration;

/// How often the bridge's control task ticks.
pub const TICK: Duration = Duration::from_millis(50);

/// How often a held drive is re-sent: well within the droids' 2 s motion fail-safe, as
/// missions re-send theirs.
pub const HEARTBEAT: Duration = Duration::from_millis(500);

/// What the droid's wheels should do, for the family to turn into its command.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Wheels {
    /// Roll at `speed` toward `heading` (degrees 0..=359), backwards when `reverse`.
    Roll {
        speed: u8,
        heading: u16,
        reverse: bool,
    },
    /// A steering robot (Robi 42): speed and turn −1 (full left) ..= 1 (full right).
    Steer { speed: u8, turn: f32 },
}

impl Wheels {
    pub fn speed(&self) -> u8 {
        match self {
            Wheels::Roll { speed, .. } | Wheels::Steer { speed, .. } => *speed,
        }
    }
}

/// How a droid moves, for turning m/s and rad/s into its commands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kinematics {
    /// It steers (Robi 42) instead of rolling toward a heading.
    pub steers: bool,
    /// It can roll backwards (`false`: a negative speed is refused).
    pub can_reverse: bool,
    /// Its speed at 255, m/s.
    pub top_speed_m_s: f32,
    /// For a steering robot: the yaw rate at full lock, rad/s.
    pub full_lock_rad_s: f32,
}

/// What a motion command asks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    Drive { speed: u8, heading: u16 },
    Twist { linear: f32, angular: f32 },
}

/// What [`Holder::tick`] wants done.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tick {
    Nothing,
    /// Write this drive (a heartbeat, or a twist's new heading).
    Send(Wheels),
    /// The command timeout passed: stop the droid (once).
    TimedOut,
}

/// Why a motion command cannot be done by this droid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CannotReverse;

/// One droid's held motion.
#[derive(Debug, Clone)]
pub struct Holder {
    kin: Kinematics,
    timeout: Duration,
    held: Option<Motion>,
    /// When the last motion command came.
    last_cmd: Duration,
    /// When the held drive was last written.
    last_sent: Duration,
    /// Up to when a twist's yaw rate has been integrated.
    integrated_at: Duration,
    /// A twist's heading, integrated (degrees, clockwise as Sphero counts).
    heading: f32,
    last_wheels: Option<Wheels>,
}

impl Holder {
    pub fn new(kin: Kinematics, timeout: Duration) -> Holder {
        Holder {
            kin,
            timeout,
            held: None,
            last_cmd: Duration::ZERO,
            last_sent: Duration::ZERO,
            integrated_at: Duration::ZERO,
            heading: 0.0,
            last_wheels: None,
        }
    }

    /// Whether a motion is held (the droid is being driven over the bridge).
    pub fn is_driving(&self) -> bool {
        self.held.is_some()
    }

    /// A drive or twist at `now`: the wheels to write now.
    pub fn command(&mut self, now: Duration, m: Motion) -> Result<Wheels, CannotReverse> {
        if let (Motion::Twist { .. }, Some(Motion::Twist { .. })) = (m, self.held) {
            // Turn for the time since the last twist before the new rate applies.
            self.integrate(now);
        }
        let w = self.wheels(m)?;
        if let Motion::Drive { heading, .. } = m {
            self.heading = heading as f32;
        }
        self.held = Some(m);
        self.last_cmd = now;
        self.last_sent = now;
        self.integrated_at = now;
        self.last_wheels = Some(w);
        Ok(w)
    }

    /// The wheels of the motion held now, if one is.
    pub fn current(&self) -> Option<Wheels> {
        self.held.and(self.last_wheels)
    }

    /// A stop (asked, an e-stop, or the link to the client lost): nothing is held.
    pub fn stop(&mut self) {
        self.held = None;
    }

    /// The heading the droid was last sent (a stop keeps it).
    pub fn heading(&self) -> u16 {
        (self.heading.rem_euclid(360.0).round() as u16) % 360
    }

    /// Advance to `now`.
    pub fn tick(&mut self, now: Duration) -> Tick {
        let Some(m) = self.held else {
            return Tick::Nothing;
        };
        if now.saturating_sub(self.last_cmd) >= self.timeout {
            self.held = None;
            return Tick::TimedOut;
        }
        if let Motion::Twist { .. } = m {
            self.integrate(now);
            if let Ok(w) = self.wheels(m)
                && (Some(w) != self.last_wheels || now.saturating_sub(self.last_sent) >= HEARTBEAT)
            {
                self.last_sent = now;
                self.last_wheels = Some(w);
                return Tick::Send(w);
            }
            return Tick::Nothing;
        }
        if now.saturating_sub(self.last_sent) >= HEARTBEAT
            && let Some(w) = self.last_wheels
        {
            self.last_sent = now;
            return Tick::Send(w);
        }
        Tick::Nothing
    }

    /// A rolling droid turns its heading at a twist's yaw rate (positive: left, so the
    /// clockwise heading decreases).
    fn integrate(&mut self, now: Duration) {
        if let Some(Motion::Twist { angular, .. }) = self.held
            && !self.kin.steers
        {
            let dt = now.saturating_sub(self.integrated_at).as_secs_f32();
            self.heading = (self.heading - angular.to_degrees() * dt).rem_euclid(360.0);
        }
        self.integrated_at = now;
    }

    fn wheels(&self, m: Motion) -> Result<Wheels, CannotReverse> {
        let k = &self.kin;
        match m {
            Motion::Drive { speed, heading } if k.steers => Ok(Wheels::Steer {
                speed,
                // A steering robot reads the heading as a turn: 0 straight, 90 full right.
                turn: {
                    let d = heading as f32;
                    let signed = if d > 180.0 { d - 360.0 } else { d };
                    (signed / 90.0).clamp(-1.0, 1.0)
                },
            }),
            Motion::Drive { speed, heading } => Ok(Wheels::Roll {
                speed,
                heading,
                reverse: false,
            }),
            Motion::Twist { linear, angular } => {
                if linear < 0.0 && !k.can_reverse {
                    return Err(CannotReverse);
                }
                let speed = (linear.abs() / k.top_speed_m_s.max(0.01) * 255.0)
                    .round()
                    .clamp(0.0, 255.0) as u8;
                if k.steers {
                    let turn = (-angular / k.full_lock_rad_s.max(0.01)).clamp(-1.0, 1.0);
                    return Ok(Wheels::Steer { speed, turn });
                }
                Ok(Wheels::Roll {
                    speed,
                    heading: self.heading(),
                    reverse: linear < 0.0,
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const ROLLER: Kinematics = Kinematics {
        steers: false,
        can_reverse: true,
        top_speed_m_s: 1.6,
        full_lock_rad_s: 1.0,
    };
    const ROBI: Kinematics = Kinematics {
        steers: true,
        can_reverse: false,
        top_speed_m_s: 0.3,
        full_lock_rad_s: 1.0,
    };

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    #[test]
    fn a_drive_is_held_then_times_out_once() {
        let mut h = Holder::new(ROLLER, ms(600));
        let w = h
            .command(
                ms(0),
                Motion::Drive {
                    speed: 100,
                    heading: 90,
                },
            )
            .unwrap();
        assert_eq!(
            w,
            Wheels::Roll {
                speed: 100,
                heading: 90,
                reverse: false
            }
        );
        assert_eq!(h.tick(ms(250)), Tick::Nothing);
        assert!(matches!(h.tick(ms(550)), Tick::Send(_)), "the heartbeat");
        assert_eq!(h.tick(ms(599)), Tick::Nothing);
        assert_eq!(h.tick(ms(600)), Tick::TimedOut);
        assert_eq!(h.tick(ms(650)), Tick::Nothing, "stopped once");
        assert!(!h.is_driving());
        assert_eq!(h.heading(), 90, "a stop keeps the heading");
    }

    #[test]
    fn each_drive_restarts_the_timeout() {
        let mut h = Holder::new(ROLLER, ms(600));
        let d = Motion::Drive {
            speed: 50,
            heading: 0,
        };
        for t in (0..3000).step_by(400) {
            h.command(ms(t), d).unwrap();
            assert_ne!(h.tick(ms(t + 399)), Tick::TimedOut);
        }
        assert_eq!(h.tick(ms(2800 + 600)), Tick::TimedOut);
    }

    #[test]
    fn a_twist_turns_left_for_positive_yaw_and_scales_speed() {
        let mut h = Holder::new(ROLLER, ms(600));
        let w = h
            .command(
                ms(0),
                Motion::Twist {
                    linear: 0.8,
                    angular: std::f32::consts::FRAC_PI_2,
                },
            )
            .unwrap();
        assert_eq!(w.speed(), 128, "0.8 m/s of 1.6 at 255");
        // Half a second at 90°/s to the left: heading 0 → 315.
        let mut last = None;
        for t in (50..=500).step_by(50) {
            if let Tick::Send(w) = h.tick(ms(t)) {
                last = Some(w);
            }
        }
        match last {
            Some(Wheels::Roll { heading, .. }) => assert_eq!(heading, 315),
            other => panic!("{other:?}"),
        }
        // Backwards: reverse, same heading.
        let w = h
            .command(
                ms(500),
                Motion::Twist {
                    linear: -0.32,
                    angular: 0.0,
                },
            )
            .unwrap();
        assert_eq!(
            w,
            Wheels::Roll {
                speed: 51,
                heading: 315,
                reverse: true
            }
        );
    }

    #[test]
    fn a_steering_robot_steers_and_cannot_reverse() {
        let mut h = Holder::new(ROBI, ms(600));
        let w = h
            .command(
                ms(0),
                Motion::Twist {
                    linear: 0.3,
                    angular: 0.5,
                },
            )
            .unwrap();
        assert_eq!(
            w,
            Wheels::Steer {
                speed: 255,
                turn: -0.5
            }
        );
        assert_eq!(
            h.command(
                ms(10),
                Motion::Twist {
                    linear: -0.1,
                    angular: 0.0
                }
            ),
            Err(CannotReverse)
        );
        let w = h
            .command(
                ms(20),
                Motion::Drive {
                    speed: 40,
                    heading: 270,
                },
            )
            .unwrap();
        assert_eq!(
            w,
            Wheels::Steer {
                speed: 40,
                turn: -1.0
            }
        );
    }

    proptest! {
        /// Whatever the commands and their timing, the droid is stopped within one tick of
        /// the timeout after the last motion command, and never before it.
        #[test]
        fn never_driving_past_the_timeout(
            gaps in proptest::collection::vec(0u64..1500, 1..20),
            timeout_ms in 100u64..3000,
            linear in -2.0f32..2.0,
            angular in -10.0f32..10.0,
        ) {
            let mut h = Holder::new(ROLLER, ms(timeout_ms));
            let mut now = 0;
            let mut last_cmd = 0;
            for g in gaps {
                let until = now + g;
                while now + 50 <= until {
                    now += 50;
                    let t = h.tick(ms(now));
                    if t == Tick::TimedOut {
                        prop_assert!(now - last_cmd >= timeout_ms);
                    }
                    if h.is_driving() {
                        prop_assert!(now - last_cmd < timeout_ms);
                    }
                }
                now = until;
                h.command(ms(now), Motion::Twist { linear, angular }).unwrap();
                last_cmd = now;
            }
            // Then nothing more: stopped by timeout + one tick.
            let mut stopped = false;
            for _ in 0..(timeout_ms / 50 + 2) {
                now += 50;
                if h.tick(ms(now)) == Tick::TimedOut {
                    stopped = true;
                }
            }
            prop_assert!(stopped && !h.is_driving());
            prop_assert!(h.heading() < 360);
        }
    }
}
