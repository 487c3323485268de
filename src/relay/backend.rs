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
    /// Where the droid is, when the backend knows it for certain (a simulated droid's body,
    /// never a real droid's guess): `serve --json` says it as the droid is released, so a
    /// client's run can be judged by where it really ended (tests/it/edu_twins.rs).
    fn pose(&mut self) -> Option<Pose> {
        None
    }
}

/// A simulated droid's true place: centimetres from where it started, and the way it faces
/// (0..360, clockwise from its starting heading).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Pose {
    pub x_cm: f32,
    pub y_cm: f32,
    pub yaw_deg: f32,
}
