//! A [`Replay`] on the app's clock. Playing, the capture position runs at the chosen speed
//! from where it was; paused, it holds. The event loop advances it on its frame ticks
//! ([`super::replay`] feeds what comes out to the live session's paths).

use super::state::ReplayView;
use crate::capture::mirror::Output;
use crate::capture::replay::{Replay, SPEEDS};
use std::time::Duration;
use tokio::time::Instant;

/// How far the short and long seeks go.
pub const SEEK_SHORT: Duration = Duration::from_secs(5);
pub const SEEK_LONG: Duration = Duration::from_secs(60);

/// A replay on the app's clock.
pub struct Player {
    pub replay: Replay,
    /// Index into [`SPEEDS`].
    speed: usize,
    paused: bool,
    /// Playing: the position is `base + (now - anchor) × speed`.
    base: Duration,
    anchor: Instant,
    file: String,
}

impl Player {
    pub fn new(replay: Replay, file: String, now: Instant) -> Player {
        Player {
            replay,
            speed: SPEEDS.iter().position(|s| *s == 1.0).unwrap_or(0),
            paused: false,
            base: Duration::ZERO,
            anchor: now,
            file,
        }
    }

    pub fn speed(&self) -> f64 {
        SPEEDS[self.speed]
    }

    pub fn paused(&self) -> bool {
        self.paused
    }

    /// Playing and not yet at the end.
    pub fn running(&self) -> bool {
        !self.paused && !self.replay.at_end()
    }

    /// Where the capture is now by the clock (not past its end).
    pub fn clock(&self, now: Instant) -> Duration {
        let t = if self.paused {
            self.base
        } else {
            self.base + now.duration_since(self.anchor).mul_f64(self.speed())
        };
        t.min(self.replay.duration())
    }

    /// Bring the replay up to the clock.
    pub fn advance(&mut self, now: Instant, out: &mut Vec<(Duration, Output)>) {
        let t = self.clock(now);
        self.replay.advance_to(t, out);
    }

    /// Hold the clock where it is now.
    fn rebase(&mut self, now: Instant) {
        self.base = self.clock(now);
        self.anchor = now;
    }

    pub fn toggle_pause(&mut self, now: Instant) {
        self.rebase(now);
        // At the end, play restarts from the start.
        if self.paused && self.replay.at_end() && self.base >= self.replay.duration() {
            self.base = Duration::ZERO;
        }
        self.paused = !self.paused;
    }

    pub fn faster(&mut self, now: Instant) {
        self.rebase(now);
        self.speed = (self.speed + 1).min(SPEEDS.len() - 1);
    }

    pub fn slower(&mut self, now: Instant) {
        self.rebase(now);
        self.speed = self.speed.saturating_sub(1);
    }

    /// Move the clock to `t`. Returns true when that is behind what was already applied:
    /// the caller resets what it shows and replays from the start
    /// ([`Player::replay_from_start`]).
    pub fn seek(&mut self, t: Duration, now: Instant) -> bool {
        let t = t.min(self.replay.duration());
        self.base = t;
        self.anchor = now;
        t < self.replay.position()
    }

    pub fn replay_from_start(&mut self) {
        self.replay.rewind();
    }

    /// Pause, and apply the next event (those at the same time too).
    pub fn step(&mut self, now: Instant, out: &mut Vec<(Duration, Output)>) {
        self.rebase(now);
        self.paused = true;
        // Catch up first, so the step is the event after what the screen shows.
        self.replay.advance_to(self.base, out);
        if self.replay.step(out) {
            self.base = self.replay.position();
        }
    }

    /// What the status bar shows.
    pub fn view(&self, now: Instant) -> ReplayView {
        let (done, total) = self.replay.progress();
        ReplayView {
            file: self.file.clone(),
            position: self.clock(now),
            duration: self.replay.duration(),
            speed: self.speed(),
            paused: self.paused,
            events_done: done,
            events: total,
        }
    }
}
