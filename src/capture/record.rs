//! `--record FILE`: a [`Link`] wrapper that writes everything crossing the link to a capture
//! file in the droidctl format ([`crate::capture`]): connects, every chunk written and
//! received with its time and endpoint, disconnects. Every link goes through it the same way,
//! so BLE, the simulator and anything later are recorded alike.
//!
//! Writes are buffered; the buffer is flushed at least every second (by a small thread, so a
//! quiet link is flushed too), on [`Recorder::finish`], when the last handle goes, and from
//! the panic hook ([`flush_all`]). A crash leaves a readable file up to the last flush. An
//! existing file is never truncated unless asked (`--force`).

use crate::capture::{self, Event, Header, Timed};
use crate::gatt::Endpoint;
use crate::link::{Connection, Link, LinkError, LinkEvent, LinkWriter};
use crate::sync::lock;
use futures_util::future::BoxFuture;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, Weak};
use std::time::Duration;
use tokio::sync::mpsc;

/// The longest the buffer waits before it is written out.
pub const FLUSH_EVERY: Duration = Duration::from_secs(1);

struct State {
    out: Option<BufWriter<File>>,
    /// Time zero (tokio time, so a recording under simulated time has simulated times).
    start: Option<tokio::time::Instant>,
    dirty: bool,
    last_flush: std::time::Instant,
    /// The first write error; later writes are dropped.
    error: Option<String>,
}

impl State {
    fn write(&mut self, text: &str) {
        let Some(out) = self.out.as_mut() else {
            return;
        };
        if let Err(e) = out.write_all(text.as_bytes()) {
            self.fail(e);
            return;
        }
        self.dirty = true;
        if self.last_flush.elapsed() >= FLUSH_EVERY {
            self.flush();
        }
    }

    fn flush(&mut self) {
        self.last_flush = std::time::Instant::now();
        if !self.dirty {
            return;
        }
        self.dirty = false;
        if let Some(out) = self.out.as_mut()
            && let Err(e) = out.flush()
        {
            self.fail(e);
        }
    }

    fn fail(&mut self, e: std::io::Error) {
        tracing::error!(error = %e, "cannot write the capture; recording stopped");
        self.error.get_or_insert_with(|| e.to_string());
        self.out = None;
    }

    fn now(&self) -> Duration {
        self.start
            .map(|s| tokio::time::Instant::now().duration_since(s))
            .unwrap_or_default()
    }
}

type Shared = Arc<Mutex<State>>;

/// Recorders alive in this process, for the panic hook.
static ACTIVE: Mutex<Vec<Weak<Mutex<State>>>> = Mutex::new(Vec::new());

/// Flush every live recorder (the panic hook calls this). Never blocks: a recorder whose lock
/// is held (by the panicking thread, say) is skipped.
pub fn flush_all() {
    let Ok(active) = ACTIVE.try_lock() else {
        return;
    };
    for w in active.iter() {
        if let Some(s) = w.upgrade()
            && let Ok(mut s) = s.try_lock()
        {
            s.flush();
        }
    }
}

/// A capture file being written. Cloning gives another handle to the same file.
#[derive(Clone)]
pub struct Recorder {
    shared: Shared,
    path: PathBuf,
    /// In a capture of several droids, the droid (1-based) this handle's events are about.
    droid: Option<usize>,
}

impl Recorder {
    /// Create `path` for writing. An existing file is refused unless `force`.
    pub fn create(path: &Path, force: bool) -> Result<Recorder, String> {
        let file = crate::output::create(path, force)?;
        let shared = Arc::new(Mutex::new(State {
            out: Some(BufWriter::with_capacity(64 * 1024, file)),
            start: None,
            dirty: false,
            last_flush: std::time::Instant::now(),
            error: None,
        }));
        if let Ok(mut a) = ACTIVE.lock() {
            a.retain(|w| w.strong_count() > 0);
            a.push(Arc::downgrade(&shared));
        }
        spawn_flusher(Arc::downgrade(&shared));
        Ok(Recorder {
            shared,
            path: path.to_path_buf(),
            droid: None,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Write the header and start the clock (call inside the runtime that runs the link).
    pub fn start(&self, header: &Header) {
        let mut s = lock(&self.shared);
        s.start = Some(tokio::time::Instant::now());
        let text = capture::header_text(header);
        s.write(&text);
        s.flush();
    }

    /// The standard header for a session with `model` named `droid`.
    pub fn header_for(model: crate::model::Model, droid: &str) -> Header {
        Header {
            droidctl: Some(env!("CARGO_PKG_VERSION").to_string()),
            model: Some(model),
            family: Some(model.protocol()),
            droid: Some(droid.to_string()),
            started: Some(capture::now_rfc3339()),
        }
    }

    /// Write the header of a capture of several droids (`headers`, in fleet order) and start
    /// the clock; each droid's events then go through [`Recorder::for_droid`].
    pub fn start_fleet(&self, headers: &[Header]) {
        let mut s = lock(&self.shared);
        s.start = Some(tokio::time::Instant::now());
        let text = capture::fleet::header_text(headers);
        s.write(&text);
        s.flush();
    }

    /// A handle recording droid `k` (0-based) of a capture started with
    /// [`Recorder::start_fleet`]: its lines carry `@k+1`.
    pub fn for_droid(&self, k: usize) -> Recorder {
        Recorder {
            droid: Some(k + 1),
            ..self.clone()
        }
    }

    /// Record `event` now.
    pub fn record(&self, event: Event) {
        self.record_before(Duration::ZERO, event);
    }

    /// Record a mark `back` before now (a mission's first sample is taken at its start).
    pub fn mark_before(&self, back: Duration, text: &str) {
        self.record_before(back, Event::Mark(text.to_string()));
    }

    fn record_before(&self, back: Duration, event: Event) {
        let mut s = lock(&self.shared);
        let at = s.now().saturating_sub(back);
        let line = capture::event_line(&Timed { at, event });
        match self.droid {
            Some(k) => s.write(&format!("@{k} {line}")),
            None => s.write(&line),
        }
    }

    pub fn flush(&self) {
        lock(&self.shared).flush();
    }

    /// End the recording: an `end` line, flushed. Later events are not written.
    pub fn finish(&self) -> Result<(), String> {
        self.record(Event::End);
        let mut s = lock(&self.shared);
        s.flush();
        if let Some(mut out) = s.out.take()
            && let Err(e) = out.flush()
        {
            s.fail(e);
        }
        match &s.error {
            Some(e) => Err(format!(
                "the capture {} is incomplete: {e}",
                self.path.display()
            )),
            None => Ok(()),
        }
    }

    /// Wrap `link` so everything over it is recorded.
    pub fn wrap(&self, link: Box<dyn Link>) -> Box<dyn Link> {
        Box::new(RecordingLink {
            inner: link,
            rec: self.clone(),
        })
    }
}

/// Flush at least every [`FLUSH_EVERY`] until the recorder is gone.
fn spawn_flusher(shared: Weak<Mutex<State>>) {
    let spawned = std::thread::Builder::new()
        .name("droidctl-record".into())
        .spawn(move || {
            loop {
                std::thread::sleep(FLUSH_EVERY / 2);
                let Some(s) = shared.upgrade() else {
                    return;
                };
                let mut s = lock(&s);
                if s.out.is_none() {
                    return;
                }
                if s.last_flush.elapsed() >= FLUSH_EVERY / 2 {
                    s.flush();
                }
            }
        });
    if let Err(e) = spawned {
        tracing::warn!(error = %e, "no flusher thread: the capture is flushed as it is written");
    }
}

struct RecordingLink {
    inner: Box<dyn Link>,
    rec: Recorder,
}

impl Link for RecordingLink {
    fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
        Box::pin(async move {
            match self.inner.open().await {
                Ok(conn) => {
                    self.rec.record(Event::Connect);
                    Ok(self.wrap(conn))
                }
                Err(e) => {
                    self.rec.record(Event::ConnectFailed(e.message.clone()));
                    Err(e)
                }
            }
        })
    }

    /// Recording changes nothing about how the link connects: cancelling and the wait
    /// before a retry are the inner link's.
    fn abort_open(&mut self) -> BoxFuture<'_, ()> {
        self.inner.abort_open()
    }

    fn retry_hint(&mut self) -> BoxFuture<'_, ()> {
        self.inner.retry_hint()
    }

    /// A relay that closes quiet clients closes a recorded one just the same: keep it alive.
    fn keepalive(&self) -> Option<std::time::Duration> {
        self.inner.keepalive()
    }

    fn framing(&self) -> Option<crate::link::Framing> {
        self.inner.framing()
    }

    fn describe(&self) -> String {
        self.inner.describe()
    }
}

impl RecordingLink {
    fn wrap(&self, conn: Connection) -> Connection {
        let Connection {
            writer,
            events: mut inner,
        } = conn;
        let (tx, rx) = mpsc::channel(1024);
        let rec = self.rec.clone();
        let closed = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let closed_by_us = closed.clone();
        // What the droid sends, recorded on its way to the session.
        tokio::spawn(async move {
            loop {
                tokio::select! {
                    ev = inner.recv() => match ev {
                        Some(LinkEvent::Data(bytes)) => {
                            rec.record(Event::In(bytes.clone()));
                            if tx.send(LinkEvent::Data(bytes)).await.is_err() {
                                return;
                            }
                        }
                        Some(LinkEvent::Disconnected(reason)) => {
                            rec.record(Event::Disconnect(reason.clone()));
                            let _ = tx.send(LinkEvent::Disconnected(reason)).await;
                            return;
                        }
                        None => {
                            // After our own close the link going quiet is no news.
                            if !closed_by_us.load(std::sync::atomic::Ordering::SeqCst) {
                                rec.record(Event::Disconnect("the link closed".into()));
                            }
                            return;
                        }
                    },
                    _ = tx.closed() => return,
                }
            }
        });
        Connection {
            writer: Box::new(RecordingWriter {
                inner: writer,
                rec: self.rec.clone(),
                closed,
            }),
            events: rx,
        }
    }
}

struct RecordingWriter {
    inner: Box<dyn LinkWriter>,
    rec: Recorder,
    closed: Arc<std::sync::atomic::AtomicBool>,
}

impl RecordingWriter {
    /// Record the write, then hand it to the link (as urgent as it was asked).
    fn recorded<'a>(
        &'a mut self,
        to: Endpoint,
        chunk: &'a [u8],
        urgent: bool,
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        Box::pin(async move {
            self.rec.record(Event::Out(to, chunk.to_vec()));
            let r = if urgent {
                self.inner.write_urgent(to, chunk).await
            } else {
                self.inner.write_to(to, chunk).await
            };
            if let Err(e) = &r {
                self.rec.record(Event::WriteFailed(e.message.clone()));
            }
            r
        })
    }
}

impl LinkWriter for RecordingWriter {
    fn write<'a>(&'a mut self, chunk: &'a [u8]) -> BoxFuture<'a, Result<(), LinkError>> {
        self.write_to(Endpoint::Api, chunk)
    }

    fn write_to<'a>(
        &'a mut self,
        to: Endpoint,
        chunk: &'a [u8],
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        self.recorded(to, chunk, false)
    }

    fn write_urgent<'a>(
        &'a mut self,
        to: Endpoint,
        chunk: &'a [u8],
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        self.recorded(to, chunk, true)
    }

    fn close(&mut self) -> BoxFuture<'_, ()> {
        Box::pin(async move {
            if !self.closed.swap(true, std::sync::atomic::Ordering::SeqCst) {
                self.rec.record(Event::Close);
            }
            self.inner.close().await;
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::capture::Capture;
    use crate::model::Model;
    use crate::sim::{Faults, SimConfig, SimLink};

    fn tmp(name: &str) -> PathBuf {
        let p = std::env::temp_dir().join(format!(
            "droidctl-record-{}-{name}.capture",
            std::process::id()
        ));
        let _ = std::fs::remove_file(&p);
        p
    }

    /// A link that wants traffic when quiet (as a relay's does).
    struct Quiet(SimLink);

    impl Link for Quiet {
        fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
            self.0.open()
        }
        fn keepalive(&self) -> Option<Duration> {
            Some(Duration::from_secs(20))
        }
        fn describe(&self) -> String {
            self.0.describe()
        }
    }

    #[test]
    fn recording_keeps_the_links_keepalive() {
        let p = tmp("keepalive");
        let rec = Recorder::create(&p, false).unwrap();
        let sim = || SimLink::new(Model::Robi42, SimConfig::default(), Faults::none());
        assert_eq!(
            rec.wrap(Box::new(Quiet(sim()))).keepalive(),
            Some(Duration::from_secs(20))
        );
        assert_eq!(rec.wrap(Box::new(sim())).keepalive(), None);
        drop(rec);
        let _ = std::fs::remove_file(&p);
    }

    #[test]
    fn an_existing_file_is_kept_without_force() {
        let p = tmp("exists");
        std::fs::write(&p, "precious").unwrap();
        let e = Recorder::create(&p, false).err().unwrap();
        assert!(e.contains("--force"), "{e}");
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "precious");
        let r = Recorder::create(&p, true).unwrap();
        drop(r);
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "");
        let _ = std::fs::remove_file(&p);
    }

    #[tokio::test(start_paused = true)]
    async fn a_sim_session_is_recorded_with_both_directions() {
        let p = tmp("sim");
        let rec = Recorder::create(&p, false).unwrap();
        rec.start(&Recorder::header_for(Model::R2D2, "R2-D2 (simulated)"));
        let link = rec.wrap(Box::new(SimLink::new(
            Model::R2D2,
            SimConfig::default(),
            Faults::none(),
        )));
        let session = crate::session::start(
            link,
            crate::session::SessionConfig {
                setup: crate::family::setup::connect_setup(
                    Model::R2D2,
                    &crate::family::setup::SetupOptions {
                        tripod: false,
                        streaming_interval_ms: 100,
                        ..Default::default()
                    },
                ),
                ..Default::default()
            },
        );
        tokio::time::sleep(Duration::from_secs(2)).await;
        // Flushed within a second (of wall time) even while the session runs.
        std::thread::sleep(Duration::from_millis(1200));
        let partial = std::fs::read_to_string(&p).unwrap();
        session.shutdown(Vec::new()).await;
        rec.finish().unwrap();
        let c = Capture::from_text(&std::fs::read_to_string(&p).unwrap()).unwrap();
        assert!(c.warnings.is_empty(), "{:?}", c.warnings);
        assert_eq!(c.header.model, Some(Model::R2D2));
        assert_eq!(c.events[0].event, Event::Connect);
        let outs = c
            .events
            .iter()
            .filter(|t| matches!(t.event, Event::Out(..)))
            .count();
        let ins = c
            .events
            .iter()
            .filter(|t| matches!(t.event, Event::In(_)))
            .count();
        assert!(outs >= 3 && ins >= 10, "{outs} out, {ins} in");
        assert_eq!(c.events.last().map(|t| &t.event), Some(&Event::End));
        assert!(c.events.iter().any(|t| t.event == Event::Close));
        assert!(partial.lines().count() > 1, "{partial}");
        let _ = std::fs::remove_file(&p);
    }
}
