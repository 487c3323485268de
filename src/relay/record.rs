//! `serve --record FILE`: every droid session the relay serves, recorded in droidctl's
//! capture format (the same as `drive`/`run --record`, so `droidctl replay` plays it).
//!
//! The relay works at the GATT level, below droidctl's `Link`, so the recording sits in a
//! [`GattBackend`] wrapper: writes to the command channel (or Robi's velocity and steering
//! inputs) are `out` lines, notifications of the droid's notify characteristics are `in`
//! lines, and handshake writes to other characteristics are marks. One capture per droid
//! session: FILE for the first, then `FILE-2`, `FILE-3` … (before the extension).

use super::backend::{
    BackendDevice, BackendError, Connected, DroidEvent, GattBackend, GattConnection,
};
use crate::capture::Event;
use crate::capture::record::Recorder;
use crate::gatt::Endpoint;
use crate::gatt::{GattProfile, GattUuid};
use futures_util::future::BoxFuture;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;
use tokio::sync::mpsc;

/// Records the sessions of the backend it wraps.
pub struct RecordingBackend {
    inner: Arc<dyn GattBackend>,
    path: PathBuf,
    force: bool,
    sessions: AtomicU32,
}

/// The capture path of the `n`th session (1-based): FILE, then FILE-2.ext, FILE-3.ext …
pub fn session_path(path: &Path, n: u32) -> PathBuf {
    if n <= 1 {
        return path.to_path_buf();
    }
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = match path.extension() {
        Some(ext) => format!("{stem}-{n}.{}", ext.to_string_lossy()),
        None => format!("{stem}-{n}"),
    };
    path.with_file_name(name)
}

impl RecordingBackend {
    /// Check now that FILE can be created (an existing one is refused without `force`), so
    /// the refusal comes before the server starts.
    pub fn new(inner: Arc<dyn GattBackend>, path: &Path, force: bool) -> Result<Self, String> {
        if !force && path.exists() {
            return Err(format!(
                "{} exists: droidctl does not overwrite a capture (--force replaces it)",
                path.display()
            ));
        }
        Ok(RecordingBackend {
            inner,
            path: path.to_path_buf(),
            force,
            sessions: AtomicU32::new(0),
        })
    }
}

impl GattBackend for RecordingBackend {
    fn scan(&self, timeout: Duration) -> BoxFuture<'_, Result<Vec<BackendDevice>, BackendError>> {
        self.inner.scan(timeout)
    }

    fn find<'a>(
        &'a self,
        name: &'a str,
        timeout: Duration,
    ) -> BoxFuture<'a, Result<Option<BackendDevice>, BackendError>> {
        self.inner.find(name, timeout)
    }

    fn connect<'a>(&'a self, address: &'a str) -> BoxFuture<'a, Result<Connected, BackendError>> {
        Box::pin(async move {
            let c = self.inner.connect(address).await?;
            let Some(model) = c.model.or(c.stop_as) else {
                tracing::warn!(droid = %c.name, "unknown model: this session is not recorded");
                return Ok(c);
            };
            let n = self.sessions.fetch_add(1, Ordering::SeqCst) + 1;
            let path = session_path(&self.path, n);
            let rec = match Recorder::create(&path, self.force) {
                Ok(r) => r,
                Err(e) => {
                    tracing::warn!(error = %e, "this session is not recorded");
                    eprintln!("droidctl serve: {e}; this session is not recorded");
                    return Ok(c);
                }
            };
            rec.start(&Recorder::header_for(model, &c.name));
            rec.record(Event::Connect);
            let profile = crate::family::gatt_profile(model);
            let (tx, rx) = mpsc::channel(1024);
            tokio::spawn(forward(c.events, tx, rec.clone(), profile.clone()));
            Ok(Connected {
                connection: Box::new(RecordingConnection {
                    inner: c.connection,
                    rec,
                    profile,
                }),
                events: rx,
                name: c.name,
                model: c.model,
                stop_as: c.stop_as,
            })
        })
    }

    fn describe(&self) -> String {
        self.inner.describe()
    }
}

/// Notifications of the notify characteristics are what a `Link` delivers as data.
async fn forward(
    mut events: mpsc::Receiver<DroidEvent>,
    tx: mpsc::Sender<DroidEvent>,
    rec: Recorder,
    profile: GattProfile,
) {
    while let Some(e) = events.recv().await {
        match &e {
            DroidEvent::Notification {
                characteristic,
                value,
            } if profile
                .notify
                .iter()
                .any(|c| c.characteristic == *characteristic) =>
            {
                rec.record(Event::In(value.clone()));
            }
            DroidEvent::Disconnected(reason) => rec.record(Event::Disconnect(reason.clone())),
            DroidEvent::Notification { .. } => {}
        }
        if tx.send(e).await.is_err() {
            break;
        }
    }
}

struct RecordingConnection {
    inner: Box<dyn GattConnection>,
    rec: Recorder,
    profile: GattProfile,
}

impl RecordingConnection {
    /// Which of the droid's inputs a characteristic is, if any.
    fn endpoint(&self, ch: GattUuid) -> Option<Endpoint> {
        [Endpoint::Api, Endpoint::Velocity, Endpoint::Steering]
            .into_iter()
            .find(|e| {
                self.profile
                    .endpoint(*e)
                    .is_some_and(|c| c.characteristic == ch)
            })
    }
}

impl GattConnection for RecordingConnection {
    fn write<'a>(
        &'a mut self,
        characteristic: GattUuid,
        data: &'a [u8],
    ) -> BoxFuture<'a, Result<(), BackendError>> {
        Box::pin(async move {
            match self.endpoint(characteristic) {
                Some(e) => self.rec.record(Event::Out(e, data.to_vec())),
                // The handshake (anti-DoS unlock, v1 wake sequence, Robi's start): not API
                // traffic, kept as a mark so the capture tells the whole story.
                None => self.rec.record(Event::Mark(format!(
                    "gatt-write {characteristic} {}",
                    crate::hex::compact(data)
                ))),
            }
            let r = self.inner.write(characteristic, data).await;
            if let Err(e) = &r {
                self.rec.record(Event::WriteFailed(e.0.clone()));
            }
            r
        })
    }

    fn subscribe(&mut self, characteristic: GattUuid) -> BoxFuture<'_, Result<(), BackendError>> {
        self.inner.subscribe(characteristic)
    }

    fn pose(&mut self) -> Option<super::backend::Pose> {
        self.inner.pose()
    }

    fn disconnect(&mut self) -> BoxFuture<'_, ()> {
        Box::pin(async move {
            self.inner.disconnect().await;
            self.rec.record(Event::Close);
            if let Err(e) = self.rec.finish() {
                tracing::warn!(error = %e, "capture incomplete");
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_file_per_session() {
        let p = Path::new("/tmp/caps/serve.txt");
        assert_eq!(session_path(p, 1), p);
        assert_eq!(session_path(p, 2), Path::new("/tmp/caps/serve-2.txt"));
        assert_eq!(
            session_path(Path::new("cap"), 3),
            Path::new("cap-3").to_path_buf()
        );
    }
}
