//! [`GattBackend`] over a droid on a serial port: `droidctl serve --serial PORT`, so an RVR
//! on a Raspberry Pi's UART is driven from another machine (droidctl's `--remote`, spherov2's
//! `tcp_adapter`) as if the Pi had reached it over Bluetooth.
//!
//! The port stands for one device, named as `--serial` names it (`RV-serial0`) at the
//! port's path. Its API characteristic is the serial line: a client's writes to it go out on
//! the port, the port's bytes come back as notifications of the profile's notify
//! characteristic. There are no other characteristics (RVR needs no handshake write); one
//! client at a time holds the port (its lock refuses a second).

use super::backend::{
    BackendDevice, BackendError, Connected, DroidEvent, GattBackend, GattConnection,
};
use crate::gatt::GattUuid;
use crate::link::serial::SerialLink;
use crate::link::{Link, LinkEvent, LinkWriter};
use crate::model::Model;
use futures_util::future::BoxFuture;
use std::path::PathBuf;
use std::time::Duration;
use tokio::sync::{Mutex, mpsc};

/// Notifications waiting for the server, at most.
const EVENTS: usize = 1024;

/// The droid on one serial port.
pub struct SerialBackend {
    path: PathBuf,
    model: Model,
    name: String,
    link: Mutex<SerialLink>,
}

impl SerialBackend {
    /// The droid of `model` on the serial port at `path`.
    pub fn new(path: impl Into<PathBuf>, model: Model) -> Self {
        let path = path.into();
        let link = SerialLink::new(&path, model);
        SerialBackend {
            name: link.droid_name(),
            path,
            model,
            link: Mutex::new(link),
        }
    }

    fn device(&self) -> BackendDevice {
        BackendDevice {
            name: self.name.clone(),
            address: self.path.display().to_string(),
        }
    }

    fn is_ours(&self, address: &str) -> bool {
        let a = address.trim();
        a == self.path.display().to_string() || a.eq_ignore_ascii_case(&self.name)
    }
}

impl GattBackend for SerialBackend {
    /// The port is always "in range": whether a droid answers on it shows on connecting.
    fn scan(&self, _timeout: Duration) -> BoxFuture<'_, Result<Vec<BackendDevice>, BackendError>> {
        Box::pin(async move { Ok(vec![self.device()]) })
    }

    fn find<'a>(
        &'a self,
        name: &'a str,
        _timeout: Duration,
    ) -> BoxFuture<'a, Result<Option<BackendDevice>, BackendError>> {
        Box::pin(async move { Ok((name == self.name).then(|| self.device())) })
    }

    fn connect<'a>(&'a self, address: &'a str) -> BoxFuture<'a, Result<Connected, BackendError>> {
        Box::pin(async move {
            if !self.is_ours(address) {
                return Err(BackendError(format!(
                    "no droid at {address}: this relay has {} on {}",
                    self.name,
                    self.path.display()
                )));
            }
            let conn = self
                .link
                .lock()
                .await
                .open()
                .await
                .map_err(|e| BackendError(e.message))?;
            let profile = crate::family::gatt_profile(self.model);
            let api = profile.write.characteristic;
            let notify = profile
                .notify
                .first()
                .map(|c| c.characteristic)
                .unwrap_or(api);
            let (tx, rx) = mpsc::channel(EVENTS);
            let mut events = conn.events;
            tokio::spawn(async move {
                loop {
                    let ev = tokio::select! {
                        _ = tx.closed() => return,
                        ev = events.recv() => ev,
                    };
                    let out = match ev {
                        Some(LinkEvent::Data(value)) => DroidEvent::Notification {
                            characteristic: notify,
                            value,
                        },
                        Some(LinkEvent::Disconnected(why)) => DroidEvent::Disconnected(why),
                        None => DroidEvent::Disconnected("the serial port closed".into()),
                    };
                    let end = matches!(out, DroidEvent::Disconnected(_));
                    if tx.send(out).await.is_err() || end {
                        return;
                    }
                }
            });
            Ok(Connected {
                connection: Box::new(SerialGatt {
                    writer: conn.writer,
                    api,
                }),
                events: rx,
                name: self.name.clone(),
                model: Some(self.model),
                stop_as: Some(self.model),
            })
        })
    }

    fn describe(&self) -> String {
        format!("{} on {}", self.model.display_name(), self.path.display())
    }
}

/// The serial line seen as GATT: one characteristic to write.
struct SerialGatt {
    writer: Box<dyn LinkWriter>,
    api: GattUuid,
}

impl GattConnection for SerialGatt {
    fn write<'a>(
        &'a mut self,
        characteristic: GattUuid,
        data: &'a [u8],
    ) -> BoxFuture<'a, Result<(), BackendError>> {
        Box::pin(async move {
            if characteristic != self.api {
                return Err(BackendError(format!(
                    "a droid on a serial port has no characteristic {characteristic}: write \
                     its packets to {}",
                    self.api
                )));
            }
            self.writer
                .write(data)
                .await
                .map_err(|e| BackendError(e.message))
        })
    }

    fn subscribe(&mut self, _characteristic: GattUuid) -> BoxFuture<'_, Result<(), BackendError>> {
        // The port's bytes flow from the start: nothing to switch on.
        Box::pin(async { Ok(()) })
    }

    fn disconnect(&mut self) -> BoxFuture<'_, ()> {
        self.writer.close()
    }
}
