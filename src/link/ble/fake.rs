//! A fake adapter and peripheral for tests: they record every operation with its tokio time,
//! answer reads from a table, and fail, hang or drop the connection on command. Public (not
//! `cfg(test)`) so integration tests and the other crates' tests can drive a [`super::BleLink`]
//! without a radio.

use super::backend::{
    Advertisement, BleAddress, BleCentral, BlePeripheral, DeviceId, DiscoveredChar, KnownDevice,
    PeripheralEvent,
};
use super::error::{BleError, BleErrorKind};
use crate::gatt::{CharRef, GattProfile, GattUuid};
use crate::sync::lock;
use futures_util::future::BoxFuture;
use futures_util::stream::{self, BoxStream, StreamExt};
use std::collections::{HashMap, HashSet};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::mpsc;
use tokio::time::Instant;

/// One operation the fake peripheral saw.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FakeOp {
    Connect,
    Discover,
    Write { ch: GattUuid, data: Vec<u8> },
    Read(GattUuid),
    Subscribe(GattUuid),
    Disconnect,
}

#[derive(Default)]
struct PeripheralState {
    chars: Vec<DiscoveredChar>,
    reads: HashMap<GattUuid, Vec<u8>>,
    log: Vec<(Instant, FakeOp)>,
    connected: bool,
    subscribed: HashSet<GattUuid>,
    listeners: Vec<mpsc::UnboundedSender<PeripheralEvent>>,
    fail_connects: u32,
    hang_connect: bool,
    fail_next_write: Option<BleError>,
    /// The adapter is off ([`FakeCentral::set_powered`]): connects fail as BlueZ's do.
    adapter_off: bool,
}

impl PeripheralState {
    fn record(&mut self, op: FakeOp) {
        self.log.push((Instant::now(), op));
    }

    fn emit(&mut self, ev: PeripheralEvent) {
        self.listeners.retain(|l| l.send(ev.clone()).is_ok());
    }

    fn require_connected(&self) -> Result<(), BleError> {
        if self.connected {
            Ok(())
        } else {
            Err(BleError::new(
                BleErrorKind::Disconnected,
                "the droid is not connected",
            ))
        }
    }

    fn require_char(&self, ch: CharRef) -> Result<(), BleError> {
        if self
            .chars
            .iter()
            .any(|d| ch.matches(d.service, d.characteristic))
        {
            Ok(())
        } else {
            Err(BleError::new(
                BleErrorKind::MissingCharacteristic,
                format!("no characteristic {ch}"),
            ))
        }
    }
}

/// A fake droid. Clones share state: keep one to inspect and steer the one the link uses.
#[derive(Clone, Default)]
pub struct FakePeripheral {
    state: Arc<Mutex<PeripheralState>>,
}

impl FakePeripheral {
    /// A device with exactly these characteristics.
    pub fn new(chars: Vec<DiscoveredChar>) -> Self {
        let p = FakePeripheral::default();
        lock(&p.state).chars = chars;
        p
    }

    /// A device offering everything `profile` uses (characteristics the profile names without
    /// a service are put in the profile's main service).
    pub fn for_profile(profile: &GattProfile) -> Self {
        let chars = profile
            .characteristics()
            .into_iter()
            .map(|c| DiscoveredChar {
                service: c.service.unwrap_or(profile.service),
                characteristic: c.characteristic,
            })
            .collect();
        FakePeripheral::new(chars)
    }

    /// Replace the characteristics service discovery finds (from the next discovery on).
    pub fn set_chars(&self, chars: Vec<DiscoveredChar>) {
        lock(&self.state).chars = chars;
    }

    /// What a read of `ch` returns (empty otherwise).
    pub fn set_read(&self, ch: GattUuid, value: Vec<u8>) {
        lock(&self.state).reads.insert(ch, value);
    }

    /// Fail the next `n` connects as BlueZ does when the droid does not answer.
    pub fn fail_connects(&self, n: u32) {
        lock(&self.state).fail_connects = n;
    }

    /// Make connects never finish (a sleeping droid), to exercise the connect timeout.
    pub fn hang_connect(&self, hang: bool) {
        lock(&self.state).hang_connect = hang;
    }

    /// Fail the next write with `err`.
    pub fn fail_next_write(&self, err: BleError) {
        lock(&self.state).fail_next_write = Some(err);
    }

    /// Send a notification on `ch`, if connected and subscribed to it (as a real device would).
    pub fn notify(&self, ch: GattUuid, value: &[u8]) {
        let mut s = lock(&self.state);
        if s.connected && s.subscribed.contains(&ch) {
            s.emit(PeripheralEvent::Notification {
                characteristic: ch,
                value: value.to_vec(),
            });
        }
    }

    /// The droid drops the connection (walked out of range, fell asleep).
    pub fn drop_connection(&self, reason: &str) {
        let mut s = lock(&self.state);
        s.connected = false;
        s.subscribed.clear();
        s.emit(PeripheralEvent::Disconnected(reason.to_string()));
        s.listeners.clear();
    }

    pub fn is_connected(&self) -> bool {
        lock(&self.state).connected
    }

    /// Every operation so far.
    pub fn ops(&self) -> Vec<FakeOp> {
        lock(&self.state)
            .log
            .iter()
            .map(|(_, o)| o.clone())
            .collect()
    }

    /// Every operation with the tokio time it happened.
    pub fn timed_ops(&self) -> Vec<(Instant, FakeOp)> {
        lock(&self.state).log.clone()
    }

    /// The writes to `ch`, in order, with their times.
    pub fn writes_to(&self, ch: GattUuid) -> Vec<(Instant, Vec<u8>)> {
        lock(&self.state)
            .log
            .iter()
            .filter_map(|(t, o)| match o {
                FakeOp::Write { ch: c, data } if *c == ch => Some((*t, data.clone())),
                _ => None,
            })
            .collect()
    }

    pub fn clear_ops(&self) {
        lock(&self.state).log.clear();
    }
}

impl BlePeripheral for FakePeripheral {
    fn connect(&self) -> BoxFuture<'_, Result<(), BleError>> {
        Box::pin(async move {
            let hang = {
                let mut s = lock(&self.state);
                s.record(FakeOp::Connect);
                if s.adapter_off {
                    return Err(BleError::from_dbus(
                        Some("org.bluez.Error.NotReady"),
                        "Resource Not Ready",
                    ));
                }
                if s.fail_connects > 0 {
                    s.fail_connects -= 1;
                    return Err(BleError::from_dbus(
                        Some("org.bluez.Error.Failed"),
                        "le-connection-abort-by-local",
                    ));
                }
                s.hang_connect
            };
            if hang {
                std::future::pending::<()>().await;
            }
            lock(&self.state).connected = true;
            Ok(())
        })
    }

    fn discover_services(&self) -> BoxFuture<'_, Result<Vec<DiscoveredChar>, BleError>> {
        Box::pin(async move {
            let mut s = lock(&self.state);
            s.record(FakeOp::Discover);
            s.require_connected()?;
            Ok(s.chars.clone())
        })
    }

    fn write<'a>(
        &'a self,
        ch: CharRef,
        data: &'a [u8],
        _with_response: bool,
    ) -> BoxFuture<'a, Result<(), BleError>> {
        Box::pin(async move {
            let mut s = lock(&self.state);
            s.require_connected()?;
            s.require_char(ch)?;
            if let Some(e) = s.fail_next_write.take() {
                return Err(e);
            }
            s.record(FakeOp::Write {
                ch: ch.characteristic,
                data: data.to_vec(),
            });
            Ok(())
        })
    }

    fn read(&self, ch: CharRef) -> BoxFuture<'_, Result<Vec<u8>, BleError>> {
        Box::pin(async move {
            let mut s = lock(&self.state);
            s.require_connected()?;
            s.require_char(ch)?;
            s.record(FakeOp::Read(ch.characteristic));
            Ok(s.reads.get(&ch.characteristic).cloned().unwrap_or_default())
        })
    }

    fn subscribe(&self, ch: CharRef) -> BoxFuture<'_, Result<(), BleError>> {
        Box::pin(async move {
            let mut s = lock(&self.state);
            s.require_connected()?;
            s.require_char(ch)?;
            s.record(FakeOp::Subscribe(ch.characteristic));
            s.subscribed.insert(ch.characteristic);
            Ok(())
        })
    }

    fn events(&self) -> BoxFuture<'_, Result<BoxStream<'static, PeripheralEvent>, BleError>> {
        Box::pin(async move {
            let (tx, rx) = mpsc::unbounded_channel();
            lock(&self.state).listeners.push(tx);
            let s = stream::unfold(rx, |mut rx| async move { rx.recv().await.map(|e| (e, rx)) });
            Ok(s.boxed())
        })
    }

    fn disconnect(&self) -> BoxFuture<'_, Result<(), BleError>> {
        Box::pin(async move {
            let mut s = lock(&self.state);
            s.record(FakeOp::Disconnect);
            if s.connected {
                s.connected = false;
                s.subscribed.clear();
                s.emit(PeripheralEvent::Disconnected("disconnected by us".into()));
                s.listeners.clear();
            }
            Ok(())
        })
    }
}

/// One device the fake adapter knows.
struct FakeDevice {
    id: DeviceId,
    name: Option<String>,
    rssi: Option<i16>,
    /// How long after the scan starts it is first heard; `None`: only remembered, never
    /// heard (listed whether scanning or not, without an RSSI).
    after: Option<Duration>,
}

struct CentralState {
    devices: Vec<FakeDevice>,
    peripherals: HashMap<DeviceId, FakePeripheral>,
    scan_started: Option<Instant>,
    scans: u32,
    fail_scan: Option<BleError>,
    powered: bool,
}

impl Default for CentralState {
    fn default() -> Self {
        CentralState {
            devices: Vec::new(),
            peripherals: HashMap::new(),
            scan_started: None,
            scans: 0,
            fail_scan: None,
            powered: true,
        }
    }
}

/// A fake adapter with scripted advertisements.
#[derive(Clone, Default)]
pub struct FakeCentral {
    state: Arc<Mutex<CentralState>>,
}

impl FakeCentral {
    pub fn new() -> Self {
        FakeCentral::default()
    }

    /// A device heard `after` the scan starts.
    pub fn advertise(&self, ad: Advertisement, after: Duration) {
        lock(&self.state).devices.push(FakeDevice {
            id: DeviceId::from_address(ad.address),
            name: ad.name,
            rssi: ad.rssi,
            after: Some(after),
        });
    }

    /// A connectable device: its advertisement (heard at once) and its peripheral.
    pub fn add_device(&self, ad: Advertisement, peripheral: FakePeripheral) {
        let id = DeviceId::from_address(ad.address);
        self.add_device_as(id, ad.name.as_deref(), ad.rssi, peripheral);
    }

    /// A connectable device known by a platform identifier (as CoreBluetooth names devices,
    /// all with the address 00:00:00:00:00:00), heard at once at `rssi`.
    pub fn add_device_as(
        &self,
        id: DeviceId,
        name: Option<&str>,
        rssi: Option<i16>,
        peripheral: FakePeripheral,
    ) {
        let mut s = lock(&self.state);
        s.peripherals.insert(id.clone(), peripheral);
        s.devices.push(FakeDevice {
            id,
            name: name.map(String::from),
            rssi,
            after: Some(Duration::ZERO),
        });
    }

    /// A device the adapter remembers but never hears (a droid asleep in a drawer): listed
    /// without an RSSI; connecting to it is the peripheral's business (give one that fails).
    pub fn remember(&self, ad: Advertisement, peripheral: Option<FakePeripheral>) {
        let id = DeviceId::from_address(ad.address);
        let mut s = lock(&self.state);
        if let Some(p) = peripheral {
            s.peripherals.insert(id.clone(), p);
        }
        s.devices.push(FakeDevice {
            id,
            name: ad.name,
            rssi: None,
            after: None,
        });
    }

    /// Make scanning fail (adapter off, permission denied, …).
    pub fn fail_scan(&self, err: BleError) {
        lock(&self.state).fail_scan = Some(err);
    }

    /// Power the adapter off or on, as `bluetoothctl power off|on`: off drops every
    /// connection and fails scans and connects with BlueZ's `NotReady`.
    pub fn set_powered(&self, on: bool) {
        let peripherals: Vec<FakePeripheral> = {
            let mut s = lock(&self.state);
            s.powered = on;
            if !on {
                s.scan_started = None;
            }
            s.peripherals.values().cloned().collect()
        };
        for p in peripherals {
            lock(&p.state).adapter_off = !on;
            if !on && p.is_connected() {
                p.drop_connection("the Bluetooth adapter was switched off");
            }
        }
    }

    /// How many scans were started.
    pub fn scans(&self) -> u32 {
        lock(&self.state).scans
    }
}

impl BleCentral for FakeCentral {
    fn start_scan(&self) -> BoxFuture<'_, Result<(), BleError>> {
        Box::pin(async move {
            let mut s = lock(&self.state);
            if let Some(e) = s.fail_scan.clone() {
                return Err(e);
            }
            if !s.powered {
                return Err(BleError::adapter_off());
            }
            s.scans += 1;
            s.scan_started = Some(Instant::now());
            Ok(())
        })
    }

    fn stop_scan(&self) -> BoxFuture<'_, Result<(), BleError>> {
        Box::pin(async move {
            lock(&self.state).scan_started = None;
            Ok(())
        })
    }

    fn devices(&self) -> BoxFuture<'_, Result<Vec<KnownDevice>, BleError>> {
        Box::pin(async move {
            let s = lock(&self.state);
            let now = Instant::now();
            let connected = |id: &DeviceId| {
                s.peripherals
                    .get(id)
                    .is_some_and(FakePeripheral::is_connected)
            };
            Ok(s.devices
                .iter()
                .filter_map(|d| {
                    let heard = match (d.after, s.scan_started) {
                        (Some(after), Some(started)) => started + after <= now,
                        _ => false,
                    };
                    if d.after.is_some() && !heard {
                        return None;
                    }
                    Some(KnownDevice {
                        id: d.id.clone(),
                        name: d.name.clone(),
                        rssi: if heard { d.rssi } else { None },
                        connected: connected(&d.id),
                    })
                })
                .collect())
        })
    }

    fn device<'a>(
        &'a self,
        id: &'a DeviceId,
    ) -> BoxFuture<'a, Result<Arc<dyn BlePeripheral>, BleError>> {
        Box::pin(async move {
            match lock(&self.state).peripherals.get(id) {
                Some(p) => Ok(Arc::new(p.clone()) as Arc<dyn BlePeripheral>),
                None => Err(BleError::new(
                    BleErrorKind::NotFound,
                    format!("no device {id}"),
                )),
            }
        })
    }

    fn powered(&self) -> BoxFuture<'_, Result<bool, BleError>> {
        Box::pin(async move { Ok(lock(&self.state).powered) })
    }

    /// Any connectable device by address, heard now or not (BlueZ keeps devices it heard a
    /// while ago).
    fn peripheral(
        &self,
        address: BleAddress,
    ) -> BoxFuture<'_, Result<Arc<dyn BlePeripheral>, BleError>> {
        Box::pin(async move {
            let s = lock(&self.state);
            match s
                .peripherals
                .iter()
                .find(|(id, _)| id.stand_in() == address)
            {
                Some((_, p)) => Ok(Arc::new(p.clone()) as Arc<dyn BlePeripheral>),
                None => Err(BleError::new(
                    BleErrorKind::NotFound,
                    format!("no device {address}"),
                )),
            }
        })
    }
}
