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
use crate::gatt::{CharRef, GattUuid};
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

/// Who a device is: the platform's own identifier for it (btleplug's `PeripheralId` as a
/// string: BlueZ's `hci0/dev_F1_22_33_44_55_66` on Linux, CoreBluetooth's UUID on macOS, the
/// address on Windows), with its Bluetooth address where the platform tells it. CoreBluetooth
/// reports 00:00:00:00:00:00 for every device, so the address alone cannot tell two droids
/// apart there: scan merging, the picker and `--address` key on the identifier.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct DeviceId {
    key: String,
    address: Option<BleAddress>,
}

impl DeviceId {
    /// `key` is the platform's identifier; an all-zero `address` counts as none.
    pub fn new(key: impl Into<String>, address: Option<BleAddress>) -> DeviceId {
        DeviceId {
            key: key.into(),
            address: address.filter(|a| *a != BleAddress::default()),
        }
    }

    /// A device known by its address only (the fake adapter, tests).
    pub fn from_address(address: BleAddress) -> DeviceId {
        DeviceId {
            key: address.to_string(),
            address: Some(address),
        }
    }

    /// The platform's identifier.
    pub fn key(&self) -> &str {
        &self.key
    }

    /// The Bluetooth address, where the platform tells it.
    pub fn address(&self) -> Option<BleAddress> {
        self.address
    }

    /// A six-byte address for callers keyed on addresses: the address, or where there is
    /// none the identifier's first six bytes ([`BleAddress::from_identifier`]).
    pub fn stand_in(&self) -> BleAddress {
        self.address
            .or_else(|| BleAddress::from_identifier(&self.key))
            .unwrap_or_default()
    }

    /// Whether `--address TEXT` names this device: its address (`AA:BB:…` or `aa-bb-…`), its
    /// platform identifier (any case), or, where there is no address, the identifier's
    /// six-byte stand-in that earlier versions showed on macOS.
    pub fn matches(&self, text: &str) -> bool {
        let text = text.trim();
        if text.is_empty() {
            return false;
        }
        if self.key.eq_ignore_ascii_case(text) {
            return true;
        }
        match (parse_mac(text), self.address) {
            (Some(a), Some(mine)) => a == mine,
            (Some(a), None) => BleAddress::from_identifier(&self.key) == Some(a),
            (None, _) => false,
        }
    }

    /// Whether `text` can name a device at all (an address, a UUID identifier, BlueZ's
    /// `hciN/dev_…`), for checking `--address` before scanning.
    pub fn is_query(text: &str) -> bool {
        let t = text.trim();
        parse_mac(t).is_some()
            || BleAddress::from_identifier(t).is_some()
            || t.strip_prefix("hci")
                .is_some_and(|rest| rest.contains("/dev_"))
    }
}

/// `AA:BB:CC:DD:EE:FF` or `aa-bb-cc-dd-ee-ff` only (no identifiers).
fn parse_mac(s: &str) -> Option<BleAddress> {
    let parts: Vec<&str> = s.trim().split([':', '-']).collect();
    if parts.len() != 6 || parts.iter().any(|p| p.len() != 2) {
        return None;
    }
    let mut out = [0u8; 6];
    for (o, p) in out.iter_mut().zip(&parts) {
        *o = u8::from_str_radix(p, 16).ok()?;
    }
    Some(BleAddress(out))
}

impl fmt::Display for DeviceId {
    /// The address where there is one, else the platform identifier: what `--address` takes.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.address {
            Some(a) => a.fmt(f),
            None => f.write_str(&self.key),
        }
    }
}

impl From<BleAddress> for DeviceId {
    fn from(a: BleAddress) -> DeviceId {
        DeviceId::from_address(a)
    }
}

/// One device the adapter knows: heard in the current scan, connected, or only remembered
/// (BlueZ lists every device it remembers, even one switched off in a drawer).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct KnownDevice {
    pub id: DeviceId,
    /// The advertised local name, if any.
    pub name: Option<String>,
    /// Signal strength in dBm when it advertised during the current scan; `None` when it
    /// did not (remembered from earlier, or connected and so not advertising).
    pub rssi: Option<i16>,
    /// Connected now (to droidctl or another program on this computer).
    pub connected: bool,
}

impl KnownDevice {
    /// Really there: it advertised during this scan (it has an RSSI) or is connected now.
    pub fn heard(&self) -> bool {
        self.rssi.is_some() || self.connected
    }
}

impl From<&Advertisement> for KnownDevice {
    fn from(ad: &Advertisement) -> KnownDevice {
        KnownDevice {
            id: DeviceId::from_address(ad.address),
            name: ad.name.clone(),
            rssi: ad.rssi,
            connected: false,
        }
    }
}

/// What a scan heard from one device, by address (see [`KnownDevice`] for the identity that
/// survives macOS).
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
    /// Start discovery. What is heard accumulates until [`BleCentral::stop_scan`].
    fn start_scan(&self) -> BoxFuture<'_, Result<(), BleError>>;
    fn stop_scan(&self) -> BoxFuture<'_, Result<(), BleError>>;
    /// Every device the adapter knows, one entry per device with its latest values: heard in
    /// this scan, connected, or only remembered ([`KnownDevice::heard`] tells).
    fn devices(&self) -> BoxFuture<'_, Result<Vec<KnownDevice>, BleError>>;
    /// A handle to a device the adapter knows. `NotFound` when it does not.
    fn device<'a>(
        &'a self,
        id: &'a DeviceId,
    ) -> BoxFuture<'a, Result<Arc<dyn BlePeripheral>, BleError>>;
    /// Whether the adapter is powered on (to wait for it after it was switched off).
    fn powered(&self) -> BoxFuture<'_, Result<bool, BleError>>;

    /// Every device the adapter knows, by address (its stand-in where the platform hides
    /// it; see [`DeviceId::stand_in`]).
    fn advertisements(&self) -> BoxFuture<'_, Result<Vec<Advertisement>, BleError>> {
        Box::pin(async move {
            Ok(self
                .devices()
                .await?
                .into_iter()
                .map(|d| Advertisement {
                    address: d.id.stand_in(),
                    name: d.name,
                    rssi: d.rssi,
                })
                .collect())
        })
    }

    /// A handle to the device at `address` (or whose stand-in it is). `NotFound` when the
    /// adapter does not know it.
    fn peripheral(
        &self,
        address: BleAddress,
    ) -> BoxFuture<'_, Result<Arc<dyn BlePeripheral>, BleError>> {
        Box::pin(async move {
            let found = self
                .devices()
                .await?
                .into_iter()
                .find(|d| d.id.stand_in() == address)
                .map(|d| d.id);
            match found {
                Some(id) => self.device(&id).await,
                None => Err(BleError::new(
                    super::BleErrorKind::NotFound,
                    format!("the adapter does not know {address}"),
                )),
            }
        })
    }
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
    fn device_ids_match_addresses_and_identifiers() {
        let linux = DeviceId::new(
            "hci0/dev_F1_22_33_44_55_66",
            Some("F1:22:33:44:55:66".parse().unwrap()),
        );
        assert_eq!(linux.to_string(), "F1:22:33:44:55:66");
        assert!(linux.matches("f1:22:33:44:55:66"));
        assert!(linux.matches("F1-22-33-44-55-66"));
        assert!(linux.matches("HCI0/dev_F1_22_33_44_55_66"));
        assert!(!linux.matches("F1:22:33:44:55:67"));
        assert!(!linux.matches(""));
        // macOS: no address (all zeros), the identifier is the name.
        let mac = DeviceId::new(
            "8e5b5b4e-1234-4a6b-9c8d-0123456789ab",
            Some(BleAddress::default()),
        );
        assert_eq!(mac.address(), None);
        assert_eq!(mac.to_string(), "8e5b5b4e-1234-4a6b-9c8d-0123456789ab");
        assert!(mac.matches("8E5B5B4E-1234-4A6B-9C8D-0123456789AB"));
        assert!(
            mac.matches("8E:5B:5B:4E:12:34"),
            "the stand-in shown before"
        );
        assert!(!mac.matches("00:00:00:00:00:00"));
        assert_eq!(mac.stand_in().to_string(), "8E:5B:5B:4E:12:34");
        let other = DeviceId::new("0f5b5b4e-1234-4a6b-9c8d-0123456789ab", None);
        assert_ne!(mac, other);
        for ok in [
            "F1:22:33:44:55:66",
            "8e5b5b4e-1234-4a6b-9c8d-0123456789ab",
            "hci0/dev_F1_22_33_44_55_66",
        ] {
            assert!(DeviceId::is_query(ok), "{ok}");
        }
        assert!(!DeviceId::is_query("droid"));
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
