//! Monitoring in the app (issue 22 points 1-3): the scope's view state (which channels, how
//! long a window, paused, axes), the streaming and collision settings in effect, and the keys
//! of the scope, its channel list and the settings palette. Both views live in [`AppState`],
//! one per droid, so they follow the droid shown.
//!
//! Applying the settings sends the family's streaming commands followed by collision
//! detection ([`crate::family::stream::reconfigure`]), and hands the session a new connect
//! setup so a reconnect keeps them.
//!
//! [`AppState`]: super::state::AppState

use super::core::App;
use super::state::Overlay;
use crate::config::{Action, Context, Key};
use crate::family::setup::{SetupOptions, connect_setup};
use crate::family::stream::{self, StreamCaps, StreamPlan};
use crate::model::Model;
use crate::telemetry::history::Channel;
use crate::tuning::{CollisionConfig, MAX_DEAD_TIME_MS, SensorGroup, SensorSet, StreamRequest};
use std::time::Duration;

/// The scope's windows, shortest first.
pub const WINDOWS: [Duration; 5] = [
    Duration::from_secs(10),
    Duration::from_secs(20),
    Duration::from_secs(30),
    Duration::from_secs(60),
    Duration::from_secs(120),
];

/// What the scope shows and how.
#[derive(Debug, Clone, PartialEq)]
pub struct ScopeView {
    /// On screen (in place of the panels and the log).
    pub visible: bool,
    /// The channels plotted, in [`Channel::ALL`] order.
    pub channels: Vec<Channel>,
    /// Index into [`WINDOWS`].
    pub window: usize,
    /// Paused: the time the plot stays at (telemetry goes on being recorded).
    pub paused_at: Option<Duration>,
    /// Axes fit the data shown; else each channel's sensor span.
    pub autoscale: bool,
}

impl ScopeView {
    /// Speed and yaw for a rolling droid; the wheels for Robi 42.
    pub fn for_model(model: Model) -> ScopeView {
        let channels = if model.reports_state_frames() {
            vec![Channel::MotorLeft, Channel::MotorRight]
        } else {
            vec![Channel::Yaw, Channel::Speed]
        };
        ScopeView {
            visible: false,
            channels,
            window: 2,
            paused_at: None,
            autoscale: true,
        }
    }

    pub fn window(&self) -> Duration {
        WINDOWS[self.window.min(WINDOWS.len() - 1)]
    }

    /// The right edge of the plot: now, or where it was paused.
    pub fn end(&self, now: Duration) -> Duration {
        self.paused_at.unwrap_or(now)
    }

    pub fn toggle(&mut self, c: Channel) {
        match self.channels.iter().position(|x| *x == c) {
            Some(i) => {
                self.channels.remove(i);
            }
            None => {
                self.channels.push(c);
                self.channels.sort();
            }
        }
    }
}

/// The streaming and collision settings: asked for, and in effect.
#[derive(Debug, Clone, PartialEq)]
pub struct MonitorView {
    /// What the model offers; `None`: it streams by itself (Robi 42) or nothing is known
    /// (replay).
    pub caps: Option<StreamCaps>,
    pub request: StreamRequest,
    /// What was sent (the request capped to the link); `None` as for `caps`.
    pub plan: Option<StreamPlan>,
    pub collision: CollisionConfig,
    /// The family configures collision detection.
    pub has_collision: bool,
    /// Settings can be sent (a live session, not a replay).
    pub live: bool,
}

impl MonitorView {
    pub fn new(model: Model, request: StreamRequest, collision: CollisionConfig) -> MonitorView {
        let family = crate::family::for_model(model);
        MonitorView {
            caps: family.stream_caps(model),
            request,
            plan: stream::plan_for(model, request),
            collision,
            has_collision: !family.collision_detection(&collision).is_empty(),
            live: true,
        }
    }

    /// The requested rate, for the screen: `10/s`, `off`, or who decides.
    pub fn requested(&self) -> String {
        match &self.plan {
            None => "own rate".into(),
            Some(p) if !p.is_on() => "off".into(),
            Some(p) => format!("{:.0}/s", p.rate_hz()),
        }
    }
}

/// A row of the settings palette.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TuningRow {
    Rate,
    Group(SensorGroup),
    Collision,
    XThreshold,
    YThreshold,
    XSpeed,
    YSpeed,
    DeadTime,
}

/// The settings being edited; sent on apply.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TuningDraft {
    pub rate_hz: u16,
    pub sensors: SensorSet,
    pub collision: CollisionConfig,
}

/// The rows `m` offers.
pub fn tuning_rows(m: &MonitorView) -> Vec<TuningRow> {
    let mut rows = Vec::new();
    if let Some(caps) = &m.caps {
        rows.push(TuningRow::Rate);
        rows.extend(caps.groups.iter().map(TuningRow::Group));
    }
    if m.has_collision {
        rows.extend([
            TuningRow::Collision,
            TuningRow::XThreshold,
            TuningRow::YThreshold,
            TuningRow::XSpeed,
            TuningRow::YSpeed,
            TuningRow::DeadTime,
        ]);
    }
    rows
}

/// Step a byte setting by ±10.
fn step_byte(v: u8, up: bool) -> u8 {
    if up {
        v.saturating_add(10)
    } else {
        v.saturating_sub(10)
    }
}

impl TuningDraft {
    /// Change `row` one step (`up`), or switch it (`None`).
    pub fn change(&mut self, caps: Option<&StreamCaps>, row: TuningRow, up: Option<bool>) {
        let c = &mut self.collision;
        match (row, up) {
            (TuningRow::Rate, Some(up)) => {
                let mut rates = vec![0u16];
                rates.extend(caps.map_or(&[][..], |c| c.rates));
                let i = rates.iter().position(|r| *r >= self.rate_hz).unwrap_or(0);
                let i = if up {
                    (i + 1).min(rates.len() - 1)
                } else {
                    i.saturating_sub(1)
                };
                self.rate_hz = rates[i];
            }
            (TuningRow::Rate, None) => self.rate_hz = if self.rate_hz == 0 { 10 } else { 0 },
            (TuningRow::Group(g), _) => self.sensors.toggle(g),
            (TuningRow::Collision, _) => c.enabled = !c.enabled,
            (TuningRow::XThreshold, Some(up)) => c.x_threshold = step_byte(c.x_threshold, up),
            (TuningRow::YThreshold, Some(up)) => c.y_threshold = step_byte(c.y_threshold, up),
            (TuningRow::XSpeed, Some(up)) => c.x_speed = step_byte(c.x_speed, up),
            (TuningRow::YSpeed, Some(up)) => c.y_speed = step_byte(c.y_speed, up),
            (TuningRow::DeadTime, Some(up)) => {
                c.dead_time_ms = if up {
                    (c.dead_time_ms / 10 * 10 + 10).min(MAX_DEAD_TIME_MS)
                } else {
                    (c.dead_time_ms / 10 * 10).saturating_sub(10)
                }
            }
            (_, None) => {}
        }
    }
}

impl App {
    /// The scope on or off.
    pub fn toggle_scope(&mut self) {
        let s = &mut self.state.droid_mut().scope;
        s.visible = !s.visible;
        self.dirty = true;
    }

    /// A key the scope binds, while it is on screen (the keys it does not bind drive).
    pub fn scope_key(&mut self, key: Key, new_press: bool) {
        let Some(a) = self.keymap.action_in(Context::Scope, &key) else {
            return;
        };
        if !new_press {
            return;
        }
        let now = self.clock();
        let s = &mut self.state.droid_mut().scope;
        match a {
            Action::ScopePause => {
                s.paused_at = match s.paused_at {
                    Some(_) => None,
                    None => Some(now),
                }
            }
            Action::ScopeZoomIn => s.window = s.window.saturating_sub(1),
            Action::ScopeZoomOut => s.window = (s.window + 1).min(WINDOWS.len() - 1),
            Action::ScopeAutoscale => s.autoscale = !s.autoscale,
            Action::ScopeChannels => self.state.overlay = Overlay::Channels { selected: 0 },
            _ => {}
        }
        self.dirty = true;
    }

    /// The channels this droid reports, as the channel list shows them.
    pub fn channels_offered(&self) -> Vec<Channel> {
        let robi = self.state.droid().model.reports_state_frames();
        Channel::ALL
            .iter()
            .copied()
            .filter(|c| c.reported_by(robi))
            .collect()
    }

    /// A key in the channel list.
    pub fn channels_key(&mut self, key: Key, new_press: bool) {
        let Overlay::Channels { selected } = self.state.overlay else {
            return;
        };
        let offered = self.channels_offered();
        let last = offered.len().saturating_sub(1);
        match self.keymap.action_in(Context::Settings, &key) {
            Some(Action::SettingsUp) => {
                self.state.overlay = Overlay::Channels {
                    selected: selected.saturating_sub(1),
                }
            }
            Some(Action::SettingsDown) => {
                self.state.overlay = Overlay::Channels {
                    selected: (selected + 1).min(last),
                }
            }
            Some(Action::SettingsToggle | Action::SettingsApply) if new_press => {
                if let Some(c) = offered.get(selected) {
                    self.state.droid_mut().scope.toggle(*c);
                }
            }
            Some(Action::SettingsClose) => self.state.overlay = Overlay::None,
            _ => {}
        }
    }

    /// Open the streaming and collision settings.
    pub fn open_tuning(&mut self) {
        let m = &self.state.droid().monitor;
        if !m.live {
            return self.hint("replay: nothing is sent (the settings are the capture's)");
        }
        if tuning_rows(m).is_empty() {
            return self.hint(format!(
                "{} sends its state by itself: nothing to set",
                self.state.droid().model.display_name()
            ));
        }
        let draft = TuningDraft {
            rate_hz: m.plan.as_ref().map_or(0, |p| p.rate_hz().round() as u16),
            sensors: m
                .plan
                .as_ref()
                .filter(|p| p.is_on())
                .map_or(m.request.sensors, |p| p.sensors),
            collision: m.collision,
        };
        self.state.overlay = Overlay::Tuning { selected: 0, draft };
    }

    /// A key in the settings palette.
    pub fn tuning_key(&mut self, key: Key, new_press: bool) {
        let rows = tuning_rows(&self.state.droid().monitor);
        let caps = self.state.droid().monitor.caps;
        let Overlay::Tuning { selected, draft } = &mut self.state.overlay else {
            return;
        };
        let row = rows.get(*selected).copied();
        match self.keymap.action_in(Context::Settings, &key) {
            Some(Action::SettingsUp) => *selected = selected.saturating_sub(1),
            Some(Action::SettingsDown) => {
                *selected = (*selected + 1).min(rows.len().saturating_sub(1))
            }
            Some(Action::SettingsLess) => {
                if let Some(r) = row {
                    draft.change(caps.as_ref(), r, Some(false));
                }
            }
            Some(Action::SettingsMore) => {
                if let Some(r) = row {
                    draft.change(caps.as_ref(), r, Some(true));
                }
            }
            Some(Action::SettingsToggle) if new_press => {
                if let Some(r) = row {
                    draft.change(caps.as_ref(), r, None);
                }
            }
            Some(Action::SettingsApply) if new_press => {
                let draft = draft.clone();
                self.state.overlay = Overlay::None;
                if let Some(mut d) = self.droid(self.chosen()) {
                    d.apply_tuning(draft);
                }
            }
            Some(Action::SettingsClose) => self.state.overlay = Overlay::None,
            _ => {}
        }
    }
}

impl super::droid::DroidMut<'_> {
    /// Send the settings: streaming (capped to the link) then collision detection, and make
    /// them the setup of every later reconnect.
    pub fn apply_tuning(&mut self, draft: TuningDraft) {
        let model = self.view.model;
        let request = StreamRequest {
            rate_hz: draft.rate_hz,
            sensors: draft.sensors,
        };
        let plan = stream::plan_for(model, request);
        let family = self.io.family;
        let mut cmds = match &plan {
            Some(p) => stream::reconfigure(model, p, &draft.collision),
            None => family.collision_detection(&draft.collision),
        };
        // The session writes them in order; a full queue is said once.
        let mut failed = None;
        if let Some(session) = &self.io.session {
            for c in cmds.drain(..) {
                if let Err(e) = session.send(c) {
                    failed = Some(e);
                    break;
                }
            }
            let setup = SetupOptions {
                tripod: self.tripod_on_connect,
                collision: draft.collision,
                ..SetupOptions::default()
            };
            let setup = match &plan {
                Some(p) => setup.with_plan(p),
                None => setup,
            };
            session.set_setup(connect_setup(model, &setup));
        }
        let m = &mut self.view.monitor;
        m.request = request;
        m.plan = plan;
        m.collision = draft.collision;
        let streaming = match &m.plan {
            Some(p) if p.is_on() => format!("streaming {} at {}", p.sensors, m.requested()),
            Some(_) => "streaming off".into(),
            None => String::new(),
        };
        let mut text = [streaming, format!("collision {}", m.collision.describe())]
            .into_iter()
            .filter(|s| !s.is_empty())
            .collect::<Vec<_>>()
            .join(" · ");
        if let Some(note) = m.plan.as_ref().and_then(|p| p.note.clone()) {
            text = format!("{note} — {text}");
        }
        if let Some(e) = failed {
            text = format!("settings not all sent: {e}");
        }
        self.hint(text);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_draft_steps_rates_groups_and_thresholds() {
        let m = MonitorView::new(
            Model::R2D2,
            StreamRequest {
                rate_hz: 10,
                sensors: SensorSet::of(&[SensorGroup::Attitude]),
            },
            CollisionConfig::default(),
        );
        let rows = tuning_rows(&m);
        assert_eq!(rows[0], TuningRow::Rate);
        assert!(rows.contains(&TuningRow::Group(SensorGroup::HeadAngle)));
        assert_eq!(rows.last(), Some(&TuningRow::DeadTime));
        let mut d = TuningDraft {
            rate_hz: 10,
            sensors: SensorSet::of(&[SensorGroup::Attitude]),
            collision: CollisionConfig::default(),
        };
        let caps = m.caps.as_ref();
        d.change(caps, TuningRow::Rate, Some(true));
        assert_eq!(d.rate_hz, 20);
        for _ in 0..9 {
            d.change(caps, TuningRow::Rate, Some(false));
        }
        assert_eq!(d.rate_hz, 0, "off is below the slowest rate");
        d.change(caps, TuningRow::Group(SensorGroup::Gyro), None);
        assert!(d.sensors.contains(SensorGroup::Gyro));
        for _ in 0..30 {
            d.change(caps, TuningRow::XThreshold, Some(true));
            d.change(caps, TuningRow::DeadTime, Some(true));
        }
        assert_eq!(d.collision.x_threshold, 255);
        assert_eq!(d.collision.dead_time_ms, 400);
        d.change(caps, TuningRow::Collision, None);
        assert!(!d.collision.enabled);
        // Robi 42 has neither streaming nor collision settings.
        let robi = MonitorView::new(Model::Robi42, m.request, CollisionConfig::default());
        assert!(tuning_rows(&robi).is_empty());
    }
}
