//! A collision as the droid's own detector reports it: in the robot's axes, as its streamed
//! accelerometer is (y forward, x to its right), so a head-on hit is on y whichever way the
//! droid faces in the room. (Fix, issue 32 point 2: the simulator reported hits in the room's
//! axes, so a droid rolling at heading 90 into the east wall reported the hit on x while its
//! streamed accelerometer braked on y; the detector is the droid's IMU, which knows no room.)

use super::physics::heading_vector;
use crate::protocol::notify::Collision;
use crate::protocol::wire::{AccelRaw, CollisionAxis};

/// The simulator's impact power per axis: the speed into the obstacle along that axis, cm/s,
/// times this. A model of ours (no source gives the droids' power scale): with it the default
/// thresholds (100 + 100 × speed) report a bump at a quarter of cruise speed, and a threshold
/// of 250 ignores it.
pub const POWER_PER_CM_S: f32 = 8.0;

/// The impact's deceleration is spread over this long, s.
const IMPACT_TIME_S: f32 = 0.05;

/// Collision detection's thresholds as configured: per axis, the power to exceed and the
/// speed term added to it (`crate::family::collision`). Robot axes: x across, y forward.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CollisionThresholds {
    pub x_threshold: u8,
    pub y_threshold: u8,
    pub x_speed: u8,
    pub y_speed: u8,
}

impl Default for CollisionThresholds {
    /// The common default of the reference clients (`droid-facts.md` §2: 90, 130, 90, 130).
    fn default() -> Self {
        CollisionThresholds {
            x_threshold: 90,
            y_threshold: 130,
            x_speed: 90,
            y_speed: 130,
        }
    }
}

impl CollisionThresholds {
    /// Which axes an impact of `power` (x, y) at `speed` (0..=255 of top speed) trips: a
    /// threshold of 0 turns its axis off; the speed term raises it as the droid goes faster.
    pub fn tripped(&self, power: (f32, f32), speed: u8) -> (bool, bool) {
        let over = |p: f32, t: u8, s: u8| t > 0 && p > t as f32 + s as f32 * speed as f32 / 255.0;
        (
            over(power.0, self.x_threshold, self.x_speed),
            over(power.1, self.y_threshold, self.y_speed),
        )
    }
}

/// A room vector (x east, y north) in the axes of a robot facing `yaw_deg`: (to its right,
/// ahead of it).
pub fn to_robot_axes(v: (f32, f32), yaw_deg: f32) -> (f32, f32) {
    let (fx, fy) = heading_vector(yaw_deg);
    // Right of the facing: the facing turned a quarter clockwise.
    let (rx, ry) = (fy, -fx);
    (v.0 * rx + v.1 * ry, v.0 * fx + v.1 * fy)
}

/// What the detector of a droid facing `yaw_deg` reports for an impact: `impact` is the
/// velocity it lost against the obstacle in room axes (cm/s, pointing at the obstacle),
/// `speed` its speed byte (0..=255 of top speed). `None` when no axis's power passes its
/// threshold (a gentle bump under a hard threshold is felt and not reported).
pub fn detect(
    thresholds: &CollisionThresholds,
    yaw_deg: f32,
    impact: (f32, f32),
    speed: u8,
    time_ms: u32,
) -> Option<Collision> {
    let (ix, iy) = to_robot_axes(impact, yaw_deg);
    let power = (ix.abs() * POWER_PER_CM_S, iy.abs() * POWER_PER_CM_S);
    let (x, y) = thresholds.tripped(power, speed);
    if !(x || y) {
        return None;
    }
    // The body decelerates against the impact, in g (÷4096 on the wire).
    let g =
        |i: f32| AccelRaw((-i / IMPACT_TIME_S / 981.0 * 4096.0).clamp(-32768.0, 32767.0) as i16);
    let signed = |i: f32| (i * POWER_PER_CM_S).clamp(-32768.0, 32767.0) as i16;
    Some(Collision {
        accel: [g(ix), g(iy), AccelRaw(4096)],
        axis: CollisionAxis { x, y },
        power: [signed(ix), signed(iy), 0],
        speed,
        time_ms,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_head_on_hit_is_on_the_forward_axis_whichever_way_the_droid_faces() {
        for yaw in [0.0f32, 90.0, 180.0, 270.0, 45.0] {
            let (fx, fy) = heading_vector(yaw);
            let c = detect(
                &CollisionThresholds::default(),
                yaw,
                (fx * 100.0, fy * 100.0),
                160,
                7,
            )
            .expect("a hit at 100 cm/s trips the default thresholds");
            assert_eq!(c.axis, CollisionAxis { x: false, y: true }, "yaw {yaw}");
            assert!(c.accel[1].g() < -1.0, "braking ahead: {c:?}");
            assert!(c.accel[0].g().abs() < 0.01, "nothing across: {c:?}");
        }
        // A hit on the droid's right side (facing north, struck from the east) is on x.
        let c = detect(&CollisionThresholds::default(), 0.0, (100.0, 0.0), 0, 0).unwrap();
        assert_eq!(c.axis, CollisionAxis { x: true, y: false });
        assert!(c.power[0] > 0 && c.power[1] == 0, "{c:?}");
    }

    #[test]
    fn robot_axes() {
        let close =
            |a: (f32, f32), b: (f32, f32)| (a.0 - b.0).abs() < 1e-4 && (a.1 - b.1).abs() < 1e-4;
        assert!(close(to_robot_axes((0.0, 1.0), 0.0), (0.0, 1.0)));
        assert!(close(to_robot_axes((1.0, 0.0), 90.0), (0.0, 1.0)));
        // Facing east, north is on its left.
        assert!(close(to_robot_axes((0.0, 1.0), 90.0), (-1.0, 0.0)));
    }
}
