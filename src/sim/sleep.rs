//! The one sleep timer of the simulated droids: inactivity, a warning some time before, then
//! sleep; any activity starts it over. The body's soft sleep (the droid stops listening
//! until woken, warning 10 s before) and the GATT droid's deep sleep (`sim --bluez
//! --idle-sleep`: it drops the link and stops advertising, [`SLEEP_GRACE`] after its
//! warning) are the same timer with other figures.

use std::time::Duration;

/// How long after its will-sleep warning an idle droid falls into deep sleep.
pub const SLEEP_GRACE: Duration = Duration::from_secs(5);

/// What the timer says when polled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SleepStep {
    /// Time to warn (once per quiet stretch).
    Warn,
    /// Asleep since `at`.
    Sleep { at: Duration },
}

/// An inactivity timer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SleepTimer {
    /// Asleep this long after the last activity.
    pub timeout: Duration,
    /// The warning comes this long before.
    pub warn_before: Duration,
    last_activity: Duration,
    warned: bool,
}

impl SleepTimer {
    pub fn new(timeout: Duration, warn_before: Duration) -> Self {
        SleepTimer {
            timeout,
            warn_before,
            last_activity: Duration::ZERO,
            warned: false,
        }
    }

    /// Something happened that keeps the droid awake: the timer starts over.
    pub fn activity(&mut self, now: Duration) {
        self.last_activity = now;
        self.warned = false;
    }

    pub fn last_activity(&self) -> Duration {
        self.last_activity
    }

    fn sleep_at(&self) -> Duration {
        self.last_activity.saturating_add(self.timeout)
    }

    fn warn_at(&self) -> Duration {
        self.sleep_at().saturating_sub(self.warn_before)
    }

    /// When the timer next has something to say.
    pub fn next_due(&self) -> Duration {
        if self.warned {
            self.sleep_at()
        } else {
            self.warn_at()
        }
    }

    /// What is due at `now`. The warning is given only when `may_warn` (a droid warns only
    /// over a link); asleep wins over a warning not yet given.
    pub fn poll(&mut self, now: Duration, may_warn: bool) -> Option<SleepStep> {
        if now >= self.sleep_at() {
            return Some(SleepStep::Sleep {
                at: self.sleep_at(),
            });
        }
        if may_warn && !self.warned && now >= self.warn_at() {
            self.warned = true;
            return Some(SleepStep::Warn);
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(n: u64) -> Duration {
        Duration::from_secs(n)
    }

    #[test]
    fn warns_once_then_sleeps_and_activity_starts_over() {
        let mut t = SleepTimer::new(s(7), s(5));
        t.activity(s(1));
        assert_eq!(t.next_due(), s(3));
        assert_eq!(t.poll(s(2), true), None);
        assert_eq!(t.poll(s(3), false), None, "no warning without a link");
        assert_eq!(t.poll(s(3), true), Some(SleepStep::Warn));
        assert_eq!(t.poll(s(4), true), None, "once");
        assert_eq!(t.next_due(), s(8));
        t.activity(s(5));
        assert_eq!(t.poll(s(7), true), Some(SleepStep::Warn));
        assert_eq!(t.poll(s(20), true), Some(SleepStep::Sleep { at: s(12) }));
    }
}
