//! [`GattBackend`] over droidctl's BLE layer ([`BleCentral`] / [`BlePeripheral`]): the real
//! radio behind `droidctl serve`, and the fake one in tests.

use super::backend::{
    BackendDevice, BackendError, Connected, DroidEvent, GattBackend, GattConnection,
};
use crate::gatt::{CharRef, GattUuid};
use crate::link::ble::{
    BleAddress, BleCentral, BleErrorKind, BlePeripheral, DiscoveredChar, PeripheralEvent,
    ScanEntry, scan,
};
use crate::model::Model;
use crate::sync::lock;
use futures_util::StreamExt;
use futures_util::future::BoxFuture;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::mpsc;
use tokio::time::timeout;

/// Each adapter call after the scan.
const OP: Duration = Duration::from_secs(10);
/// Looking for a device the adapter forgot, before connecting.
const RESCAN: Duration = Duration::from_secs(5);
/// Notifications waiting for the client task.
const EVENTS: usize = 1024;

/// Device names remembered between scans, at most (see [`BleBackend::remember`]).
const MAX_NAMES: usize = 1024;

/// The local Bluetooth adapter as a relay backend.
pub struct BleBackend {
    central: Arc<dyn BleCentral>,
    /// One scan at a time: a client's stop must not end another's scan.
    scanning: tokio::sync::Mutex<()>,
    /// Names heard, for INIT's status line and the model (the stop command needs it).
    names: Mutex<HashMap<BleAddress, String>>,
}

impl BleBackend {
    /// How many device names are remembered.
    pub fn names_remembered(&self) -> usize {
        lock(&self.names).len()
    }

    pub fn new(central: Arc<dyn BleCentral>) -> Self {
        BleBackend {
            central,
            scanning: tokio::sync::Mutex::new(()),
            names: Mutex::new(HashMap::new()),
        }
    }

    /// Keep the names heard, for INIT (bounded: see [`MAX_NAMES`]).
    pub(crate) fn remember(&self, entries: &[ScanEntry]) {
        let mut names = lock(&self.names);
        // Phones and headphones rotate random addresses: the names heard would pile up for
        // as long as the relay runs. Past the bound only this scan's devices are kept.
        if names.len() + entries.len() > MAX_NAMES {
            names.retain(|a, _| entries.iter().any(|e| e.address == *a));
        }
        for e in entries {
            if let Some(n) = &e.name {
                names.insert(e.address, n.clone());
            }
        }
    }

    async fn scan_for(
        &self,
        t: Duration,
        done: impl Fn(&[ScanEntry]) -> bool,
    ) -> Result<Vec<ScanEntry>, BackendError> {
        let _one = self.scanning.lock().await;
        let entries = scan::scan(self.central.as_ref(), t, done)
            .await
            .map_err(|e| BackendError(e.message))?;
        self.remember(&entries);
        Ok(entries)
    }

    async fn peripheral(
        &self,
        address: BleAddress,
    ) -> Result<Arc<dyn BlePeripheral>, BackendError> {
        match timeout(OP, self.central.peripheral(address)).await {
            Ok(Ok(p)) => return Ok(p),
            Ok(Err(e)) if e.kind != BleErrorKind::NotFound => return Err(BackendError(e.message)),
            Err(_) => return Err("the Bluetooth adapter did not answer".into()),
            Ok(Err(_)) => {}
        }
        // The adapter forgot it (BlueZ drops devices it has not heard for a while).
        self.scan_for(RESCAN, |es| es.iter().any(|e| e.address == address))
            .await?;
        match timeout(OP, self.central.peripheral(address)).await {
            Ok(Ok(p)) => Ok(p),
            Ok(Err(e)) => Err(BackendError(e.message)),
            Err(_) => Err("the Bluetooth adapter did not answer".into()),
        }
    }

    async fn connect_ble(&self, address: &str) -> Result<Connected, BackendError> {
        let addr: BleAddress = address.parse().map_err(BackendError)?;
        let p = self.peripheral(addr).await?;
        let ok = |r: Result<Result<(), crate::link::ble::BleError>, _>, what: &str| match r {
            Ok(Ok(())) => Ok(()),
            Ok(Err(e)) => Err(BackendError(e.message)),
            Err(_) => Err(BackendError(format!("{what} {address} timed out"))),
        };
        if let Err(e) = ok(timeout(OP, p.connect()).await, "connecting to") {
            let _ = timeout(OP, p.disconnect()).await;
            return Err(e);
        }
        let setup = async {
            let chars = match timeout(OP, p.discover_services()).await {
                Ok(Ok(c)) => c,
                Ok(Err(e)) => return Err(BackendError(e.message)),
                Err(_) => return Err(format!("discovering services of {address} timed out").into()),
            };
            let events = match timeout(OP, p.events()).await {
                Ok(Ok(s)) => s,
                Ok(Err(e)) => return Err(BackendError(e.message)),
                Err(_) => return Err("the Bluetooth adapter did not answer".into()),
            };
            Ok((chars, events))
        };
        let (chars, mut events) = match setup.await {
            Ok(v) => v,
            Err(e) => {
                let _ = timeout(OP, p.disconnect()).await;
                return Err(e);
            }
        };
        let (tx, rx) = mpsc::channel(EVENTS);
        tokio::spawn(async move {
            loop {
                let ev = tokio::select! {
                    _ = tx.closed() => return,
                    ev = events.next() => ev,
                };
                let out = match ev {
                    Some(PeripheralEvent::Notification {
                        characteristic,
                        value,
                    }) => DroidEvent::Notification {
                        characteristic,
                        value,
                    },
                    Some(PeripheralEvent::Disconnected(r)) => DroidEvent::Disconnected(r),
                    None => DroidEvent::Disconnected("Bluetooth stopped reporting events".into()),
                };
                let last = matches!(out, DroidEvent::Disconnected(_));
                if tx.send(out).await.is_err() || last {
                    return;
                }
            }
        });
        let mut name = lock(&self.names).get(&addr).cloned().unwrap_or_default();
        if name.is_empty() {
            // A client that knew the address without scanning through us: the adapter may
            // still know the name (the model decides which stop to write).
            if let Ok(Ok(ads)) = timeout(OP, self.central.advertisements()).await
                && let Some(n) = ads
                    .into_iter()
                    .find(|a| a.address == addr)
                    .and_then(|a| a.name)
            {
                name = n;
            }
        }
        let model = Model::from_advertised_name(&name);
        Ok(Connected {
            stop_as: model.or_else(|| family_of(&chars)),
            connection: Box::new(BleConnection { p, chars }),
            events: rx,
            model,
            name,
        })
    }
}

impl GattBackend for BleBackend {
    fn scan(&self, t: Duration) -> BoxFuture<'_, Result<Vec<BackendDevice>, BackendError>> {
        Box::pin(async move {
            let entries = self.scan_for(t, |_| false).await?;
            Ok(entries
                .into_iter()
                .map(|e| BackendDevice {
                    name: e.name.unwrap_or_default(),
                    address: e.address.to_string(),
                })
                .collect())
        })
    }

    fn find<'a>(
        &'a self,
        name: &'a str,
        t: Duration,
    ) -> BoxFuture<'a, Result<Option<BackendDevice>, BackendError>> {
        Box::pin(async move {
            let is = |e: &ScanEntry| e.name.as_deref() == Some(name);
            let entries = self.scan_for(t, |es| es.iter().any(is)).await?;
            Ok(entries.into_iter().find(is).map(|e| BackendDevice {
                name: e.name.unwrap_or_default(),
                address: e.address.to_string(),
            }))
        })
    }

    fn connect<'a>(&'a self, address: &'a str) -> BoxFuture<'a, Result<Connected, BackendError>> {
        Box::pin(self.connect_ble(address))
    }

    fn describe(&self) -> String {
        "droids over Bluetooth LE".to_string()
    }
}

/// A model of the family whose command characteristic the device has (each family's stop
/// command is the same for all its models).
fn family_of(chars: &[DiscoveredChar]) -> Option<Model> {
    crate::family::all()
        .into_iter()
        .find(|f| {
            let write = f.gatt_profile(f.representative()).write;
            chars
                .iter()
                .any(|d| write.matches(d.service, d.characteristic))
        })
        .map(|f| f.representative())
}

struct BleConnection {
    p: Arc<dyn BlePeripheral>,
    chars: Vec<DiscoveredChar>,
}

impl BleConnection {
    fn char_ref(&self, ch: GattUuid) -> Result<CharRef, BackendError> {
        self.chars
            .iter()
            .find(|d| d.characteristic == ch)
            .map(|d| CharRef::new(d.service, d.characteristic))
            .ok_or_else(|| BackendError(format!("the droid has no characteristic {ch}")))
    }
}

impl GattConnection for BleConnection {
    fn write<'a>(
        &'a mut self,
        ch: GattUuid,
        data: &'a [u8],
    ) -> BoxFuture<'a, Result<(), BackendError>> {
        Box::pin(async move {
            let c = self.char_ref(ch)?;
            self.p
                .write(c, data, true)
                .await
                .map_err(|e| BackendError(e.message))
        })
    }

    fn subscribe(&mut self, ch: GattUuid) -> BoxFuture<'_, Result<(), BackendError>> {
        Box::pin(async move {
            let c = self.char_ref(ch)?;
            self.p
                .subscribe(c)
                .await
                .map_err(|e| BackendError(e.message))
        })
    }

    fn disconnect(&mut self) -> BoxFuture<'_, ()> {
        Box::pin(async move {
            let _ = self.p.disconnect().await;
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::ble::DeviceId;
    use crate::link::ble::fake::FakeCentral;

    fn entry(i: u32) -> ScanEntry {
        let address = BleAddress([0x4A, 0, (i >> 16) as u8, (i >> 8) as u8, i as u8, 1]);
        ScanEntry {
            name: Some(format!("phone {i}")),
            model: None,
            id: DeviceId::from(address),
            address,
            rssi: Some(-80),
            heard: true,
        }
    }

    /// Rotating random addresses are heard scan after scan: the names kept stay bounded.
    #[test]
    fn names_of_rotating_addresses_do_not_pile_up() {
        let b = BleBackend::new(Arc::new(FakeCentral::new()));
        for scan in 0..50u32 {
            let heard: Vec<ScanEntry> = (0..100).map(|i| entry(scan * 100 + i)).collect();
            b.remember(&heard);
            assert!(
                b.names_remembered() <= MAX_NAMES,
                "{}",
                b.names_remembered()
            );
        }
        // The latest scan's names are kept.
        assert!(b.names_remembered() >= 100);
    }
}
