//! The `Link`: bytes to and from a droid. BLE, the simulator and anything later (a network
//! bridge) implement it; the session, control loop, script runner and UI know only this trait.
//!
//! A link is opened into a [`Connection`]: a writer half and a channel of events, so the
//! session can wait for incoming bytes and write at the same time.

pub mod backoff;
pub mod ble;
pub mod remote;
pub mod serial;

use crate::gatt::Endpoint;
use futures_util::future::BoxFuture;
use std::fmt;
use tokio::sync::mpsc;

/// What a link says while the Bluetooth adapter is switched off during a session (shown as
/// the link state, instead of "reconnecting"): not fatal, it reconnects once the adapter is
/// powered again.
pub const ADAPTER_OFF_WAITING: &str = "Bluetooth adapter is off — waiting";

/// Why a link failed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LinkError {
    pub message: String,
    /// Nothing will change by retrying (no adapter, permission denied): give up at once.
    pub fatal: bool,
}

impl LinkError {
    pub fn transient(message: impl Into<String>) -> Self {
        LinkError {
            message: message.into(),
            fatal: false,
        }
    }

    pub fn fatal(message: impl Into<String>) -> Self {
        LinkError {
            message: message.into(),
            fatal: true,
        }
    }
}

impl fmt::Display for LinkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for LinkError {}

/// What arrives from an open connection.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LinkEvent {
    /// Bytes from the droid. Not a packet boundary (`droid-facts.md` §1).
    Data(Vec<u8>),
    /// The connection is gone; the reason is for people.
    Disconnected(String),
}

/// The writing half of an open connection.
pub trait LinkWriter: Send {
    /// Write one chunk to the command channel (at most the link's chunk size, 20 bytes for
    /// BLE).
    fn write<'a>(&'a mut self, chunk: &'a [u8]) -> BoxFuture<'a, Result<(), LinkError>>;
    /// Write one chunk to `to`. Links with only a command channel need not override this.
    fn write_to<'a>(
        &'a mut self,
        to: Endpoint,
        chunk: &'a [u8],
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        match to {
            Endpoint::Api => self.write(chunk),
            other => Box::pin(async move {
                Err(LinkError::fatal(format!(
                    "this link has no {} input",
                    other.name()
                )))
            }),
        }
    }
    /// Write one chunk to `to` now, without waiting for the link's own pacing slot: the
    /// emergency stop's path (the session's pacing is skipped for it too). The pacing after
    /// it counts from this write. Links that do not pace need not override this.
    fn write_urgent<'a>(
        &'a mut self,
        to: Endpoint,
        chunk: &'a [u8],
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        self.write_to(to, chunk)
    }
    /// Close the connection (best effort).
    fn close(&mut self) -> BoxFuture<'_, ()>;
}

/// An open connection: write with `writer`, read `events` until `Disconnected` or `None`.
pub struct Connection {
    pub writer: Box<dyn LinkWriter>,
    pub events: mpsc::Receiver<LinkEvent>,
}

/// Something that can connect to a droid.
pub trait Link: Send {
    /// Connect, including the model's handshake (e.g. the v2 anti-DoS write), and subscribe to
    /// notifications. Called again after a disconnect to reconnect.
    fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>>;
    /// Cancel a connect that `open` was still making when the caller gave up on it (the
    /// future was dropped): the radio stack may still be connecting.
    fn abort_open(&mut self) -> BoxFuture<'_, ()> {
        Box::pin(async {})
    }
    /// Resolves when retrying now is worthwhile although the backoff delay has not run out
    /// (the Bluetooth adapter that was switched off is powered again). Never, by default.
    fn retry_hint(&mut self) -> BoxFuture<'_, ()> {
        Box::pin(std::future::pending())
    }
    /// How long the link may go without a write before it is closed under the session (a
    /// relay closes silent clients): the session writes something harmless in time. `None`
    /// (the default): the link stays open however quiet.
    fn keepalive(&self) -> Option<std::time::Duration> {
        None
    }
    /// The link's own write size and pacing, where they are not the model's Bluetooth ones
    /// (a serial line has no 20-byte ATT payload). `None` (the default): the session's
    /// configuration stands.
    fn framing(&self) -> Option<Framing> {
        None
    }
    /// A name for the status bar: "R2-D2 D2-1A2B (simulated)".
    fn describe(&self) -> String;
}

/// How a link wants the session's writes: at most `chunk_size` bytes each, one per `pacing`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Framing {
    pub chunk_size: usize,
    pub pacing: std::time::Duration,
}
