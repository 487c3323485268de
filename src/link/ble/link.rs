//! [`BleLink`]: the [`Link`] over Bluetooth LE, written against [`BleCentral`] /
//! [`BlePeripheral`] so the same code runs on BlueZ and on the fake peripheral in tests.
//!
//! `open()` runs: find the device → connect → discover services → check the profile's
//! characteristics exist → the handshake → subscribe → forward notifications as one byte stream.
//! Every step is bounded by a timeout, and any failure after connecting disconnects again so
//! BlueZ is not left holding a half-open connection that would make the next attempt fail.

use super::backend::{BleAddress, BleCentral, BlePeripheral, DeviceId, PeripheralEvent};
use super::error::{BleError, BleErrorKind};
use crate::gatt::{CharRef, GattProfile, GattUuid, HandshakeStep};
use crate::link::{Connection, Link, LinkError, LinkEvent, LinkWriter};
use crate::model::Model;
use futures_util::StreamExt;
use futures_util::future::BoxFuture;
use futures_util::stream::BoxStream;
use std::future::Future;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::mpsc;
use tokio::time::{Instant, sleep, sleep_until, timeout};

/// How long each BLE step may take. Defaults are generous: BlueZ connects to a droid in about
/// a second when it is awake, and a sleeping droid does not answer at all.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BleTimeouts {
    pub connect: Duration,
    pub discover: Duration,
    /// Each read, write, subscribe and disconnect.
    pub op: Duration,
    /// Scanning again for a device the adapter has forgotten (BlueZ drops unpaired devices it
    /// has not heard from for a while).
    pub rescan: Duration,
}

impl Default for BleTimeouts {
    fn default() -> Self {
        BleTimeouts {
            connect: Duration::from_secs(10),
            discover: Duration::from_secs(10),
            op: Duration::from_secs(5),
            rescan: Duration::from_secs(5),
        }
    }
}

/// How often a rescan looks for the device it lost.
const RESCAN_POLL: Duration = Duration::from_millis(250);

/// How often a link waiting for a switched-off adapter asks whether it is back.
const POWER_POLL: Duration = Duration::from_millis(250);

/// Capacity of the event channel: notifications arrive at most every few ms.
const EVENT_CAPACITY: usize = 1024;

/// A droid over Bluetooth LE. Each `open()` connects afresh, so the session's reconnects re-run
/// the whole handshake.
///
/// The first `open()` fails for good on what retrying cannot fix (the adapter off, a device
/// lacking the droid's characteristics). Once a connection was made, those are passing: the
/// adapter switched off mid-session is waited for ([`crate::link::ADAPTER_OFF_WAITING`], and
/// [`Link::retry_hint`] fires when it is powered again), a characteristic missing on a
/// reconnect (services half-resolved) is retried with the session's backoff.
pub struct BleLink {
    central: Arc<dyn BleCentral>,
    id: DeviceId,
    name: String,
    model: Model,
    profile: GattProfile,
    timeouts: BleTimeouts,
    /// The peripheral `open` is connecting to, until it returns: what `abort_open` cancels
    /// when the caller drops the open future (quitting mid-connect).
    connecting: Option<Arc<dyn BlePeripheral>>,
    /// A connection was made once: what was fatal on the first open is passing now.
    opened_once: bool,
    /// The last open found the adapter switched off.
    adapter_off: bool,
}

impl BleLink {
    /// A link to the device `id` (or a [`BleAddress`]), a `model` speaking `profile`.
    pub fn new(
        central: Arc<dyn BleCentral>,
        id: impl Into<DeviceId>,
        name: impl Into<String>,
        model: Model,
        profile: GattProfile,
    ) -> Self {
        BleLink {
            central,
            id: id.into(),
            name: name.into(),
            model,
            profile,
            timeouts: BleTimeouts::default(),
            connecting: None,
            opened_once: false,
            adapter_off: false,
        }
    }

    /// Replace the profile (e.g. another write pacing: one client uses 12 ms for R2-D2).
    pub fn with_profile(mut self, profile: GattProfile) -> Self {
        self.profile = profile;
        self
    }

    pub fn with_timeouts(mut self, timeouts: BleTimeouts) -> Self {
        self.timeouts = timeouts;
        self
    }

    pub fn model(&self) -> Model {
        self.model
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// The device's address (its stand-in where the platform hides it).
    pub fn address(&self) -> BleAddress {
        self.id.stand_in()
    }

    pub fn id(&self) -> &DeviceId {
        &self.id
    }

    pub fn profile(&self) -> &GattProfile {
        &self.profile
    }

    /// Run `f` within `limit`, naming `what` if it takes too long.
    async fn bounded<T>(
        &self,
        what: &str,
        limit: Duration,
        f: impl Future<Output = Result<T, BleError>>,
    ) -> Result<T, BleError> {
        match timeout(limit, f).await {
            Ok(r) => r,
            Err(_) => Err(BleError::timeout(
                &format!("{what} {}", self.name),
                limit.as_secs_f64(),
            )),
        }
    }

    /// The device handle, scanning briefly if the adapter has forgotten it.
    async fn find(&self) -> Result<Arc<dyn BlePeripheral>, BleError> {
        let op = self.timeouts.op;
        match self
            .bounded("looking up", op, self.central.device(&self.id))
            .await
        {
            Err(e) if e.kind == BleErrorKind::NotFound => {}
            other => return other,
        }
        tracing::info!(device = %self.id, "device unknown to the adapter; scanning for it");
        self.bounded("scanning for", op, self.central.start_scan())
            .await?;
        let deadline = Instant::now() + self.timeouts.rescan;
        let mut seen = false;
        while Instant::now() < deadline {
            let devices = self
                .bounded("scanning for", op, self.central.devices())
                .await?;
            if devices.iter().any(|d| d.id == self.id) {
                seen = true;
                break;
            }
            sleep(RESCAN_POLL).await;
        }
        let _ = timeout(op, self.central.stop_scan()).await;
        if !seen {
            return Err(BleError::new(
                BleErrorKind::NotFound,
                format!(
                    "{} ({}) is not advertising — wake it (tap it or put it on its charger)",
                    self.name, self.id
                ),
            ));
        }
        self.bounded("looking up", op, self.central.device(&self.id))
            .await
    }

    async fn open_ble(&mut self) -> Result<Connection, BleError> {
        let p = self.find().await?;
        self.connecting = Some(p.clone());
        if let Err(e) = self
            .bounded("connecting to", self.timeouts.connect, p.connect())
            .await
        {
            // A timed-out connect may still be pending inside BlueZ: cancel it.
            let _ = timeout(self.timeouts.op, p.disconnect()).await;
            self.connecting = None;
            return Err(e);
        }
        let r = match self.after_connect(&p).await {
            Ok(conn) => Ok(conn),
            Err(e) => {
                let _ = timeout(self.timeouts.op, p.disconnect()).await;
                Err(e)
            }
        };
        self.connecting = None;
        r
    }

    async fn after_connect(&self, p: &Arc<dyn BlePeripheral>) -> Result<Connection, BleError> {
        let t = self.timeouts;
        let found = self
            .bounded("discovering services of", t.discover, p.discover_services())
            .await?;
        for ch in self.profile.characteristics() {
            if !found
                .iter()
                .any(|d| ch.matches(d.service, d.characteristic))
            {
                return Err(BleError::new(
                    BleErrorKind::MissingCharacteristic,
                    format!(
                        "{} has no characteristic {ch}: it does not look like a {} — pick \
                         another with --name/--address (see `droidctl scan`)",
                        self.name,
                        self.model.display_name()
                    ),
                ));
            }
        }
        // Before the handshake and subscribing, so no notification or disconnect is missed.
        let events = self.bounded("listening to", t.op, p.events()).await?;
        // What the handshake reads is the start of the incoming stream (Robi 42's handshake
        // announces the protocol version and the frame interval).
        let mut read_values = Vec::new();
        for step in &self.profile.handshake {
            match step {
                HandshakeStep::Write { ch, bytes, .. } => {
                    self.bounded("handshake with", t.op, p.write(*ch, bytes, true))
                        .await?;
                }
                HandshakeStep::Read { ch, expect_len } => {
                    let v = self.bounded("handshake with", t.op, p.read(*ch)).await?;
                    if expect_len.is_some_and(|n| n != v.len()) {
                        tracing::warn!(
                            characteristic = %ch,
                            got = v.len(),
                            expected = ?expect_len,
                            "unexpected handshake read length"
                        );
                    }
                    read_values.push(v);
                }
            }
        }
        for ch in &self.profile.notify {
            self.bounded("subscribing to", t.op, p.subscribe(*ch))
                .await?;
        }
        let (tx, rx) = mpsc::channel(EVENT_CAPACITY);
        let notify: Vec<GattUuid> = self
            .profile
            .notify
            .iter()
            .map(|c| c.characteristic)
            .collect();
        for v in read_values.into_iter().filter(|v| !v.is_empty()) {
            let _ = tx.try_send(LinkEvent::Data(v));
        }
        tokio::spawn(forward(events, notify, tx));
        Ok(Connection {
            writer: Box::new(BleWriter {
                peripheral: Some(p.clone()),
                ch: self.profile.write,
                inputs: self.profile.inputs.clone(),
                chunk_size: self.profile.chunk_size.max(1),
                pacing: self.profile.pacing,
                with_response: self.profile.write_with_response,
                op_timeout: t.op,
                next_write: None,
                name: self.name.clone(),
            }),
            events: rx,
        })
    }
}

/// Turn peripheral events into link events until the connection or the reader goes away.
async fn forward(
    mut events: BoxStream<'static, PeripheralEvent>,
    notify: Vec<GattUuid>,
    tx: mpsc::Sender<LinkEvent>,
) {
    loop {
        let ev = tokio::select! {
            _ = tx.closed() => return,
            ev = events.next() => ev,
        };
        match ev {
            Some(PeripheralEvent::Notification {
                characteristic,
                value,
            }) => {
                if value.is_empty() || !notify.contains(&characteristic) {
                    continue;
                }
                if tx.send(LinkEvent::Data(value)).await.is_err() {
                    return;
                }
            }
            Some(PeripheralEvent::Disconnected(reason)) => {
                let _ = tx.send(LinkEvent::Disconnected(reason)).await;
                return;
            }
            None => {
                let _ = tx
                    .send(LinkEvent::Disconnected(
                        "Bluetooth stopped reporting events".into(),
                    ))
                    .await;
                return;
            }
        }
    }
}

impl Link for BleLink {
    fn abort_open(&mut self) -> BoxFuture<'_, ()> {
        Box::pin(async move {
            if let Some(p) = self.connecting.take() {
                tracing::info!(name = %self.name, "cancelling the connect in progress");
                let _ = timeout(self.timeouts.op, p.disconnect()).await;
            }
        })
    }

    fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
        Box::pin(async move {
            let r = self.open_ble().await;
            self.adapter_off = matches!(&r, Err(e) if e.kind == BleErrorKind::AdapterOff);
            match r {
                Ok(conn) => {
                    self.opened_once = true;
                    Ok(conn)
                }
                // Mid-session the adapter may come back: wait for it.
                Err(e) if self.opened_once && e.kind == BleErrorKind::AdapterOff => {
                    tracing::warn!(error = %e, "the Bluetooth adapter is off; waiting for it");
                    Err(LinkError::transient(crate::link::ADAPTER_OFF_WAITING))
                }
                // A reconnect that finds the services half-resolved: try again.
                Err(e) if self.opened_once && e.kind == BleErrorKind::MissingCharacteristic => {
                    tracing::warn!(error = %e, "a characteristic is missing on reconnect; retrying");
                    Err(LinkError::transient(e.message))
                }
                Err(e) => {
                    tracing::warn!(error = %e, fatal = e.fatal(), "BLE open failed");
                    Err(LinkError::from(e))
                }
            }
        })
    }

    fn retry_hint(&mut self) -> BoxFuture<'_, ()> {
        Box::pin(async move {
            if !self.adapter_off {
                return std::future::pending().await;
            }
            loop {
                sleep(POWER_POLL).await;
                if let Ok(Ok(true)) = timeout(self.timeouts.op, self.central.powered()).await {
                    tracing::info!("the Bluetooth adapter is on again; reconnecting");
                    self.adapter_off = false;
                    return;
                }
            }
        })
    }

    fn describe(&self) -> String {
        format!("{} {} ({})", self.model.display_name(), self.name, self.id)
    }
}

/// Writes to the profile's write characteristic, never more than `chunk_size` bytes at once
/// and never faster than `pacing`, whatever the caller does.
struct BleWriter {
    peripheral: Option<Arc<dyn BlePeripheral>>,
    ch: CharRef,
    inputs: Vec<(crate::gatt::Endpoint, CharRef)>,
    chunk_size: usize,
    pacing: Duration,
    with_response: bool,
    op_timeout: Duration,
    /// When the next write may start.
    next_write: Option<Instant>,
    name: String,
}

impl LinkWriter for BleWriter {
    fn write<'a>(&'a mut self, chunk: &'a [u8]) -> BoxFuture<'a, Result<(), LinkError>> {
        let ch = self.ch;
        self.write_char(ch, chunk, false)
    }

    fn write_to<'a>(
        &'a mut self,
        to: crate::gatt::Endpoint,
        chunk: &'a [u8],
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        self.write_endpoint(to, chunk, false)
    }

    /// The emergency stop: written without waiting out the pacing slot (measured through
    /// btleplug on the virtual BlueZ, that wait was 55–77 ms of the stop's p50).
    fn write_urgent<'a>(
        &'a mut self,
        to: crate::gatt::Endpoint,
        chunk: &'a [u8],
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        self.write_endpoint(to, chunk, true)
    }

    fn close(&mut self) -> BoxFuture<'_, ()> {
        Box::pin(async move {
            if let Some(p) = self.peripheral.take() {
                let _ = timeout(self.op_timeout, p.disconnect()).await;
            }
        })
    }
}

impl BleWriter {
    /// Write to the characteristic of `to`, paced unless `urgent`.
    fn write_endpoint<'a>(
        &'a mut self,
        to: crate::gatt::Endpoint,
        chunk: &'a [u8],
        urgent: bool,
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        let ch = match to {
            crate::gatt::Endpoint::Api => Some(self.ch),
            other => self
                .inputs
                .iter()
                .find(|(e, _)| *e == other)
                .map(|(_, c)| *c),
        };
        match ch {
            Some(ch) => self.write_char(ch, chunk, urgent),
            None => Box::pin(async move {
                Err(LinkError::fatal(format!(
                    "{} has no {} input",
                    self.name,
                    to.name()
                )))
            }),
        }
    }

    /// Write to `ch` in chunks, paced (unless `urgent`); every endpoint shares the one
    /// pacing clock.
    fn write_char<'a>(
        &'a mut self,
        ch: CharRef,
        chunk: &'a [u8],
        urgent: bool,
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        Box::pin(async move {
            let p = self
                .peripheral
                .clone()
                .ok_or_else(|| LinkError::transient("the Bluetooth link is closed"))?;
            for piece in chunk.chunks(self.chunk_size) {
                if let Some(at) = self.next_write.filter(|_| !urgent) {
                    sleep_until(at).await;
                }
                let r = timeout(self.op_timeout, p.write(ch, piece, self.with_response)).await;
                // Pace from the end of the write: a write with response can take a while, and
                // the droid needs the gap after it has processed the bytes.
                self.next_write = Some(Instant::now() + self.pacing);
                match r {
                    Ok(Ok(())) => {}
                    Ok(Err(e)) => return Err(e.into()),
                    Err(_) => {
                        return Err(LinkError::transient(format!(
                            "writing to {} timed out after {:.0} s",
                            self.name,
                            self.op_timeout.as_secs_f64()
                        )));
                    }
                }
            }
            Ok(())
        })
    }
}
