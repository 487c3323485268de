//! When to draw a frame. Frames are drawn only when something visible changed, at most every
//! [`RENDER_EVERY`] while someone is at the keys (or the droid is driven, or a replay plays),
//! and at most every [`IDLE_RENDER_EVERY`] once nobody has touched anything for
//! [`ACTIVE_FOR`]: an idle app shows what the droid streams at a few frames per second.
//!
//! A small state machine without IO: times are offsets from the app's start, so it is tested
//! without a clock.

use std::time::Duration;

pub const RENDER_EVERY: Duration = Duration::from_millis(50);
pub const IDLE_RENDER_EVERY: Duration = Duration::from_millis(250);
pub const ACTIVE_FOR: Duration = Duration::from_secs(3);

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FramePacer {
    /// When the last frame was drawn (`None`: never, draw at once).
    last_frame: Option<Duration>,
    /// The operator touched something: frames come fast until then.
    active_until: Duration,
}

impl FramePacer {
    /// At the start, as if the operator had just touched a key.
    pub fn new(now: Duration) -> FramePacer {
        FramePacer {
            last_frame: None,
            active_until: now + ACTIVE_FOR,
        }
    }

    /// The operator pressed a key or moved the gamepad.
    pub fn touched(&mut self, now: Duration) {
        self.active_until = now + ACTIVE_FOR;
    }

    /// Whether frames come at the fast rate now; `busy` says the droid is driven or a replay
    /// plays.
    pub fn active(&self, now: Duration, busy: bool) -> bool {
        busy || now < self.active_until
    }

    /// The earliest time the next frame may be drawn.
    pub fn next_frame(&self, now: Duration, busy: bool) -> Duration {
        let every = if self.active(now, busy) {
            RENDER_EVERY
        } else {
            IDLE_RENDER_EVERY
        };
        self.last_frame.map_or(Duration::ZERO, |t| t + every)
    }

    /// A frame was drawn at `now`.
    pub fn drawn(&mut self, now: Duration) {
        self.last_frame = Some(now);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    #[test]
    fn first_frame_at_once_then_fast_while_active() {
        let mut p = FramePacer::new(ms(0));
        assert_eq!(p.next_frame(ms(0), false), ms(0));
        p.drawn(ms(10));
        assert_eq!(p.next_frame(ms(10), false), ms(60));
    }

    #[test]
    fn idle_after_three_seconds_untouched() {
        let mut p = FramePacer::new(ms(0));
        p.drawn(ms(3_000));
        assert_eq!(p.next_frame(ms(3_000), false), ms(3_250));
        // Driving or playing keeps the fast rate without a touch.
        assert_eq!(p.next_frame(ms(3_000), true), ms(3_050));
        // A key makes it fast again for three seconds.
        p.touched(ms(3_100));
        assert_eq!(p.next_frame(ms(3_100), false), ms(3_050));
        assert!(p.active(ms(6_099), false));
        assert!(!p.active(ms(6_100), false));
    }
}
