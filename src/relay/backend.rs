//! What `droidctl serve` relays to: a [`GattBackend`] that scans and connects, and per
//! droid a [`GattConnection`] that writes and subscribes by characteristic UUID, with its
//! notifications and disconnect on a channel.
//!
//! Two implementations: [`super::ble_backend::BleBackend`] over droidctl's BLE layer
//! ([`crate::link::ble::BleCentral`]), and [`super::sim_backend::SimBackend`] over simulated
//! droids at the GATT level ([`crate::sim::gatt::GattDroid`]). Tests add their own fakes.

use crate::gatt::GattUuid;
use crate::model::Model;
use futures_util::future::BoxFuture;
use std::fmt;
use std::time::Duration;
use tokio::sync::mpsc;

/// A device a scan heard.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BackendDevice {
    /// The advertised name (empty when the device advertises none).
    pub name: String,
    /// The address as the backend names it; [`GattBackend::connect`] takes it back.
    pub address: String,
}

/// Why a backend operation failed: one line, sent to the client as an ERROR's message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BackendError(pub String);

impl fmt::Display for BackendError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BackendError {}

impl From<String> for BackendError {
    fn from(s: String) -> Self {
        BackendError(s)
    }
}

impl From<&str> for BackendError {
    fn from(s: &str) -> Self {
        BackendError(s.to_string())
    }
}

/// What a connected droid reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum DroidEvent {
    Notification {
        characteristic: GattUuid,
        value: Vec<u8>,
    },
    /// The droid is gone; the reason is for people.
    Disconnected(String),
}

/// A droid the server connected to.
pub struct Connected {
    pub connection: Box<dyn GattConnection>,
    /// Notifications of subscribed characteristics, then `Disconnected`. The backend must
    /// not block on it for long: the server reads it continuously.
    pub events: mpsc::Receiver<DroidEvent>,
    /// The advertised name, when known.
    pub name: String,
    /// The model, when the name says it.
    pub model: Option<Model>,
    /// A model of the droid's family, to stop it when its client goes (the stop command is
    /// the family's): the model, else what the GATT table shows.
    pub stop_as: Option<Model>,
}

/// The droids behind the relay.
pub trait GattBackend: Send + Sync + 'static {
    /// Every device heard within `timeout`.
    fn scan(&self, timeout: Duration) -> BoxFuture<'_, Result<Vec<BackendDevice>, BackendError>>;
    /// The device advertising exactly `name`, as soon as it is heard, within `timeout`.
    fn find<'a>(
        &'a self,
        name: &'a str,
        timeout: Duration,
    ) -> BoxFuture<'a, Result<Option<BackendDevice>, BackendError>>;
    /// Connect (and discover services). No handshake: the client writes it.
    fn connect<'a>(&'a self, address: &'a str) -> BoxFuture<'a, Result<Connected, BackendError>>;
    /// "Bluetooth", "3 simulated droids": for the status line.
    fn describe(&self) -> String;
}

/// One connected droid.
pub trait GattConnection: Send {
    /// Write `data` to `characteristic`, with response.
    fn write<'a>(
        &'a mut self,
        characteristic: GattUuid,
        data: &'a [u8],
    ) -> BoxFuture<'a, Result<(), BackendError>>;
    /// Start notifications of `characteristic` (they arrive on the events channel).
    fn subscribe(&mut self, characteristic: GattUuid) -> BoxFuture<'_, Result<(), BackendError>>;
    /// Disconnect (best effort).
    fn disconnect(&mut self) -> BoxFuture<'_, ()>;
}

/// A characteristic UUID as clients send it: `00010002-574f-4f20-5370-6865726f2121` (any
/// case), the same without hyphens, or a 16-bit `2a00` / `0x2A00` on the Bluetooth base.
pub fn parse_uuid(s: &str) -> Option<GattUuid> {
    let t = s.trim();
    let t = t
        .strip_prefix("0x")
        .or_else(|| t.strip_prefix("0X"))
        .unwrap_or(t);
    if t.len() == 4 && t.chars().all(|c| c.is_ascii_hexdigit()) {
        return u16::from_str_radix(t, 16).ok().map(GattUuid::from_u16);
    }
    let hex: String = if t.len() == 36 {
        let b = t.as_bytes();
        if [8, 13, 18, 23].iter().any(|&i| b[i] != b'-') {
            return None;
        }
        t.chars().filter(|c| *c != '-').collect()
    } else {
        t.to_string()
    };
    if hex.len() != 32 || !hex.chars().all(|c| c.is_ascii_hexdigit()) {
        return None;
    }
    u128::from_str_radix(&hex, 16).ok().map(GattUuid::from_u128)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::family::robi::gatt::ROBI_FRAMES;
    use crate::family::v2::gatt::V2_API;

    #[test]
    fn uuids_parse_in_every_form() {
        assert_eq!(
            parse_uuid("00010002-574f-4f20-5370-6865726f2121"),
            Some(V2_API)
        );
        assert_eq!(
            parse_uuid("00010002-574F-4F20-5370-6865726F2121"),
            Some(V2_API)
        );
        assert_eq!(parse_uuid("00010002574f4f2053706865726f2121"), Some(V2_API));
        assert_eq!(parse_uuid("8765"), Some(ROBI_FRAMES));
        assert_eq!(parse_uuid("0x8765"), Some(ROBI_FRAMES));
        assert_eq!(parse_uuid("00010002-574f-4f20-5370-6865726f212"), None);
        assert_eq!(parse_uuid("00010002+574f-4f20-5370-6865726f2121"), None);
        assert_eq!(parse_uuid("zz"), None);
        assert_eq!(parse_uuid("é"), None);
    }
}
