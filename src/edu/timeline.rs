//! A timed call's steps (`spin`'s headings, `fade`'s colours, `strobe`'s blinks, `roll`'s and
//! `rawMotor`'s stop), made one at a time when due rather than listed up front: a pending
//! call is a few numbers whatever its duration or count, and a step is a function of its
//! index (issue 37: 990 pending `spin`s once listed 7 GB of steps).
//!
//! Every step says the whole state it sets (a heading to drive toward, a colour for the main
//! light), so a player that is late may play only the last step due and skip the ones before
//! it: the robot ends where it would have, as spherov2's time-driven loops (`spin`, `fade`)
//! do when its link is slow. Sans-IO: [`super::run`] plays it on droidctl's clock.
//!
//! `spin` is paced by its link, not by a clock ([`Timeline::paced`]): each of its steps is
//! made when the one before it was answered, its heading a function of the time since the
//! call ([`Timeline::spin_step`]), as spherov2's `SpheroEduAPI.spin` does.

use super::api::{Act, Driver, STEP};
use std::time::Duration;

/// What a timed call does over time.
#[derive(Debug, Clone, PartialEq)]
pub enum Steps {
    /// Nothing: the call only waits (`delay`, `scrollMatrixText`, `speak`).
    None,
    /// One step (`roll`'s stop, `rawMotor`'s stop).
    Once(Duration, Vec<Act>),
    /// `spin` over `d`: a step made `elapsed` after the call drives at `speed` toward `from`
    /// turned by [`spin_turned`] degrees in `angle`'s direction; the first at 0, each next
    /// once the one before was answered, the last the first to turn the whole `|angle|`
    /// ([`Timeline::spin_step`]). Its promise resolves once that last step is answered.
    Spin {
        from: i64,
        angle: i64,
        speed: i64,
        d: Duration,
    },
    /// `fade`: `count − 1` mixes, [`STEP`] apart from the first at [`STEP`], then `to` at `d`.
    Fade {
        from: [u8; 3],
        to: [u8; 3],
        d: Duration,
        count: u64,
    },
    /// `strobe`: `2 · count` steps `period` apart from 0, dark first, then `rgb`, in turn.
    Strobe {
        rgb: [u8; 3],
        period: Duration,
        count: u64,
    },
}

/// A timed call: its steps, and when its promise resolves (after the last step).
#[derive(Debug, Clone, PartialEq)]
pub struct Timeline {
    pub steps: Steps,
    pub end: Duration,
}

/// Degrees a `spin` of `|angle|` = `total` over `d` has turned `elapsed` after the call:
/// `round(min(elapsed / d, 1) · total)`, rounding half to even.
///
/// Source: spherov2's `SpheroEduAPI.spin` (sphero_edu.py): it loops while the degrees gone
/// are short of `abs(angle)`, each time sending the heading turned by
/// `round(min((time.time() - start) / duration, 1.) * abs_angle)` with Python's `round`
/// (half to even) and waiting for the droid's answer; its first step, at 0 s, turns 0°, and
/// its last goes once that rounds to the whole angle ("performance of spin is guaranteed,
/// but may be longer than the specified duration", its docstring says). Sphero's own Edu
/// documentation says nothing of how a spin is paced, so spherov2, the field's library, is
/// the judge (tests/it/edu_twins.rs, `figure_eight`).
pub fn spin_turned(total: u64, d: Duration, elapsed: Duration) -> u64 {
    let f = if d.is_zero() {
        1.0
    } else {
        (elapsed.as_secs_f64() / d.as_secs_f64()).min(1.0)
    };
    // `total` is at most a few million degrees (MAX_SECONDS): exact in f64.
    (f * total as f64)
        .round_ties_even()
        .clamp(0.0, total as f64) as u64
}

/// `d · k`, saturating (no step is past [`super::api::MAX_SECONDS`] anyway).
fn times(d: Duration, k: u64) -> Duration {
    let n = d.as_nanos().saturating_mul(u128::from(k));
    Duration::from_nanos(u64::try_from(n).unwrap_or(u64::MAX))
}

impl Timeline {
    /// A wait with no step.
    pub fn wait(end: Duration) -> Timeline {
        Timeline {
            steps: Steps::None,
            end,
        }
    }

    /// How many steps.
    pub fn len(&self) -> u64 {
        match &self.steps {
            Steps::None => 0,
            Steps::Once(..) => 1,
            // Paced: made one at a time as answers come ([`Timeline::spin_step`]), not
            // counted up front; at least one.
            Steps::Spin { .. } => 1,
            Steps::Fade { count, .. } => (*count).max(1),
            Steps::Strobe { count, .. } => count.saturating_mul(2),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// When step `i` (0-based, below [`Timeline::len`]) is due, since the call.
    pub fn at(&self, i: u64) -> Duration {
        match &self.steps {
            Steps::None => self.end,
            Steps::Once(at, _) => *at,
            Steps::Spin { .. } => Duration::ZERO,
            Steps::Fade { d, .. } => {
                if i.saturating_add(1) >= self.len() {
                    *d
                } else {
                    times(STEP, i + 1)
                }
            }
            Steps::Strobe { period, .. } => times(*period, i),
        }
    }

    /// Step `i`'s actions.
    pub fn acts(&self, i: u64) -> Vec<Act> {
        match &self.steps {
            Steps::None => Vec::new(),
            Steps::Once(_, acts) => acts.clone(),
            Steps::Spin { .. } => self.spin_step(Duration::ZERO).0,
            Steps::Fade { from, to, d, .. } => {
                if i.saturating_add(1) >= self.len() {
                    return vec![Act::Main(*to)];
                }
                let f = self.at(i).as_secs_f64() / d.as_secs_f64().max(f64::MIN_POSITIVE);
                let f = f.clamp(0.0, 1.0);
                let mix = |a: u8, b: u8| (a as f64 * (1.0 - f) + b as f64 * f).round() as u8;
                vec![Act::Main([
                    mix(from[0], to[0]),
                    mix(from[1], to[1]),
                    mix(from[2], to[2]),
                ])]
            }
            Steps::Strobe { rgb, .. } => {
                vec![Act::Main(if i & 1 == 1 { *rgb } else { [0, 0, 0] })]
            }
        }
    }

    /// Whether the steps are paced by the link rather than the clock: each made once the one
    /// before it was answered (`spin`, [`Timeline::spin_step`]).
    pub fn paced(&self) -> bool {
        matches!(self.steps, Steps::Spin { .. })
    }

    /// The step of a paced timeline made `elapsed` after the call, and whether it is the last
    /// (nothing for a timeline that is not paced).
    pub fn spin_step(&self, elapsed: Duration) -> (Vec<Act>, bool) {
        let Steps::Spin {
            from,
            angle,
            speed,
            d,
        } = &self.steps
        else {
            return (Vec::new(), true);
        };
        let total = angle.unsigned_abs();
        let turned = spin_turned(total, *d, elapsed);
        // At most MAX_SECONDS' worth of degrees: far inside i64.
        let heading = from + angle.signum() * turned as i64;
        (vec![Driver::drive(heading, *speed)], turned >= total)
    }

    /// The last step at or after `i` that is due `elapsed` after the call (`None`: step `i`
    /// is not due yet, or there is none). Steps are in time order: a binary search.
    pub fn last_due(&self, i: u64, elapsed: Duration) -> Option<u64> {
        let len = self.len();
        if i >= len || self.at(i) > elapsed {
            return None;
        }
        // at(lo) <= elapsed; find the last such index below len.
        let (mut lo, mut hi) = (i, len);
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if self.at(mid) <= elapsed {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(lo)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_strobe_of_any_count_is_a_few_numbers_and_its_steps_alternate() {
        let t = Timeline {
            steps: Steps::Strobe {
                rgb: [255, 0, 0],
                period: Duration::from_millis(50),
                count: 1_000_000,
            },
            end: Duration::from_secs(100_000),
        };
        assert!(std::mem::size_of::<Timeline>() < 128);
        assert_eq!(t.len(), 2_000_000);
        assert_eq!(t.acts(0), vec![Act::Main([0, 0, 0])]);
        assert_eq!(t.acts(1_999_999), vec![Act::Main([255, 0, 0])]);
        assert_eq!(t.at(3), Duration::from_millis(150));
        // Late by a second: only the last step due is played.
        assert_eq!(t.last_due(0, Duration::from_millis(1_020)), Some(20));
        assert_eq!(t.last_due(21, Duration::from_millis(1_020)), None);
        assert_eq!(
            t.last_due(0, Duration::from_secs(1_000_000)),
            Some(1_999_999)
        );
    }

    /// spherov2 rounds with Python's `round`: half to even (sphero_edu.py `spin`).
    #[test]
    fn a_spins_turn_rounds_half_to_even_and_stops_at_the_whole_angle() {
        let s = Duration::from_secs;
        let ms = Duration::from_millis;
        // 2° over 1 s: 0.5° at 250 ms rounds to 0, 1.5° at 750 ms to 2.
        assert_eq!(spin_turned(2, s(1), ms(250)), 0);
        assert_eq!(spin_turned(2, s(1), ms(750)), 2);
        assert_eq!(spin_turned(360, s(2), ms(1_000)), 180);
        assert_eq!(spin_turned(360, s(2), s(60)), 360);
        assert_eq!(spin_turned(90, Duration::ZERO, Duration::ZERO), 90);
    }

    #[test]
    fn a_fade_mixes_then_ends_on_its_colour() {
        let t = Timeline {
            steps: Steps::Fade {
                from: [0, 0, 0],
                to: [200, 100, 0],
                d: Duration::from_millis(200),
                count: 4,
            },
            end: Duration::from_millis(200),
        };
        assert_eq!(t.len(), 4);
        assert_eq!(t.acts(1), vec![Act::Main([100, 50, 0])]);
        assert_eq!(t.at(3), Duration::from_millis(200));
        assert_eq!(t.acts(3), vec![Act::Main([200, 100, 0])]);
        // No time at all: one step, the colour.
        let t = Timeline {
            steps: Steps::Fade {
                from: [0, 0, 0],
                to: [1, 2, 3],
                d: Duration::ZERO,
                count: 0,
            },
            end: Duration::ZERO,
        };
        assert_eq!((t.len(), t.acts(0)), (1, vec![Act::Main([1, 2, 3])]));
    }
}
