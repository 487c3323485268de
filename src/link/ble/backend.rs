//! The radio-free interface the BLE link and scanner are written against.
//!
//! [`BleCentral`] (the adapter: scan, find a peripheral) and [`BlePeripheral`] (one device:
//! connect, discover, read, write, subscribe, events) are all the generic code needs. The
//! btleplug implementation is a thin translation layer (`btleplug_backend.rs`); the fake one
//! (`fake.rs`) lets every behaviour above it — handshakes, chunking, pacing, reconnects, scan
//! sorting — be tested on tokio's paused clock without a radio.
//!
//! Timeouts are not part of the interface: the generic code wraps each call in
//! `tokio::time::timeout`, so they behave the same (and are tested) for every backend.

use super::BleError;
use crate::link::gatt::{CharRef, GattUuid};
use futures_util::future::BoxFuture;
use futures_util::stream::BoxStream;
use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

/// A Bluetooth device address, `AA:BB:CC:DD:EE:FF`.
///
/// On macOS, where CoreBluetooth hides real addresses, it is the first six bytes of the
/// identifier the Mac gave the device ([`BleAddress::from_identifier`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct BleAddress(pub [u8; 6]);

impl fmt::Display for BleAddress {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let b = self.0;
        write!(
            f,
            "{:02X}:{:02X}:{:02X}:{:02X}:{:02X}:{:02X}",
            b[0], b[1], b[2], b[3], b[4], b[5]
        )
    }
}

impl BleAddress {
    /// The address standing for a device known only by a UUID identifier (CoreBluetooth's,
    /// `8E5B5B4E-1234-4A6B-9C8D-0123456789AB`): its first six bytes, `8E:5B:5B:4E:12:34`.
    /// Unique enough among the devices in range, and stable on that Mac.
    pub fn from_identifier(uuid: &str) -> Option<BleAddress> {
        let groups: Vec<&str> = uuid.trim().split('-').collect();
        let lens: Vec<usize> = groups.iter().map(|g| g.len()).collect();
        if lens != [8, 4, 4, 4, 12]
            || !groups
                .iter()
                .all(|g| g.chars().all(|c| c.is_ascii_hexdigit()))
        {
            return None;
        }
        let hex: String = groups.concat();
        let mut out = [0u8; 6];
        for (i, o) in out.iter_mut().enumerate() {
            *o = u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).ok()?;
        }
        Some(BleAddress(out))
    }
}

impl FromStr for BleAddress {
    type Err = String;

    /// Accepts `AA:BB:CC:DD:EE:FF` or `aa-bb-cc-dd-ee-ff`, or a macOS device identifier (a
    /// UUID; see [`BleAddress::from_identifier`]).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if let Some(a) = BleAddress::from_identifier(s) {
            return Ok(a);
        }
        let bad = || format!("`{s}` is not a Bluetooth address like AA:BB:CC:DD:EE:FF");
        let parts: Vec<&str> = s.trim().split([':', '-']).collect();
        if parts.len() != 6 {
            return Err(bad());
        }
        let mut out = [0u8; 6];
        for (o, p) in out.iter_mut().zip(&parts) {
            if p.len() != 2 {
                return Err(bad());
            }
            *o = u8::from_str_radix(p, 16).map_err(|_| bad())?;
        }
        Ok(BleAddress(out))
    }
}

/// What a scan heard from one device.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Advertisement {
    pub address: BleAddress,
    /// The advertised local name, if any.
    pub name: Option<String>,
    /// Signal strength in dBm; `None` when BlueZ knows the device but did not hear it in this
    /// scan (cached from earlier, or connected and so not advertising).
    pub rssi: Option<i16>,
}

/// A characteristic found by service discovery.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DiscoveredChar {
    pub service: GattUuid,
    pub characteristic: GattUuid,
}

/// Something a connected peripheral reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PeripheralEvent {
    /// A notification or indication value.
    Notification {
        characteristic: GattUuid,
        value: Vec<u8>,
    },
    /// The connection dropped; the reason is for people.
    Disconnected(String),
}

/// The local adapter.
pub trait BleCentral: Send + Sync {
    /// Start discovery. Advertisements accumulate until [`BleCentral::stop_scan`].
    fn start_scan(&self) -> BoxFuture<'_, Result<(), BleError>>;
    fn stop_scan(&self) -> BoxFuture<'_, Result<(), BleError>>;
    /// Every device heard so far (one entry per address, latest values).
    fn advertisements(&self) -> BoxFuture<'_, Result<Vec<Advertisement>, BleError>>;
    /// A handle to a device seen by a scan. `NotFound` when the adapter does not know it.
    fn peripheral(
        &self,
        address: BleAddress,
    ) -> BoxFuture<'_, Result<Arc<dyn BlePeripheral>, BleError>>;
}

/// One remote device.
pub trait BlePeripheral: Send + Sync {
    fn connect(&self) -> BoxFuture<'_, Result<(), BleError>>;
    /// Discover services and return every characteristic found.
    fn discover_services(&self) -> BoxFuture<'_, Result<Vec<DiscoveredChar>, BleError>>;
    fn write<'a>(
        &'a self,
        ch: CharRef,
        data: &'a [u8],
        with_response: bool,
    ) -> BoxFuture<'a, Result<(), BleError>>;
    fn read(&self, ch: CharRef) -> BoxFuture<'_, Result<Vec<u8>, BleError>>;
    /// Enable notifications (or indications) on `ch`.
    fn subscribe(&self, ch: CharRef) -> BoxFuture<'_, Result<(), BleError>>;
    /// Notifications and disconnects from now on. Ask before subscribing so nothing is missed.
    fn events(&self) -> BoxFuture<'_, Result<BoxStream<'static, PeripheralEvent>, BleError>>;
    fn disconnect(&self) -> BoxFuture<'_, Result<(), BleError>>;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_round_trip() {
        let a: BleAddress = "f1:22:33:44:55:a6".parse().unwrap();
        assert_eq!(a.to_string(), "F1:22:33:44:55:A6");
        assert_eq!("F1-22-33-44-55-A6".parse::<BleAddress>(), Ok(a));
        assert!("F1:22:33:44:55".parse::<BleAddress>().is_err());
        assert!("F1:22:33:44:55:GG".parse::<BleAddress>().is_err());
        assert!("F1:22:33:44:55:666".parse::<BleAddress>().is_err());
    }

    #[test]
    fn macos_identifiers_stand_for_addresses() {
        let id = "8e5b5b4e-1234-4a6b-9c8d-0123456789ab";
        let a = BleAddress::from_identifier(id).unwrap();
        assert_eq!(a.to_string(), "8E:5B:5B:4E:12:34");
        // `--address` takes the identifier or the address shown for it.
        assert_eq!(id.to_uppercase().parse::<BleAddress>(), Ok(a));
        assert_eq!("8E:5B:5B:4E:12:34".parse::<BleAddress>(), Ok(a));
        assert_eq!(
            BleAddress::from_identifier("8e5b5b4e-1234-4a6b-9c8d-0123456789a"),
            None
        );
        assert_eq!(
            BleAddress::from_identifier("8e5b5b4e-1234-4a6b-9c8d-0123456789ag"),
            None
        );
        assert_eq!(BleAddress::from_identifier("F1:22:33:44:55:66"), None);
    }
}
