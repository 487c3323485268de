//! The remote-control service: the two bytes droidctl writes, and what the robot makes of them.
//!
//! Velocity and steering are each one byte, written to their own characteristic of the
//! remote-control service ([`crate::family::robi::gatt::ROBI_VELOCITY`],
//! [`crate::family::robi::gatt::ROBI_STEERING`]). The spec (`robi-rsrcp.md`) is read-only and says
//! nothing about them; everything here is `droid-facts.md` §5, which describes the Robi42Lib
//! firmware (`RobiLive`).

/// The steering byte for "straight": 0 maps to 128 (128/255 ≈ 0.502). The firmware has no dead
/// band, so 128 steers very slightly right (s' ≈ +0.004) and 127 very slightly left; 128 is
/// the rounding of 127.5 and what [`steering_byte`]`(0.0)` gives.
pub const STEERING_STRAIGHT: u8 = 128;

/// Each side drives its stepper at side × 30 000 Hz (`droid-facts.md` §5).
pub const STEPPER_MAX_HZ: f32 = 30_000.0;
/// Below this step rate the firmware switches the stepper off (`droid-facts.md` §5).
pub const STEPPER_MIN_HZ: f32 = 100.0;

/// Forward speed 0..1 to the velocity byte (×255, rounded). The robot drives forward only (its
/// motor direction is fixed at start-up), so negative values are 0; above 1 is 1; NaN is 0 (stop).
pub fn velocity_byte(v: f32) -> u8 {
    if v.is_nan() {
        return 0;
    }
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// Steering −1 (full left) .. 0 (straight) .. +1 (full right) to the steering byte, which the
/// robot reads as byte/255 with 0.5 straight. Clamped; NaN steers straight
/// ([`STEERING_STRAIGHT`]).
pub fn steering_byte(s: f32) -> u8 {
    if s.is_nan() {
        return STEERING_STRAIGHT;
    }
    ((s.clamp(-1.0, 1.0) + 1.0) * 0.5 * 255.0).round() as u8
}

/// The firmware's differential mix, each side in 0..1 (`droid-facts.md` §5):
/// v = vb/255, s = sb/255, s' = 2(s − 0.5), left = clamp01(v(1 + s')),
/// right = clamp01(v(1 − s')). Full steering turns on the spot only in the sense that the
/// inner wheel stops: the robot cannot reverse a side.
pub fn wheel_speeds(velocity_byte: u8, steering_byte: u8) -> (f32, f32) {
    let v = f32::from(velocity_byte) / 255.0;
    let s = f32::from(steering_byte) / 255.0;
    let sp = 2.0 * (s - 0.5);
    let clamp01 = |x: f32| x.clamp(0.0, 1.0);
    (clamp01(v * (1.0 + sp)), clamp01(v * (1.0 - sp)))
}

/// The step rate a side in 0..1 drives its stepper at: side × [`STEPPER_MAX_HZ`], or 0 when
/// that is below [`STEPPER_MIN_HZ`] (the firmware switches the stepper off).
pub fn stepper_hz(side: f32) -> f32 {
    let hz = side.clamp(0.0, 1.0) * STEPPER_MAX_HZ;
    if hz < STEPPER_MIN_HZ { 0.0 } else { hz }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes() {
        assert_eq!(velocity_byte(0.0), 0);
        assert_eq!(velocity_byte(1.0), 255);
        assert_eq!(velocity_byte(0.5), 128);
        assert_eq!(velocity_byte(-0.3), 0);
        assert_eq!(velocity_byte(7.0), 255);
        assert_eq!(velocity_byte(f32::NAN), 0);
        assert_eq!(steering_byte(-1.0), 0);
        assert_eq!(steering_byte(0.0), STEERING_STRAIGHT);
        assert_eq!(steering_byte(1.0), 255);
        assert_eq!(steering_byte(-5.0), 0);
        assert_eq!(steering_byte(f32::NAN), STEERING_STRAIGHT);
    }

    #[test]
    fn mix() {
        assert_eq!(wheel_speeds(0, 0), (0.0, 0.0));
        assert_eq!(wheel_speeds(255, 0), (0.0, 1.0));
        assert_eq!(wheel_speeds(255, 255), (1.0, 0.0));
        let (l, r) = wheel_speeds(255, STEERING_STRAIGHT);
        assert_eq!(l, 1.0);
        assert!((r - 0.996).abs() < 1e-3, "{r}");
        assert_eq!(stepper_hz(1.0), 30_000.0);
        assert_eq!(stepper_hz(0.003), 0.0);
        assert!((stepper_hz(0.005) - 150.0).abs() < 0.01);
    }
}
