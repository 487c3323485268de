//! When a droid is ready (issue 31 point 3): `connected` only says the link is up; the
//! session then writes its connect setup (wake, a stop, the fail-safe, stance, collision
//! detection, streaming …) and until that is done a drive may do nothing. R2-D2 and R2-Q5
//! ignore drives until they stand on three legs: the setup's `perform-leg-action` tripod
//! takes about 2 s (`droid-facts.md` §2: "Tripod is required for rolling. A stance change
//! takes about 2 s and ends with the leg-action-complete notification"); a drive the session
//! writes meanwhile is answered `ok` and lost.
//!
//! So each droid is *ready* once, after its link says connected, a ping queued behind the
//! setup has been answered (the setup was written before it and the droid answers), and,
//! for a droid with legs, the leg-action-complete notification came (or
//! [`STANCE_WAIT`] passed). Robi 42 is ready once connected (no setup, and its ping would
//! be a stop). The link object says it (`"ready":true`); a drive or twist held
//! before it is written again at once, so it moves the droid as soon as it can.

use super::Bridge;
use super::feeds::link_out;
use crate::protocol::notify::Notification;
use crate::session::{LinkState, SessionEvent};
use std::sync::Weak;
use std::time::Duration;
use tokio::sync::broadcast;

/// How long after connecting a droid with legs is waited for its stance change to end,
/// at most (it takes about 2 s); then it counts as ready anyway.
pub const STANCE_WAIT: Duration = Duration::from_secs(4);

/// How long a ping that failed (a timeout) waits before the next one.
const RETRY: Duration = Duration::from_millis(250);

/// Pings unanswered for this long after connecting: the droid counts as ready anyway (its
/// setup was written long ago; a droid that answers nothing would otherwise never be).
const GIVE_UP: Duration = Duration::from_secs(10);

/// Watch droid `i`'s link and say when it is ready, for as long as the bridge lives.
pub async fn watch(bridge: Weak<Bridge>, i: usize) {
    let Some((session, family, model, name, mut state)) = bridge.upgrade().and_then(|b| {
        let m = b.fleet.member(i)?;
        Some((
            m.session.clone(),
            m.family,
            m.model,
            m.name.clone(),
            b.fleet.link_state(i)?,
        ))
    }) else {
        return;
    };
    loop {
        // Not ready until connected again.
        while *state.borrow_and_update() != LinkState::Connected {
            if state.changed().await.is_err() {
                return;
            }
        }
        let mut events = session.subscribe();
        let setup_done = async {
            let started = tokio::time::Instant::now();
            // Robi 42 has no connect setup to wait for and no ping that is not a command
            // (its "ping" is the remote control's stop): ready once connected.
            while model.protocol() != crate::model::Protocol::Rsrcp {
                match session.request(family.ping()).await {
                    Ok(_) => break,
                    Err(crate::session::RequestError::Closed) => return false,
                    // Unanswered for this long: the setup is long written; say ready
                    // rather than never.
                    Err(_) if started.elapsed() >= GIVE_UP => break,
                    Err(_) => tokio::time::sleep(RETRY).await,
                }
            }
            if model.has_legs() {
                let left = STANCE_WAIT.saturating_sub(started.elapsed());
                let _ = tokio::time::timeout(left, stance_done(&mut events)).await;
            }
            true
        };
        let done = tokio::select! {
            d = setup_done => d,
            // The link changed meanwhile: start over.
            _ = state.changed() => continue,
        };
        if !done {
            return;
        }
        let Some(b) = bridge.upgrade() else {
            return;
        };
        if *state.borrow() != LinkState::Connected {
            continue;
        }
        b.set_ready(i, true);
        b.emit(Some(i), link_out(&name, &LinkState::Connected, true));
        b.release_first_commands(i);
        b.resend_held(i);
        drop(b);
        if state.changed().await.is_err() {
            return;
        }
    }
}

/// Until the droid says its stance change ended.
async fn stance_done(events: &mut broadcast::Receiver<SessionEvent>) {
    loop {
        match events.recv().await {
            Ok(SessionEvent::Notification(Notification::LegActionComplete)) => return,
            Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => {}
            Err(broadcast::error::RecvError::Closed) => std::future::pending().await,
        }
    }
}

impl Bridge {
    /// Wait until droid `i` has been ready once since the bridge started (at once when it
    /// has), for at most `bound`: whether it has. The stdio reader reads no command for a
    /// droid before that (issue 40 point 11), so a piped script's first lines do not race
    /// the connection; past `bound` the command is carried out as it comes (a droid still
    /// down answers that it is not connected).
    pub async fn first_ready(&self, i: usize, bound: Duration) -> bool {
        let Some(d) = self.droids.get(i) else {
            return false;
        };
        let mut rx = d.was_ready.subscribe();
        let ready = tokio::time::timeout(bound, rx.wait_for(|r| *r)).await;
        matches!(ready, Ok(Ok(_)))
    }

    /// A reply's note for a drive or twist sent to droid `i` before it is ready.
    pub(super) fn not_ready_note(&self, i: usize) -> Option<String> {
        if self.is_ready(i) {
            return None;
        }
        let m = self.fleet.member(i)?;
        let what = if m.model.has_legs() {
            "its connect setup is running: it stands on three legs first"
        } else {
            "its connect setup is running"
        };
        Some(format!(
            "{} is not ready yet ({what}): the drive is held and moves it once its link says \
             \"ready\":true",
            m.name
        ))
    }

    /// Write droid `i`'s held drive or twist again now (it became ready).
    pub(super) fn resend_held(&self, i: usize) {
        let w = self.droids.get(i).and_then(|d| d.lock().holder.current());
        if let Some(w) = w {
            self.write_wheels(i, w);
        }
    }

    /// Stop droid `i` where it is: speed 0 at the heading it reports now, not at the last
    /// heading it was sent, which a droid still turning toward it would turn on to (a twist
    /// leaves the droid behind its integrated heading); as an emergency stop. Without a
    /// reported heading (or on a steering robot), the session's stop at the last heading.
    pub(super) fn stop_here(&self, i: usize) {
        let Some(m) = self.fleet.member(i) else {
            return;
        };
        let measured = self
            .fleet
            .telemetry(i)
            .and_then(|t| t.borrow().heading())
            .filter(|_| !m.family.steers());
        match measured {
            Some(h) => m
                .session
                .emergency_stop(crate::family::intent::stop_command(m.family, m.model, h)),
            None => m.session.stop_now(m.family),
        }
    }
}
