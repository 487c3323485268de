//! Which keys are held. With the kitty keyboard protocol the terminal reports releases; without
//! it, a release is inferred: a key stays held until no press or repeat arrives for a timeout
//! that is longer after the first press (the terminal's auto-repeat delay, ~500 ms) and shorter
//! once repeats flow (~30 per second). Losing focus releases every key.

use crate::config::Key;
use std::collections::HashMap;
use std::time::Duration;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReleaseMode {
    /// Releases arrive as events.
    Reported,
    /// Releases are inferred from silence.
    Emulated { first: Duration, repeat: Duration },
}

#[derive(Debug, Clone, Copy)]
struct Held {
    last: Duration,
    repeats: u32,
}

#[derive(Debug, Clone)]
pub struct HeldKeys {
    mode: ReleaseMode,
    held: HashMap<Key, Held>,
}

impl HeldKeys {
    pub fn new(mode: ReleaseMode) -> Self {
        HeldKeys {
            mode,
            held: HashMap::new(),
        }
    }

    pub fn mode(&self) -> ReleaseMode {
        self.mode
    }

    /// A press (or, in emulated mode, an auto-repeat that looks like one). Returns true when
    /// the key was not already held: a new press, for one-shot actions.
    pub fn press(&mut self, key: Key, now: Duration) -> bool {
        match self.held.get_mut(&key) {
            Some(h) => {
                h.last = now;
                h.repeats += 1;
                false
            }
            None => {
                self.held.insert(
                    key,
                    Held {
                        last: now,
                        repeats: 0,
                    },
                );
                true
            }
        }
    }

    /// An explicit repeat event (kitty protocol). Only a key already held is refreshed: a key
    /// whose press was not taken (pressed in another place, or let go since) stays released
    /// however long it repeats.
    pub fn repeat(&mut self, key: Key, now: Duration) {
        if let Some(h) = self.held.get_mut(&key) {
            h.last = now;
            h.repeats += 1;
        }
    }

    pub fn release(&mut self, key: Key) -> bool {
        self.held.remove(&key).is_some()
    }

    /// Focus lost, or anything else that must let go of everything.
    pub fn release_all(&mut self) -> Vec<Key> {
        self.held.drain().map(|(k, _)| k).collect()
    }

    /// Release keys whose repeats stopped (emulated mode only); returns them.
    pub fn expire(&mut self, now: Duration) -> Vec<Key> {
        let ReleaseMode::Emulated { first, repeat } = self.mode else {
            return Vec::new();
        };
        let gone: Vec<Key> = self
            .held
            .iter()
            .filter(|(_, h)| {
                now.saturating_sub(h.last) >= if h.repeats == 0 { first } else { repeat }
            })
            .map(|(k, _)| *k)
            .collect();
        for k in &gone {
            self.held.remove(k);
        }
        gone
    }

    /// When the next emulated release is due, to schedule a wake-up.
    pub fn next_expiry(&self) -> Option<Duration> {
        let ReleaseMode::Emulated { first, repeat } = self.mode else {
            return None;
        };
        self.held
            .values()
            .map(|h| h.last + if h.repeats == 0 { first } else { repeat })
            .min()
    }

    pub fn is_held(&self, key: &Key) -> bool {
        self.held.contains_key(key)
    }

    pub fn keys(&self) -> impl Iterator<Item = &Key> {
        self.held.keys()
    }

    pub fn is_empty(&self) -> bool {
        self.held.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const W: Key = Key::ch('w');

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    fn emulated() -> HeldKeys {
        HeldKeys::new(ReleaseMode::Emulated {
            first: ms(600),
            repeat: ms(150),
        })
    }

    #[test]
    fn emulated_release_waits_longer_before_repeats_start() {
        let mut h = emulated();
        assert!(h.press(W, ms(0)));
        // The terminal's repeat delay: no events for 500 ms, still held.
        assert!(h.expire(ms(500)).is_empty());
        assert!(h.is_held(&W));
        // Repeats flow every 33 ms.
        for t in (530..2000).step_by(33) {
            assert!(!h.press(W, ms(t)));
            assert!(h.expire(ms(t + 20)).is_empty());
        }
        // Repeats stop at ~1991 ms: released within the shorter timeout.
        assert!(h.expire(ms(2100)).is_empty());
        assert_eq!(h.expire(ms(2141)), vec![W]);
        assert!(!h.is_held(&W));
    }

    #[test]
    fn a_single_tap_releases_after_the_first_timeout() {
        let mut h = emulated();
        h.press(W, ms(0));
        assert_eq!(h.next_expiry(), Some(ms(600)));
        assert!(h.expire(ms(599)).is_empty());
        assert_eq!(h.expire(ms(600)), vec![W]);
        assert_eq!(h.next_expiry(), None);
    }

    #[test]
    fn reported_mode_needs_release_events() {
        let mut h = HeldKeys::new(ReleaseMode::Reported);
        h.press(W, ms(0));
        assert!(h.expire(ms(100_000)).is_empty());
        assert!(h.is_held(&W));
        assert!(h.release(W));
        assert!(!h.is_held(&W));
    }

    #[test]
    fn a_repeat_does_not_hold_a_key_that_was_let_go() {
        let mut h = HeldKeys::new(ReleaseMode::Reported);
        h.repeat(W, ms(0));
        assert!(!h.is_held(&W), "a repeat without its press holds nothing");
        h.press(W, ms(0));
        h.release_all();
        h.repeat(W, ms(50));
        assert!(
            h.is_empty(),
            "let go by a place change: repeats do not take it back"
        );
    }

    #[test]
    fn focus_loss_releases_everything() {
        let mut h = emulated();
        h.press(W, ms(0));
        h.press(Key::ch('a'), ms(0));
        assert_eq!(h.release_all().len(), 2);
        assert!(h.is_empty());
    }
}
