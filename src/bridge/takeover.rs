//! A client id taken over (issue 37 point 7): two clients with the same client id knock each
//! other off for ever, and a bridge that sees it says so and waits instead of ending. Split
//! from [`super::mqtt`] as its own job (sans-IO: the times are given).

use std::time::Duration;
use tokio::time::Instant;

/// How many connections in a row ended by the broker within [`TAKEOVER_WINDOW`] of being made
/// mean that another client has taken the session over.
pub const TAKEOVERS: u32 = 3;

/// A connection the broker ends sooner than this after accepting it counts as taken over.
pub const TAKEOVER_WINDOW: Duration = Duration::from_secs(2);

/// How long a droid's connection waits after [`TAKEOVERS`] quick ends before it tries again.
pub const TAKEOVER_BACKOFF: Duration = Duration::from_secs(30);

/// Two clients with the same client id knock each other off for ever: the broker ends the
/// older connection whenever the other one connects (MQTT 3.1.1, 3.1.4-2). Seen from one of
/// them: connections accepted, then ended within moments, again and again. (sans-IO: the
/// times are given.)
#[derive(Debug, Default)]
pub struct Takeovers {
    since: Option<Instant>,
    quick: u32,
}

impl Takeovers {
    /// A connection was accepted at `now`.
    pub fn connected(&mut self, now: Instant) {
        self.since = Some(now);
    }

    /// The connection ended at `now`: true when that makes [`TAKEOVERS`] quick ends in a row
    /// (counted afresh after that, so each such run is said once).
    pub fn lost(&mut self, now: Instant) -> bool {
        match self.since.take() {
            Some(t) if now.duration_since(t) < TAKEOVER_WINDOW => self.quick += 1,
            Some(_) => self.quick = 0,
            // Not connected: a failed attempt says nothing either way.
            None => {}
        }
        let taken = self.quick >= TAKEOVERS;
        if taken {
            self.quick = 0;
        }
        taken
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repeated_immediate_ends_are_a_takeover_and_a_long_connection_resets_the_count() {
        let t0 = Instant::now();
        let at = |ms: u64| t0 + Duration::from_millis(ms);
        let mut t = Takeovers::default();
        // The broker restarting: a long connection, then failed attempts, then back.
        t.connected(at(0));
        assert!(!t.lost(at(60_000)));
        assert!(!t.lost(at(61_000)));
        assert!(!t.lost(at(62_000)));
        // Another client with the same id: ended within moments each time.
        let mut now = 70_000;
        for n in 1..=TAKEOVERS * 2 {
            t.connected(at(now));
            now += 300;
            assert_eq!(
                t.lost(at(now)),
                n % TAKEOVERS == 0,
                "takeover {n}: said once a run"
            );
            now += 250;
        }
        // Two quick ends and a long connection between: no takeover.
        let mut t = Takeovers::default();
        for (up, down) in [(0, 100), (400, 500), (800, 10_000), (10_300, 10_400)] {
            t.connected(at(up));
            assert!(!t.lost(at(down)));
        }
    }
}
