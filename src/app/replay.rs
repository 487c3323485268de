//! The app on a capture: the player advanced on frame ticks, what it produces fed to the same
//! telemetry, packet log and link-state paths as a live session's events, and the replay
//! actions (pause, speed, seek, step). Nothing is ever sent.

use super::core::App;
use super::packet_log::PacketLog;
use super::player::{SEEK_LONG, SEEK_SHORT};
use super::state::ReplayView;
use crate::capture::mirror::Output;
use crate::config::Action;
use crate::session::{LinkState, SessionStats};
use crate::telemetry::Stance;
use std::time::Duration;
use tokio::time::Instant;

impl App {
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
                Output::StanceRequested(a) => self.state.telemetry.stance_requested(a),
                Output::StanceRead(s) => {
                    if self.state.telemetry.stance == Stance::Unknown {
                        self.state.telemetry.stance = Stance::from_state(s);
                    }
                }
                Output::Mark(_) => {}
                Output::Command(c) => self.commanded(&c),
            }
        }
        if let Some(p) = &self.player {
            let st = p.replay.mirror().stats();
            if st != self.state.stats {
                self.state.stats = st;
                self.dirty = true;
            }
        }
    }

    /// A command of the capture: the Drive and Lights (or dome) panels show it as it was sent,
    /// not the local controller's idle state.
    fn commanded(&mut self, c: &crate::family::Command) {
        let family = self.family;
        let control = &mut self.state.control;
        if let Some(d) = family.read_drive(c) {
            control.speed = d.speed;
            control.heading = d.heading;
            control.reverse = d.reverse;
            control.steer = d.steer;
            control.deadman = d.speed == 0;
            self.dirty = true;
        }
        if let Some(a) = family.read_head(c) {
            control.head_target = a;
            self.dirty = true;
        }
        if let Some(l) = family.read_leds(self.state.model, c) {
            if l.main.is_some() {
                self.state.leds.main = l.main;
            }
            if l.back.is_some() {
                self.state.leds.back = l.back;
            }
            self.dirty = true;
        }
    }

    /// Replay: bring the capture up to the clock (every droid's of a fleet), and the status
    /// bar's position.
    pub fn replay_frame(&mut self) {
        let chosen = self.chosen();
        self.with_droid(chosen, App::replay_frame_one);
        self.each_other(App::replay_frame_one);
    }

    fn replay_frame_one(&mut self) {
        let Some(p) = self.player.as_mut() else {
            return;
        };
        let mut outs = std::mem::take(&mut self.replayed);
        p.advance(Instant::now(), &mut outs);
        let view = p.view(Instant::now());
        self.on_replayed(&mut outs);
        self.replayed = outs;
        self.show_replay(view);
    }

    fn show_replay(&mut self, view: ReplayView) {
        // The position is shown to a tenth of a second: redraw when that changes.
        let shown = |v: &ReplayView| {
            (
                v.position.as_millis() / 100,
                v.paused,
                (v.speed * 100.0) as u64,
                v.events_done,
            )
        };
        if self.state.replay.as_ref().map(shown) != Some(shown(&view)) {
            self.dirty = true;
        }
        self.state.now = view.position;
        self.state.replay = Some(view);
    }

    /// A replay action from the key map's replay table.
    pub fn on_replay_action(&mut self, a: Action) {
        let now = Instant::now();
        let Some(p) = self.player.as_mut() else {
            return;
        };
        let mut outs = std::mem::take(&mut self.replayed);
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
                p.step(now, &mut outs);
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
            // Back in time: forget what the capture showed, then play it again up to there.
            p.replay_from_start();
            outs.clear();
            let log = &self.state.log;
            let mut fresh = PacketLog::with_capacity(log.capacity());
            fresh.decoded = log.decoded;
            fresh.filter = log.filter.clone();
            self.state.log = fresh;
            self.state.telemetry = Default::default();
            self.state.stats = SessionStats::default();
            let source = self.state.control.source;
            self.state.control = Default::default();
            self.state.control.source = source;
            self.state.leds = Default::default();
            self.state.link = LinkState::Connecting;
            self.state.rate_in = 0.0;
            self.state.rate_out = 0.0;
        }
        self.replayed = outs;
        self.replay_frame();
        self.dirty = true;
    }
}
