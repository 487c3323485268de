//! Fault injection: for the simulated link ([`Faults`], all drawn from one seed: same seed,
//! same run) and for the GATT-level droid ([`GattFaults`], the `--fault` of `sim --bluez`
//! and `serve --sim`, parsed here).

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

/// Faults the droid can inject at the GATT level. The command-line syntax (`--fault`) is
/// parsed by [`GattFaults::add`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct GattFaults {
    /// Refuse this many connection attempts, counting from the first (`u32::MAX`: all).
    pub refuse_connects: u32,
    /// Drop a connection this long after it was made: the first one only, or every one with
    /// `disconnect_every`.
    pub disconnect_after: Option<Duration>,
    pub disconnect_every: bool,
    /// Service discovery takes this long after a connect.
    pub slow_resolve: Duration,
    /// Not a fault but a droid's habit (`sim --bluez --idle-sleep SECS`): after this long
    /// without a command (a write; counted from its first connection on) the droid sends its
    /// will-sleep warning, and [`SLEEP_GRACE`](super::sleep::SLEEP_GRACE) later, with still
    /// nothing received, it falls asleep for good: it drops the connection and stops
    /// advertising. Robi 42 has no sleep timer and ignores it.
    pub idle_sleep: Option<Duration>,
}

/// The `--fault` forms, for messages.
pub const FAULT_SYNTAX: &str = "disconnect-after=SECS, disconnect-every=SECS, refuse-connect[=N] \
                                or slow-resolve=SECS";

impl GattFaults {
    pub fn none() -> Self {
        GattFaults::default()
    }

    /// Every `--fault` of a command line (`sim --bluez`, `serve --sim`), one message for any
    /// that cannot be read.
    pub fn parse_all(specs: &[String]) -> Result<GattFaults, String> {
        let mut faults = GattFaults::none();
        for f in specs {
            faults
                .add(f)
                .map_err(|e| format!("--fault: {e} ({FAULT_SYNTAX})"))?;
        }
        Ok(faults)
    }

    /// Add one fault in its command-line form: `disconnect-after=SECS` (drop the first
    /// connection SECS after it was made), `disconnect-every=SECS` (drop every connection
    /// SECS after it was made), `refuse-connect` (refuse every connection attempt),
    /// `refuse-connect=N` (refuse the first N), `slow-resolve=SECS` (services resolve SECS
    /// after each connect).
    pub fn add(&mut self, spec: &str) -> Result<(), String> {
        let spec = spec.trim();
        let (name, value) = match spec.split_once('=') {
            Some((n, v)) => (n.trim(), Some(v.trim())),
            None => (spec, None),
        };
        let secs = |v: Option<&str>| -> Result<Duration, String> {
            let v = v.ok_or_else(|| format!("`{name}` needs a number of seconds: {name}=SECS"))?;
            let s: f64 = v
                .parse()
                .map_err(|_| format!("`{spec}`: `{v}` is not a number of seconds"))?;
            if !s.is_finite() || !(0.0..=3600.0).contains(&s) {
                return Err(format!("`{spec}`: seconds must be within 0..=3600"));
            }
            Ok(Duration::from_secs_f64(s))
        };
        match name {
            "disconnect-after" => {
                self.disconnect_after = Some(secs(value)?);
                self.disconnect_every = false;
            }
            "disconnect-every" => {
                let d = secs(value)?;
                if d.is_zero() {
                    return Err(format!("`{spec}`: a connection must last some time"));
                }
                self.disconnect_after = Some(d);
                self.disconnect_every = true;
            }
            "refuse-connect" => {
                self.refuse_connects = match value {
                    None => u32::MAX,
                    Some(v) => v.parse().map_err(|_| {
                        format!("`{spec}`: `{v}` is not a count of connection attempts")
                    })?,
                }
            }
            "slow-resolve" => self.slow_resolve = secs(value)?,
            _ => return Err(format!("unknown fault `{spec}`: use {FAULT_SYNTAX}")),
        }
        Ok(())
    }

    /// The faults in effect, in their command-line form.
    pub fn describe(&self) -> Vec<String> {
        let mut out = Vec::new();
        if let Some(d) = self.disconnect_after {
            let name = if self.disconnect_every {
                "disconnect-every"
            } else {
                "disconnect-after"
            };
            out.push(format!("{name}={}", d.as_secs_f64()));
        }
        match self.refuse_connects {
            0 => {}
            u32::MAX => out.push("refuse-connect".into()),
            n => out.push(format!("refuse-connect={n}")),
        }
        if !self.slow_resolve.is_zero() {
            out.push(format!("slow-resolve={}", self.slow_resolve.as_secs_f64()));
        }
        out
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
