//! The real radio: [`BleCentral`] / [`BlePeripheral`] on btleplug (BlueZ on Linux). The only
//! file that touches btleplug or D-Bus; it translates calls and errors and holds no logic worth
//! testing, so that the logic can be tested without a radio.

use super::backend::{
    Advertisement, BleAddress, BleCentral, BlePeripheral, DiscoveredChar, PeripheralEvent,
};
use super::error::{BleError, BleErrorKind};
use crate::link::gatt::{CharRef, GattUuid};
use btleplug::api::{
    BDAddr, Central as _, CentralEvent, CentralState, Characteristic, Manager as _,
    Peripheral as _, ScanFilter, WriteType,
};
use btleplug::platform::{Adapter, Manager, Peripheral};
use futures_util::future::{BoxFuture, ready};
use futures_util::stream::{self, BoxStream, StreamExt};
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::oneshot;
use tokio::time::timeout;

/// Bound on getting hold of an adapter. BlueZ answers in milliseconds when it is there; the
/// bound is what makes `droidctl scan` fail fast instead of hanging when it is not.
const SETUP_TIMEOUT: Duration = Duration::from_secs(4);

/// The system's first Bluetooth adapter, or a one-line reason there is none.
///
/// Checks, in order: the D-Bus system bus, BlueZ on it, an adapter, the adapter powered on.
/// Never takes much longer than [`SETUP_TIMEOUT`] twice, whatever state the system is in.
pub async fn open_central() -> Result<Arc<dyn BleCentral>, BleError> {
    preflight().await?;
    let manager = timeout(SETUP_TIMEOUT, Manager::new())
        .await
        .map_err(|_| bluez_silent("connecting to BlueZ"))?
        .map_err(map_err)?;
    let adapters = timeout(SETUP_TIMEOUT, manager.adapters())
        .await
        .map_err(|_| bluez_silent("listing adapters"))?
        .map_err(map_err)?;
    let adapter = adapters
        .into_iter()
        .next()
        .ok_or_else(BleError::no_adapter)?;
    // Surfaces permission errors before `adapter_state`, which reports any failure as "off".
    timeout(SETUP_TIMEOUT, adapter.adapter_info())
        .await
        .map_err(|_| bluez_silent("reading the adapter"))?
        .map_err(map_err)?;
    let state = timeout(SETUP_TIMEOUT, adapter.adapter_state())
        .await
        .map_err(|_| bluez_silent("reading the adapter state"))?
        .map_err(map_err)?;
    if state == CentralState::PoweredOff {
        return Err(BleError::adapter_off());
    }
    Ok(Arc::new(BtleCentral { adapter }))
}

fn bluez_silent(what: &str) -> BleError {
    BleError::new(
        BleErrorKind::BluezNotRunning,
        format!(
            "BlueZ did not answer ({what}) within {} s — check `systemctl status bluetooth`, or \
             try `droidctl --sim`",
            SETUP_TIMEOUT.as_secs()
        ),
    )
}

/// Check the system bus and BlueZ with plain D-Bus calls before btleplug.
///
/// btleplug reports both "no bus" and "no BlueZ" as an opaque error, and its bus connect blocks
/// the thread. Asking the bus ourselves gives typed D-Bus error names; doing it on a plain
/// thread (not tokio's blocking pool, which a runtime waits for on shutdown) keeps a hung
/// socket from hanging the program.
async fn preflight() -> Result<(), BleError> {
    // BlueZ, and so this check, exist only on Linux; other platforms' btleplug backends need
    // no system bus.
    if !cfg!(target_os = "linux") {
        return Ok(());
    }
    let (tx, rx) = oneshot::channel();
    std::thread::Builder::new()
        .name("dbus-preflight".into())
        .spawn(move || {
            let _ = tx.send(probe_system_bus());
        })
        .map_err(|e| BleError::new(BleErrorKind::Other, format!("cannot start a thread: {e}")))?;
    match timeout(SETUP_TIMEOUT, rx).await {
        Ok(Ok(r)) => r,
        Ok(Err(_)) => Err(BleError::no_system_bus("the D-Bus check failed")),
        Err(_) => Err(BleError::no_system_bus("it did not answer")),
    }
}

fn probe_system_bus() -> Result<(), BleError> {
    let dbus_err = |e: dbus::Error| BleError::from_dbus(e.name(), e.message().unwrap_or(""));
    let conn = dbus::blocking::Connection::new_system().map_err(|e| {
        // Whatever the name, failing to reach the system bus means there is none for us.
        let detail = e.message().unwrap_or("").to_string();
        match e.name() {
            Some(n) if n.ends_with(".AccessDenied") => BleError::permission_denied(),
            _ => BleError::no_system_bus(&detail),
        }
    })?;
    let bus = conn.with_proxy(
        "org.freedesktop.DBus",
        "/org/freedesktop/DBus",
        Duration::from_secs(2),
    );
    let (running,): (bool,) = bus
        .method_call("org.freedesktop.DBus", "NameHasOwner", ("org.bluez",))
        .map_err(dbus_err)?;
    if running {
        return Ok(());
    }
    // Not running but activatable: the bus starts it on first use.
    let (names,): (Vec<String>,) = bus
        .method_call("org.freedesktop.DBus", "ListActivatableNames", ())
        .map_err(dbus_err)?;
    if names.iter().any(|n| n == "org.bluez") {
        Ok(())
    } else {
        Err(BleError::bluez_not_running())
    }
}

/// Map a btleplug error.
///
/// BlueZ failures arrive as `Error::Other` wrapping bluez-async's error, which wraps the D-Bus
/// error. We do not depend on bluez-async to downcast it, so the D-Bus name and message are
/// read back from its `Debug` text (`D-Bus error: MESSAGE (NAME)`), the one stable rendering.
fn map_err(e: btleplug::Error) -> BleError {
    use btleplug::Error as E;
    match e {
        E::PermissionDenied => BleError::permission_denied(),
        E::NoAdapterAvailable => BleError::no_adapter(),
        E::DeviceNotFound => BleError::new(
            BleErrorKind::NotFound,
            "BlueZ no longer knows the device — scan again (is the droid awake?)",
        ),
        E::NotConnected => BleError::new(BleErrorKind::Disconnected, "the droid is not connected"),
        E::TimedOut(d) => BleError::timeout("a Bluetooth operation", d.as_secs_f64()),
        E::NoSuchCharacteristic | E::UnexpectedCharacteristic => BleError::new(
            BleErrorKind::MissingCharacteristic,
            "the device lacks a characteristic the droid needs",
        ),
        E::Other(inner) => {
            let debug = format!("{inner:?}");
            if let Some((name, message)) = dbus_error_in(&debug) {
                return BleError::from_dbus(Some(&name), &message);
            }
            let text = inner.to_string();
            let lower = text.to_ascii_lowercase();
            if lower.contains("no bluetooth adapters") {
                BleError::no_adapter()
            } else if lower.contains("service discovery timed out") {
                BleError::new(
                    BleErrorKind::Timeout,
                    "service discovery timed out — is the droid awake and near? tap it or put \
                     it on its charger",
                )
            } else if lower.contains("not found") && lower.contains("uuid") {
                BleError::new(BleErrorKind::MissingCharacteristic, text)
            } else {
                BleError::new(BleErrorKind::Other, format!("Bluetooth error: {text}"))
            }
        }
        other => BleError::new(BleErrorKind::Other, format!("Bluetooth error: {other}")),
    }
}

/// The D-Bus error name inside a btleplug error, if it wraps one.
fn dbus_name(e: &btleplug::Error) -> Option<String> {
    match e {
        btleplug::Error::Other(inner) => dbus_error_in(&format!("{inner:?}")).map(|(n, _)| n),
        _ => None,
    }
}

/// Find `D-Bus error: MESSAGE (NAME)` in a `Debug` rendering; returns (name, message).
fn dbus_error_in(debug: &str) -> Option<(String, String)> {
    const MARK: &str = "D-Bus error: ";
    let rest = &debug[debug.find(MARK)? + MARK.len()..];
    let open = rest.rfind(" (")?;
    let after = &rest[open + 2..];
    let name = &after[..after.find(')')?];
    if !name.contains('.') || name.contains(' ') {
        return None;
    }
    Some((name.to_string(), rest[..open].to_string()))
}

fn gatt(u: u128) -> GattUuid {
    GattUuid::from_u128(u)
}

struct BtleCentral {
    adapter: Adapter,
}

impl BleCentral for BtleCentral {
    fn start_scan(&self) -> BoxFuture<'_, Result<(), BleError>> {
        Box::pin(async move {
            // No service filter: v1 droids and Robi do not always advertise their services.
            match self.adapter.start_scan(ScanFilter::default()).await {
                // Our own discovery already running is fine.
                Err(e) if dbus_name(&e).is_some_and(|n| n.ends_with(".InProgress")) => Ok(()),
                r => r.map_err(map_err),
            }
        })
    }

    fn stop_scan(&self) -> BoxFuture<'_, Result<(), BleError>> {
        Box::pin(async move { self.adapter.stop_scan().await.map_err(map_err) })
    }

    fn advertisements(&self) -> BoxFuture<'_, Result<Vec<Advertisement>, BleError>> {
        Box::pin(async move {
            let peripherals = self.adapter.peripherals().await.map_err(map_err)?;
            let mut out = Vec::with_capacity(peripherals.len());
            for p in peripherals {
                // A device that vanished between the listing and this call is simply skipped.
                let Ok(Some(props)) = p.properties().await else {
                    continue;
                };
                out.push(Advertisement {
                    address: BleAddress(props.address.into()),
                    // On BlueZ `local_name` is the Alias, which a user may have renamed and
                    // which falls back to the address for nameless devices; the advertised
                    // Name is what identifies the model.
                    name: props.advertisement_name.or(props.local_name),
                    rssi: props.rssi,
                });
            }
            Ok(out)
        })
    }

    fn peripheral(
        &self,
        address: BleAddress,
    ) -> BoxFuture<'_, Result<Arc<dyn BlePeripheral>, BleError>> {
        Box::pin(async move {
            let want = BDAddr::from(address.0);
            let peripherals = self.adapter.peripherals().await.map_err(map_err)?;
            match peripherals.into_iter().find(|p| p.address() == want) {
                Some(peripheral) => Ok(Arc::new(BtlePeripheral {
                    adapter: self.adapter.clone(),
                    peripheral,
                }) as Arc<dyn BlePeripheral>),
                None => Err(BleError::new(
                    BleErrorKind::NotFound,
                    format!("the adapter does not know {address}"),
                )),
            }
        })
    }
}

struct BtlePeripheral {
    adapter: Adapter,
    peripheral: Peripheral,
}

impl BtlePeripheral {
    fn characteristic(&self, ch: CharRef) -> Result<Characteristic, BleError> {
        self.peripheral
            .characteristics()
            .into_iter()
            .find(|c| ch.matches(gatt(c.service_uuid.as_u128()), gatt(c.uuid.as_u128())))
            .ok_or_else(|| {
                BleError::new(
                    BleErrorKind::MissingCharacteristic,
                    format!("the device has no characteristic {ch}"),
                )
            })
    }
}

impl BlePeripheral for BtlePeripheral {
    fn connect(&self) -> BoxFuture<'_, Result<(), BleError>> {
        Box::pin(async move { self.peripheral.connect().await.map_err(map_err) })
    }

    fn discover_services(&self) -> BoxFuture<'_, Result<Vec<DiscoveredChar>, BleError>> {
        Box::pin(async move {
            self.peripheral.discover_services().await.map_err(map_err)?;
            Ok(self
                .peripheral
                .characteristics()
                .into_iter()
                .map(|c| DiscoveredChar {
                    service: gatt(c.service_uuid.as_u128()),
                    characteristic: gatt(c.uuid.as_u128()),
                })
                .collect())
        })
    }

    fn write<'a>(
        &'a self,
        ch: CharRef,
        data: &'a [u8],
        with_response: bool,
    ) -> BoxFuture<'a, Result<(), BleError>> {
        Box::pin(async move {
            let c = self.characteristic(ch)?;
            let kind = if with_response {
                WriteType::WithResponse
            } else {
                WriteType::WithoutResponse
            };
            self.peripheral.write(&c, data, kind).await.map_err(map_err)
        })
    }

    fn read(&self, ch: CharRef) -> BoxFuture<'_, Result<Vec<u8>, BleError>> {
        Box::pin(async move {
            let c = self.characteristic(ch)?;
            self.peripheral.read(&c).await.map_err(map_err)
        })
    }

    fn subscribe(&self, ch: CharRef) -> BoxFuture<'_, Result<(), BleError>> {
        Box::pin(async move {
            let c = self.characteristic(ch)?;
            self.peripheral.subscribe(&c).await.map_err(map_err)
        })
    }

    fn events(&self) -> BoxFuture<'_, Result<BoxStream<'static, PeripheralEvent>, BleError>> {
        Box::pin(async move {
            let values = self
                .peripheral
                .notifications()
                .await
                .map_err(map_err)?
                .map(|n| PeripheralEvent::Notification {
                    characteristic: gatt(n.uuid.as_u128()),
                    value: n.value,
                });
            // Disconnects are adapter events in btleplug; keep only this device's.
            let id = self.peripheral.id();
            let gone = self
                .adapter
                .events()
                .await
                .map_err(map_err)?
                .filter_map(move |e| {
                    ready(match e {
                        CentralEvent::DeviceDisconnected(d) if d == id => Some(
                            PeripheralEvent::Disconnected("the droid disconnected".into()),
                        ),
                        _ => None,
                    })
                });
            Ok(stream::select(values, gone).boxed())
        })
    }

    fn disconnect(&self) -> BoxFuture<'_, Result<(), BleError>> {
        Box::pin(async move { self.peripheral.disconnect().await.map_err(map_err) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_dbus_names_in_debug_text() {
        assert_eq!(
            dbus_error_in(
                "DbusError(D-Bus error: le-connection-abort-by-local (org.bluez.Error.Failed))"
            ),
            Some((
                "org.bluez.Error.Failed".into(),
                "le-connection-abort-by-local".into()
            ))
        );
        assert_eq!(
            dbus_error_in("D-Bus error: Resource Not Ready (org.bluez.Error.NotReady)"),
            Some((
                "org.bluez.Error.NotReady".into(),
                "Resource Not Ready".into()
            ))
        );
        assert_eq!(
            dbus_error_in("D-Bus error: a (b) c (org.bluez.Error.Failed)"),
            Some(("org.bluez.Error.Failed".into(), "a (b) c".into()))
        );
        assert_eq!(dbus_error_in("ServiceDiscoveryTimedOut"), None);
    }

    #[test]
    fn maps_typed_btleplug_errors() {
        use btleplug::Error as E;
        assert_eq!(map_err(E::NoAdapterAvailable).kind, BleErrorKind::NoAdapter);
        assert_eq!(
            map_err(E::PermissionDenied).kind,
            BleErrorKind::PermissionDenied
        );
        assert_eq!(map_err(E::NotConnected).kind, BleErrorKind::Disconnected);
        assert_eq!(
            map_err(E::TimedOut(Duration::from_secs(3))).kind,
            BleErrorKind::Timeout
        );
        let dbus = dbus::Error::new_custom("org.bluez.Error.NotReady", "Resource Not Ready");
        assert_eq!(
            map_err(E::Other(Box::new(dbus))).kind,
            BleErrorKind::AdapterOff
        );
    }

    /// On a machine without a system bus (containers, CI) the preflight says so, quickly.
    #[tokio::test]
    async fn preflight_without_a_bus_is_a_clear_fatal_error() {
        if std::env::var_os("DBUS_SYSTEM_BUS_ADDRESS").is_some()
            || std::path::Path::new("/run/dbus/system_bus_socket").exists()
        {
            return;
        }
        let e = preflight().await.unwrap_err();
        assert!(e.fatal(), "{e}");
        assert!(e.message.contains("--sim"), "{e}");
    }
}
