//! The real radio: [`BleCentral`] / [`BlePeripheral`] on btleplug (BlueZ on Linux,
//! CoreBluetooth on macOS, WinRT on Windows). The only file that touches btleplug or D-Bus; it
//! translates calls and errors and holds no logic worth testing, so that the logic can be
//! tested without a radio. The error texts each platform gives are mapped, and tested, in
//! [`BleError::from_platform_text`].

use super::backend::{
    BleAddress, BleCentral, BlePeripheral, DeviceId, DiscoveredChar, KnownDevice, PeripheralEvent,
};
use super::error::{BleError, BleErrorKind, DBUS_MARK, Os, dbus_error_in};
use crate::gatt::{CharRef, GattUuid};
use btleplug::api::{
    Central as _, CentralEvent, CentralState, Characteristic, Manager as _, Peripheral as _,
    ScanFilter, WriteType,
};
use btleplug::platform::{Adapter, Manager, Peripheral};
use futures_util::future::{BoxFuture, ready};
use futures_util::stream::{self, BoxStream, StreamExt};
use std::sync::Arc;
use std::time::Duration;
use tokio::time::timeout;

/// Bound on getting hold of an adapter. BlueZ answers in milliseconds when it is there; the
/// bound is what makes `droidctl scan` fail fast instead of hanging when it is not.
const SETUP_TIMEOUT: Duration = Duration::from_secs(4);

/// On macOS, listing the adapter waits for CoreBluetooth's first state report, which the first
/// run holds back until the user answers the "allow Bluetooth" prompt for the terminal app.
const PROMPT_TIMEOUT: Duration = Duration::from_secs(12);

/// How long CoreBluetooth and WinRT may report the adapter state as unknown (starting up,
/// resetting) before that counts as "unavailable".
const SETTLE_TIMEOUT: Duration = Duration::from_secs(2);

/// The system's first Bluetooth adapter, or a one-line reason there is none.
///
/// Checks, in order: (Linux) the D-Bus system bus and BlueZ on it; an adapter; the adapter
/// powered on. Never takes much longer than [`SETUP_TIMEOUT`] twice, whatever state the system
/// is in (on macOS, [`PROMPT_TIMEOUT`] while the permission prompt is up).
pub async fn open_central() -> Result<Arc<dyn BleCentral>, BleError> {
    let adapter = list_adapters()
        .await?
        .into_iter()
        .next()
        .ok_or_else(|| BleError::no_adapter_on(Os::CURRENT))?;
    usable(&adapter).await?;
    Ok(Arc::new(BtleCentral { adapter }))
}

/// Every Bluetooth adapter to drive droids through, by name (`hci0`, `hci1` on Linux; the
/// platform's description elsewhere): those `names` lists (each must be there and on), or
/// without names every adapter that is on (at least one). Several adapters share a fleet's
/// droids (`--adapter`).
pub async fn open_adapters(
    names: &[String],
) -> Result<Vec<(String, Arc<dyn BleCentral>)>, BleError> {
    let os = Os::CURRENT;
    let mut all = Vec::new();
    for adapter in list_adapters().await? {
        let info = timeout(SETUP_TIMEOUT, adapter.adapter_info())
            .await
            .map_err(|_| stack_silent("reading the adapter", SETUP_TIMEOUT))?
            .map_err(map_err)?;
        // BlueZ says `hci0 (usb:v1D6Bp0246d0537)`: the name is the first word.
        let name = info.split_whitespace().next().unwrap_or(&info).to_string();
        all.push((name, adapter));
    }
    if all.is_empty() {
        return Err(BleError::no_adapter_on(os));
    }
    let known: Vec<String> = all.iter().map(|(n, _)| n.clone()).collect();
    let mut out: Vec<(String, Arc<dyn BleCentral>)> = Vec::new();
    let mut first_error = None;
    for (name, adapter) in all {
        let wanted = names.is_empty() || names.iter().any(|n| n.eq_ignore_ascii_case(&name));
        if !wanted {
            continue;
        }
        match usable(&adapter).await {
            Ok(()) => out.push((name, Arc::new(BtleCentral { adapter }))),
            // Asked for by name: it must work.
            Err(e) if !names.is_empty() => {
                return Err(BleError::new(e.kind, format!("{name}: {}", e.message)));
            }
            Err(e) => {
                tracing::warn!(adapter = %name, error = %e, "adapter not usable; skipped");
                first_error.get_or_insert(e);
            }
        }
    }
    if let Some(missing) = names
        .iter()
        .find(|n| !known.iter().any(|k| k.eq_ignore_ascii_case(n)))
    {
        return Err(BleError::new(
            BleErrorKind::NoAdapter,
            format!(
                "no Bluetooth adapter called {missing}: this computer has {}",
                known.join(", ")
            ),
        ));
    }
    match (out.is_empty(), first_error) {
        (true, Some(e)) => Err(e),
        (true, None) => Err(BleError::no_adapter_on(os)),
        (false, _) => Ok(out),
    }
}

/// The system's adapters, after checking (Linux) the D-Bus system bus and BlueZ on it.
async fn list_adapters() -> Result<Vec<Adapter>, BleError> {
    let os = Os::CURRENT;
    preflight().await?;
    let manager = timeout(SETUP_TIMEOUT, Manager::new())
        .await
        .map_err(|_| stack_silent(&format!("connecting to {}", os.stack()), SETUP_TIMEOUT))?
        .map_err(map_err)?;
    let list_timeout = if os == Os::MacOs {
        PROMPT_TIMEOUT
    } else {
        SETUP_TIMEOUT
    };
    timeout(list_timeout, manager.adapters())
        .await
        .map_err(|_| match os {
            Os::MacOs => BleError::new(
                BleErrorKind::PermissionDenied,
                format!(
                    "CoreBluetooth did not answer within {} s — if macOS asks whether this \
                     terminal may use Bluetooth, allow it (System Settings → Privacy & Security \
                     → Bluetooth) and run again, or try `droidctl --sim`",
                    list_timeout.as_secs()
                ),
            ),
            _ => stack_silent("listing adapters", list_timeout),
        })?
        .map_err(map_err)
}

/// Check `adapter` can be used: readable (permission errors surface here) and powered on.
async fn usable(adapter: &Adapter) -> Result<(), BleError> {
    let os = Os::CURRENT;
    // Surfaces permission errors before `adapter_state`, which reports any failure as "off".
    timeout(SETUP_TIMEOUT, adapter.adapter_info())
        .await
        .map_err(|_| stack_silent("reading the adapter", SETUP_TIMEOUT))?
        .map_err(map_err)?;
    let read_state = || async {
        timeout(SETUP_TIMEOUT, adapter.adapter_state())
            .await
            .map_err(|_| stack_silent("reading the adapter state", SETUP_TIMEOUT))?
            .map_err(map_err)
    };
    let mut state = read_state().await?;
    // BlueZ reports on or off. CoreBluetooth and WinRT also report "unknown": briefly while
    // starting, and for good when the terminal app is not allowed Bluetooth (macOS) or the
    // radio is disabled (Windows).
    if os != Os::Linux {
        let settle = tokio::time::Instant::now() + SETTLE_TIMEOUT;
        while state == CentralState::Unknown && tokio::time::Instant::now() < settle {
            tokio::time::sleep(Duration::from_millis(100)).await;
            state = read_state().await?;
        }
        if state == CentralState::Unknown {
            return Err(BleError::unavailable_on(os));
        }
    }
    if state == CentralState::PoweredOff {
        return Err(BleError::adapter_off_on(os));
    }
    Ok(())
}

/// The platform's Bluetooth stack did not answer `what` in time.
fn stack_silent(what: &str, after: Duration) -> BleError {
    let os = Os::CURRENT;
    BleError::new(
        BleErrorKind::BluezNotRunning,
        format!(
            "{} did not answer ({what}) within {} s — {}, or try `droidctl --sim`",
            os.stack(),
            after.as_secs(),
            os.check_hint()
        ),
    )
}

/// BlueZ, and so the D-Bus check, exist only on Linux; other platforms' btleplug backends need
/// no system bus.
#[cfg(not(target_os = "linux"))]
async fn preflight() -> Result<(), BleError> {
    Ok(())
}

/// Check the system bus and BlueZ with plain D-Bus calls before btleplug.
///
/// btleplug reports both "no bus" and "no BlueZ" as an opaque error, and its bus connect blocks
/// the thread. Asking the bus ourselves gives typed D-Bus error names; doing it on a plain
/// thread (not tokio's blocking pool, which a runtime waits for on shutdown) keeps a hung
/// socket from hanging the program.
#[cfg(target_os = "linux")]
async fn preflight() -> Result<(), BleError> {
    let (tx, rx) = tokio::sync::oneshot::channel();
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

#[cfg(target_os = "linux")]
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
/// Typed errors map directly; the rest by their text, per platform, in
/// [`BleError::from_platform_text`]. BlueZ failures arrive as `Error::Other` wrapping
/// bluez-async's error, which wraps the D-Bus error. We do not depend on bluez-async to
/// downcast it, so the D-Bus name and message are read back from its `Debug` text
/// (`D-Bus error: MESSAGE (NAME)`), the one stable rendering.
fn map_err(e: btleplug::Error) -> BleError {
    use btleplug::Error as E;
    let os = Os::CURRENT;
    match e {
        E::PermissionDenied => BleError::permission_denied_on(os),
        E::NoAdapterAvailable => BleError::no_adapter_on(os),
        E::DeviceNotFound => BleError::device_gone_on(os),
        E::NotConnected => BleError::new(BleErrorKind::Disconnected, "the droid is not connected"),
        E::TimedOut(d) => BleError::timeout("a Bluetooth operation", d.as_secs_f64()),
        E::NoSuchCharacteristic | E::UnexpectedCharacteristic => BleError::new(
            BleErrorKind::MissingCharacteristic,
            "the device lacks a characteristic the droid needs",
        ),
        E::Other(inner) => {
            let debug = format!("{inner:?}");
            let text = if debug.contains(DBUS_MARK) {
                debug
            } else {
                inner.to_string()
            };
            BleError::from_platform_text(os, &text)
        }
        other => BleError::from_platform_text(os, &other.to_string()),
    }
}

/// The D-Bus error name inside a btleplug error, if it wraps one.
fn dbus_name(e: &btleplug::Error) -> Option<String> {
    match e {
        btleplug::Error::Other(inner) => dbus_error_in(&format!("{inner:?}")).map(|(n, _)| n),
        _ => None,
    }
}

/// Who a peripheral is: btleplug's `PeripheralId` as a string (BlueZ's `hci0/dev_…`,
/// CoreBluetooth's UUID, WinRT's address) with the address where the platform tells it.
/// CoreBluetooth hides devices' real addresses and reports 00:00:00:00:00:00 for all, which
/// [`DeviceId::new`] takes as none: there the identifier is the name `--address` takes.
fn id_of(p: &Peripheral) -> DeviceId {
    DeviceId::new(p.id().to_string(), Some(BleAddress(p.address().into())))
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

    fn devices(&self) -> BoxFuture<'_, Result<Vec<KnownDevice>, BleError>> {
        Box::pin(async move {
            let peripherals = self.adapter.peripherals().await.map_err(map_err)?;
            let mut out = Vec::with_capacity(peripherals.len());
            for p in peripherals {
                // A device that vanished between the listing and this call is simply skipped.
                let Ok(Some(props)) = p.properties().await else {
                    continue;
                };
                // BlueZ has an RSSI only for a device heard in the current discovery; one
                // without may still be there because it is connected (it stops advertising).
                let connected = props.rssi.is_none() && p.is_connected().await.unwrap_or(false);
                out.push(KnownDevice {
                    id: id_of(&p),
                    // On BlueZ `local_name` is the Alias, which a user may have renamed and
                    // which falls back to the address for nameless devices; the advertised
                    // Name is what identifies the model.
                    name: props.advertisement_name.or(props.local_name),
                    rssi: props.rssi,
                    connected,
                });
            }
            Ok(out)
        })
    }

    fn device<'a>(
        &'a self,
        id: &'a DeviceId,
    ) -> BoxFuture<'a, Result<Arc<dyn BlePeripheral>, BleError>> {
        Box::pin(async move {
            let peripherals = self.adapter.peripherals().await.map_err(map_err)?;
            match peripherals
                .into_iter()
                .find(|p| p.id().to_string() == id.key())
            {
                Some(peripheral) => Ok(Arc::new(BtlePeripheral {
                    adapter: self.adapter.clone(),
                    peripheral,
                }) as Arc<dyn BlePeripheral>),
                None => Err(BleError::new(
                    BleErrorKind::NotFound,
                    format!("the adapter does not know {id}"),
                )),
            }
        })
    }

    fn powered(&self) -> BoxFuture<'_, Result<bool, BleError>> {
        Box::pin(async move {
            let state = self.adapter.adapter_state().await.map_err(map_err)?;
            Ok(state == CentralState::PoweredOn)
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
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn maps_wrapped_dbus_errors() {
        use btleplug::Error as E;
        let dbus = dbus::Error::new_custom("org.bluez.Error.NotReady", "Resource Not Ready");
        assert_eq!(
            map_err(E::Other(Box::new(dbus))).kind,
            BleErrorKind::AdapterOff
        );
    }

    /// On a machine without a system bus (containers, CI) the preflight says so, quickly.
    #[cfg(target_os = "linux")]
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
