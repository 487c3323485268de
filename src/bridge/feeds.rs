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

/// The link object for a state.
pub fn link_out(droid: &str, s: &LinkState) -> Out {
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
        attempt,
        reason,
    }
}

/// The MQTT last will: the bridge is gone.
pub fn offline(droid: &str) -> Out {
    Out::Link {
        droid: droid.to_string(),
        state: "offline",
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

/// A sample every 1/rate while the droid is connected.
async fn samples(bridge: Weak<Bridge>, i: usize, name: String) {
    let (rate, telemetry, state) = match bridge.upgrade() {
        Some(b) => (
            b.settings.telemetry_hz.max(1),
            b.fleet.telemetry(i),
            b.fleet.link_state(i),
        ),
        None => return,
    };
    let (Some(telemetry), Some(state)) = (telemetry, state) else {
        return;
    };
    let mut every = tokio::time::interval(Duration::from_secs(1) / rate as u32);
    every.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        every.tick().await;
        let Some(b) = bridge.upgrade() else {
            return;
        };
        if *state.borrow() != LinkState::Connected {
            continue;
        }
        let mut sample = crate::mission::sample_of(&telemetry.borrow(), b.t_ms());
        if sample.battery_v.is_none() {
            sample.battery_v = b.battery(i);
        }
        b.emit(
            Some(i),
            Out::Telemetry {
                droid: name.clone(),
                sample,
            },
        );
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
            Some(b) => b.emit(Some(i), link_out(&name, &now)),
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
