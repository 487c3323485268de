//! A timed call's steps (`spin`'s headings, `fade`'s colours, `strobe`'s blinks, `roll`'s and
//! `rawMotor`'s stop), made one at a time when due rather than listed up front: a pending
//! call is a few numbers whatever its duration or count, and a step is a function of its
//! index (issue 37: 990 pending `spin`s once listed 7 GB of steps).
//!
//! Every step says the whole state it sets (a heading to drive toward, a colour for the main
//! light), so a player that is late may play only the last step due and skip the ones before
//! it: the robot ends where it would have, as spherov2's time-driven loops (`spin`, `fade`)
//! do when its link is slow. Sans-IO: [`super::run`] plays it on droidctl's clock.

use super::api::{Act, Driver, STEP};
use std::time::Duration;

/// What a timed call does over time.
#[derive(Debug, Clone, PartialEq)]
pub enum Steps {
    /// Nothing: the call only waits (`delay`, `scrollMatrixText`, `speak`).
    None,
    /// One step (`roll`'s stop, `rawMotor`'s stop).
    Once(Duration, Vec<Act>),
    /// `spin`: `count` steps, [`STEP`] apart from the first at [`STEP`]; step `k` (1-based)
    /// drives at `speed` toward `from` turned by `round(k / count · |angle|)` degrees in
    /// `angle`'s direction.
    Spin {
        from: i64,
        angle: i64,
        speed: i64,
        count: u64,
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
            Steps::Spin { count, .. } => *count,
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
            // The last step at the end, not past it (the count is the end in steps, rounded up).
            Steps::Spin { .. } => times(STEP, i.saturating_add(1)).min(self.end),
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
            Steps::Spin {
                from,
                angle,
                speed,
                count,
            } => {
                let k = i.saturating_add(1);
                let frac = (k as f64 / (*count).max(1) as f64).min(1.0);
                let delta = (frac * angle.unsigned_abs() as f64).round() as i64;
                vec![Driver::drive(from + angle.signum() * delta, *speed)]
            }
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
