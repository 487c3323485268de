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

/// The unwrapped angle of `heading` (0..360) for a drive command: the one nearest the last
/// commanded target `last` (commands a spin sends arrive a few degrees apart, so nearest the
/// last one follows the spin through 360), but never more than one turn from where the body
/// faces, `yaw` (a target that ran further ahead drops its whole turns).
pub fn unwrap_toward(last: f32, yaw: f32, heading: f32) -> f32 {
    let mut t = last + angle_diff(last, heading);
    while t - yaw > 360.0 {
        t -= 360.0;
    }
    while yaw - t > 360.0 {
        t += 360.0;
    }
    t
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

    #[test]
    fn a_spins_targets_unwrap_the_way_it_goes() {
        // A spin's targets a few degrees apart go on past 360, however far the body lags.
        let mut t = 0.0;
        for h in (0..=360).step_by(9) {
            t = unwrap_toward(t, 10.0, (h % 360) as f32);
        }
        assert_eq!(t, 360.0);
        // Backwards too.
        assert_eq!(unwrap_toward(-350.0, -300.0, 0.0), -360.0);
        // Never more than a turn ahead of the body.
        assert_eq!(unwrap_toward(700.0, 0.0, 20.0), 20.0);
    }
}
