//! Packets per second in and out, for the status bar: the session's counters sampled once a
//! second on the session's time (wall time live, capture time in replay, where a paused
//! capture has no rate and a seek back restarts the count). No IO: the caller gives the
//! counters and the time.

use crate::session::SessionStats;
use std::time::Duration;

#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Rates {
    prev: SessionStats,
    prev_at: Duration,
}

impl Rates {
    pub fn new(stats: SessionStats, at: Duration) -> Rates {
        Rates {
            prev: stats,
            prev_at: at,
        }
    }

    /// The counters at `at`: (in, out) per second since the last sample, or `None` when no
    /// time passed (a paused replay keeps the rates it showed).
    pub fn sample(&mut self, stats: SessionStats, at: Duration) -> Option<(f32, f32)> {
        let secs = at.saturating_sub(self.prev_at).as_secs_f32();
        // The counters went back: a replay restarted from its start.
        let restarted = stats.received < self.prev.received;
        if secs <= 0.0 && !restarted {
            return None;
        }
        let secs = secs.max(1e-3);
        let rate_in = stats.received.saturating_sub(self.prev.received) as f32 / secs;
        let rate_out = stats.sent.saturating_sub(self.prev.sent) as f32 / secs;
        self.prev = stats;
        self.prev_at = at;
        Some((rate_in, rate_out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stats(received: u64, sent: u64) -> SessionStats {
        SessionStats {
            received,
            sent,
            ..SessionStats::default()
        }
    }

    fn s(n: f32) -> Duration {
        Duration::from_secs_f32(n)
    }

    #[test]
    fn counts_per_second_of_session_time() {
        let mut r = Rates::new(stats(0, 0), s(0.0));
        assert_eq!(r.sample(stats(10, 4), s(1.0)), Some((10.0, 4.0)));
        assert_eq!(r.sample(stats(30, 4), s(3.0)), Some((10.0, 0.0)));
    }

    #[test]
    fn paused_keeps_and_restart_resets() {
        let mut r = Rates::new(stats(0, 0), s(0.0));
        assert_eq!(r.sample(stats(10, 0), s(2.0)), Some((5.0, 0.0)));
        // Paused replay: the clock did not move.
        assert_eq!(r.sample(stats(10, 0), s(2.0)), None);
        // Seek back: the counters restart, and so do the rates.
        assert_eq!(r.sample(stats(0, 0), s(1.0)), Some((0.0, 0.0)));
        assert_eq!(r.sample(stats(6, 0), s(3.0)), Some((3.0, 0.0)));
    }
}
