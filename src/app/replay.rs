//! The app on a capture: the player advanced on frame ticks, what it produces fed to the same
//! telemetry, packet log and link-state paths as a live session's events, and the replay
//! actions (pause, speed, seek, step). Nothing is ever sent.

use super::core::App;
use super::droid::DroidMut;
use super::packet_log::PacketLog;
use super::player::{SEEK_LONG, SEEK_SHORT};
use super::state::ReplayView;
use crate::capture::mirror::Output;
use crate::config::Action;
use crate::session::{LinkState, SessionStats};
use crate::telemetry::Stance;
use std::time::Duration;
use tokio::time::Instant;

impl DroidMut<'_> {
    /// What the replay produced, through the same paths as a live session's events.
    fn on_replayed(&mut self, outs: &mut Vec<(Duration, Output)>) {
        for (at, o) in outs.drain(..) {
            match o {
                Output::Log(entry) => self.on_log(&entry),
                Output::Notification(n) => self.on_notification(&n, at),
                Output::BadNotification { name, reason } => {
                    tracing::debug!(name, %reason, "malformed notification in the capture")
                }
                Output::Link(s) => self.on_link(s),
                Output::Battery(v) => self.on_battery(v),
                Output::StanceRequested(a) => self.view.telemetry.stance_requested(a),
                Output::StanceRead(s) => {
                    if self.view.telemetry.stance == Stance::Unknown {
                        self.view.telemetry.stance = Stance::from_state(s);
                    }
                }
                Output::Mark(_) => {}
                Output::Command(c) => self.commanded(&c),
            }
        }
    }

    /// A command of the capture: the Drive and Lights (or dome) panels show it as it was sent,
    /// not the local controller's idle state.
    fn commanded(&mut self, c: &crate::family::Command) {
        let family = self.io.family;
        let control = &mut self.view.control;
        if let Some(d) = family.read_drive(c) {
            control.speed = d.speed;
            control.heading = d.heading;
            control.reverse = d.reverse;
            control.steer = d.steer;
            control.deadman = d.speed == 0;
            *self.dirty = true;
        }
        if let Some(a) = family.read_head(c) {
            control.head_target = a;
            *self.dirty = true;
        }
        if let Some(l) = family.read_leds(self.view.model, c) {
            if l.main.is_some() {
                self.view.leds.main = l.main;
            }
            if l.back.is_some() {
                self.view.leds.back = l.back;
            }
            *self.dirty = true;
        }
    }

    /// Bring its capture up to the clock; the status bar's position.
    fn replay_frame(&mut self, scratch: &mut Vec<(Duration, Output)>) {
        let Some(p) = self.io.player.as_mut() else {
            return;
        };
        p.advance(Instant::now(), scratch);
        let view = p.view(Instant::now());
        self.on_replayed(scratch);
        // The position is shown to a tenth of a second: redraw when that changes.
        let shown = |v: &ReplayView| {
            (
                v.position.as_millis() / 100,
                v.paused,
                (v.speed * 100.0) as u64,
                v.events_done,
            )
        };
        if self.view.replay.as_ref().map(shown) != Some(shown(&view)) {
            *self.dirty = true;
        }
        *self.screen_now = view.position;
        self.view.replay = Some(view);
    }

    /// A replay action; returns whether the capture went back in time (its view starts
    /// afresh and plays again up to there).
    fn replay_action(&mut self, a: Action, scratch: &mut Vec<(Duration, Output)>) -> bool {
        let now = Instant::now();
        let Some(p) = self.io.player.as_mut() else {
            return false;
        };
        let at = p.clock(now);
        let restart = match a {
            Action::ReplayPause => {
                p.toggle_pause(now);
                false
            }
            Action::ReplayFaster => {
                p.faster(now);
                false
            }
            Action::ReplaySlower => {
                p.slower(now);
                false
            }
            Action::ReplayStep => {
                p.step(now, scratch);
                false
            }
            Action::ReplayForward => p.seek(at + SEEK_SHORT, now),
            Action::ReplayBack => p.seek(at.saturating_sub(SEEK_SHORT), now),
            Action::ReplayForwardLong => p.seek(at + SEEK_LONG, now),
            Action::ReplayBackLong => p.seek(at.saturating_sub(SEEK_LONG), now),
            Action::ReplayStart => p.seek(Duration::ZERO, now),
            Action::ReplayEnd => p.seek(p.replay.duration(), now),
            _ => false,
        };
        if restart {
            p.replay_from_start();
            scratch.clear();
            let v = &mut *self.view;
            v.telemetry = Default::default();
            v.stats = SessionStats::default();
            let source = v.control.source;
            v.control = Default::default();
            v.control.source = source;
            v.leds = Default::default();
            v.link = LinkState::Connecting;
            v.rate_in = 0.0;
            v.rate_out = 0.0;
        } else {
            // A step's events.
            self.on_replayed(scratch);
        }
        restart
    }
}

impl App {
    /// Replay: bring every droid's capture up to the clock, the chosen one's last (its
    /// position is the one the screen shows).
    pub fn replay_frame(&mut self) {
        let mut scratch = std::mem::take(&mut self.replayed);
        let chosen = self.chosen();
        let order = (0..self.len()).filter(|i| *i != chosen).chain([chosen]);
        for i in order {
            if let Some(mut d) = self.droid(i) {
                d.replay_frame(&mut scratch);
            }
        }
        self.replayed = scratch;
    }

    /// A replay action from the key map's replay table: every droid of a fleet's capture
    /// plays on the same clock.
    pub fn on_replay_action(&mut self, a: Action) {
        let mut scratch = std::mem::take(&mut self.replayed);
        let mut restarted = false;
        for i in 0..self.len() {
            if let Some(mut d) = self.droid(i) {
                restarted |= d.replay_action(a, &mut scratch);
            }
        }
        if restarted {
            // Back in time: forget what the capture showed, then play it again up to there.
            let log = &self.state.log;
            let mut fresh = PacketLog::with_capacity(log.capacity());
            fresh.decoded = log.decoded;
            fresh.filter = log.filter.clone();
            self.state.log = fresh;
        }
        self.replayed = scratch;
        self.replay_frame();
        self.dirty = true;
    }
}
