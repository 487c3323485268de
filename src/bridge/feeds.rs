//! What each droid of the bridge reports, as [`Out`] objects: a telemetry sample at the
//! bridge's rate (the sample `run --json` prints: [`crate::mission::sample_of`]), every
//! collision as it comes, the battery on a poll, and every change of its link.
//!
//! The tasks hold the bridge weakly: they end with it.

use super::Bridge;
use super::schema::{Out, axis_label};
use crate::protocol::notify::Notification;
use crate::session::{LinkState, SessionEvent};
use std::sync::{Arc, Weak};
use std::time::Duration;
use tokio::sync::broadcast;
use tokio::task::JoinHandle;

/// The link object for a state; `ready` only counts when connected.
pub fn link_out(droid: &str, s: &LinkState, ready: bool) -> Out {
    let (state, attempt, reason) = match s {
        LinkState::Connecting => ("connecting", None, None),
        LinkState::Connected => ("connected", None, None),
        LinkState::Reconnecting { attempt, reason } => {
            ("reconnecting", Some(*attempt), Some(reason.clone()))
        }
        LinkState::Closed { reason } => ("closed", None, reason.clone()),
    };
    Out::Link {
        droid: droid.to_string(),
        state,
        ready: ready && *s == LinkState::Connected,
        attempt,
        reason,
    }
}

/// The MQTT last will: the bridge is gone.
pub fn offline(droid: &str) -> Out {
    Out::Link {
        droid: droid.to_string(),
        state: "offline",
        ready: false,
        attempt: None,
        reason: None,
    }
}

/// Start droid `i`'s feeds.
pub fn spawn(bridge: &Arc<Bridge>, i: usize) -> Vec<JoinHandle<()>> {
    let weak = Arc::downgrade(bridge);
    let Some(m) = bridge.fleet.member(i) else {
        return Vec::new();
    };
    let name = m.name.clone();
    vec![
        tokio::spawn(samples(weak.clone(), i, name.clone())),
        tokio::spawn(collisions(
            weak.clone(),
            i,
            m.session.subscribe(),
            name.clone(),
        )),
        tokio::spawn(link(weak.clone(), i, name.clone())),
        tokio::spawn(battery(weak, i, name)),
    ]
}

/// A sample each time the droid reported something new (issue 31 point 2), at the rate it
/// offers ([`Bridge::telemetry_hz`], what `hello` and `info` say), evenly spaced (issue 40
/// point 9): a sample goes out [`settle`] after the report that starts it, so the parts of
/// one report that come as several notifications (RVR's: its two processors' and sensors',
/// about 10 ms apart) make one sample, and never sooner than one interval after the sample
/// before; reports that come faster are folded into the next sample, and nothing is
/// repeated while the droid reports nothing. A droid that reports at the rate it offers is
/// sampled once per report, late by jitter only: never two of its reports folded into one
/// unless one comes a whole interval late.
async fn samples(bridge: Weak<Bridge>, i: usize, name: String) {
    let (telemetry, state) = match bridge.upgrade() {
        Some(b) => (b.fleet.telemetry(i), b.fleet.link_state(i)),
        None => return,
    };
    let (Some(mut telemetry), Some(state)) = (telemetry, state) else {
        return;
    };
    let mut last: Option<tokio::time::Instant> = None;
    loop {
        if telemetry.changed().await.is_err() {
            return;
        }
        let interval = match bridge.upgrade() {
            Some(b) => {
                // A droid that streams nothing (0) still reports now and then: at most the
                // bridge's rate.
                let hz = match b.telemetry_hz(i) {
                    0 => b.settings.telemetry_hz,
                    hz => hz,
                };
                Duration::from_secs(1) / u32::from(hz.max(1))
            }
            None => return,
        };
        let now = tokio::time::Instant::now();
        let at = (now + settle(interval)).max(last.map_or(now, |l| l + interval));
        tokio::time::sleep_until(at).await;
        let Some(b) = bridge.upgrade() else {
            return;
        };
        if *state.borrow() != LinkState::Connected {
            telemetry.mark_unchanged();
            continue;
        }
        let sample = {
            let t = telemetry.borrow_and_update();
            crate::mission::sample_of(&t, b.t_ms())
        };
        b.emit(Some(i), telemetry_out(&name, sample, b.battery(i)));
        last = Some(at);
    }
}

/// How long a sample waits after the report that starts it, for the rest of that report:
/// a quarter of the interval, at most 25 ms (RVR's notifications of one report span about
/// 20 ms).
pub fn settle(interval: Duration) -> Duration {
    (interval / 4).min(Duration::from_millis(25))
}

/// The telemetry object of a sample: the battery as last read when the droid does not
/// notify it, and the position as a ROS user reads it.
pub fn telemetry_out(droid: &str, mut sample: crate::mission::Sample, battery: Option<f32>) -> Out {
    if sample.battery_v.is_none() {
        sample.battery_v = battery;
    }
    let odom = match (sample.x_cm, sample.y_cm) {
        (Some(x), Some(y)) => Some(super::schema::Odom::from_droid(
            x,
            y,
            // The droid's own yaw where it streams one, else the heading it reports.
            sample.yaw_deg.or_else(|| sample.heading.map(f32::from)),
        )),
        _ => None,
    };
    Out::Telemetry {
        droid: droid.to_string(),
        sample,
        odom,
    }
}

/// Every collision the droid reports.
async fn collisions(
    bridge: Weak<Bridge>,
    i: usize,
    mut rx: broadcast::Receiver<SessionEvent>,
    name: String,
) {
    let mut count = 0u32;
    loop {
        match rx.recv().await {
            Ok(SessionEvent::Notification(Notification::Collision(c))) => {
                let Some(b) = bridge.upgrade() else {
                    return;
                };
                count = count.saturating_add(1);
                b.emit(
                    Some(i),
                    Out::Collision {
                        droid: name.clone(),
                        t_ms: b.t_ms(),
                        axis: axis_label(c.axis.x, c.axis.y),
                        power: [c.power[0], c.power[1]],
                        speed: c.speed,
                        collisions: count,
                    },
                );
            }
            Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => {}
            Err(broadcast::error::RecvError::Closed) => return,
        }
    }
}

/// The link's state now, then every change.
async fn link(bridge: Weak<Bridge>, i: usize, name: String) {
    let Some(mut state) = bridge.upgrade().and_then(|b| b.fleet.link_state(i)) else {
        return;
    };
    loop {
        let now = state.borrow_and_update().clone();
        match bridge.upgrade() {
            Some(b) => {
                // A change of the link: not ready until [`super::ready`] says so anew.
                b.set_ready(i, false);
                b.emit(Some(i), link_out(&name, &now, false))
            }
            None => return,
        }
        if state.changed().await.is_err() {
            return;
        }
    }
}

/// The battery, read when the droid connects and then every poll interval.
async fn battery(bridge: Weak<Bridge>, i: usize, name: String) {
    let Some((session, family, model, every, mut state)) = bridge.upgrade().and_then(|b| {
        let m = b.fleet.member(i)?;
        Some((
            m.session.clone(),
            m.family,
            m.model,
            b.settings.battery_poll,
            b.fleet.link_state(i)?,
        ))
    }) else {
        return;
    };
    let Some(ask) = family.battery_request_for(model) else {
        return;
    };
    loop {
        // Wait for the link, then read.
        while *state.borrow_and_update() != LinkState::Connected {
            if state.changed().await.is_err() {
                return;
            }
        }
        if let Ok(p) = session.request(ask.clone()).await
            && let Some(v) = family.battery_volts_for(model, p.data())
        {
            let Some(b) = bridge.upgrade() else {
                return;
            };
            b.set_battery(i, v);
            b.emit(
                Some(i),
                Out::Battery {
                    droid: name.clone(),
                    t_ms: b.t_ms(),
                    volts: v,
                },
            );
        }
        tokio::time::sleep(every).await;
    }
}
