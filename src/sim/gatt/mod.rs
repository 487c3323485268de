//! A simulated droid at the GATT level, for fronts that speak GATT to other programs: the
//! virtual BlueZ of `droidctl sim --bluez` (`super::bluez`) and, later, a TCP relay.
//!
//! Sans-IO like the rest of the simulator: the front hands in connects, reads, writes and
//! subscriptions with the time they happen, and calls [`GattDroid::advance`] to collect what
//! is due (notifications, already cut as a droid cuts them; service resolution; a fault
//! dropping the link). No clock, no thread, no transport: a test drives it with plain
//! durations.
//!
//! Behind it is the same droid as `--sim` ([`crate::sim::wire_droid`]); the GATT table comes
//! from the model's profile ([`GattProfile::for_model`]), and so does the handshake the
//! droid insists on before it listens:
//! - API v2 (R2-D2, R2-Q5, BB-9E): writes to the API characteristic are ignored until
//!   `usetheforce...band` is written to the anti-DoS characteristic 00020005;
//! - API v1 (BB-8, SPRK+, Ollie): commands are ignored until the wake sequence, `011i3` to
//!   2bbd, `07` to 2bb2, `01` to 2bbf, in that order;
//! - Robi 42: frames flow only after `01` is written to the start confirmation 0x4234; the
//!   handshake characteristic 0x4744 reads 5 bytes (version, MSDT).
//!
//! Reads in the handshake are allowed at any time and required by none. Every connection
//! starts locked again. One connection at a time, as the droids have.

mod table;

pub use super::faults::{FAULT_SYNTAX, GattFaults};
pub use super::sleep::SLEEP_GRACE;
pub use table::{CharDef, CharFlags, ServiceDef, gatt_table};

use super::sleep::{SleepStep, SleepTimer};
use super::{SimConfig, SimState, WireDroid, wire_droid};
use crate::gatt::{ATT_PAYLOAD, Endpoint, GattProfile, GattUuid, HandshakeStep};
use crate::model::Model;
use std::collections::VecDeque;
use std::fmt;
use std::time::Duration;

/// The longest value one write may carry (the ATT limit for an attribute value).
pub const MAX_WRITE: usize = 512;

/// Bound on what waits for the front between two [`GattDroid::advance`] calls.
const OUTBOX_MAX: usize = 4096;

/// Why a GATT operation failed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum GattError {
    NotConnected,
    /// The droid already has a connection (it takes one at a time).
    AlreadyConnected,
    /// The connection attempt failed (the `refuse-connect` fault).
    Refused,
    /// Connected, but service discovery has not finished.
    NotResolved,
    UnknownCharacteristic(GattUuid),
    ReadNotPermitted,
    WriteNotPermitted,
    /// Subscribing to a characteristic that does not notify.
    NotifyNotSupported,
    /// Unsubscribing from a characteristic not subscribed to.
    NotNotifying,
    /// A write longer than [`MAX_WRITE`].
    InvalidLength(usize),
    /// The droid fell asleep ([`GattFaults::idle_sleep`]): it no longer answers.
    Asleep,
}

impl fmt::Display for GattError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GattError::NotConnected => f.write_str("not connected"),
            GattError::AlreadyConnected => f.write_str("the droid already has a connection"),
            GattError::Refused => f.write_str("the droid refused the connection"),
            GattError::NotResolved => f.write_str("services are not resolved yet"),
            GattError::UnknownCharacteristic(u) => write!(f, "no characteristic {u}"),
            GattError::ReadNotPermitted => f.write_str("read not permitted"),
            GattError::WriteNotPermitted => f.write_str("write not permitted"),
            GattError::NotifyNotSupported => f.write_str("the characteristic does not notify"),
            GattError::NotNotifying => f.write_str("no notify session started"),
            GattError::InvalidLength(n) => {
                write!(f, "a write of {n} bytes (at most {MAX_WRITE})")
            }
            GattError::Asleep => f.write_str("the droid is asleep"),
        }
    }
}

impl std::error::Error for GattError {}

/// What [`GattDroid::advance`] reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum GattEvent {
    /// A notification on a subscribed characteristic: at most 20 bytes (Robi: one frame).
    Notification {
        characteristic: GattUuid,
        value: Vec<u8>,
    },
    /// Service discovery of the current connection finished.
    ServicesResolved,
    /// The droid dropped the connection (the disconnect fault); `after` is how long it
    /// lasted.
    Dropped { after: Duration },
}

/// The link as the droid sees it.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct GattStatus {
    pub connected: bool,
    pub services_resolved: bool,
    /// The handshake is complete: the droid listens (v2 unlocked, v1 awake, Robi started).
    pub unlocked: bool,
    /// Characteristics notifying.
    pub notifying: Vec<GattUuid>,
    /// Connections made, attempts refused, connections dropped by the fault.
    pub connects: u32,
    pub refused: u32,
    pub dropped: u32,
    /// Fell asleep for good ([`GattFaults::idle_sleep`]): no connections any more, no
    /// advertising. A [`GattEvent::Dropped`] with this set is the droid falling asleep.
    pub asleep: bool,
}

/// A droid behind its GATT table.
pub struct GattDroid {
    model: Model,
    profile: GattProfile,
    table: Vec<ServiceDef>,
    droid: Box<dyn WireDroid>,
    faults: GattFaults,
    /// Values of the readable characteristics (Robi's handshake).
    readable: Vec<(GattUuid, Vec<u8>)>,
    /// The handshake's writes, in order; `progress` of them done on this connection.
    unlock: Vec<(GattUuid, Vec<u8>)>,
    progress: usize,
    status: GattStatus,
    connected_at: Duration,
    resolve_at: Duration,
    drop_at: Option<Duration>,
    attempts: u32,
    now: Duration,
    outbox: VecDeque<GattEvent>,
    /// The deep sleep of [`GattFaults::idle_sleep`], counted from any write or connect; `None`
    /// without it, or for a droid that never sleeps (Robi 42).
    idle: Option<SleepTimer>,
}

impl GattDroid {
    pub fn new(model: Model, cfg: SimConfig, faults: GattFaults) -> Self {
        let profile = crate::family::gatt_profile(model);
        let droid = wire_droid(model, cfg);
        // What the handshake reads (Robi: its version and interval), as the front says.
        let readable = profile
            .handshake
            .iter()
            .filter_map(|s| match s {
                HandshakeStep::Read { ch, .. } => {
                    Some((ch.characteristic, droid.handshake_value()))
                }
                HandshakeStep::Write { .. } => None,
            })
            .collect();
        let idle = faults
            .idle_sleep
            .filter(|_| droid.will_sleep().is_some())
            .map(|limit| SleepTimer::new(limit.saturating_add(SLEEP_GRACE), SLEEP_GRACE));
        let unlock = profile
            .handshake
            .iter()
            .filter_map(|s| match s {
                HandshakeStep::Write { ch, bytes, .. } => Some((ch.characteristic, bytes.clone())),
                HandshakeStep::Read { .. } => None,
            })
            .collect();
        GattDroid {
            model,
            table: gatt_table(model),
            droid,
            profile,
            faults,
            readable,
            unlock,
            progress: 0,
            status: GattStatus::default(),
            connected_at: Duration::ZERO,
            resolve_at: Duration::ZERO,
            drop_at: None,
            attempts: 0,
            now: Duration::ZERO,
            outbox: VecDeque::new(),
            idle,
        }
    }

    pub fn model(&self) -> Model {
        self.model
    }

    pub fn profile(&self) -> &GattProfile {
        &self.profile
    }

    /// The services and characteristics a client discovers.
    pub fn table(&self) -> &[ServiceDef] {
        &self.table
    }

    pub fn faults(&self) -> &GattFaults {
        &self.faults
    }

    /// What the droid shows that no packet says (BOLT's matrix), for traces.
    pub fn shows(&self) -> Option<String> {
        self.droid.shows()
    }

    /// The droid's body (position, speed, LEDs …) as of the last call.
    pub fn state(&self) -> &SimState {
        self.droid.state()
    }

    pub fn status(&self) -> &GattStatus {
        &self.status
    }

    /// Time never runs backwards, whatever the front passes in.
    fn tick(&mut self, now: Duration) -> Duration {
        self.now = self.now.max(now);
        self.now
    }

    fn def(&self, ch: GattUuid) -> Result<&CharDef, GattError> {
        self.table
            .iter()
            .flat_map(|s| &s.characteristics)
            .find(|c| c.uuid == ch)
            .ok_or(GattError::UnknownCharacteristic(ch))
    }

    fn ready(&self) -> Result<(), GattError> {
        if !self.status.connected {
            Err(GattError::NotConnected)
        } else if !self.status.services_resolved {
            Err(GattError::NotResolved)
        } else {
            Ok(())
        }
    }

    /// A central connects. Fails when the droid has a connection already, or when the
    /// `refuse-connect` fault says so. Services resolve after the `slow-resolve` delay (at
    /// the next [`advance`](Self::advance) without it).
    pub fn connect(&mut self, now: Duration) -> Result<(), GattError> {
        let now = self.tick(now);
        if self.status.asleep {
            return Err(GattError::Asleep);
        }
        if self.status.connected {
            return Err(GattError::AlreadyConnected);
        }
        self.attempts = self.attempts.saturating_add(1);
        if self.attempts <= self.faults.refuse_connects {
            self.status.refused += 1;
            return Err(GattError::Refused);
        }
        let first = self.status.connects == 0;
        self.status.connects += 1;
        self.status.connected = true;
        self.status.services_resolved = false;
        self.status.unlocked = false;
        self.status.notifying.clear();
        self.progress = 0;
        self.connected_at = now;
        self.activity(now);
        self.resolve_at = now + self.faults.slow_resolve;
        self.drop_at = self
            .faults
            .disconnect_after
            .filter(|_| first || self.faults.disconnect_every)
            .map(|d| now + d);
        // Let the droid catch up with the time it spent alone.
        let _ = self.droid.advance(now);
        if self.unlock.is_empty() {
            self.unlocked(now);
        }
        Ok(())
    }

    /// The central disconnects.
    pub fn disconnect(&mut self, now: Duration) -> Result<(), GattError> {
        let now = self.tick(now);
        if !self.status.connected {
            return Err(GattError::NotConnected);
        }
        self.link_gone(now);
        Ok(())
    }

    fn link_gone(&mut self, now: Duration) {
        self.status.connected = false;
        self.status.services_resolved = false;
        self.status.unlocked = false;
        self.status.notifying.clear();
        self.progress = 0;
        self.drop_at = None;
        self.outbox.clear();
        self.droid.disconnected(now);
    }

    /// The handshake is complete.
    fn unlocked(&mut self, now: Duration) {
        self.status.unlocked = true;
        // Robi starts its frames here; the v1 and v2 droids have nothing to do.
        let _ = self.droid.connect(now);
    }

    /// Read a characteristic.
    pub fn read(&mut self, ch: GattUuid, now: Duration) -> Result<Vec<u8>, GattError> {
        self.tick(now);
        self.ready()?;
        if !self.def(ch)?.flags.contains(CharFlags::READ) {
            return Err(GattError::ReadNotPermitted);
        }
        Ok(self
            .readable
            .iter()
            .find(|(c, _)| *c == ch)
            .map(|(_, v)| v.clone())
            .unwrap_or_default())
    }

    /// Write to a characteristic (with or without response: the droid does not care). A
    /// write the droid ignores (a command before the handshake, a wrong unlock) still
    /// succeeds, as on the air.
    pub fn write(&mut self, ch: GattUuid, bytes: &[u8], now: Duration) -> Result<(), GattError> {
        let now = self.tick(now);
        self.ready()?;
        if !self.def(ch)?.flags.writable() {
            return Err(GattError::WriteNotPermitted);
        }
        if bytes.len() > MAX_WRITE {
            return Err(GattError::InvalidLength(bytes.len()));
        }
        self.activity(now);
        if !self.status.unlocked {
            if let Some((c, want)) = self.unlock.get(self.progress)
                && *c == ch
                && want.as_slice() == bytes
            {
                self.progress += 1;
                if self.progress == self.unlock.len() {
                    self.unlocked(now);
                }
            }
            return Ok(());
        }
        let to = self
            .profile
            .inputs
            .iter()
            .find(|(_, c)| c.characteristic == ch)
            .map(|(e, _)| *e)
            .or((self.profile.write.characteristic == ch).then_some(Endpoint::Api));
        if let Some(to) = to {
            let packets = self.droid.receive_at(to, bytes, now);
            self.deliver(packets);
        }
        Ok(())
    }

    /// Subscribe to a characteristic's notifications.
    pub fn start_notify(&mut self, ch: GattUuid, now: Duration) -> Result<(), GattError> {
        self.tick(now);
        self.ready()?;
        if !self.def(ch)?.flags.contains(CharFlags::NOTIFY) {
            return Err(GattError::NotifyNotSupported);
        }
        if !self.status.notifying.contains(&ch) {
            self.status.notifying.push(ch);
        }
        Ok(())
    }

    /// Unsubscribe.
    pub fn stop_notify(&mut self, ch: GattUuid, now: Duration) -> Result<(), GattError> {
        self.tick(now);
        self.ready()?;
        self.def(ch)?;
        let before = self.status.notifying.len();
        self.status.notifying.retain(|c| *c != ch);
        if self.status.notifying.len() == before {
            return Err(GattError::NotNotifying);
        }
        Ok(())
    }

    /// The droid's packets as notifications, cut as a droid cuts them: each packet on its
    /// own, in pieces of at most 20 bytes (Robi: one frame per notification). Nobody
    /// subscribed, nobody hears them.
    fn deliver(&mut self, packets: Vec<Vec<u8>>) {
        let Some(ch) = self.profile.notify.first().map(|c| c.characteristic) else {
            return;
        };
        if !self.status.connected || !self.status.notifying.contains(&ch) {
            return;
        }
        let whole = self.droid.whole_notifications();
        for p in packets {
            let pieces: Vec<Vec<u8>> = if whole {
                vec![p]
            } else {
                p.chunks(ATT_PAYLOAD).map(<[u8]>::to_vec).collect()
            };
            for value in pieces.into_iter().filter(|v| !v.is_empty()) {
                if self.outbox.len() >= OUTBOX_MAX {
                    self.outbox.pop_front();
                }
                self.outbox.push_back(GattEvent::Notification {
                    characteristic: ch,
                    value,
                });
            }
        }
    }

    fn activity(&mut self, now: Duration) {
        if let Some(t) = &mut self.idle {
            t.activity(now);
        }
    }

    /// The idle sleep: the warning when due (the front's own will-sleep packet), then falling
    /// asleep. Returns when it fell asleep while connected (the connection's drop time).
    fn idle(&mut self, now: Duration) -> Option<Duration> {
        // The timer starts with the first connection (a droid just switched on waits for
        // its host), then runs connected or not.
        if self.status.asleep || self.status.connects == 0 {
            return None;
        }
        match self.idle.as_mut()?.poll(now, self.status.connected)? {
            SleepStep::Sleep { at } => {
                self.status.asleep = true;
                self.status.connected.then_some(at)
            }
            SleepStep::Warn => {
                if let Some(p) = self.droid.will_sleep() {
                    self.deliver(vec![p]);
                }
                None
            }
        }
    }

    /// Let time pass: what is due, in order (services resolved, notifications, a dropped
    /// link). The droid keeps moving whether anyone is connected or not.
    pub fn advance(&mut self, now: Duration) -> Vec<GattEvent> {
        let now = self.tick(now);
        let mut out = Vec::new();
        if let Some(at) = self.idle(now) {
            // Fell asleep: whatever the droid had to say is lost with the link.
            let packets = self.droid.advance(at);
            self.deliver(packets);
            out.extend(self.outbox.drain(..));
            self.status.dropped += 1;
            let after = at.saturating_sub(self.connected_at);
            self.link_gone(at);
            let _ = self.droid.advance(now);
            out.push(GattEvent::Dropped { after });
            return out;
        }
        if self.status.connected && !self.status.services_resolved && now >= self.resolve_at {
            self.status.services_resolved = true;
            out.push(GattEvent::ServicesResolved);
        }
        // Up to the drop first, so what the droid sent before it still arrives.
        let drop_at = self.drop_at.filter(|t| *t <= now);
        let packets = self.droid.advance(drop_at.unwrap_or(now));
        self.deliver(packets);
        out.extend(self.outbox.drain(..));
        if let Some(at) = drop_at {
            self.status.dropped += 1;
            let after = at.saturating_sub(self.connected_at);
            self.link_gone(at);
            let _ = self.droid.advance(now);
            out.push(GattEvent::Dropped { after });
        }
        out
    }
}

#[cfg(test)]
mod tests;
