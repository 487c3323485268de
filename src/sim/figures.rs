//! Each simulated model's own physical figures: how close its centre comes to a wall (half
//! its width), how fast it turns to a new heading, and how far apart its drive wheels are (for
//! raw motor power, which turns the body by the difference of the two sides).
//!
//! `droid-facts.md` gives none of these. Turn rates are spherov2.py's (`sphero_edu.py`,
//! `SpheroEduAPI.spin`: its least time per revolution, `time_pre_rev`, the pace at which it
//! moves the target heading: 0.45 s by default, which covers BOLT and BB-9E; 0.5 s Mini;
//! 0.6 s Ollie, and BB-8 and SPRK+, whose classes there derive from Ollie's (`toy/bb8.py`,
//! `toy/sprk2.py`); 0.7 s R2-D2 and R2-Q5; 1.5 s RVR). Issue 32 point 1: at one 180°/s for
//! every model a spin fell behind that pace. Sizes are the makers' published
//! product dimensions (*unverified*: a single source each, kept here to be changed): Mini
//! 42 mm across; BOLT, SPRK+ and BB-8's ball 73 mm; BB-9E's ball about 80 mm; Ollie 114 mm
//! across its wheels; R2-D2 and R2-Q5 about 12 cm across the legs; RVR about 22 cm long.

use crate::model::Model;

/// One model's figures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Figures {
    /// Half the droid's width, cm.
    pub radius_cm: f32,
    /// Fastest turn toward a commanded heading, °/s.
    pub turn_rate_deg_s: f32,
    /// Distance between the drive wheels, cm (raw motors). *Unverified*: for the balls, the
    /// inner drive's wheels run near the shell, so about the ball's width.
    pub track_cm: f32,
}

/// °/s for spherov2's least time per revolution.
const fn per_rev(seconds: f32) -> f32 {
    360.0 / seconds
}

/// The model's figures; `None` for Robi 42, whose simulator front has its own.
pub fn of(model: Model) -> Option<Figures> {
    let f = |diameter_cm: f32, rev_s: f32, track_cm: f32| Figures {
        radius_cm: diameter_cm / 2.0,
        turn_rate_deg_s: per_rev(rev_s),
        track_cm,
    };
    Some(match model {
        Model::Mini => f(4.2, 0.5, 3.6),
        // BOLT+'s shell as BOLT's (unverified: no published dimension of its own).
        Model::Bolt | Model::BoltPlus => f(7.3, 0.45, 6.4),
        Model::SprkPlus | Model::BB8 => f(7.3, 0.6, 6.4),
        Model::BB9E => f(8.0, 0.45, 7.0),
        Model::Ollie => f(11.4, 0.6, 11.4),
        Model::R2D2 | Model::R2Q5 => f(12.0, 0.7, 10.0),
        Model::Rvr => f(22.0, 1.5, 18.0),
        Model::Robi42 => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_model_turns_a_spin_at_spherov2_pace_and_has_its_own_size() {
        let mini = of(Model::Mini).unwrap();
        assert!(
            (mini.radius_cm - 2.1).abs() < 1e-6,
            "the Mini is 4.2 cm across"
        );
        assert!((mini.turn_rate_deg_s - 720.0).abs() < 1e-3);
        assert!((of(Model::Bolt).unwrap().turn_rate_deg_s - 800.0).abs() < 1e-3);
        assert!((of(Model::Ollie).unwrap().turn_rate_deg_s - 600.0).abs() < 1e-3);
        assert!(of(Model::R2D2).unwrap().turn_rate_deg_s > 500.0);
        assert!((of(Model::Rvr).unwrap().turn_rate_deg_s - 240.0).abs() < 1e-3);
        assert_eq!(of(Model::Robi42), None);
    }
}
