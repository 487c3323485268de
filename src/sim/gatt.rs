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

use super::{SimConfig, SimRobi, SimState, WireDroid, wire_droid};
use crate::family::v2::gatt::V2_SERVICE;
use crate::gatt::Endpoint;
use crate::gatt::{ATT_PAYLOAD, CharRef, GattProfile, GattUuid, HandshakeStep};
use crate::model::{Model, Protocol};
use std::collections::VecDeque;
use std::fmt;
use std::time::Duration;

/// The longest value one write may carry (the ATT limit for an attribute value).
pub const MAX_WRITE: usize = 512;

/// Bound on what waits for the front between two [`GattDroid::advance`] calls.
const OUTBOX_MAX: usize = 4096;

bitflags::bitflags! {
    /// What a characteristic allows, as its GATT properties say.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub struct CharFlags: u8 {
        const READ = 0x02;
        const WRITE_WITHOUT_RESPONSE = 0x04;
        const WRITE = 0x08;
        const NOTIFY = 0x10;
    }
}

impl CharFlags {
    /// The flag names BlueZ uses (`org.bluez.GattCharacteristic1.Flags`).
    pub fn names(self) -> Vec<&'static str> {
        [
            (CharFlags::READ, "read"),
            (CharFlags::WRITE_WITHOUT_RESPONSE, "write-without-response"),
            (CharFlags::WRITE, "write"),
            (CharFlags::NOTIFY, "notify"),
        ]
        .into_iter()
        .filter(|(f, _)| self.contains(*f))
        .map(|(_, n)| n)
        .collect()
    }

    pub fn writable(self) -> bool {
        self.intersects(CharFlags::WRITE | CharFlags::WRITE_WITHOUT_RESPONSE)
    }
}

/// One characteristic of the table.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CharDef {
    pub uuid: GattUuid,
    pub flags: CharFlags,
}

/// One primary service and its characteristics, in the order a droid lists them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServiceDef {
    pub uuid: GattUuid,
    pub characteristics: Vec<CharDef>,
}

/// The GATT table of `model`, as its profile describes it: every characteristic the profile
/// writes, reads or subscribes to, in the service it lives in.
pub fn gatt_table(model: Model) -> Vec<ServiceDef> {
    let profile = crate::family::gatt_profile(model);
    let writable = CharFlags::WRITE | CharFlags::WRITE_WITHOUT_RESPONSE;
    let mut chars: Vec<(CharRef, CharFlags)> = Vec::new();
    let mut add = |c: CharRef, f: CharFlags| match chars
        .iter_mut()
        .find(|(x, _)| x.characteristic == c.characteristic)
    {
        Some((_, flags)) => *flags |= f,
        None => chars.push((c, f)),
    };
    add(profile.write, writable);
    for (_, c) in &profile.inputs {
        add(*c, writable);
    }
    for c in &profile.notify {
        add(*c, CharFlags::NOTIFY);
    }
    for step in &profile.handshake {
        match step {
            HandshakeStep::Write { ch, .. } => add(*ch, writable),
            HandshakeStep::Read { ch, .. } => add(*ch, CharFlags::READ),
        }
    }
    let mut table: Vec<ServiceDef> = Vec::new();
    for (c, flags) in chars {
        let service = c.home(profile.service);
        let def = CharDef {
            uuid: c.characteristic,
            flags,
        };
        match table.iter_mut().find(|s| s.uuid == service) {
            Some(s) => s.characteristics.push(def),
            None => table.push(ServiceDef {
                uuid: service,
                characteristics: vec![def],
            }),
        }
    }
    // The main service first, as droids list it.
    table.sort_by_key(|s| s.uuid != profile.service && s.uuid != V2_SERVICE);
    table
}

/// Faults the droid can inject at the GATT level. The command-line syntax (`--fault`) is
/// parsed by [`GattFaults::add`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct GattFaults {
    /// Refuse this many connection attempts, counting from the first (`u32::MAX`: all).
    pub refuse_connects: u32,
    /// Drop a connection this long after it was made: the first one only, or every one with
    /// `disconnect_every`.
    pub disconnect_after: Option<Duration>,
    pub disconnect_every: bool,
    /// Service discovery takes this long after a connect.
    pub slow_resolve: Duration,
    /// Not a fault but a droid's habit (`sim --bluez --idle-sleep SECS`): after this long
    /// without a command (a write; counted from its first connection on) the droid sends its
    /// will-sleep warning, and [`SLEEP_GRACE`] later, with still nothing received, it falls
    /// asleep for good: it drops the connection and stops advertising. Robi 42 has no sleep
    /// timer and ignores it.
    pub idle_sleep: Option<Duration>,
}

/// How long after its will-sleep warning an idle droid falls asleep.
pub const SLEEP_GRACE: Duration = Duration::from_secs(5);

/// The `--fault` forms, for messages.
pub const FAULT_SYNTAX: &str = "disconnect-after=SECS, disconnect-every=SECS, refuse-connect[=N] \
                                or slow-resolve=SECS";

impl GattFaults {
    pub fn none() -> Self {
        GattFaults::default()
    }

    /// Add one fault in its command-line form: `disconnect-after=SECS` (drop the first
    /// connection SECS after it was made), `disconnect-every=SECS` (drop every connection
    /// SECS after it was made), `refuse-connect` (refuse every connection attempt),
    /// `refuse-connect=N` (refuse the first N), `slow-resolve=SECS` (services resolve SECS
    /// after each connect).
    pub fn add(&mut self, spec: &str) -> Result<(), String> {
        let spec = spec.trim();
        let (name, value) = match spec.split_once('=') {
            Some((n, v)) => (n.trim(), Some(v.trim())),
            None => (spec, None),
        };
        let secs = |v: Option<&str>| -> Result<Duration, String> {
            let v = v.ok_or_else(|| format!("`{name}` needs a number of seconds: {name}=SECS"))?;
            let s: f64 = v
                .parse()
                .map_err(|_| format!("`{spec}`: `{v}` is not a number of seconds"))?;
            if !s.is_finite() || !(0.0..=3600.0).contains(&s) {
                return Err(format!("`{spec}`: seconds must be within 0..=3600"));
            }
            Ok(Duration::from_secs_f64(s))
        };
        match name {
            "disconnect-after" => {
                self.disconnect_after = Some(secs(value)?);
                self.disconnect_every = false;
            }
            "disconnect-every" => {
                let d = secs(value)?;
                if d.is_zero() {
                    return Err(format!("`{spec}`: a connection must last some time"));
                }
                self.disconnect_after = Some(d);
                self.disconnect_every = true;
            }
            "refuse-connect" => {
                self.refuse_connects = match value {
                    None => u32::MAX,
                    Some(v) => v.parse().map_err(|_| {
                        format!("`{spec}`: `{v}` is not a count of connection attempts")
                    })?,
                }
            }
            "slow-resolve" => self.slow_resolve = secs(value)?,
            _ => return Err(format!("unknown fault `{spec}`: use {FAULT_SYNTAX}")),
        }
        Ok(())
    }

    /// The faults in effect, in their command-line form.
    pub fn describe(&self) -> Vec<String> {
        let mut out = Vec::new();
        if let Some(d) = self.disconnect_after {
            let name = if self.disconnect_every {
                "disconnect-every"
            } else {
                "disconnect-after"
            };
            out.push(format!("{name}={}", d.as_secs_f64()));
        }
        match self.refuse_connects {
            0 => {}
            u32::MAX => out.push("refuse-connect".into()),
            n => out.push(format!("refuse-connect={n}")),
        }
        if !self.slow_resolve.is_zero() {
            out.push(format!("slow-resolve={}", self.slow_resolve.as_secs_f64()));
        }
        out
    }
}

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
    /// The last command (any write) or connect, for the idle sleep.
    last_activity: Duration,
    will_sleep_sent: bool,
}

impl GattDroid {
    pub fn new(model: Model, cfg: SimConfig, faults: GattFaults) -> Self {
        let profile = crate::family::gatt_profile(model);
        let readable = profile
            .handshake
            .iter()
            .filter_map(|s| match s {
                HandshakeStep::Read { ch, .. } => Some(ch.characteristic),
                HandshakeStep::Write { .. } => None,
            })
            .map(|c| {
                // Only Robi reads anything: its handshake (version, MSDT).
                let value = if model.protocol() == Protocol::Rsrcp {
                    SimRobi::new(cfg.clone()).handshake().encode().to_vec()
                } else {
                    Vec::new()
                };
                (c, value)
            })
            .collect();
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
            droid: wire_droid(model, cfg),
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
            last_activity: Duration::ZERO,
            will_sleep_sent: false,
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
        self.last_activity = now;
        self.will_sleep_sent = false;
    }

    /// The idle droid's will-sleep warning, as its family sends it: v2 Power/will-sleep
    /// (13h/19h), v1 the pre-sleep async message (ID 05h). Robi has none.
    fn will_sleep_packet(&self) -> Option<Vec<u8>> {
        match self.model.protocol() {
            Protocol::SpheroV2 => {
                Some(crate::protocol::v2::Packet::notification(0x13, 0x19, Vec::new()).encode())
            }
            Protocol::SpheroV1 => {
                use crate::protocol::v1::{AsyncPacket, Packet};
                Packet::Async(AsyncPacket::new(0x05, Vec::new()))
                    .encode()
                    .ok()
            }
            Protocol::Rsrcp => None,
        }
    }

    /// The idle sleep: the warning when due, then falling asleep. Returns when it fell
    /// asleep while connected (the connection's drop time).
    fn idle(&mut self, now: Duration) -> Option<Duration> {
        let limit = self.faults.idle_sleep?;
        // The timer starts with the first connection (a droid just switched on waits for
        // its host), then runs connected or not.
        if self.status.asleep
            || self.status.connects == 0
            || self.model.protocol() == Protocol::Rsrcp
        {
            return None;
        }
        let idle = now.saturating_sub(self.last_activity);
        let asleep_after = limit.saturating_add(SLEEP_GRACE);
        if idle >= asleep_after {
            self.status.asleep = true;
            if self.status.connected {
                return Some(self.last_activity.saturating_add(asleep_after));
            }
        } else if idle >= limit && self.status.connected && !self.will_sleep_sent {
            self.will_sleep_sent = true;
            if let Some(p) = self.will_sleep_packet() {
                self.deliver(vec![p]);
            }
        }
        None
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
mod tests {
    use super::*;
    use crate::family::robi::gatt::{ROBI_FRAMES, ROBI_HANDSHAKE, ROBI_START, ROBI_VELOCITY};
    use crate::family::v1::gatt::{V1_ANTI_DOS, V1_COMMANDS, V1_TX_POWER, V1_WAKE};
    use crate::family::v2::gatt::{V2_ANTI_DOS, V2_ANTI_DOS_SERVICE, V2_API, V2_UNLOCK};
    use crate::protocol::v2::{Decoder, Packet, cmd};

    const MS: Duration = Duration::from_millis(1);

    fn ms(n: u64) -> Duration {
        MS * n as u32
    }

    fn droid(model: Model, faults: GattFaults) -> GattDroid {
        GattDroid::new(model, SimConfig::for_model(model), faults)
    }

    /// Connected, services resolved, subscribed to the profile's notifications.
    fn ready(model: Model) -> GattDroid {
        let mut d = droid(model, GattFaults::none());
        d.connect(ms(0)).unwrap();
        assert_eq!(d.advance(ms(1)), [GattEvent::ServicesResolved]);
        for c in d.profile().notify.clone() {
            d.start_notify(c.characteristic, ms(1)).unwrap();
        }
        d
    }

    fn notifications(events: &[GattEvent]) -> Vec<Vec<u8>> {
        events
            .iter()
            .filter_map(|e| match e {
                GattEvent::Notification { value, .. } => Some(value.clone()),
                _ => None,
            })
            .collect()
    }

    fn ping_v2() -> Vec<u8> {
        cmd::ping().to_packet(1).encode()
    }

    fn v2_packets(bytes: &[u8]) -> Vec<Packet> {
        Decoder::new()
            .decode_all(bytes)
            .into_iter()
            .filter_map(Result::ok)
            .collect()
    }

    #[test]
    fn tables_hold_every_profile_characteristic() {
        for model in Model::ALL {
            let table = gatt_table(model);
            let profile = crate::family::gatt_profile(model);
            for c in profile.characteristics() {
                assert!(
                    table
                        .iter()
                        .any(|s| s.characteristics.iter().any(|d| c.matches(s.uuid, d.uuid))),
                    "{model:?}: {c} missing"
                );
            }
            assert_eq!(
                table[0].uuid, profile.service,
                "{model:?}: main service first"
            );
        }
        let v2 = gatt_table(Model::R2D2);
        assert_eq!(v2.len(), 2);
        assert_eq!(v2[1].uuid, V2_ANTI_DOS_SERVICE);
        let api = &v2[0].characteristics[0];
        assert_eq!(api.uuid, V2_API);
        assert_eq!(
            api.flags.names(),
            ["write-without-response", "write", "notify"]
        );
        let robi = gatt_table(Model::Robi42);
        let handshake = robi
            .iter()
            .flat_map(|s| &s.characteristics)
            .find(|c| c.uuid == ROBI_HANDSHAKE)
            .unwrap();
        assert_eq!(handshake.flags, CharFlags::READ);
    }

    #[test]
    fn v2_ignores_commands_until_unlocked() {
        let mut d = ready(Model::R2D2);
        d.write(V2_API, &ping_v2(), ms(10)).unwrap();
        assert!(notifications(&d.advance(ms(20))).is_empty(), "locked");
        assert_eq!(d.state().commands, 0);
        // A wrong unlock does nothing either.
        d.write(V2_ANTI_DOS, b"usetheforce", ms(30)).unwrap();
        d.write(V2_API, &ping_v2(), ms(40)).unwrap();
        assert!(notifications(&d.advance(ms(50))).is_empty());
        d.write(V2_ANTI_DOS, V2_UNLOCK, ms(60)).unwrap();
        assert!(d.status().unlocked);
        d.write(V2_API, &ping_v2(), ms(70)).unwrap();
        let bytes = notifications(&d.advance(ms(80))).concat();
        let answers = v2_packets(&bytes);
        assert_eq!(answers.len(), 1, "{bytes:02x?}");
        assert!(answers[0].is_response());
        // A new connection is locked again.
        d.disconnect(ms(90)).unwrap();
        d.connect(ms(100)).unwrap();
        d.advance(ms(101));
        d.start_notify(V2_API, ms(101)).unwrap();
        d.write(V2_API, &ping_v2(), ms(110)).unwrap();
        assert!(notifications(&d.advance(ms(120))).is_empty());
    }

    #[test]
    fn v1_needs_the_whole_wake_sequence_in_order() {
        let roll = crate::protocol::v1::Packet::Command(crate::protocol::v1::CommandPacket::new(
            0x02,
            0x30,
            1,
            vec![80, 0, 0, 1],
        ))
        .encode()
        .unwrap();
        let mut d = ready(Model::BB8);
        let send = |d: &mut GattDroid, t: u64| {
            d.write(V1_COMMANDS, &roll, ms(t)).unwrap();
            notifications(&d.advance(ms(t + 5)))
        };
        assert!(send(&mut d, 10).is_empty(), "asleep");
        // Wake before the unlock: ignored.
        d.write(V1_WAKE, &[1], ms(20)).unwrap();
        d.write(V1_ANTI_DOS, b"011i3", ms(30)).unwrap();
        assert!(send(&mut d, 40).is_empty(), "unlocked but not awake");
        d.write(V1_TX_POWER, &[7], ms(50)).unwrap();
        d.write(V1_WAKE, &[1], ms(60)).unwrap();
        assert!(d.status().unlocked);
        let answer = send(&mut d, 70).concat();
        assert!(
            answer.starts_with(&[0xFF, 0xFF, 0x00, 0x01]),
            "{answer:02x?}"
        );
        assert_eq!(d.state().commands, 1);
    }

    #[test]
    fn robi_reads_its_handshake_and_frames_flow_after_the_start() {
        let mut d = ready(Model::Robi42);
        assert_eq!(d.read(ROBI_HANDSHAKE, ms(5)).unwrap().len(), 5);
        assert!(
            notifications(&d.advance(ms(500))).is_empty(),
            "no frames yet"
        );
        assert_eq!(
            d.read(ROBI_FRAMES, ms(500)),
            Err(GattError::ReadNotPermitted)
        );
        d.write(ROBI_START, &[1], ms(500)).unwrap();
        let events = d.advance(ms(1000));
        let frames = notifications(&events);
        // One frame per notification, every 100 ms.
        assert!((5..=6).contains(&frames.len()), "{}", frames.len());
        assert!(
            frames
                .iter()
                .all(|f| f[0] == 0x7E && f.last() == Some(&0x7F))
        );
        assert!(events.iter().all(|e| matches!(
            e,
            GattEvent::Notification { characteristic, .. } if *characteristic == ROBI_FRAMES
        )));
        // The remote control drives it.
        d.write(ROBI_VELOCITY, &[255], ms(1000)).unwrap();
        d.advance(ms(3000));
        assert!(d.state().y_cm.abs() + d.state().x_cm.abs() > 10.0);
        // The host goes: the motors stop.
        d.disconnect(ms(3000)).unwrap();
        d.advance(ms(4000));
        assert!(d.state().velocity_cm_s.abs() < 1.0);
    }

    #[test]
    fn notifications_are_cut_at_20_bytes() {
        let mut d = ready(Model::R2D2);
        d.write(V2_ANTI_DOS, V2_UNLOCK, ms(1)).unwrap();
        // The connect setup turns on sensor streaming, whose packets are longer than 20 bytes.
        let c = crate::family::setup::connect_setup(
            Model::R2D2,
            &crate::family::setup::SetupOptions::default(),
        );
        for (i, cmd) in c.iter().enumerate() {
            let family = crate::family::for_model(Model::R2D2);
            let mut codec = family.codec();
            let (writes, _) = codec.encode_writes(cmd, i as u8, true);
            for (_, w) in writes {
                for chunk in w.chunks(20) {
                    d.write(V2_API, chunk, ms(10 + i as u64 * 120)).unwrap();
                }
            }
        }
        let events = d.advance(ms(5000));
        let values = notifications(&events);
        assert!(values.len() > 20);
        assert!(values.iter().all(|v| !v.is_empty() && v.len() <= 20));
        assert!(values.iter().any(|v| v.len() == 20), "long packets are cut");
        let packets = v2_packets(&values.concat());
        assert!(packets.iter().any(|p| p.did == 0x18 && p.cid == 0x02));
        // Unsubscribed: silence.
        d.stop_notify(V2_API, ms(5000)).unwrap();
        assert!(notifications(&d.advance(ms(6000))).is_empty());
        assert_eq!(
            d.stop_notify(V2_API, ms(6000)),
            Err(GattError::NotNotifying)
        );
    }

    #[test]
    fn one_connection_at_a_time() {
        let mut d = droid(Model::R2D2, GattFaults::none());
        d.connect(ms(0)).unwrap();
        assert_eq!(d.connect(ms(1)), Err(GattError::AlreadyConnected));
        d.disconnect(ms(2)).unwrap();
        assert_eq!(d.disconnect(ms(3)), Err(GattError::NotConnected));
        d.connect(ms(4)).unwrap();
        assert_eq!(d.status().connects, 2);
    }

    #[test]
    fn operations_need_a_resolved_connection() {
        let mut faults = GattFaults::none();
        faults.add("slow-resolve=1.5").unwrap();
        let mut d = droid(Model::R2D2, faults);
        assert_eq!(d.write(V2_API, &[1], ms(0)), Err(GattError::NotConnected));
        d.connect(ms(0)).unwrap();
        assert!(d.advance(ms(1000)).is_empty());
        assert_eq!(
            d.start_notify(V2_API, ms(1000)),
            Err(GattError::NotResolved)
        );
        assert_eq!(d.advance(ms(1500)), [GattEvent::ServicesResolved]);
        d.start_notify(V2_API, ms(1500)).unwrap();
        assert_eq!(
            d.start_notify(V2_ANTI_DOS, ms(1500)),
            Err(GattError::NotifyNotSupported)
        );
        let unknown = GattUuid::from_u16(0x1234);
        assert_eq!(
            d.write(unknown, &[1], ms(1500)),
            Err(GattError::UnknownCharacteristic(unknown))
        );
        assert_eq!(
            d.write(V2_API, &[0; 513], ms(1500)),
            Err(GattError::InvalidLength(513))
        );
    }

    #[test]
    fn refused_connections_then_accepted() {
        let mut faults = GattFaults::none();
        faults.add("refuse-connect=2").unwrap();
        let mut d = droid(Model::BB8, faults);
        assert_eq!(d.connect(ms(0)), Err(GattError::Refused));
        assert_eq!(d.connect(ms(10)), Err(GattError::Refused));
        d.connect(ms(20)).unwrap();
        assert_eq!(d.status().refused, 2);
        let mut always = GattFaults::none();
        always.add("refuse-connect").unwrap();
        let mut d = droid(Model::BB8, always);
        assert!((0..50).all(|i| d.connect(ms(i)) == Err(GattError::Refused)));
        assert!(!d.status().connected);
    }

    #[test]
    fn the_disconnect_fault_drops_the_first_connection_only() {
        let mut faults = GattFaults::none();
        faults.add("disconnect-after=1").unwrap();
        let mut d = droid(Model::R2D2, faults);
        d.connect(ms(100)).unwrap();
        d.advance(ms(500));
        assert!(d.status().connected);
        let events = d.advance(ms(1200));
        assert_eq!(
            events.last(),
            Some(&GattEvent::Dropped {
                after: Duration::from_secs(1)
            })
        );
        assert!(!d.status().connected);
        assert_eq!(
            d.write(V2_API, &[1], ms(1300)),
            Err(GattError::NotConnected)
        );
        // Still there: a new connection lasts.
        d.connect(ms(2000)).unwrap();
        let later = d.advance(ms(10_000));
        assert!(!later.iter().any(|e| matches!(e, GattEvent::Dropped { .. })));
        assert_eq!(d.status().dropped, 1);

        let mut every = GattFaults::none();
        every.add("disconnect-every=0.5").unwrap();
        let mut d = droid(Model::R2D2, every);
        for i in 0..3u64 {
            d.connect(ms(i * 1000)).unwrap();
            let ev = d.advance(ms(i * 1000 + 600));
            assert!(matches!(ev.last(), Some(GattEvent::Dropped { .. })), "{i}");
        }
    }

    #[test]
    fn fault_syntax() {
        let mut f = GattFaults::none();
        for spec in ["disconnect-after=2.5", "refuse-connect=3", "slow-resolve=1"] {
            f.add(spec).unwrap();
        }
        assert_eq!(
            f.describe(),
            ["disconnect-after=2.5", "refuse-connect=3", "slow-resolve=1"]
        );
        for bad in [
            "explode",
            "disconnect-after",
            "disconnect-after=soon",
            "slow-resolve=-1",
            "slow-resolve=NaN",
            "refuse-connect=many",
            "disconnect-every=0",
        ] {
            assert!(GattFaults::none().add(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn time_never_runs_backwards() {
        let mut d = ready(Model::R2D2);
        d.advance(ms(1000));
        // An older time is taken as the current one.
        d.write(V2_ANTI_DOS, V2_UNLOCK, ms(10)).unwrap();
        d.advance(ms(5));
        assert!(d.status().unlocked);
    }

    #[test]
    fn an_idle_droid_warns_then_falls_asleep_for_good() {
        let secs = |n: u64| Duration::from_secs(n);
        let faults = GattFaults {
            idle_sleep: Some(secs(2)),
            ..GattFaults::none()
        };
        let mut d = droid(Model::R2D2, faults.clone());
        d.connect(ms(0)).unwrap();
        d.advance(ms(1));
        let api = d.profile().notify[0].characteristic;
        d.start_notify(api, ms(1)).unwrap();
        d.write(V2_ANTI_DOS, V2_UNLOCK, ms(2)).unwrap();
        assert!(notifications(&d.advance(ms(1900))).is_empty());
        // The warning at 2 s without a command, once.
        let warned = v2_packets(&notifications(&d.advance(ms(2100))).concat());
        assert_eq!(warned.len(), 1);
        assert_eq!((warned[0].did, warned[0].cid), (0x13, 0x19));
        assert!(notifications(&d.advance(ms(3000))).is_empty());
        // A command puts it off; then nothing more: asleep 5 s after the next warning.
        d.write(V2_API, &ping_v2(), ms(4000)).unwrap();
        let evs = d.advance(ms(6100));
        assert!(
            v2_packets(&notifications(&evs).concat())
                .iter()
                .any(|p| (p.did, p.cid) == (0x13, 0x19))
        );
        assert!(!d.status().asleep);
        let evs = d.advance(ms(11_100));
        assert_eq!(evs.last(), Some(&GattEvent::Dropped { after: ms(11_000) }));
        assert!(d.status().asleep && !d.status().connected);
        assert_eq!(d.connect(ms(12_000)), Err(GattError::Asleep));
        // Robi has no sleep timer.
        let mut robi = droid(Model::Robi42, faults);
        robi.connect(ms(0)).unwrap();
        robi.advance(secs(60));
        assert!(robi.status().connected && !robi.status().asleep);
    }
}
