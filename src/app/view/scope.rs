//! The scope's and the monitoring settings' view state, one per droid in
//! [`crate::app::AppState`]: which channels, how long a window, paused, axes; the streaming
//! and collision settings in effect and the settings palette's draft. The keys that change
//! them are [`crate::app::monitor`]'s; the UI reads them.

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
