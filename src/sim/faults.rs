//! Fault injection for the simulated link, all drawn from one seed: same seed, same run.

use crate::rng::Rng;
use std::time::Duration;

/// What can go wrong between host and droid.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Faults {
    pub seed: u64,
    /// Split the droid's bytes at random points (pieces of 1..=20 bytes) instead of one
    /// notification per packet.
    pub split: bool,
    /// Probability that a byte is lost, in each direction.
    pub drop_rate: f64,
    /// Probability that a byte is replaced by a random one, in each direction.
    pub corrupt_rate: f64,
    /// One-way delay, plus a random extra of up to `jitter`. Order is preserved.
    pub latency: Duration,
    pub jitter: Duration,
    /// Times (since the link was created) at which the connection drops.
    pub disconnect_at: Vec<Duration>,
    /// The first N connection attempts fail (to exercise the backoff).
    pub fail_opens: u32,
}

impl Faults {
    pub fn none() -> Self {
        Faults::default()
    }

    /// Drop and corrupt bytes per the rates.
    pub fn mangle(&self, rng: &mut Rng, bytes: &[u8]) -> Vec<u8> {
        if self.drop_rate <= 0.0 && self.corrupt_rate <= 0.0 {
            return bytes.to_vec();
        }
        let mut out = Vec::with_capacity(bytes.len());
        for &b in bytes {
            if rng.chance(self.drop_rate) {
                continue;
            }
            out.push(if rng.chance(self.corrupt_rate) {
                rng.byte()
            } else {
                b
            });
        }
        out
    }

    /// Cut bytes into notification-sized pieces (at most 20 bytes each).
    pub fn pieces(&self, rng: &mut Rng, bytes: &[u8], max: usize) -> Vec<Vec<u8>> {
        let max = max.max(1);
        if !self.split {
            return bytes.chunks(max).map(<[u8]>::to_vec).collect();
        }
        let mut out = Vec::new();
        let mut rest = bytes;
        while !rest.is_empty() {
            let n = (1 + rng.below(max as u64) as usize).min(rest.len());
            out.push(rest[..n].to_vec());
            rest = &rest[n..];
        }
        out
    }

    /// The delay for one delivery.
    pub fn delay(&self, rng: &mut Rng) -> Duration {
        let jitter_us = self.jitter.as_micros() as u64;
        self.latency + Duration::from_micros(rng.below(jitter_us + 1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_are_bounded_and_complete() {
        let f = Faults {
            split: true,
            ..Faults::none()
        };
        let mut rng = Rng::new(3);
        let data: Vec<u8> = (0..=255).collect();
        let pieces = f.pieces(&mut rng, &data, 20);
        assert!(pieces.iter().all(|p| !p.is_empty() && p.len() <= 20));
        assert_eq!(pieces.concat(), data);
        assert!(
            pieces.len() > 13,
            "random splits are smaller than 20 on average"
        );
        let whole = Faults::none().pieces(&mut rng, &data, 20);
        assert_eq!(whole.len(), 13);
    }

    #[test]
    fn mangling_follows_rates_and_seed() {
        let f = Faults {
            corrupt_rate: 0.1,
            drop_rate: 0.1,
            ..Faults::none()
        };
        let data = vec![0u8; 10_000];
        let a = f.mangle(&mut Rng::new(9), &data);
        let b = f.mangle(&mut Rng::new(9), &data);
        assert_eq!(a, b);
        assert!((8700..9300).contains(&a.len()), "{}", a.len());
        let changed = a.iter().filter(|&&x| x != 0).count();
        assert!((700..1100).contains(&changed), "{changed}");
        assert_eq!(Faults::none().mangle(&mut Rng::new(1), &data), data);
    }
}
