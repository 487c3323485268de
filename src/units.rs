//! Unit newtypes shared by the protocol core, the simulator, the control loop and the UI.
//!
//! The wire mixes degrees as `u16` (headings), degrees as `f32` (the dome), milliseconds and
//! centimetres; keeping each in its own type stops a heading from being passed where a dome
//! angle is expected.

use std::fmt;

/// A compass heading in whole degrees, 0..=359, clockwise, 0 = the droid's "forward"
/// as set by Reset Yaw (`droid-facts.md` §2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct Heading(u16);

impl Heading {
    pub const MAX: u16 = 359;

    /// A heading, rejecting values outside 0..=359.
    pub fn new(deg: u16) -> Option<Self> {
        (deg <= Self::MAX).then_some(Self(deg))
    }

    /// Any angle wrapped into 0..=359 (rounded to the nearest degree).
    pub fn wrapped(deg: f64) -> Self {
        let d = deg.rem_euclid(360.0).round() as i64 % 360;
        Self(d as u16)
    }

    pub fn degrees(self) -> u16 {
        self.0
    }

    /// The heading turned by `delta` degrees (positive = clockwise), wrapped.
    pub fn turned(self, delta: f64) -> Self {
        Self::wrapped(self.0 as f64 + delta)
    }

    /// The opposite heading, used when reversing (reference clients add 180°).
    pub fn reversed(self) -> Self {
        Self((self.0 + 180) % 360)
    }
}

impl fmt::Display for Heading {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}°", self.0)
    }
}

/// An angle in degrees as a float (dome position, attitude).
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Default)]
pub struct Degrees(pub f32);

impl fmt::Display for Degrees {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:.1}°", self.0)
    }
}

/// The dome's commandable range, −160..=180° (`droid-facts.md` §2; the seed's radians are wrong).
pub const HEAD_MIN_DEG: f32 = -160.0;
pub const HEAD_MAX_DEG: f32 = 180.0;

/// A dome angle within −160..=180°.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Default)]
pub struct HeadAngle(f32);

impl HeadAngle {
    pub fn new(deg: f32) -> Option<Self> {
        (deg.is_finite() && (HEAD_MIN_DEG..=HEAD_MAX_DEG).contains(&deg)).then_some(Self(deg))
    }

    /// Clamp any finite angle into the dome's range (NaN becomes 0).
    pub fn clamped(deg: f32) -> Self {
        if deg.is_nan() {
            return Self(0.0);
        }
        Self(deg.clamp(HEAD_MIN_DEG, HEAD_MAX_DEG))
    }

    pub fn degrees(self) -> f32 {
        self.0
    }
}

/// A duration in milliseconds as carried on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct Ms(pub u32);

impl From<Ms> for std::time::Duration {
    fn from(ms: Ms) -> Self {
        std::time::Duration::from_millis(ms.0 as u64)
    }
}

/// A distance in centimetres.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Default)]
pub struct Cm(pub f32);

/// A speed in centimetres per second.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Default)]
pub struct CmPerSec(pub f32);

/// A battery voltage in volts.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Default)]
pub struct Volts(pub f32);

/// `v` without the sign of a zero: -0.0 is 0.0. Text and JSON never show a negative zero
/// (`pitch=-0.0`, `"pitch_deg":-0.0`: issue 30); values pass through this where they are
/// formatted or serialized.
pub fn signless(v: f64) -> f64 {
    if v == 0.0 { 0.0 } else { v }
}

/// [`signless`] for f32 readings.
pub fn signless32(v: f32) -> f32 {
    if v == 0.0 { 0.0 } else { v }
}

/// `v` with `prec` decimals, never `-0` or `-0.00`: a value that rounds to zero prints as zero.
pub fn fixed(v: f64, prec: usize) -> String {
    let s = format!("{:.prec$}", signless(v));
    match s.strip_prefix('-') {
        Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest.to_string(),
        _ => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_negative_zeros() {
        assert_eq!(fixed(-0.3, 0), "0");
        assert_eq!(fixed(-0.004, 2), "0.00");
        assert_eq!(fixed(-0.0, 1), "0.0");
        assert_eq!(fixed(-0.6, 0), "-1");
        assert_eq!(fixed(-1.25, 1), "-1.2");
        assert_eq!(signless(-0.0).to_string(), "0");
        assert_eq!(signless32(-0.0).to_string(), "0");
    }

    #[test]
    fn heading_range_and_wrap() {
        assert_eq!(Heading::new(359).map(Heading::degrees), Some(359));
        assert_eq!(Heading::new(360), None);
        assert_eq!(Heading::wrapped(-90.0).degrees(), 270);
        assert_eq!(Heading::wrapped(720.4).degrees(), 0);
        assert_eq!(Heading::wrapped(359.6).degrees(), 0);
        assert_eq!(Heading::new(10).unwrap().turned(-20.0).degrees(), 350);
        assert_eq!(Heading::new(270).unwrap().reversed().degrees(), 90);
    }

    #[test]
    fn head_angle_range() {
        assert!(HeadAngle::new(180.0).is_some());
        assert!(HeadAngle::new(-160.0).is_some());
        assert!(HeadAngle::new(180.5).is_none());
        assert!(HeadAngle::new(f32::NAN).is_none());
        assert_eq!(HeadAngle::clamped(-500.0).degrees(), -160.0);
        assert_eq!(HeadAngle::clamped(f32::NAN).degrees(), 0.0);
    }
}
