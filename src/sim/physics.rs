//! Motion: speed ramps, turning, dead reckoning and walls. Heading 0 → +y, 90 → +x, in cm.

/// Shortest signed angle from `from` to `to`, in −180..=180.
pub fn angle_diff(from: f32, to: f32) -> f32 {
    let mut d = (to - from) % 360.0;
    if d > 180.0 {
        d -= 360.0;
    } else if d < -180.0 {
        d += 360.0;
    }
    d
}

/// Move `value` toward `target` by at most `max_step`.
pub fn approach(value: f32, target: f32, max_step: f32) -> f32 {
    if (target - value).abs() <= max_step {
        target
    } else {
        value + max_step * (target - value).signum()
    }
}

/// Wrap an angle into 0..360.
pub fn wrap360(a: f32) -> f32 {
    let w = a.rem_euclid(360.0);
    if w >= 360.0 { 0.0 } else { w }
}

/// Unit vector of a compass heading (0 → +y, 90 → +x).
pub fn heading_vector(deg: f32) -> (f32, f32) {
    let r = deg.to_radians();
    (r.sin(), r.cos())
}

/// Which walls a position has crossed, and the position clamped inside.
pub fn clamp_to_room(x: f32, y: f32, half_w: f32, half_h: f32) -> ((f32, f32), bool, bool) {
    let cx = x.clamp(-half_w, half_w);
    let cy = y.clamp(-half_h, half_h);
    ((cx, cy), cx != x, cy != y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angles() {
        assert_eq!(angle_diff(350.0, 10.0), 20.0);
        assert_eq!(angle_diff(10.0, 350.0), -20.0);
        assert_eq!(wrap360(-90.0), 270.0);
        assert_eq!(approach(0.0, 10.0, 3.0), 3.0);
        assert_eq!(approach(9.0, 10.0, 3.0), 10.0);
        let (x, y) = heading_vector(90.0);
        assert!((x - 1.0).abs() < 1e-6 && y.abs() < 1e-6);
        let ((cx, _), hx, hy) = clamp_to_room(250.0, 0.0, 190.0, 190.0);
        assert_eq!((cx, hx, hy), (190.0, true, false));
    }
}
